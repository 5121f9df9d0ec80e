/*
 * mvt_tracker.c - the tracker's configuration, the frame's measurements and the loop: one call of
 * the body model's steps per frame (mvt_body.c), the output, and the choice of detections kept
 * under a flood.
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
    c->init_vel_std_ms = MVT_R(1.0);
    c->numerics.max_pos_std_m = MVT_R(1.0);
    c->volume.margin_m = MVT_R(0.5);
    c->numerics.var_floor_m2 = MVT_R(1e-10);
    c->volume.exit_margin_m = MVT_R(0.5);
    c->body.halfwidth_m = MVT_R(0.2);
    c->population.p_detect = MVT_R(0.9);
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

/* The body's and the population's parameters in their physical ranges (mvt_tracker.h). */
static int body_config_ok(const mvt_tracker_config_t *c)
{
    return c->body.head_height_m >= MVT_R(1.0) && c->body.head_height_m <= MVT_R(2.5) && c->body.head_height_sd_m >= MVT_R(0.02) &&
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
    return body_config_ok(c) && mvt_imm_config_check(&c->motion) == MVT_OK && c->numerics.gate_chi2 > MVT_R(0.0) &&
           c->paper.gamma > MVT_R(0.0) && c->paper.delta > MVT_R(0.0) && c->init_vel_std_ms > MVT_R(0.0) &&
           c->numerics.max_pos_std_m > MVT_R(0.0) && c->volume.margin_m >= MVT_R(0.0) && c->numerics.var_floor_m2 >= MVT_R(0.0) &&
           c->volume.exit_margin_m >= MVT_R(0.0) && isfinite(c->volume.exit_margin_m) && c->body.halfwidth_m >= MVT_R(0.0) &&
           isfinite(c->body.halfwidth_m) && c->population.p_detect > MVT_R(0.0) && c->population.p_detect < MVT_R(1.0) &&
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
        self->tracks[t].cameras_placed_prev = self->tracks[t].cameras_placed;
        self->tracks[t].cameras_placed = 0u;
        self->tracks[t].heads_prev = self->tracks[t].heads;
        self->tracks[t].heads = 0u;
    }
    mvt_body_step(self, frame, order, n_order, dt);
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
