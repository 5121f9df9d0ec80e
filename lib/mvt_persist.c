/*
 * mvt_persist.c - the trackers' persistent state: save, check and restore (a daemon's checkpoint),
 * and the identity floor for a restart without one.
 *
 * A restored state must never be half loaded and never carry a value the filters would choke on
 * (a checkpoint file is input like any other: its checksum catches accidents, not every bug that
 * wrote it), so resume checks everything first and copies only then.
 */
#include <math.h>
#include <string.h>

#include "mvt_linalg.h"
#include "mvt_pft.h"
#include "mvt_tracker.h"
#include "mvt_trk.h"

/* Positions within the tracked volume widened by MVT_PERSIST_SLACK_M, speeds below
 * MVT_PERSIST_MAX_SPEED: any tracker keeps its estimates far inside these (it deletes tracks that
 * leave the volume plus a margin), while a value beyond them would overflow the integer pixel
 * arithmetic downstream even though it is finite. */
#define MVT_PERSIST_SLACK_M MVT_R(10.0)
#define MVT_PERSIST_MAX_SPEED MVT_R(100.0)
#define MVT_PERSIST_MAX_VAR MVT_R(1e6)
#define MVT_PERSIST_MAX_PX MVT_R(1e6)

static int status_ok(int32_t s)
{
    return s == MVT_TRACK_TENTATIVE || s == MVT_TRACK_CONFIRMED || s == MVT_TRACK_COASTING;
}

/* Finite, symmetric and positive definite (a Cholesky factor exists). */
static int covariance_ok(const mvt_real P[36])
{
    mvt_real l[36];
    if (!mvt_la_all_finite(P, 36)) {
        return 0;
    }
    for (int i = 0; i < 6; i++) {
        for (int j = 0; j < i; j++) {
            const mvt_real a = P[i * 6 + j], b = P[j * 6 + i];
            if (MVT_FABS(a - b) > MVT_R(1e-3) * (MVT_FABS(a) + MVT_FABS(b)) + MVT_R(1e-12)) {
                return 0;
            }
        }
    }
    for (int i = 0; i < 6; i++) {
        if (!(P[i * 7] <= MVT_PERSIST_MAX_VAR)) {
            return 0;
        }
    }
    memcpy(l, P, sizeof(l));
    return mvt_la_cholesky(6, l) == MVT_OK;
}

/* Time stamps may not lie after the state's clock, nor before 0 (tracker time starts at a message
 * time >= 0 and only grows), nor so far before it that a time difference could overflow. */
static int time_ok(int64_t t, int64_t now)
{
    return t >= 0 && t <= now && t >= now - (INT64_C(1) << 60); /* now is in 0..2^61 */
}

static int place_ok(const mvt_tracker_config_t *c, const mvt_real pos[3], const mvt_real vel[3])
{
    for (int i = 0; i < 3; i++) {
        if (!(pos[i] >= c->volume.min[i] - MVT_PERSIST_SLACK_M && pos[i] <= c->volume.max[i] + MVT_PERSIST_SLACK_M) ||
            !(MVT_FABS(vel[i]) <= MVT_PERSIST_MAX_SPEED)) {
            return 0;
        }
    }
    return 1;
}

static int estimate_ok(const mvt_tracker_config_t *c, const mvt_cv_state_t *s, int64_t now)
{
    return mvt_la_all_finite(s->x, 6) && covariance_ok(s->P) && place_ok(c, s->x, s->x + 3) && time_ok(s->utime_us, now);
}

/* An IMM bank (mvt_trk_motion.c: used unless the motion is one constant-velocity model): every
 * model's estimate as good as the combined one and at its time, probabilities that sum to 1. */
static int bank_ok(const mvt_tracker_config_t *c, const mvt_track_t *tr)
{
    if (c->motion.n == 1 && mvt_imm_model_is(&c->motion.model[0], MVT_MOTION_CV)) {
        return 1;
    }
    mvt_real sum = MVT_R(0.0);
    for (int j = 0; j < c->motion.n; j++) {
        const mvt_real mu = tr->imm.mu[j];
        if (!(mu >= MVT_R(0.0) && mu <= MVT_R(1.0)) || tr->imm.m[j].utime_us != tr->s.utime_us ||
            !estimate_ok(c, &tr->imm.m[j], tr->s.utime_us)) {
            return 0;
        }
        sum += mu;
    }
    return MVT_FABS(sum - MVT_R(1.0)) <= MVT_R(1e-3);
}

static int ids_unique(const int32_t *ids, int n)
{
    for (int i = 0; i < n; i++) {
        for (int j = i + 1; j < n && ids[i] != 0; j++) {
            if (ids[i] == ids[j]) {
                return 0;
            }
        }
    }
    return 1;
}

void mvt_tracker_save(const mvt_tracker_t *self, mvt_tracker_persist_t *out)
{
    MVT_ASSERT(self != NULL && out != NULL);
    memset(out, 0, sizeof(*out));
    memcpy(out->tracks, self->tracks, sizeof(out->tracks));
    out->next_id = self->next_id;
    out->have_time = self->have_time;
    out->last_utime_us = self->last_utime_us;
    out->counters = self->counters;
    memcpy(out->clutter_n, self->clutter_n, sizeof(out->clutter_n));
    memcpy(out->p_detect_k, self->p_detect_k, sizeof(out->p_detect_k));
    memcpy(out->p_hidden_k, self->p_hidden_k, sizeof(out->p_hidden_k));
    memcpy(out->p_bg_k, self->p_bg_k, sizeof(out->p_bg_k));
    memcpy(out->foot_ahead_k, self->foot_ahead_k, sizeof(out->foot_ahead_k));
    memcpy(out->foot_var_k, self->foot_var_k, sizeof(out->foot_var_k));
    memcpy(out->p_feet_k, self->p_feet_k, sizeof(out->p_feet_k));
    memcpy(out->frag_n, self->frag_n, sizeof(out->frag_n));
}

/* The head height of the last frame seen: in the volume widened like positions, a variance. */
static int seen_height_ok(const mvt_tracker_config_t *c, const mvt_track_t *tr)
{
    return tr->seen_z >= c->volume.min[2] - MVT_PERSIST_SLACK_M && tr->seen_z <= c->volume.max[2] + MVT_PERSIST_SLACK_M &&
           tr->seen_zz >= MVT_R(0.0) && tr->seen_zz <= MVT_PERSIST_MAX_VAR &&
           tr->z_mean >= c->volume.min[2] - MVT_PERSIST_SLACK_M && tr->z_mean <= c->volume.max[2] + MVT_PERSIST_SLACK_M &&
           tr->z_var >= MVT_R(0.0) && tr->z_var <= MVT_PERSIST_MAX_VAR;
}

/* Each camera's memory of displacement (mvt_imm_view_t) and the displacement it holds from an
 * onset (mvt_trk_onset_t): probabilities, finite pixels no larger than a picture could hold, times no
 * later than the state's (an onset's last detection included), a time since its confirmation that
 * is a time. */
static int views_ok(const mvt_track_t *tr, int64_t now)
{
    for (int k = 0; k < MVT_MAX_CAMERAS; k++) {
        const mvt_imm_view_t *v = &tr->view[k];
        const mvt_trk_onset_t *o = &tr->onset[k];
        if (!(v->p >= MVT_R(0.0) && v->p <= MVT_R(1.0)) || !(MVT_FABS(v->y[0]) <= MVT_PERSIST_MAX_PX) ||
            !(MVT_FABS(v->y[1]) <= MVT_PERSIST_MAX_PX) || !time_ok(v->utime_us, now) ||
            !(MVT_FABS(o->head[0]) <= MVT_PERSIST_MAX_PX) || !(MVT_FABS(o->head[1]) <= MVT_PERSIST_MAX_PX) ||
            !(MVT_FABS(o->y[0]) <= MVT_PERSIST_MAX_PX) || !(MVT_FABS(o->y[1]) <= MVT_PERSIST_MAX_PX) ||
            !(o->p >= MVT_R(0.0) && o->p <= MVT_R(1.0)) || !(o->seen_s >= MVT_R(0.0) && o->seen_s <= MVT_R(1e6)) ||
            (o->confirmed_us != 0 && !(time_ok(o->confirmed_us, now) &&
                                       mvt_us_to_s(now - o->confirmed_us) >= o->seen_s))) {
            return 0;
        }
    }
    return 1;
}

static int tracker_state_ok(const mvt_tracker_config_t *c, const mvt_tracker_persist_t *p)
{
    if (p->next_id <= 0 || (p->have_time != 0 && p->have_time != 1) || p->last_utime_us < 0 ||
        p->last_utime_us > (INT64_C(1) << 61)) {
        return 0;
    }
    for (int k = 0; k < MVT_MAX_CAMERAS; k++) {
        if (!(p->clutter_n[k] >= MVT_R(0.0) && p->clutter_n[k] <= (mvt_real)MVT_MAX_DETECTIONS) ||
            !(p->p_detect_k[k] >= MVT_R(0.0) && p->p_detect_k[k] < MVT_R(1.0)) ||
            !(p->p_hidden_k[k] >= MVT_R(0.0) && p->p_hidden_k[k] < MVT_R(1.0)) ||
            !(p->p_bg_k[k] >= MVT_R(0.0) && p->p_bg_k[k] < MVT_R(1.0)) ||
            !(p->foot_ahead_k[k] >= MVT_R(0.0) && p->foot_ahead_k[k] <= MVT_R(1.0)) ||
            !(p->foot_var_k[k] >= MVT_R(0.0) && p->foot_var_k[k] <= MVT_R(1.0)) ||
            !(p->p_feet_k[k] >= MVT_R(0.0) && p->p_feet_k[k] <= MVT_R(1.0)) ||
            !(p->frag_n[k] >= MVT_R(0.0) && p->frag_n[k] <= (mvt_real)MVT_MAX_DETECTIONS)) {
            return 0;
        }
    }
    int32_t ids[MVT_MAX_TARGETS];
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        const mvt_track_t *tr = &p->tracks[t];
        ids[t] = tr->id;
        if (tr->id == 0) {
            continue;
        }
        const int64_t now = p->last_utime_us;
        if (tr->id < 0 || !p->have_time || !status_ok(tr->status) || !estimate_ok(c, &tr->s, now) ||
            !time_ok(tr->last_update_us, now) || !bank_ok(c, tr) || !isfinite(tr->exist_lo) ||
            (tr->dormant != 0 && tr->dormant != 1) || (tr->was_shown != 0 && tr->was_shown != 1) ||
            !(tr->one_view_s >= MVT_R(0.0)) || !isfinite(tr->one_view_s) || !(tr->agree_s >= MVT_R(0.0)) ||
            !isfinite(tr->agree_s) || !seen_height_ok(c, tr) ||
            !mvt_trk_app_ok(&tr->app) || !views_ok(tr, now)) {
            return 0;
        }
    }
    return ids_unique(ids, MVT_MAX_TARGETS); /* every identity at most once */
}

static void shift_track_clocks(mvt_track_t *tracks, int64_t by_us)
{
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        if (tracks[t].id != 0) {
            tracks[t].last_update_us += by_us;
        }
    }
}

static int unobserved_ok(int64_t unobserved_us)
{
    return unobserved_us >= 0 && unobserved_us < (INT64_C(1) << 60);
}

mvt_err_t mvt_tracker_resume(mvt_tracker_t *self, const mvt_tracker_persist_t *p, int64_t unobserved_us)
{
    MVT_ASSERT(self != NULL && p != NULL);
    if (!unobserved_ok(unobserved_us) || !tracker_state_ok(&self->cfg, p)) {
        return MVT_ERR_INVALID;
    }
    memcpy(self->tracks, p->tracks, sizeof(self->tracks));
    shift_track_clocks(self->tracks, unobserved_us);
    self->next_id = p->next_id;
    self->have_time = p->have_time;
    self->last_utime_us = p->last_utime_us;
    self->counters = p->counters;
    memcpy(self->clutter_n, p->clutter_n, sizeof(self->clutter_n));
    memcpy(self->p_detect_k, p->p_detect_k, sizeof(self->p_detect_k));
    memcpy(self->p_hidden_k, p->p_hidden_k, sizeof(self->p_hidden_k));
    memcpy(self->p_bg_k, p->p_bg_k, sizeof(self->p_bg_k));
    memcpy(self->foot_ahead_k, p->foot_ahead_k, sizeof(self->foot_ahead_k));
    memcpy(self->foot_var_k, p->foot_var_k, sizeof(self->foot_var_k));
    memcpy(self->p_feet_k, p->p_feet_k, sizeof(self->p_feet_k));
    memcpy(self->frag_n, p->frag_n, sizeof(self->frag_n));
    return MVT_OK;
}

void mvt_tracker_reserve_ids(mvt_tracker_t *self, int32_t first)
{
    MVT_ASSERT(self != NULL);
    if (first > self->next_id) {
        self->next_id = first;
    }
}

void mvt_pft_save(const mvt_pft_t *self, mvt_pft_persist_t *out)
{
    MVT_ASSERT(self != NULL && out != NULL);
    memset(out, 0, sizeof(*out));
    mvt_tracker_save(&self->det, &out->det);
    memcpy(out->targets, self->targets, sizeof(out->targets));
    out->next_id = self->next_id;
    out->have_time = self->have_time;
    out->last_utime_us = self->last_utime_us;
    for (int r = 0; r < MVT_MAX_TARGETS; r++) {
        out->lost[r].id = self->lost[r].id;
        out->lost[r].blob_id = self->lost[r].blob_id;
        out->lost[r].until_us = self->lost[r].until_us;
    }
    out->rng = self->rng;
    out->counters = self->counters;
}

static int pool_ok(const mvt_tracker_config_t *c, const mvt_pf_pool_t *pool, int n)
{
    if (pool->n != n) {
        return 0;
    }
    mvt_real sum = MVT_R(0.0);
    for (int i = 0; i < n; i++) {
        const mvt_real v[9] = {pool->x[i], pool->y[i], pool->z[i], pool->vx[i], pool->vy[i],
                               pool->vz[i], pool->h[i], pool->s[i], pool->w[i]};
        if (!mvt_la_all_finite(v, 9) || !(pool->w[i] >= MVT_R(0.0)) || !place_ok(c, v, v + 3) ||
            !(pool->h[i] >= MVT_R(0.0) && pool->h[i] <= MVT_R(1.0)) ||
            !(pool->s[i] >= MVT_R(0.0) && pool->s[i] <= MVT_R(1.0))) {
            return 0;
        }
        sum += pool->w[i];
    }
    return MVT_FABS(sum - MVT_R(1.0)) < MVT_R(1e-2); /* saved between frames: normalised weights */
}

static int pft_state_ok(const mvt_pft_t *self, const mvt_pft_persist_t *p)
{
    if (p->next_id <= 0 || (p->have_time != 0 && p->have_time != 1) || p->last_utime_us < 0 ||
        p->last_utime_us > (INT64_C(1) << 61) || (p->rng.inc & 1u) == 0u) {
        return 0; /* a PCG stream increment is odd */
    }
    int32_t ids[MVT_MAX_TARGETS];
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        const mvt_pft_target_t *a = &p->targets[t];
        ids[t] = a->id;
        if (a->id == 0) {
            continue;
        }
        const int64_t now = p->last_utime_us;
        if (a->id < 0 || !p->have_time || !status_ok(a->status) || a->supported_frames < 0 || a->blob_id < 0 ||
            !time_ok(a->last_supported_us, now) || a->recover_until_us < 0 || a->recover_until_us > (INT64_C(1) << 61) ||
            !place_ok(&self->cfg.det, a->est.mean, a->est.vel) || !isfinite(a->est.head_z) ||
            !(MVT_FABS(a->est.head_z) <= MVT_R(100.0)) || !place_ok(&self->cfg.det, a->est.box_min, a->est.vel) ||
            !place_ok(&self->cfg.det, a->est.box_max, a->est.vel) || !mvt_la_all_finite(a->est.cov, 6) ||
            !isfinite(a->est.hue) || !isfinite(a->est.saturation) || !pool_ok(&self->cfg.det, &a->pool, self->cfg.num_particles)) {
            return 0;
        }
    }
    for (int r = 0; r < MVT_MAX_TARGETS; r++) {
        if (p->lost[r].id < 0 || p->lost[r].blob_id < 0 || p->lost[r].until_us < 0 ||
            p->lost[r].until_us > (INT64_C(1) << 61)) {
            return 0;
        }
    }
    return ids_unique(ids, MVT_MAX_TARGETS);
}

mvt_err_t mvt_pft_resume(mvt_pft_t *self, const mvt_pft_persist_t *p, int64_t unobserved_us)
{
    MVT_ASSERT(self != NULL && p != NULL);
    if (!unobserved_ok(unobserved_us) || !tracker_state_ok(&self->det.cfg, &p->det) || !pft_state_ok(self, p)) {
        return MVT_ERR_INVALID;
    }
    (void)mvt_tracker_resume(&self->det, &p->det, unobserved_us); /* checked above: cannot fail */
    memcpy(self->targets, p->targets, sizeof(self->targets));
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        mvt_pft_target_t *a = &self->targets[t];
        if (a->id != 0) {
            a->last_supported_us += unobserved_us;
            a->recover_until_us += a->recover_until_us != 0 ? unobserved_us : 0;
        }
    }
    for (int r = 0; r < MVT_MAX_TARGETS; r++) {
        self->lost[r].id = p->lost[r].id;
        self->lost[r].blob_id = p->lost[r].blob_id;
        self->lost[r].until_us = p->lost[r].until_us + (p->lost[r].id != 0 ? unobserved_us : 0);
    }
    self->next_id = p->next_id;
    self->have_time = p->have_time;
    self->last_utime_us = p->last_utime_us;
    self->rng = p->rng;
    self->counters = p->counters;
    return MVT_OK;
}

void mvt_pft_reserve_ids(mvt_pft_t *self, int32_t first)
{
    MVT_ASSERT(self != NULL);
    mvt_tracker_reserve_ids(&self->det, first);
    if (first > self->next_id) {
        self->next_id = first;
    }
}
