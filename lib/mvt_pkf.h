/*
 * mvt_pkf.h - projective measurement update: one camera's pixel observation of a 3D state.
 *
 * Canton-Ferrer et al.'s Projective Kalman Filter observes the homogeneous state through the
 * camera projection matrices. Two linearisations are offered (docs/filters.md measures them):
 *
 *  MVT_PKF_JACOBIAN  H = d h / d X at the predicted state, h = the full OpenCV projection with
 *                    distortion, z = the raw detection. This is the EKF form; the default.
 *  MVT_PKF_PAPER     the paper's Eq. 18: H = alpha_k P_k (pixel rows), alpha_k = 1 / (P_k^3 s),
 *                    z = the undistorted (ideal) detection, pixel origin as calibrated (OpenCV:
 *                    top-left). Faithful reproduction.
 *  MVT_PKF_PAPER_CENTRED  Eq. 18 with pixel coordinates centred on the principal point.
 *
 * In every form only the two pixel rows of a camera enter the update (the third homogeneous row
 * is identically 1 and would pin the depth to the prediction), a camera with the predicted point
 * at or behind it is not used, and an occluded (gated-out) view is left out, the beta_k = infinity
 * of Eq. 20. Updates are sequential per camera, each relinearised at the current estimate.
 */
#ifndef MVT_PKF_H
#define MVT_PKF_H

#include "mvt_camera.h"
#include "mvt_cv.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mvt_pkf_lin {
    MVT_PKF_JACOBIAN = 0,
    MVT_PKF_PAPER = 1,
    MVT_PKF_PAPER_CENTRED = 2
} mvt_pkf_lin_t;

/* One detection prepared once per frame for every track that looks at it. */
typedef struct mvt_pkf_meas {
    mvt_real raw[2];    /* pixels as detected (distorted) */
    mvt_real ideal[2];  /* undistorted pinhole pixels with the same K */
    mvt_real xn[2];     /* undistorted normalised coordinates */
    mvt_real var_px2;   /* pixel variance */
} mvt_pkf_meas_t;

/* The innovation of one camera's measurement against one state. */
typedef struct mvt_pkf_innov {
    mvt_real y[2];   /* innovation z - h(x), pixels */
    mvt_real H[6];   /* 2x3 observation rows on the position (velocity columns are zero) */
    mvt_real S[3];   /* innovation covariance H P H^T + R, packed xx xy yy, px^2 */
    mvt_real r;      /* measurement variance, px^2 (R = r I) */
    mvt_real d2;     /* squared Mahalanobis distance y^T S^-1 y (chi-square, 2 dof) */
} mvt_pkf_innov_t;

/* A state's predicted observation in one camera, computed once and shared by every detection the
 * state is tested against (gating is then ~20 flops per pair). */
typedef struct mvt_pkf_pred {
    mvt_pkf_lin_t lin;
    mvt_real h[2];      /* predicted point: raw pixels (JACOBIAN) or ideal pixels (PAPER forms) */
    mvt_real H[6];      /* 2x3 observation rows on the position */
    mvt_real hph[3];    /* H Ppp H^T, packed xx xy yy, px^2 */
    mvt_real depth_m;   /* depth of the predicted point in the camera (> 0) */
} mvt_pkf_pred_t;

/* Undistorts a detection once. MVT_ERR_NONFINITE / MVT_ERR_NUMERIC / MVT_ERR_INVALID (sigma). */
mvt_err_t mvt_pkf_meas_make(const mvt_camera_t *cam, const mvt_real uv[2], mvt_real sigma_px,
                            mvt_pkf_meas_t *out);

/* Predicted observation of state s in camera cam. MVT_ERR_BEHIND when the predicted point is at
 * or behind the camera. ~90 flops. */
mvt_err_t mvt_pkf_predict_obs(const mvt_cv_state_t *s, const mvt_camera_t *cam, mvt_pkf_lin_t lin,
                              mvt_pkf_pred_t *out);

/* Innovation of meas against a predicted observation; extra_px2 (packed xx xy yy, may be NULL)
 * is added to the measurement covariance (merged blobs). MVT_ERR_NUMERIC when S is not positive
 * definite. ~25 flops. */
mvt_err_t mvt_pkf_innovation_from(const mvt_pkf_pred_t *pred, const mvt_pkf_meas_t *meas,
                                  const mvt_real *extra_px2, mvt_pkf_innov_t *out);

/* H P and H P H^T (packed xx xy yy) of a pixel point's 2x3 Jacobian H (row-major) against the
 * position block of the 6x6 covariance P: hp 2x3 row-major; hph may be NULL. ~30 flops. */
void mvt_pkf_hph(const mvt_real H[6], const mvt_real P[36], mvt_real hp[6], mvt_real hph[3]);

/* in->d2 = y^T S^-1 y from in->y and in->S (after either changed). MVT_ERR_NUMERIC when S is not
 * positive definite or d2 not finite. ~12 flops. */
mvt_err_t mvt_pkf_innov_d2(mvt_pkf_innov_t *in);

/* Innovation of meas against state s in camera cam (predict_obs, then innovation_from). MVT_ERR_BEHIND when the predicted point is
 * at or behind the camera, MVT_ERR_NUMERIC when S is not positive definite. ~100 flops. */
mvt_err_t mvt_pkf_innovation(const mvt_cv_state_t *s, const mvt_camera_t *cam, mvt_pkf_lin_t lin,
                             const mvt_pkf_meas_t *meas, mvt_pkf_innov_t *out);

/* Kalman update with a computed innovation (Joseph form, ~350 flops). */
mvt_err_t mvt_pkf_update(mvt_cv_state_t *s, const mvt_pkf_innov_t *in);

/* The paper's association distance (Eq. 22-26): the ellipsoid of semi-axes^2 gamma * var_m2
 * around the predicted position is projected through camera cam as the outline conic of its dual
 * quadric (V proportional to (P W^-1 P^T)^-1); V is scaled so that the projected ellipse's
 * boundary is at distance 1 (the paper leaves the scale open). dist = sqrt(d^T V d), d = ideal
 * detection minus the outline's centre (so dist <= 1 exactly inside the projected ellipsoid). MVT_ERR_BEHIND / MVT_ERR_NUMERIC on bad geometry. */
mvt_err_t mvt_pkf_paper_distance(const mvt_cv_state_t *s, const mvt_camera_t *cam,
                                 const mvt_real var_m2[3], mvt_real gamma,
                                 const mvt_pkf_meas_t *meas, mvt_real *dist);

#ifdef __cplusplus
}
#endif

#endif /* MVT_PKF_H */
