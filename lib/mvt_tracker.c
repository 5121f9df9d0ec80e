/*
 * mvt_tracker.c - the tracker loop: measurements, predict, associate + update per camera, delete,
 * initiate. The steps live in mvt_trk_*.c.
 */
#include "mvt_tracker.h"

#include <math.h>
#include <string.h>

#include "mvt_linalg.h"
#include "mvt_body.h"
#include "mvt_trk.h"

void mvt_tracker_config_default(mvt_tracker_config_t *c)
{
    memset(c, 0, sizeof(*c));
    c->filter = MVT_FILTER_PROJECTIVE;
    c->lin = MVT_PKF_JACOBIAN;
    c->gate = MVT_GATE_CHI2;
    mvt_imm_config_default(&c->motion);
    c->numerics.gate_chi2 = MVT_R(13.8);
    c->paper.gamma = MVT_R(6.0);
    for (int i = 0; i < 3; i++) {
        c->paper.var_m2[i] = MVT_R(0.04) * MVT_R(0.04);
        c->volume.min[i] = MVT_R(-5.0);
        c->volume.max[i] = MVT_R(5.0);
    }
    c->volume.min[2] = MVT_R(0.0);
    c->volume.max[2] = MVT_R(3.0);
    c->paper.delta = MVT_R(1.0);
    c->rules.birth_reproj_sigma = MVT_R(4.0);
    c->rules.birth_min_reproj_px = MVT_R(4.0);
    c->rules.birth_min_views = 2;
    c->rules.birth_min_sep_m = MVT_R(0.4);
    c->init_vel_std_ms = MVT_R(1.0);
    c->rules.seen_min_views = 2;
    c->rules.seen_max_std_m = MVT_R(0.0);
    c->rules.confirm_hits = 3;
    c->rules.confirm_window = 5;
    c->rules.tentative_max_misses = 2;
    c->rules.coast_max_s = MVT_R(2.0);
    c->numerics.max_pos_std_m = MVT_R(1.0);
    c->volume.margin_m = MVT_R(0.5);
    c->numerics.var_floor_m2 = MVT_R(1e-10);
    c->rules.merge = MVT_MERGE_NEITHER;
    c->rules.merge_width_m = MVT_R(0.5);
    c->rules.merge_ambiguity = MVT_R(4.0);
    c->rules.dup_dist_m = MVT_R(0.25);
    c->volume.exit_margin_m = MVT_R(0.5);
    c->rules.exit_coast_s = MVT_R(0.3);
    c->rules.occlusion = 1;
    c->body.halfwidth_m = MVT_R(0.2);
    c->rules.occluded_max_s = MVT_R(10.0);
    c->rules.exclusion_m = MVT_R(0.4);
    c->rules.contra_views = 2;
    c->rules.contra_max_s = MVT_R(0.5);
    c->population.p_detect = MVT_R(0.9);
    c->rules.recover_s = MVT_R(3.0);
    c->lifecycle = MVT_LIFECYCLE_BODY;
    c->body.head_height_m = MVT_R(1.70);
    c->body.head_height_sd_m = MVT_R(0.15);
    c->body.foot_sd_m = MVT_R(0.12);
    c->population.birth_per_s = MVT_R(0.1);
    c->population.stay_s = MVT_R(600.0);
    c->population.exit_s = MVT_R(2.0);
    c->population.clutter_per_frame = MVT_R(0.5);
    c->population.exist_confirm = MVT_R(0.9);
    c->population.exist_delete = MVT_R(0.01);
}

/* MVT_LIFECYCLE_BODY's parameters in their physical ranges (mvt_tracker.h). */
static int body_config_ok(const mvt_tracker_config_t *c)
{
    return (c->lifecycle == MVT_LIFECYCLE_RULES || c->lifecycle == MVT_LIFECYCLE_BODY) &&
           c->body.head_height_m >= MVT_R(1.0) && c->body.head_height_m <= MVT_R(2.5) && c->body.head_height_sd_m >= MVT_R(0.02) &&
           c->body.head_height_sd_m <= MVT_R(0.5) && c->body.foot_sd_m >= MVT_R(0.01) && c->body.foot_sd_m <= MVT_R(0.5) &&
           c->population.birth_per_s >= MVT_R(1e-4) && c->population.birth_per_s <= MVT_R(10.0) && c->population.stay_s > MVT_R(0.0) &&
           isfinite(c->population.stay_s) && c->population.exit_s > MVT_R(0.0) && isfinite(c->population.exit_s) &&
           c->population.clutter_per_frame >= MVT_R(0.01) && c->population.clutter_per_frame <= MVT_R(100.0) &&
           c->population.exist_confirm > MVT_R(0.5) && c->population.exist_confirm < MVT_R(1.0) && c->population.exist_delete > MVT_R(0.0) &&
           c->population.exist_delete < MVT_R(0.5) && c->body.halfwidth_m > MVT_R(0.0);
}

static int config_ok(const mvt_tracker_config_t *c)
{
    if (c->volume.num_occluders < 0 || c->volume.num_occluders > MVT_MAX_OCCLUDERS) {
        return 0;
    }
    for (int o = 0; o < c->volume.num_occluders; o++) {
        for (int i = 0; i < 3; i++) {
            const mvt_real lo = c->volume.occluder_min[o][i], hi = c->volume.occluder_max[o][i];
            if (!isfinite(lo) || !isfinite(hi) || !(hi > lo)) {
                return 0;
            }
        }
    }
    for (int i = 0; i < 3; i++) {
        if (!(c->paper.var_m2[i] > MVT_R(0.0)) ||
            !isfinite(c->volume.min[i]) || !isfinite(c->volume.max[i]) || !(c->volume.max[i] > c->volume.min[i])) {
            return 0;
        }
    }
    return body_config_ok(c) && mvt_imm_config_check(&c->motion) == MVT_OK && c->numerics.gate_chi2 > MVT_R(0.0) && c->paper.gamma > MVT_R(0.0) && c->paper.delta > MVT_R(0.0) &&
           c->rules.birth_reproj_sigma > MVT_R(0.0) && c->rules.birth_min_reproj_px >= MVT_R(0.0) && c->rules.birth_min_views >= 2 &&
           c->rules.birth_min_sep_m >= MVT_R(0.0) && c->init_vel_std_ms > MVT_R(0.0) && c->rules.confirm_window >= 1 &&
           c->rules.seen_min_views >= 1 && c->rules.seen_max_std_m >= MVT_R(0.0) && isfinite(c->rules.seen_max_std_m) &&
           c->rules.confirm_window <= 32 && c->rules.confirm_hits >= 1 && c->rules.confirm_hits <= c->rules.confirm_window &&
           c->rules.tentative_max_misses >= 1 && c->rules.coast_max_s > MVT_R(0.0) && c->numerics.max_pos_std_m > MVT_R(0.0) &&
           c->volume.margin_m >= MVT_R(0.0) && c->numerics.var_floor_m2 >= MVT_R(0.0) &&
           c->rules.merge_width_m > MVT_R(0.0) && isfinite(c->rules.merge_width_m) && c->rules.dup_dist_m >= MVT_R(0.0) &&
           c->rules.merge_ambiguity >= MVT_R(0.0) && isfinite(c->rules.merge_ambiguity) &&
           isfinite(c->rules.dup_dist_m) && c->volume.exit_margin_m >= MVT_R(0.0) && isfinite(c->volume.exit_margin_m) &&
           c->rules.exit_coast_s > MVT_R(0.0) && isfinite(c->rules.exit_coast_s) &&
           (c->rules.occlusion == 0 || c->rules.occlusion == 1) && c->body.halfwidth_m >= MVT_R(0.0) &&
           isfinite(c->body.halfwidth_m) && c->rules.occluded_max_s > MVT_R(0.0) && isfinite(c->rules.occluded_max_s) &&
           c->rules.exclusion_m >= MVT_R(0.0) && isfinite(c->rules.exclusion_m) &&
           c->rules.contra_views >= 1 && c->rules.contra_max_s > MVT_R(0.0) && isfinite(c->rules.contra_max_s) &&
           c->population.p_detect > MVT_R(0.0) && c->population.p_detect < MVT_R(1.0) &&
           c->rules.recover_s >= MVT_R(0.0) && c->rules.recover_s <= MVT_R(3600.0) &&
           (c->rules.merge == MVT_MERGE_NEITHER || c->rules.merge == MVT_MERGE_SHARE || c->rules.merge == MVT_MERGE_OFF ||
            c->rules.merge == MVT_MERGE_TOP) &&
           (c->filter == MVT_FILTER_PROJECTIVE || c->filter == MVT_FILTER_TRIANGULATE) &&
           (c->gate == MVT_GATE_CHI2 || c->gate == MVT_GATE_PAPER) &&
           (c->lin == MVT_PKF_JACOBIAN || c->lin == MVT_PKF_PAPER || c->lin == MVT_PKF_PAPER_CENTRED);
}

mvt_err_t mvt_tracker_init(mvt_tracker_t *self, const mvt_tracker_config_t *cfg, const mvt_camera_t *cams,
                           int num_cameras)
{
    MVT_ASSERT(self != NULL && cfg != NULL && cams != NULL);
    if (num_cameras < 1 || num_cameras > MVT_MAX_CAMERAS || !config_ok(cfg)) {
        return MVT_ERR_INVALID;
    }
    memset(self, 0, sizeof(*self));
    self->cfg = *cfg;
    self->num_cameras = num_cameras;
    memcpy(self->cams, cams, (size_t)num_cameras * sizeof(cams[0]));
    self->next_id = 1;
    return MVT_OK;
}

/* Undistorts every detection once; counts and drops what is unusable. */
static void prepare_measurements(mvt_tracker_t *self, const mvt_frame_t *frame)
{
    for (int k = 0; k < self->num_cameras; k++) {
        const mvt_view_t *v = &frame->views[k];
        self->num_meas[k] = 0;
        if (!v->observed) {
            continue;
        }
        int n = v->num_detections;
        if (n < 0) {
            n = 0;
        }
        if (n > MVT_MAX_DETECTIONS) {
            self->counters.detections_over_capacity += (uint64_t)(n - MVT_MAX_DETECTIONS);
            n = MVT_MAX_DETECTIONS;
        }
        self->num_meas[k] = n;
        const mvt_camera_t *cam = &self->cams[k];
        for (int d = 0; d < n; d++) {
            const mvt_detection_t *det = &v->det[d];
            const mvt_real uv[2] = {det->u, det->v};
            const mvt_real sigma = det->sigma_px > MVT_R(0.0) ? det->sigma_px : cam->sigma_px;
            self->used[k][d] = 0;
            self->meas_ok[k][d] = 0;
            self->chroma_ok[k][d] = (uint8_t)mvt_trk_chroma(det, self->chroma[k][d]);
            const mvt_err_t err = mvt_pkf_meas_make(cam, uv, sigma, &self->meas[k][d]);
            if (err == MVT_OK) {
                self->meas_ok[k][d] = 1;
            } else if (err == MVT_ERR_NONFINITE) {
                self->counters.detections_nonfinite++;
            } else {
                self->counters.detections_undistort_failed++;
            }
        }
    }
}

/* Updates track t with measurement m of camera k (detection d of the view, or -1: the head read
 * from the view's mask) and keeps the frame's books. Returns 1 when the update was made. */
static int apply_measurement(mvt_tracker_t *self, int t, int k, const mvt_pkf_meas_t *m, int d, int merged)
{
    mvt_track_t *tr = &self->tracks[t];
    mvt_pkf_innov_t in;
    const mvt_real *extra = d >= 0 && self->merge_wide[t] ? self->merge_cov[t] : NULL;
    mvt_err_t err = mvt_pkf_innovation_from(&self->pred[t], m, extra, &in);
    if (err == MVT_OK) {
        err = mvt_trk_update_pkf(self, tr, k, &in, extra);
    }
    if (err != MVT_OK) {
        self->counters.numeric_faults++;
        return 0;
    }
    if (tr->status != MVT_TRACK_TENTATIVE) {
        self->ev_llr[t] += mvt_trk_detected_llr(self, k, &in);
    }
    tr->cameras_used |= 1u << k;
    if (tr->view[k].p < MVT_R(0.5)) {
        tr->cameras_placed |= 1u << k;
    }
    self->counters.updates++;
    self->counters.merged_updates += (uint64_t)merged;
    if (d >= 0 && self->chroma_ok[k][d] && self->merge_nb[t] < 0 && !merged) {
        /* a blob that may hold an unresolved neighbour mixes two people's colour */
        mvt_trk_app_update(&tr->app, self->chroma[k][d]);
    }
    return 1;
}

static void step_projective(mvt_tracker_t *self, const mvt_frame_t *frame, const int order[], int n_order)
{
    const mvt_tracker_config_t *c = &self->cfg;
    for (int oi = 0; oi < n_order; oi++) {
        const int k = order[oi];
        const int64_t tk = frame->views[k].utime_us;
        for (int t = 0; t < MVT_MAX_TARGETS; t++) {
            if (self->tracks[t].id != 0) {
                mvt_trk_predict_pos(self, &self->tracks[t], tk);
            }
        }
        int assign[MVT_MAX_TARGETS];
        uint8_t merged[MVT_MAX_TARGETS];
        mvt_trk_associate(self, &frame->views[k], k, assign, merged);
        memset(self->top_ok, 0, sizeof(self->top_ok));
        if (c->rules.occlusion) {
            mvt_trk_occlusion(self, &frame->views[k], k, assign);
        }
        for (int t = 0; t < MVT_MAX_TARGETS; t++) {
            if (self->tracks[t].id == 0) {
                continue;
            }
            if (assign[t] >= 0) {
                apply_measurement(self, t, k, &self->meas[k][assign[t]], assign[t], merged[t]);
            } else if (self->top_ok[t] && apply_measurement(self, t, k, &self->top_meas[t], -1, 0)) {
                self->counters.mask_top_updates++;
            }
        }
    }
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        if (self->tracks[t].id != 0) {
            mvt_trk_settle(self, &self->tracks[t]);
        }
    }
}

static void step_triangulate(mvt_tracker_t *self, const mvt_frame_t *frame, const int order[], int n_order)
{
    const mvt_tracker_config_t *c = &self->cfg;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        if (self->tracks[t].id != 0) {
            mvt_trk_predict(self, &self->tracks[t], frame->utime_us);
        }
    }
    /* association of each camera's detections to the predicted tracks (the same gate as the
     * projective filters, so that the comparison isolates the estimator) */
    int assign[MVT_MAX_CAMERAS][MVT_MAX_TARGETS];
    uint8_t merged[MVT_MAX_TARGETS];
    for (int oi = 0; oi < n_order; oi++) {
        mvt_trk_associate(self, &frame->views[order[oi]], order[oi], assign[oi], merged);
    }
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0) {
            continue;
        }
        mvt_tri_obs_t obs[MVT_MAX_CAMERAS];
        int n = 0;
        for (int oi = 0; oi < n_order; oi++) {
            const int d = assign[oi][t];
            if (d >= 0) {
                const int k = order[oi];
                obs[n].cam = k;
                obs[n].xn[0] = self->meas[k][d].xn[0];
                obs[n].xn[1] = self->meas[k][d].xn[1];
                obs[n].var_px2 = self->meas[k][d].var_px2;
                n++;
            }
        }
        if (n < 2) {
            continue;
        }
        const mvt_real thr = c->rules.birth_reproj_sigma * MVT_SQRT(obs[0].var_px2);
        uint32_t used_bits = 0u;
        const mvt_err_t err = mvt_trk_update_triangulated(
            self, tr, obs, n, thr > c->rules.birth_min_reproj_px ? thr : c->rules.birth_min_reproj_px, &used_bits);
        if (err == MVT_OK) {
            tr->cameras_used |= used_bits;
            self->counters.updates++;
        } else if (err != MVT_ERR_DEGENERATE) {
            self->counters.numeric_faults++;
        }
    }
}

void mvt_tracker_output(const mvt_tracker_t *self, int64_t utime_us, mvt_output_t *out)
{
    out->utime_us = utime_us;
    out->num_tracks = 0;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        const mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0 || tr->dormant) {
            continue;
        }
        mvt_track_out_t *o = &out->tracks[out->num_tracks++];
        o->id = tr->id;
        o->status = tr->status;
        const mvt_real *P = tr->s.P;
        for (int i = 0; i < 3; i++) {
            o->pos_m[i] = tr->s.x[i];
            o->vel_ms[i] = tr->s.x[i + 3];
            const mvt_real sd = MVT_SQRT(P[i * 6 + i]);
            o->extent_min[i] = tr->s.x[i] - MVT_R(2.0) * sd;
            o->extent_max[i] = tr->s.x[i] + MVT_R(2.0) * sd;
        }
        o->cov_m2[0] = P[0];
        o->cov_m2[1] = P[1];
        o->cov_m2[2] = P[2];
        o->cov_m2[3] = P[7];
        o->cov_m2[4] = P[8];
        o->cov_m2[5] = P[14];
        o->cameras_used = tr->cameras_used;
        mvt_trk_app_hue_sat(&tr->app, &o->hue, &o->saturation);
    }
}

mvt_err_t mvt_tracker_step(mvt_tracker_t *self, const mvt_frame_t *frame, mvt_output_t *out)
{
    MVT_ASSERT(self != NULL && frame != NULL);
    if (self->have_time && frame->utime_us < self->last_utime_us) {
        self->counters.frames_time_backwards++;
        return MVT_ERR_INVALID;
    }
    const mvt_real dt = self->have_time ? mvt_us_to_s(frame->utime_us - self->last_utime_us) : MVT_R(0.0);
    const mvt_real forget = MVT_EXP(-dt / MVT_TRK_NEED_MEMORY_S);
    const int body = self->cfg.lifecycle == MVT_LIFECYCLE_BODY;
    if (!body) {
        mvt_trk_existence(self, dt);
    }
    self->have_time = 1;
    self->last_utime_us = frame->utime_us;
    self->counters.frames++;
    prepare_measurements(self, frame);
    if (!body) {
        mvt_trk_evidence_weights(self, frame);
    }

    /* observed cameras in capture-time order (insertion sort, stable, <= MVT_MAX_CAMERAS) */
    int order[MVT_MAX_CAMERAS];
    int n_order = 0;
    for (int k = 0; k < self->num_cameras; k++) {
        if (!frame->views[k].observed) {
            continue;
        }
        int i = n_order++;
        while (i > 0 && frame->views[order[i - 1]].utime_us > frame->views[k].utime_us) {
            order[i] = order[i - 1];
            i--;
        }
        order[i] = k;
    }
    for (int k = self->num_cameras; k < MVT_MAX_CAMERAS; k++) {
        if (frame->views[k].observed) {
            self->counters.views_unknown_camera++;
        }
    }
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        self->tracks[t].cameras_used = 0u;
        self->tracks[t].cameras_placed_prev = self->tracks[t].cameras_placed;
        self->tracks[t].cameras_placed = 0u;
        self->tracks[t].cameras_occluded = 0u;
        self->tracks[t].need_llr *= forget;
        self->tracks[t].cameras_uncovered = 0u;
        self->tracks[t].cameras_empty = 0u;
        self->tracks[t].cameras_fg = 0u;
        self->visible[t] = 0u;
        self->ev_llr[t] = MVT_R(0.0);
    }
    if (body) {
        mvt_body_step(self, frame, order, n_order, dt);
        if (out != NULL) {
            mvt_tracker_output(self, frame->utime_us, out);
        }
        return MVT_OK;
    }

    mvt_trk_reacquire(self, frame, order, n_order);
    if (self->cfg.filter == MVT_FILTER_PROJECTIVE) {
        step_projective(self, frame, order, n_order);
    } else {
        step_triangulate(self, frame, order, n_order);
    }
    if (self->cfg.rules.exclusion_m > MVT_R(0.0)) {
        mvt_trk_exclusion(self);
    }
    mvt_trk_hold_height(self);
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        if (self->tracks[t].id != 0) {
            mvt_trk_predict(self, &self->tracks[t], frame->utime_us);
        }
    }
    mvt_trk_delete(self, frame->utime_us);
    mvt_trk_initiate(self, frame, order, n_order);
    if (out != NULL) {
        mvt_tracker_output(self, frame->utime_us, out);
    }
    return MVT_OK;
}

int mvt_tracker_select(const mvt_tracker_t *self, int cam, const mvt_detection_t *in, int n_in,
                       int keep[MVT_MAX_DETECTIONS])
{
    MVT_ASSERT(self != NULL && in != NULL && keep != NULL);
    if (n_in <= 0 || cam < 0 || cam >= self->num_cameras) {
        return 0;
    }
    if (n_in <= MVT_MAX_DETECTIONS) {
        for (int i = 0; i < n_in; i++) {
            keep[i] = i;
        }
        return n_in;
    }
    const mvt_camera_t *camera = &self->cams[cam];
    int n = 0;
    /* 1. each track's nearest detection inside its gate (raw pixels, Jacobian prediction) */
    for (int t = 0; t < MVT_MAX_TARGETS && n < MVT_MAX_DETECTIONS; t++) {
        const mvt_track_t *tr = &self->tracks[t];
        mvt_pkf_pred_t pred;
        if (tr->id == 0 || mvt_pkf_predict_obs(&tr->s, camera, MVT_PKF_JACOBIAN, &pred) != MVT_OK) {
            continue;
        }
        int best = -1;
        mvt_real best_d2 = MVT_R(0.0);
        for (int i = 0; i < n_in; i++) {
            const mvt_real sigma = in[i].sigma_px > MVT_R(0.0) ? in[i].sigma_px : camera->sigma_px;
            mvt_pkf_meas_t m;
            m.raw[0] = in[i].u;
            m.raw[1] = in[i].v;
            m.ideal[0] = m.ideal[1] = m.xn[0] = m.xn[1] = MVT_R(0.0);
            m.var_px2 = sigma * sigma;
            mvt_pkf_innov_t inn;
            if (!isfinite(in[i].u) || !isfinite(in[i].v) || !isfinite(sigma) ||
                mvt_pkf_innovation_from(&pred, &m, NULL, &inn) != MVT_OK || !(inn.d2 <= self->cfg.numerics.gate_chi2)) {
                continue;
            }
            if (best < 0 || inn.d2 < best_d2) {
                best = i;
                best_d2 = inn.d2;
            }
        }
        int dup = 0;
        for (int j = 0; j < n && !dup; j++) {
            dup = keep[j] == best;
        }
        if (best >= 0 && !dup) {
            keep[n++] = best;
        }
    }
    const int n_track = n;
    /* 2. the rest by decreasing score (a NaN score ranks last), ties by input order: a bounded
     * sorted insertion into keep[n_track..] */
    for (int i = 0; i < n_in; i++) {
        int taken = 0;
        for (int j = 0; j < n_track && !taken; j++) {
            taken = keep[j] == i;
        }
        if (taken) {
            continue;
        }
        const mvt_real s = isfinite(in[i].score) ? in[i].score : MVT_R(-1e30);
        int pos = n;
        while (pos > n_track) {
            const int o = keep[pos - 1];
            const mvt_real so = isfinite(in[o].score) ? in[o].score : MVT_R(-1e30);
            if (!(s > so)) {
                break;
            }
            pos--;
        }
        if (pos >= MVT_MAX_DETECTIONS) {
            continue;
        }
        const int last = n < MVT_MAX_DETECTIONS ? n : MVT_MAX_DETECTIONS - 1;
        for (int j = last; j > pos; j--) {
            keep[j] = keep[j - 1];
        }
        keep[pos] = i;
        if (n < MVT_MAX_DETECTIONS) {
            n++;
        }
    }
    /* increasing input order */
    for (int i = 1; i < n; i++) {
        const int key = keep[i];
        int j = i - 1;
        while (j >= 0 && keep[j] > key) {
            keep[j + 1] = keep[j];
            j--;
        }
        keep[j + 1] = key;
    }
    return n;
}
