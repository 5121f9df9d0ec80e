/*
 * mvt_imm.h - interacting multiple models (Blom and Bar-Shalom, IEEE TAC 33(8), 1988) over the
 * constant-velocity state of mvt_cv.
 *
 * People walk, stop, turn, stand talking and start again. One white-noise-acceleration model with
 * one q cannot fit all of it: low, it lags every turn; high, it jitters while people stand. The
 * IMM runs a small bank of motion models on the same 6-state [X Y Z Vx Vy Vz] and lets the
 * measurements say which one the person follows:
 *
 *   mix      for every model j, its prior is the moment-matched mixture of all models' estimates
 *            weighted by P(model i before | model j now) = p_ij mu_i / c_j, c_j = sum_i p_ij mu_i
 *   predict  each model with its own dynamics; mu_j <- c_j
 *   update   each camera's measurement updates every model (Joseph form); mu_j is multiplied by
 *            that model's measurement likelihood N(y_j; 0, S_j) and renormalised
 *   combine  the output (and what gating, occlusion and association use) is the mixture's mean
 *            and covariance: x = sum mu_j x_j, P = sum mu_j (P_j + (x_j - x)(x_j - x)^T)
 *
 * Model kinds, per axis (a model may walk in X and Y and hold its height, or the reverse):
 *   MVT_MOTION_CV     constant velocity, white acceleration of density q (m^2/s^3) on the axis
 *                     (mvt_cv_predict)
 *   MVT_MOTION_STILL  the axis holds: the head wanders along it as a random walk of diffusion q
 *                     (m^2/s) and has no velocity of its own beyond a sway of variance q / (1 s)
 *                     that does not persist (F_vv = 0)
 * Switching is a continuous-time Markov chain: model j is left at rate leave_hz[j] (mean stay
 * 1 / leave_hz), for any of the other models alike, so over an interval dt
 * p_jj = exp(-leave_hz dt) and p_jk = (1 - p_jj) / (n - 1). It depends on dt, so the several
 * predictions of one frame (cameras at different capture times) compose consistently.
 *
 * Impulsive noise: a camera's detection may be displaced (an occluded head, the top of a merged
 * blob, a bad segmentation). Each pixel measurement is therefore modelled as the person's with
 * probability 1 - p_outlier and as a displaced point within outlier_radius_px otherwise: every
 * model's likelihood is (1 - p_outlier) N(y_j; 0, S_j) + p_outlier / (pi r^2), and it is updated
 * with weight w_j = P(right | y_j) (the PDA filter's one-measurement form: x += w K y,
 * P = P - w K S K^T + w (1 - w) (K y)(K y)^T). A far detection then moves the estimate little and
 * is no evidence of a manoeuvre (without this, the manoeuvre model explains a wrong blob, widens
 * the gate and takes the next one). A displacement also lasts: mvt_imm_update_view remembers, per
 * camera, whether the last detection was displaced and by how much, and lets that displacement
 * continue (outlier_persist_s, outlier_drift_px2_s).
 *
 * Every measurement in the tracker is linearised at the combined estimate (one projection per
 * camera and track): model j's innovation is y_j = y - H (x_j - x) and its covariance
 * S_j = H P_j H^T + R. The models differ by millimetres, far inside the range where the
 * projection is linear: against a textbook IMM that relinearises every model at its own estimate
 * the combined position differs by 20 um over 200 frames (tests/test_oracle.cpp), and this way
 * each camera is projected once per track, not once per model.
 *
 * Statically allocated: MVT_IMM_MODELS (default 4) is the bank's capacity; a configuration uses
 * 1..MVT_IMM_MODELS of them (mvt_imm_config_single, one model and p_outlier 0, is exactly the
 * single filter).
 */
#ifndef MVT_IMM_H
#define MVT_IMM_H

#include "mvt_cv.h"

#ifdef __cplusplus
extern "C" {
#endif

#ifndef MVT_IMM_MODELS
#define MVT_IMM_MODELS 4
#endif
#if MVT_IMM_MODELS < 1 || MVT_IMM_MODELS > 8
#error "MVT_IMM_MODELS must be in 1..8"
#endif

typedef enum mvt_motion_kind {
    MVT_MOTION_CV = 0,
    MVT_MOTION_STILL = 1
} mvt_motion_kind_t;

typedef struct mvt_imm_model {
    mvt_motion_kind_t kind[3]; /* per axis X, Y, Z */
    mvt_real q[3];      /* CV: acceleration density, m^2/s^3; STILL: diffusion, m^2/s; per axis, > 0 */
    mvt_real leave_hz;  /* rate of leaving this model, 1/s, >= 0 (0 with one model only) */
} mvt_imm_model_t;

typedef struct mvt_imm_config {
    int n;                                /* models in use, 1..MVT_IMM_MODELS */
    mvt_imm_model_t model[MVT_IMM_MODELS];
    mvt_real p_outlier;                   /* probability that a camera's detection of a person is
                                             displaced (occluded head, a merged blob's top, a bad
                                             segmentation), in [0, 1); default 0.1 */
    mvt_real outlier_radius_px;           /* ... and then lies anywhere within this radius of the
                                             head, pixels, > 0; default 150 */
    mvt_real outlier_persist_s;           /* a displacement lasts this long on average (a merged
                                             blob's top stays while two people overlap), s, >= 0;
                                             0: every frame's detection is displaced or not
                                             independently of the last one's */
    mvt_real outlier_drift_px2_s;         /* ... and wanders meanwhile as a random walk of this
                                             diffusion, px^2/s, >= 0 */
} mvt_imm_config_t;

/* What a view's last detection of a track said about displacement (mvt_imm_update_view): the
 * probability that it was displaced and by how much. Zeroed: nothing known. */
typedef struct mvt_imm_view {
    mvt_real p;       /* P(displaced | that detection), [0, 1] */
    mvt_real y[2];    /* its offset from the predicted head, px */
    int64_t utime_us; /* its time */
} mvt_imm_view_t;

typedef struct mvt_imm {
    mvt_cv_state_t m[MVT_IMM_MODELS]; /* each model's estimate */
    mvt_real mu[MVT_IMM_MODELS];      /* model probabilities, sum 1 */
} mvt_imm_t;

/* The default bank for people (docs/filters.md, "Motion that adapts"):
 *   0 standing  STILL on every axis, q 2.5e-5 m^2/s (the head wanders 5 mm in a second); leaves
 *               at 0.2 /s (stands 5 s on average)
 *   1 walking   X, Y CV q 0.3 m^2/s^3 (speed drifts ~0.5 m/s per second); the height STILL,
 *               q 4e-4 m^2/s (a walking head bobs ~2 cm, it does not climb); leaves at 0.3 /s
 *   2 turning   CV, q 3 m^2/s^3 horizontally (a turn, a start, a stop: ~1.7 m/s^2 for ~1 s),
 *               0.1 vertically (the one model in which a moving head may also correct its height:
 *               a track born at a wrong height); leaves at 1.5 /s (lasts ~0.7 s)
 *   3 sitting   X, Y STILL q 2.5e-5 m^2/s; the height CV q 1 m^2/s^3 (sitting down, getting up,
 *   or rising  crouching: ~0.6 m/s for under a second); leaves at 1.3 /s (lasts ~0.75 s)
 * A build with a smaller MVT_IMM_MODELS keeps the first models. */
void mvt_imm_config_default(mvt_imm_config_t *c);

/* A one-model bank that is exactly the single constant-velocity filter with q. */
void mvt_imm_config_single(mvt_imm_config_t *c, const mvt_real q[3]);

/* 1 when every axis of model m is of kind k. */
int mvt_imm_model_is(const mvt_imm_model_t *m, mvt_motion_kind_t k);

/* MVT_OK, or MVT_ERR_INVALID for a count out of range, an unknown kind, a q that is not finite
 * and > 0, or a leave rate that is not finite and >= 0. */
mvt_err_t mvt_imm_config_check(const mvt_imm_config_t *c);

/* The chain's stationary probabilities (mean stays 1 / leave_hz, shares proportional to them);
 * uniform when a rate is 0. */
void mvt_imm_stationary(const mvt_imm_config_t *c, mvt_real mu[MVT_IMM_MODELS]);

/* Starts every model at s (the combined estimate is s itself); mu at the stationary shares. */
void mvt_imm_init(mvt_imm_t *imm, const mvt_imm_config_t *c, const mvt_cv_state_t *s);

/* Mixing, per-model prediction to utime_us (no-op unless later than the estimate's time) and the
 * combined estimate into s. ~(n^2 + 5 n) * 42 flops + n predictions. MVT_ERR_INVALID for a bad
 * interval. */
mvt_err_t mvt_imm_predict_to(mvt_imm_t *imm, const mvt_imm_config_t *c, int64_t utime_us, mvt_cv_state_t *s);

/* One position measurement linearised at the combined estimate s: H (m x 3 rows on the position,
 * row-major), y = z - h(s), noise = R plus any widening (m x m, row-major); m is 2 (a camera's
 * pixels) or 3 (a point). Every model is updated with y_j = y - H (x_j - x),
 * S_j = H P_j H^T + noise (m = 2: robustly, with p_outlier); mu by the likelihoods; s
 * recombined. MVT_ERR_NUMERIC (nothing changed) when some S_j is not positive definite. */
mvt_err_t mvt_imm_update(mvt_imm_t *imm, const mvt_imm_config_t *c, int m, const mvt_real *H, const mvt_real *y,
                         const mvt_real *noise, mvt_cv_state_t *s);

/* mvt_imm_update_pos for a pixel measurement (m = 2) of the view whose memory is *view (updated).
 * A displaced detection tends to stay displaced by about the same offset for a while (an occluding
 * blob, a merged blob's top): with probability view->p exp(-dt / outlier_persist_s) the last
 * displacement continues, and the detection then lies at view->y from the predicted head, spread
 * by the prediction's H P H^T, the noise of both detections (2 R) and the drift over dt; otherwise
 * the detection is displaced anew with p_outlier or is the person's. Every model is updated with the probability
 * that the detection is the person's; *view receives the probability that it was displaced, its
 * offset y and s->utime_us. S: the combined estimate's innovation covariance H P H^T + noise,
 * packed xx xy yy (mvt_pkf_innov_t.S, which gating already computed). With outlier_persist_s 0 or
 * p_outlier 0 it is mvt_imm_update_pos. */
mvt_err_t mvt_imm_update_view(mvt_imm_t *imm, const mvt_imm_config_t *c, const mvt_real *H, const mvt_real *y,
                              const mvt_real *noise, const mvt_real S[3], mvt_imm_view_t *view, mvt_cv_state_t *s);
/* The same with other evidence of the detection (the blob's bottom) weighing "the person's" against
 * "displaced" by its likelihood ratio own_lr (> 0; 1: none). */
mvt_err_t mvt_imm_update_view_lr(mvt_imm_t *imm, const mvt_imm_config_t *c, const mvt_real *H, const mvt_real *y,
                                 const mvt_real *noise, const mvt_real S[3], mvt_imm_view_t *view, mvt_real own_lr,
                                 mvt_cv_state_t *s);

/* mvt_imm_predict_to and mvt_imm_update for several cameras in a row: s receives only what projecting
 * and gating the next camera read, the combined position and the position block of P (the velocity
 * and P's velocity rows and columns are left as they were, stale). Call mvt_imm_combine after the
 * last, before anything reads the velocity or its covariance. The whole combination after every
 * camera was a quarter of the IMM step's time. */
mvt_err_t mvt_imm_predict_to_pos(mvt_imm_t *imm, const mvt_imm_config_t *c, int64_t utime_us, mvt_cv_state_t *s);
mvt_err_t mvt_imm_update_pos(mvt_imm_t *imm, const mvt_imm_config_t *c, int m, const mvt_real *H, const mvt_real *y,
                             const mvt_real *noise, mvt_cv_state_t *s);

/* mvt_cv_truncate_ex (mvt_imm_truncate) or mvt_cv_truncate_ground on every model (value moved by
 * H (x_j - x)), then recombined. The truncation's mass is not evidence for one motion model over
 * another: mu is left as it is. */
mvt_err_t mvt_imm_truncate(mvt_imm_t *imm, const mvt_imm_config_t *c, const mvt_real H[3], mvt_real value,
                           mvt_real extra_var, mvt_real lo, mvt_real hi, mvt_cv_state_t *s);
mvt_err_t mvt_imm_truncate_ground(mvt_imm_t *imm, const mvt_imm_config_t *c, const mvt_real H[3], mvt_real value,
                                  mvt_real extra_var, mvt_real lo, mvt_real hi, mvt_cv_state_t *s);

/* mvt_cv_repair on every model and on s. */
mvt_err_t mvt_imm_repair(mvt_imm_t *imm, const mvt_imm_config_t *c, mvt_cv_state_t *s, mvt_real var_floor);

/* The combined estimate of the bank into s (time: model 0's). */
void mvt_imm_combine(const mvt_imm_t *imm, const mvt_imm_config_t *c, mvt_cv_state_t *s);

#ifdef __cplusplus
}
#endif

#endif /* MVT_IMM_H */
