/*
 * mvt_cv.h - constant-velocity target state shared by every Kalman-type filter in the core.
 *
 * The PKF paper's state is the homogeneous 8-vector s = [X Y Z 1 Vx Vy Vz 0]^T (Eq. 14) with an
 * 8x8 covariance whose 4th and 8th rows and columns are zero. Those entries are constants, so the
 * core stores only the six that vary: x = [X Y Z Vx Vy Vz] (m, m/s) and their 6x6 covariance;
 * the 8x8 form is recovered by inserting the constants (tests do exactly that against Eigen).
 *
 * Motion model: white-noise acceleration with spectral density q (m^2/s^3) per axis,
 * F = [I dt I; 0 I] (the paper's Eq. 16 with the actual frame interval dt instead of 1/T),
 * Q = q [dt^3/3 I, dt^2/2 I; dt^2/2 I, dt I].
 */
#ifndef MVT_CV_H
#define MVT_CV_H

#include "mvt_types.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mvt_cv_state {
    mvt_real x[6];    /* X Y Z (m), Vx Vy Vz (m/s) */
    mvt_real P[36];   /* covariance, row-major, kept symmetric */
    int64_t utime_us; /* time the estimate refers to */
} mvt_cv_state_t;

/* Starts a state at pos with position covariance pos_cov (3x3) and isotropic velocity variance
 * vel_var (m^2/s^2); velocity 0. */
void mvt_cv_init(mvt_cv_state_t *s, const mvt_real pos[3], const mvt_real pos_cov[9],
                 mvt_real vel_var, int64_t utime_us);

/* Predicts by dt_s >= 0 seconds (~120 flops). MVT_ERR_INVALID for negative/non-finite dt. */
mvt_err_t mvt_cv_predict(mvt_cv_state_t *s, mvt_real dt_s, const mvt_real q[3]);

/* Predicts to utime_us if it is later than the state's time (no-op otherwise). */
mvt_err_t mvt_cv_predict_to(mvt_cv_state_t *s, int64_t utime_us, const mvt_real q[3]);

/* Kalman update with a direct 3D position measurement z (m) of covariance R (3x3, m^2), Joseph
 * form. If gate_chi2 > 0 and the squared Mahalanobis distance exceeds it, the state is left
 * unchanged and MVT_ERR_GATED returned. d2 (may be NULL) receives the distance. ~400 flops. */
mvt_err_t mvt_cv_update_point(mvt_cv_state_t *s, const mvt_real z[3], const mvt_real R[9],
                              mvt_real gate_chi2, mvt_real *d2);

/* Symmetrises P, floors its diagonal at var_floor and checks that it is finite and positive
 * definite. MVT_ERR_NUMERIC if the position block is not PD after repair. */
mvt_err_t mvt_cv_repair(mvt_cv_state_t *s, mvt_real var_floor);

/* Constrains the position to lo <= H x <= hi (H: one row on the position, value: H x's current
 * value, or a linearised model's prediction of it): the Gaussian prior of H x (mean value,
 * variance H Ppp H^T) is truncated to [lo, hi] and the state moved to the truncated normal's mean
 * and variance along H (Simon and Simon's PDF truncation, applied as one scalar Kalman update
 * with the equivalent measurement, so velocity follows through the cross-covariance). *mass (may
 * be NULL) receives the prior probability of [lo, hi]. MVT_ERR_INVALID unless lo < hi (finite),
 * MVT_ERR_NUMERIC when [lo, hi] holds less than 1e-6 of the prior. A band much wider than the
 * prior around the mean changes (almost) nothing. ~150 flops. */
mvt_err_t mvt_cv_truncate(mvt_cv_state_t *s, const mvt_real H[3], mvt_real value, mvt_real lo, mvt_real hi,
                          mvt_real *mass);

/* mvt_cv_truncate of a functional H x + w, w an independent zero-mean term of variance extra_var
 * (another state's share of a joint constraint, e.g. H x_a - H x_b with x_b's variance): the
 * truncation acts on the sum, this state takes its share of the update. extra_var >= 0. */
mvt_err_t mvt_cv_truncate_ex(mvt_cv_state_t *s, const mvt_real H[3], mvt_real value, mvt_real extra_var, mvt_real lo,
                             mvt_real hi, mvt_real *mass);

/* mvt_cv_truncate_ex of a constraint on the ground position (H[2] = 0) that leaves the height and
 * the vertical speed as they are (their gain rows are zero; the covariance by the Joseph form,
 * which holds for any gain). Repeated ground constraints on a person nobody sees (hidden in
 * others' blobs, pushed apart by exclusion) otherwise move the height through the cross-covariance
 * a single view's ray left: a hidden head sank from 1.5 m to 0.4 m in 3 s. */
mvt_err_t mvt_cv_truncate_ground(mvt_cv_state_t *s, const mvt_real H[3], mvt_real value, mvt_real extra_var,
                                 mvt_real lo, mvt_real hi, mvt_real *mass);

/* Joseph-form covariance update for a measurement that observes only the position:
 * P <- (I - K H) P (I - K H)^T + K R K^T with H = [Hp 0] (m x 3 block), K (6 x m), R (m x m),
 * all row-major, m <= 3. Shared by the point and projective updates. */
void mvt_cv_joseph(mvt_cv_state_t *s, int m, const mvt_real *hp, const mvt_real *k, const mvt_real *r);

/* The same with H P (m x 6, row-major) and S = H P H^T + R (m x m) already computed. */
void mvt_cv_joseph_hp(mvt_cv_state_t *s, int m, const mvt_real *hpP, const mvt_real *S, const mvt_real *k);

#ifdef __cplusplus
}
#endif

#endif /* MVT_CV_H */
