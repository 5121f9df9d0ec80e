/*
 * mvt_trk_motion.c - a track's motion model: every change the tracker makes to a track's
 * estimate goes through here. With one constant-velocity model the estimate is tr->s itself
 * (mvt_cv, mvt_pkf: bit for bit the single filter); with an IMM bank (mvt_imm.h) each operation
 * acts on every model and tr->s is their combination, which is what the body model's steps and
 * the output read.
 */
#include <math.h>
#include <string.h>

#include "mvt_linalg.h"
#include "mvt_trk.h"

static int single(const mvt_tracker_t *self)
{
    return self->cfg.motion.n == 1 && mvt_imm_model_is(&self->cfg.motion.model[0], MVT_MOTION_CV);
}

/* Cameras other than k that placed tr (updated it as the person's) this frame or the one before. */
static uint32_t placed_by_others(const mvt_track_t *tr, int k)
{
    return (tr->cameras_placed | tr->cameras_placed_prev) & ~(1u << k);
}

void mvt_trk_start(mvt_tracker_t *self, mvt_track_t *tr, const mvt_real x[3], const mvt_real cov[9], int64_t utime_us)
{
    const mvt_real v = self->cfg.init_vel_std_ms;
    mvt_cv_init(&tr->s, x, cov, v * v, utime_us);
    if (!single(self)) {
        mvt_imm_init(&tr->imm, &self->cfg.motion, &tr->s);
    }
}

void mvt_trk_predict(mvt_tracker_t *self, mvt_track_t *tr, int64_t utime_us)
{
    if (single(self)) {
        (void)mvt_cv_predict_to(&tr->s, utime_us, self->cfg.motion.model[0].q);
    } else {
        (void)mvt_imm_predict_to(&tr->imm, &self->cfg.motion, utime_us, &tr->s);
    }
}

void mvt_trk_predict_pos(mvt_tracker_t *self, mvt_track_t *tr, int64_t utime_us)
{
    if (single(self)) {
        (void)mvt_cv_predict_to(&tr->s, utime_us, self->cfg.motion.model[0].q);
    } else {
        (void)mvt_imm_predict_to_pos(&tr->imm, &self->cfg.motion, utime_us, &tr->s);
    }
}

/* Whether a view's detection z jumped off its last one: beyond the chi-square gate of
 * two points' noise (2R) and the head's motion in the picture over a frame (the estimate's velocity
 * and its spread, through the head's Jacobian in). */
static int head_jumped(const mvt_tracker_t *self, const mvt_track_t *tr, const mvt_pkf_innov_t *in,
                       const mvt_real last[2], const mvt_real z[2])
{
    const mvt_real dt = self->frame_dt_s;
    const mvt_real *H = in->H, *P = tr->s.P, *v = &tr->s.x[3];
    mvt_real e[2], hp[2][3];
    for (int r = 0; r < 2; r++) {
        const mvt_real *h = &H[r * 3];
        e[r] = z[r] - last[r] - dt * (h[0] * v[0] + h[1] * v[1] + h[2] * v[2]);
        for (int c = 0; c < 3; c++) {
            hp[r][c] = h[0] * P[3 * 6 + 3 + c] + h[1] * P[4 * 6 + 3 + c] + h[2] * P[5 * 6 + 3 + c];
        }
    }
    const mvt_real dt2 = dt * dt;
    const mvt_real S[3] = {MVT_R(2.0) * in->r + dt2 * (hp[0][0] * H[0] + hp[0][1] * H[1] + hp[0][2] * H[2]),
                           dt2 * (hp[0][0] * H[3] + hp[0][1] * H[4] + hp[0][2] * H[5]),
                           MVT_R(2.0) * in->r + dt2 * (hp[1][0] * H[3] + hp[1][1] * H[4] + hp[1][2] * H[5])};
    mvt_real Si[3];
    if (mvt_la_inv2_sym(S, Si) != MVT_OK) {
        return 0;
    }
    const mvt_real d2 = Si[0] * e[0] * e[0] + MVT_R(2.0) * Si[1] * e[0] * e[1] + Si[2] * e[1] * e[1];
    return d2 > self->cfg.numerics.gate_chi2;
}

void mvt_trk_onset_seen(mvt_tracker_t *self, mvt_track_t *tr, int k, const mvt_pkf_innov_t *in, const mvt_real z[2],
                        int gated)
{
    mvt_trk_onset_t *o = &tr->onset[k];
    const uint32_t bit = 1u << k;
    const int before = (tr->heads_prev & bit) != 0u;
    const mvt_real last[2] = {o->head[0], o->head[1]};
    o->head[0] = z[0];
    o->head[1] = z[1];
    tr->heads |= bit;
    if (gated || single(self) || !(self->cfg.motion.outlier_persist_s > MVT_R(0.0))) {
        return; /* a detection inside the gate is judged by the update (mvt_trk_onset_judged) */
    }
    const int confirmed = mvt_trk_popcount(placed_by_others(tr, k)) >= 2;
    const int jumped = before && tr->view[k].p < MVT_R(0.5) && confirmed && head_jumped(self, tr, in, last, z);
    const int64_t now = tr->s.utime_us;
    if (jumped) {
        o->p = MVT_R(1.0) - self->cfg.motion.p_outlier;
    } else if (o->confirmed_us != 0) {
        /* does it continue the held displacement: within two points' noise and the drift since? */
        const mvt_real dt = mvt_us_to_s(now - o->confirmed_us) - o->seen_s;
        const mvt_real e0 = in->y[0] - o->y[0], e1 = in->y[1] - o->y[1];
        const mvt_real var = MVT_R(2.0) * in->r + self->cfg.motion.outlier_drift_px2_s * dt;
        if (!((e0 * e0 + e1 * e1) / var <= self->cfg.numerics.gate_chi2)) {
            o->confirmed_us = 0; /* another displacement, or none: the memory judges it */
            return;
        }
    } else {
        return;
    }
    o->y[0] = in->y[0];
    o->y[1] = in->y[1];
    if (jumped || confirmed) {
        o->confirmed_us = now;
        o->seen_s = MVT_R(0.0);
    } else {
        o->seen_s = mvt_us_to_s(now - o->confirmed_us);
    }
}

void mvt_trk_onset_judged(mvt_track_t *tr, int k)
{
    mvt_trk_onset_t *o = &tr->onset[k];
    const mvt_imm_view_t *v = &tr->view[k];
    if (o->confirmed_us == 0) {
        return;
    }
    if (!(v->p >= MVT_R(0.5))) {
        o->confirmed_us = 0; /* the head again: the displacement has ended */
        return;
    }
    o->y[0] = v->y[0];
    o->y[1] = v->y[1];
    if (mvt_trk_popcount(placed_by_others(tr, k)) >= 2) {
        o->p = v->p;
        o->confirmed_us = v->utime_us;
        o->seen_s = MVT_R(0.0);
    } else {
        o->seen_s = mvt_us_to_s(v->utime_us - o->confirmed_us);
    }
}

void mvt_trk_settle(mvt_tracker_t *self, mvt_track_t *tr)
{
    if (!single(self)) {
        mvt_imm_combine(&tr->imm, &self->cfg.motion, &tr->s);
    }
}

mvt_err_t mvt_trk_update_pkf(mvt_tracker_t *self, mvt_track_t *tr, int k, const mvt_pkf_innov_t *in,
                             const mvt_real *extra_px2)
{
    return mvt_trk_update_head(self, tr, k, in, extra_px2, MVT_R(1.0), MVT_R(1.0));
}

mvt_err_t mvt_trk_update_head(mvt_tracker_t *self, mvt_track_t *tr, int k, const mvt_pkf_innov_t *in,
                              const mvt_real *extra_px2, mvt_real shown, mvt_real own_lr)
{
    if (single(self)) {
        return mvt_pkf_update(&tr->s, in);
    }
    const mvt_real e[3] = {extra_px2 != NULL ? extra_px2[0] : MVT_R(0.0), extra_px2 != NULL ? extra_px2[1] : MVT_R(0.0),
                           extra_px2 != NULL ? extra_px2[2] : MVT_R(0.0)};
    const mvt_real noise[4] = {in->r + e[0], e[1], e[1], in->r + e[2]};
    /* A view's detection may be judged displaced as its last one was only while two other views
     * place the person (this frame or the one before): with fewer, the track's own error looks
     * like a lasting displacement (one view leaves the depth free), and the track would stop
     * following its person. A displacement seen to begin while two views placed the person is not
     * the track's error: it stands in, as likely as it was when two views last confirmed it times
     * the chance that it has lasted since. Measured in docs/filters.md (Lasting displacements). */
    if (mvt_trk_popcount(placed_by_others(tr, k)) < 2) {
        const mvt_trk_onset_t *o = &tr->onset[k];
        if (o->confirmed_us != 0 && self->cfg.motion.outlier_persist_s > MVT_R(0.0)) {
            mvt_imm_view_t *v = &tr->view[k];
            v->p = o->p * MVT_EXP(-o->seen_s / self->cfg.motion.outlier_persist_s);
            v->y[0] = o->y[0];
            v->y[1] = o->y[1];
            v->utime_us = o->confirmed_us + (int64_t)(o->seen_s * MVT_R(1e6));
        } else {
            tr->view[k].p = MVT_R(0.0);
        }
    }
    if (shown < MVT_R(1.0)) {
        /* the head shows with probability `shown`; otherwise the point is another part of the body */
        mvt_imm_config_t c = self->cfg.motion;
        c.p_outlier = MVT_R(1.0) - (shown > MVT_R(0.0) ? shown : MVT_R(0.0)) * (MVT_R(1.0) - c.p_outlier);
        return mvt_imm_update_view_lr(&tr->imm, &c, in->H, in->y, noise, in->S, &tr->view[k], own_lr, &tr->s);
    }
    return mvt_imm_update_view_lr(&tr->imm, &self->cfg.motion, in->H, in->y, noise, in->S, &tr->view[k], own_lr, &tr->s);
}

/* A pixel point's update with the bank's outlier prior raised to p_out; position only (within a
 * camera's pass) or the whole combined state. */
static mvt_err_t update_pixels(mvt_tracker_t *self, mvt_track_t *tr, const mvt_pkf_innov_t *in, mvt_real p_out,
                               int position_only)
{
    if (single(self)) {
        return mvt_pkf_update(&tr->s, in);
    }
    mvt_imm_config_t c = self->cfg.motion;
    c.p_outlier = p_out > c.p_outlier ? p_out : c.p_outlier;
    const mvt_real noise[4] = {in->r, MVT_R(0.0), MVT_R(0.0), in->r};
    return position_only ? mvt_imm_update_pos(&tr->imm, &c, 2, in->H, in->y, noise, &tr->s)
                         : mvt_imm_update(&tr->imm, &c, 2, in->H, in->y, noise, &tr->s);
}

mvt_err_t mvt_trk_update_pixels(mvt_tracker_t *self, mvt_track_t *tr, const mvt_pkf_innov_t *in)
{
    return update_pixels(self, tr, in, MVT_R(0.0), 0);
}

mvt_err_t mvt_trk_update_pixels_robust(mvt_tracker_t *self, mvt_track_t *tr, const mvt_pkf_innov_t *in, mvt_real p_out)
{
    return update_pixels(self, tr, in, p_out, 1);
}

mvt_err_t mvt_trk_update_point(mvt_tracker_t *self, mvt_track_t *tr, const mvt_real z[3], const mvt_real R[9])
{
    if (single(self)) {
        return mvt_cv_update_point(&tr->s, z, R, MVT_R(0.0), NULL);
    }
    if (!mvt_la_all_finite(z, 3) || !mvt_la_all_finite(R, 9)) {
        return MVT_ERR_NONFINITE;
    }
    static const mvt_real eye3[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    const mvt_real y[3] = {z[0] - tr->s.x[0], z[1] - tr->s.x[1], z[2] - tr->s.x[2]};
    return mvt_imm_update(&tr->imm, &self->cfg.motion, 3, eye3, y, R, &tr->s);
}

mvt_err_t mvt_trk_update_triangulated(mvt_tracker_t *self, mvt_track_t *tr, const mvt_tri_obs_t *obs, int n,
                                      mvt_real thresh_px, uint32_t *used)
{
    mvt_real x[3], cov[9];
    uint32_t inl = 0u;
    *used = 0u;
    if (mvt_tri_robust(self->cams, obs, n, thresh_px, x, &inl, NULL) != MVT_OK) {
        return MVT_ERR_DEGENERATE;
    }
    mvt_tri_obs_t in[MVT_MAX_CAMERAS];
    int m = 0;
    uint32_t bits = 0u;
    for (int i = 0; i < n; i++) {
        if (inl & (1u << i)) {
            in[m++] = obs[i];
            bits |= 1u << obs[i].cam;
        }
    }
    if (mvt_tri_linear(self->cams, in, m, x) != MVT_OK || mvt_tri_covariance(self->cams, in, m, x, cov) != MVT_OK) {
        return MVT_ERR_DEGENERATE;
    }
    const mvt_err_t err = mvt_trk_update_point(self, tr, x, cov);
    *used = err == MVT_OK ? bits : 0u;
    return err;
}

mvt_err_t mvt_trk_truncate(mvt_tracker_t *self, mvt_track_t *tr, const mvt_real H[3], mvt_real value, mvt_real lo,
                           mvt_real hi)
{
    if (single(self)) {
        return mvt_cv_truncate(&tr->s, H, value, lo, hi, NULL);
    }
    return mvt_imm_truncate(&tr->imm, &self->cfg.motion, H, value, MVT_R(0.0), lo, hi, &tr->s);
}

mvt_err_t mvt_trk_truncate_ground(mvt_tracker_t *self, mvt_track_t *tr, const mvt_real H[3], mvt_real value,
                                  mvt_real extra_var, mvt_real lo, mvt_real hi)
{
    if (single(self)) {
        return mvt_cv_truncate_ground(&tr->s, H, value, extra_var, lo, hi, NULL);
    }
    return mvt_imm_truncate_ground(&tr->imm, &self->cfg.motion, H, value, extra_var, lo, hi, &tr->s);
}

void mvt_trk_widen_ground(mvt_tracker_t *self, mvt_track_t *tr, const mvt_real H[3], mvt_real var)
{
    const int one = single(self);
    for (int j = 0; j < (one ? 1 : self->cfg.motion.n); j++) {
        mvt_cv_state_t *st = one ? &tr->s : &tr->imm.m[j];
        for (int a = 0; a < 2; a++) {
            for (int b = 0; b < 2; b++) {
                st->P[a * 6 + b] += var * H[a] * H[b];
            }
        }
    }
    if (!one) {
        mvt_imm_combine(&tr->imm, &self->cfg.motion, &tr->s);
    }
}

mvt_err_t mvt_trk_repair(mvt_tracker_t *self, mvt_track_t *tr)
{
    if (single(self)) {
        return mvt_cv_repair(&tr->s, self->cfg.numerics.var_floor_m2);
    }
    return mvt_imm_repair(&tr->imm, &self->cfg.motion, &tr->s, self->cfg.numerics.var_floor_m2);
}
