/*
 * mvt_trk_motion.c - a track's motion model: every change the tracker makes to a track's
 * estimate goes through here. With one constant-velocity model the estimate is tr->s itself
 * (mvt_cv, mvt_pkf: bit for bit the single filter); with an IMM bank (mvt_imm.h) each operation
 * acts on every model and tr->s is their combination, which is what the body model's steps and
 * the output read.
 */
#include <string.h>

#include "mvt_linalg.h"
#include "mvt_trk.h"

static int single(const mvt_tracker_t *self)
{
    return self->cfg.motion.n == 1 && mvt_imm_model_is(&self->cfg.motion.model[0], MVT_MOTION_CV);
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
     * following its person. Measured in docs/filters.md (Lasting displacements). */
    const uint32_t others = (tr->cameras_placed | tr->cameras_placed_prev) & ~(1u << k);
    if (mvt_trk_popcount(others) < 2) {
        tr->view[k].p = MVT_R(0.0);
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
