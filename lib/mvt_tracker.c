#include "mvt_tracker.h"

#include <math.h>
#include <string.h>

#include "mvt_linalg.h"

#define COST_NONE MVT_R(-1.0)

void mvt_tracker_config_default(mvt_tracker_config_t *c)
{
    memset(c, 0, sizeof(*c));
    c->filter = MVT_FILTER_PROJECTIVE;
    c->lin = MVT_PKF_JACOBIAN;
    c->gate = MVT_GATE_CHI2;
    c->q_m2s3[0] = MVT_R(0.5);
    c->q_m2s3[1] = MVT_R(0.5);
    c->q_m2s3[2] = MVT_R(0.05);
    c->gate_chi2 = MVT_R(13.8);
    c->paper_gamma = MVT_R(6.0);
    for (int i = 0; i < 3; i++) {
        c->paper_var_m2[i] = MVT_R(0.04) * MVT_R(0.04);
        c->volume_min[i] = MVT_R(-5.0);
        c->volume_max[i] = MVT_R(5.0);
    }
    c->volume_min[2] = MVT_R(0.0);
    c->volume_max[2] = MVT_R(3.0);
    c->paper_delta = MVT_R(1.0);
    c->birth_reproj_sigma = MVT_R(4.0);
    c->birth_min_reproj_px = MVT_R(4.0);
    c->birth_min_views = 2;
    c->birth_min_sep_m = MVT_R(0.4);
    c->init_vel_std_ms = MVT_R(1.0);
    c->confirm_hits = 3;
    c->confirm_window = 5;
    c->tentative_max_misses = 2;
    c->coast_max_s = MVT_R(1.0);
    c->max_pos_std_m = MVT_R(1.0);
    c->volume_margin_m = MVT_R(0.5);
    c->var_floor_m2 = MVT_R(1e-10);
}

static int config_ok(const mvt_tracker_config_t *c)
{
    for (int i = 0; i < 3; i++) {
        if (!(c->q_m2s3[i] > MVT_R(0.0)) || !isfinite(c->q_m2s3[i]) || !(c->paper_var_m2[i] > MVT_R(0.0)) ||
            !isfinite(c->volume_min[i]) || !isfinite(c->volume_max[i]) || !(c->volume_max[i] > c->volume_min[i])) {
            return 0;
        }
    }
    return c->gate_chi2 > MVT_R(0.0) && c->paper_gamma > MVT_R(0.0) && c->paper_delta > MVT_R(0.0) &&
           c->birth_reproj_sigma > MVT_R(0.0) && c->birth_min_reproj_px >= MVT_R(0.0) && c->birth_min_views >= 2 &&
           c->birth_min_sep_m >= MVT_R(0.0) && c->init_vel_std_ms > MVT_R(0.0) && c->confirm_window >= 1 &&
           c->confirm_window <= 32 && c->confirm_hits >= 1 && c->confirm_hits <= c->confirm_window &&
           c->tentative_max_misses >= 1 && c->coast_max_s > MVT_R(0.0) && c->max_pos_std_m > MVT_R(0.0) &&
           c->volume_margin_m >= MVT_R(0.0) && c->var_floor_m2 >= MVT_R(0.0) &&
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

static int popcount32(uint32_t x)
{
    int n = 0;
    while (x != 0u) {
        x &= x - 1u;
        n++;
    }
    return n;
}

static int inside_volume(const mvt_tracker_config_t *c, const mvt_real x[3])
{
    for (int i = 0; i < 3; i++) {
        if (!(x[i] >= c->volume_min[i] - c->volume_margin_m) || !(x[i] <= c->volume_max[i] + c->volume_margin_m)) {
            return 0;
        }
    }
    return 1;
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

/* Gating cost of detection d in camera k for track t, or COST_NONE when outside the gate. */
static mvt_real gate_cost(mvt_tracker_t *self, mvt_track_t *tr, int k, int d)
{
    const mvt_tracker_config_t *c = &self->cfg;
    mvt_pkf_innov_t in;
    const mvt_pkf_lin_t lin = c->filter == MVT_FILTER_PROJECTIVE ? c->lin : MVT_PKF_JACOBIAN;
    const mvt_err_t err = mvt_pkf_innovation(&tr->s, &self->cams[k], lin, &self->meas[k][d], &in);
    if (err != MVT_OK) {
        return COST_NONE;
    }
    if (c->gate == MVT_GATE_PAPER) {
        mvt_real dist;
        if (mvt_pkf_paper_distance(&tr->s, &self->cams[k], c->paper_var_m2, c->paper_gamma, &self->meas[k][d],
                                   &dist) != MVT_OK) {
            return COST_NONE;
        }
        return dist <= c->paper_delta ? dist : COST_NONE;
    }
    return in.d2 <= c->gate_chi2 ? in.d2 : COST_NONE;
}

/* Fills self->cost for camera k, then assigns greedily by increasing cost (each detection to at
 * most one track, each track at most one detection). assign[t] = detection or -1. */
static void associate_camera(mvt_tracker_t *self, int k, int assign[MVT_MAX_TARGETS])
{
    const int nd = self->num_meas[k];
    int any_in_gate[MVT_MAX_TARGETS];
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        assign[t] = -1;
        any_in_gate[t] = 0;
        mvt_track_t *tr = &self->tracks[t];
        for (int d = 0; d < nd; d++) {
            self->cost[t][d] = COST_NONE;
            if (tr->id == 0 || !self->meas_ok[k][d] || self->used[k][d]) {
                continue;
            }
            self->cost[t][d] = gate_cost(self, tr, k, d);
            if (self->cost[t][d] >= MVT_R(0.0)) {
                any_in_gate[t] = 1;
            }
        }
    }
    for (;;) {
        mvt_real best = MVT_R(0.0);
        int bt = -1, bd = -1;
        for (int t = 0; t < MVT_MAX_TARGETS; t++) {
            if (self->tracks[t].id == 0 || assign[t] >= 0) {
                continue;
            }
            for (int d = 0; d < nd; d++) {
                const mvt_real cst = self->cost[t][d];
                if (cst >= MVT_R(0.0) && !self->used[k][d] && (bt < 0 || cst < best)) {
                    best = cst;
                    bt = t;
                    bd = d;
                }
            }
        }
        if (bt < 0) {
            break;
        }
        assign[bt] = bd;
        self->used[k][bd] = 1;
    }
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        if (self->tracks[t].id != 0 && nd > 0 && !any_in_gate[t]) {
            self->counters.gated_out++;
        }
    }
}

static void step_projective(mvt_tracker_t *self, const mvt_frame_t *frame, const int order[], int n_order)
{
    const mvt_tracker_config_t *c = &self->cfg;
    for (int oi = 0; oi < n_order; oi++) {
        const int k = order[oi];
        const int64_t tk = frame->views[k].utime_us;
        for (int t = 0; t < MVT_MAX_TARGETS; t++) {
            if (self->tracks[t].id != 0) {
                (void)mvt_cv_predict_to(&self->tracks[t].s, tk, c->q_m2s3);
            }
        }
        int assign[MVT_MAX_TARGETS];
        associate_camera(self, k, assign);
        for (int t = 0; t < MVT_MAX_TARGETS; t++) {
            mvt_track_t *tr = &self->tracks[t];
            if (tr->id == 0 || assign[t] < 0) {
                continue;
            }
            mvt_pkf_innov_t in;
            mvt_err_t err = mvt_pkf_innovation(&tr->s, &self->cams[k], c->lin, &self->meas[k][assign[t]], &in);
            if (err == MVT_OK) {
                err = mvt_pkf_update(&tr->s, &in);
            }
            if (err == MVT_OK) {
                tr->cameras_used |= 1u << k;
                self->counters.updates++;
            } else if (err == MVT_ERR_BEHIND) {
                self->counters.behind_camera++;
            } else {
                self->counters.numeric_faults++;
            }
        }
    }
}

static void step_triangulate(mvt_tracker_t *self, const mvt_frame_t *frame, const int order[], int n_order)
{
    const mvt_tracker_config_t *c = &self->cfg;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        if (self->tracks[t].id != 0) {
            (void)mvt_cv_predict_to(&self->tracks[t].s, frame->utime_us, c->q_m2s3);
        }
    }
    /* association of each camera's detections to the predicted tracks (the same gate as the
     * projective filters, so that the comparison isolates the estimator) */
    int assign[MVT_MAX_CAMERAS][MVT_MAX_TARGETS];
    for (int oi = 0; oi < n_order; oi++) {
        associate_camera(self, order[oi], assign[oi]);
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
        mvt_real x[3], cov[9];
        uint32_t inl = 0;
        const mvt_real thr = c->birth_reproj_sigma * MVT_SQRT(obs[0].var_px2);
        if (mvt_tri_robust(self->cams, obs, n, thr > c->birth_min_reproj_px ? thr : c->birth_min_reproj_px, x, &inl,
                           NULL) != MVT_OK) {
            continue;
        }
        mvt_tri_obs_t in[MVT_MAX_CAMERAS];
        int m = 0;
        uint32_t used_bits = 0;
        for (int i = 0; i < n; i++) {
            if (inl & (1u << i)) {
                in[m++] = obs[i];
                used_bits |= 1u << obs[i].cam;
            }
        }
        /* the baseline of [10, 18]: the linear least-squares point, first-order covariance */
        if (mvt_tri_linear(self->cams, in, m, x) != MVT_OK || mvt_tri_covariance(self->cams, in, m, x, cov) != MVT_OK) {
            continue;
        }
        if (mvt_cv_update_point(&tr->s, x, cov, MVT_R(0.0), NULL) == MVT_OK) {
            tr->cameras_used |= used_bits;
            self->counters.updates++;
        } else {
            self->counters.numeric_faults++;
        }
    }
}

static mvt_real birth_threshold(const mvt_tracker_config_t *c, const mvt_pkf_meas_t *m)
{
    const mvt_real t = c->birth_reproj_sigma * MVT_SQRT(m->var_px2);
    return t > c->birth_min_reproj_px ? t : c->birth_min_reproj_px;
}

static int near_existing_track(const mvt_tracker_t *self, const mvt_real x[3])
{
    const mvt_real r2 = self->cfg.birth_min_sep_m * self->cfg.birth_min_sep_m;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        const mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0) {
            continue;
        }
        const mvt_real dx = tr->s.x[0] - x[0], dy = tr->s.x[1] - x[1], dz = tr->s.x[2] - x[2];
        if (dx * dx + dy * dy + dz * dz < r2) {
            return 1;
        }
    }
    return 0;
}

/* Best-supported unused multi-view point, or 0 when none reaches birth_min_views. */
static int find_birth(mvt_tracker_t *self, const int order[], int n_order, mvt_tri_obs_t obs[], int det_of[], int *n_obs)
{
    const mvt_tracker_config_t *c = &self->cfg;
    int best_n = 0;
    mvt_real best_err = MVT_R(0.0);
    for (int ai = 0; ai < n_order; ai++) {
        const int a = order[ai];
        for (int i = 0; i < self->num_meas[a]; i++) {
            if (!self->meas_ok[a][i] || self->used[a][i]) {
                continue;
            }
            for (int bi = ai + 1; bi < n_order; bi++) {
                const int b = order[bi];
                for (int j = 0; j < self->num_meas[b]; j++) {
                    if (!self->meas_ok[b][j] || self->used[b][j]) {
                        continue;
                    }
                    mvt_tri_obs_t cand[MVT_MAX_CAMERAS];
                    int cand_det[MVT_MAX_CAMERAS];
                    const mvt_pkf_meas_t *ma = &self->meas[a][i], *mb = &self->meas[b][j];
                    cand[0] = (mvt_tri_obs_t){a, {ma->xn[0], ma->xn[1]}, ma->var_px2};
                    cand[1] = (mvt_tri_obs_t){b, {mb->xn[0], mb->xn[1]}, mb->var_px2};
                    cand_det[0] = i;
                    cand_det[1] = j;
                    mvt_real x[3];
                    if (mvt_tri_linear(self->cams, cand, 2, x) != MVT_OK || !inside_volume(c, x)) {
                        continue;
                    }
                    const mvt_real ea = mvt_tri_reproj_px(self->cams, &cand[0], x);
                    const mvt_real eb = mvt_tri_reproj_px(self->cams, &cand[1], x);
                    if (ea > birth_threshold(c, ma) || eb > birth_threshold(c, mb)) {
                        continue;
                    }
                    int n = 2;
                    mvt_real err = ea + eb;
                    for (int ci = 0; ci < n_order; ci++) {
                        const int k = order[ci];
                        if (k == a || k == b) {
                            continue;
                        }
                        int bd = -1;
                        mvt_real be = MVT_R(0.0);
                        for (int d = 0; d < self->num_meas[k]; d++) {
                            if (!self->meas_ok[k][d] || self->used[k][d]) {
                                continue;
                            }
                            const mvt_pkf_meas_t *mk = &self->meas[k][d];
                            const mvt_tri_obs_t o = {k, {mk->xn[0], mk->xn[1]}, mk->var_px2};
                            const mvt_real e = mvt_tri_reproj_px(self->cams, &o, x);
                            if (e <= birth_threshold(c, mk) && (bd < 0 || e < be)) {
                                bd = d;
                                be = e;
                            }
                        }
                        if (bd >= 0) {
                            const mvt_pkf_meas_t *mk = &self->meas[k][bd];
                            cand[n] = (mvt_tri_obs_t){k, {mk->xn[0], mk->xn[1]}, mk->var_px2};
                            cand_det[n] = bd;
                            err += be;
                            n++;
                        }
                    }
                    if (n > best_n || (n == best_n && err < best_err)) {
                        best_n = n;
                        best_err = err;
                        memcpy(obs, cand, (size_t)n * sizeof(cand[0]));
                        memcpy(det_of, cand_det, (size_t)n * sizeof(cand_det[0]));
                    }
                }
            }
        }
    }
    *n_obs = best_n;
    return best_n >= c->birth_min_views;
}

static void initiate(mvt_tracker_t *self, const mvt_frame_t *frame, const int order[], int n_order)
{
    const mvt_tracker_config_t *c = &self->cfg;
    for (int round = 0; round < MVT_MAX_TARGETS; round++) {
        mvt_tri_obs_t obs[MVT_MAX_CAMERAS];
        int det_of[MVT_MAX_CAMERAS];
        int n = 0;
        if (!find_birth(self, order, n_order, obs, det_of, &n)) {
            return;
        }
        for (int i = 0; i < n; i++) { /* consumed whatever happens next */
            self->used[obs[i].cam][det_of[i]] = 1;
        }
        mvt_real x[3], cov[9];
        uint32_t inl = 0;
        int m = 0;
        const mvt_real thr = birth_threshold(c, &self->meas[obs[0].cam][det_of[0]]);
        if (mvt_tri_robust(self->cams, obs, n, thr, x, &inl, &m) != MVT_OK || m < c->birth_min_views ||
            !inside_volume(c, x) || near_existing_track(self, x)) {
            continue;
        }
        mvt_tri_obs_t in[MVT_MAX_CAMERAS];
        uint32_t bits = 0;
        int mi = 0;
        for (int i = 0; i < n; i++) {
            if (inl & (1u << i)) {
                in[mi++] = obs[i];
                bits |= 1u << obs[i].cam;
            }
        }
        if (mvt_tri_covariance(self->cams, in, mi, x, cov) != MVT_OK) {
            continue;
        }
        int slot = -1;
        for (int t = 0; t < MVT_MAX_TARGETS; t++) {
            if (self->tracks[t].id == 0) {
                slot = t;
                break;
            }
        }
        if (slot < 0) {
            self->counters.births_refused_full++;
            continue;
        }
        mvt_track_t *tr = &self->tracks[slot];
        memset(tr, 0, sizeof(*tr));
        tr->id = self->next_id++;
        if (self->next_id <= 0) { /* 2^31 births: wrap to 1 rather than reuse 0 or go negative */
            self->next_id = 1;
        }
        tr->status = c->confirm_hits <= 1 ? MVT_TRACK_CONFIRMED : MVT_TRACK_TENTATIVE;
        mvt_cv_init(&tr->s, x, cov, c->init_vel_std_ms * c->init_vel_std_ms, frame->utime_us);
        tr->cameras_used = bits;
        tr->hit_history = 1u;
        tr->last_update_us = frame->utime_us;
        self->counters.births++;
    }
}

static void manage(mvt_tracker_t *self, int64_t now_us)
{
    const mvt_tracker_config_t *c = &self->cfg;
    const uint32_t window = c->confirm_window >= 32 ? 0xffffffffu : ((1u << c->confirm_window) - 1u);
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0) {
            continue;
        }
        const int hit = tr->cameras_used != 0u;
        tr->hit_history = (tr->hit_history << 1) | (hit ? 1u : 0u);
        if (hit) {
            tr->misses = 0;
            tr->last_update_us = now_us;
        } else {
            tr->misses++;
        }
        int drop = 0;
        if (mvt_cv_repair(&tr->s, c->var_floor_m2) != MVT_OK) {
            self->counters.numeric_faults++;
            drop = 1;
        }
        const mvt_real *P = tr->s.P;
        const mvt_real var_max = c->max_pos_std_m * c->max_pos_std_m;
        const mvt_real unseen_s = (mvt_real)((double)(now_us - tr->last_update_us) * 1e-6);
        switch (tr->status) {
        case MVT_TRACK_TENTATIVE:
            if (tr->misses >= c->tentative_max_misses) {
                drop = 1;
            } else if (popcount32(tr->hit_history & window) >= c->confirm_hits) {
                tr->status = MVT_TRACK_CONFIRMED;
            }
            break;
        case MVT_TRACK_CONFIRMED:
        case MVT_TRACK_COASTING:
            tr->status = hit ? MVT_TRACK_CONFIRMED : MVT_TRACK_COASTING;
            if (unseen_s > c->coast_max_s) {
                drop = 1;
            }
            break;
        default:
            drop = 1;
            break;
        }
        if (P[0] > var_max || P[7] > var_max || P[14] > var_max || !inside_volume(c, tr->s.x)) {
            drop = 1;
        }
        if (drop) {
            tr->id = 0;
            self->counters.deletions++;
        }
    }
}

void mvt_tracker_output(const mvt_tracker_t *self, int64_t utime_us, mvt_output_t *out)
{
    out->utime_us = utime_us;
    out->num_tracks = 0;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        const mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0) {
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
        o->hue = MVT_R(-1.0);
        o->saturation = MVT_R(-1.0);
    }
}

mvt_err_t mvt_tracker_step(mvt_tracker_t *self, const mvt_frame_t *frame, mvt_output_t *out)
{
    MVT_ASSERT(self != NULL && frame != NULL);
    if (self->have_time && frame->utime_us < self->last_utime_us) {
        self->counters.frames_time_backwards++;
        return MVT_ERR_INVALID;
    }
    self->have_time = 1;
    self->last_utime_us = frame->utime_us;
    self->counters.frames++;
    prepare_measurements(self, frame);

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
    }

    if (self->cfg.filter == MVT_FILTER_PROJECTIVE) {
        step_projective(self, frame, order, n_order);
    } else {
        step_triangulate(self, frame, order, n_order);
    }
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        if (self->tracks[t].id != 0) {
            (void)mvt_cv_predict_to(&self->tracks[t].s, frame->utime_us, self->cfg.q_m2s3);
        }
    }
    manage(self, frame->utime_us);
    initiate(self, frame, order, n_order);
    if (out != NULL) {
        mvt_tracker_output(self, frame->utime_us, out);
    }
    return MVT_OK;
}
