/*
 * mvt_tri.h - multi-view triangulation of one 3D point from undistorted detections.
 *
 * Used for track birth (with the reprojection check), and by the triangulate-then-Kalman baseline
 * (--mode kf). Cost is bounded by the number of views n <= MVT_MAX_CAMERAS.
 */
#ifndef MVT_TRI_H
#define MVT_TRI_H

#include "mvt_camera.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One view of the point: camera index into the camera array and its undistorted normalised
 * coordinates (mvt_cam_undistort), with pixel variance. */
typedef struct mvt_tri_obs {
    int cam;
    mvt_real xn[2];
    mvt_real var_px2;
} mvt_tri_obs_t;

/* Linear least squares (DLT with X4 = 1, rows scaled to pixels). MVT_ERR_DEGENERATE with fewer
 * than 2 views or near-parallel rays; MVT_ERR_BEHIND when the point lands behind a view. O(n). */
mvt_err_t mvt_tri_linear(const mvt_camera_t *cams, const mvt_tri_obs_t *obs, int n, mvt_real x[3]);

/* Gauss-Newton on the weighted reprojection error from the start point x (iters <= 10). */
mvt_err_t mvt_tri_refine(const mvt_camera_t *cams, const mvt_tri_obs_t *obs, int n, int iters, mvt_real x[3]);

/* Reprojection error (pixels, ideal image) of x in view obs. Returns a huge value behind the camera. */
mvt_real mvt_tri_reproj_px(const mvt_camera_t *cams, const mvt_tri_obs_t *obs, const mvt_real x[3]);

/* First-order covariance of the point: (sum_k J_k^T J_k / var_k)^-1, m^2, 3x3. */
mvt_err_t mvt_tri_covariance(const mvt_camera_t *cams, const mvt_tri_obs_t *obs, int n, const mvt_real x[3],
                             mvt_real cov[9]);

/* Robust triangulation: all views first; if a reprojection error exceeds thresh_px, every pair of
 * views is tried (at most n(n-1)/2 pairs, each O(n)) and the one with most inliers (then least
 * error) wins; the result is refined on its inliers. inliers (bit k = obs[k]) and n_inliers may be
 * NULL. MVT_ERR_DEGENERATE when fewer than 2 views agree. */
mvt_err_t mvt_tri_robust(const mvt_camera_t *cams, const mvt_tri_obs_t *obs, int n, mvt_real thresh_px,
                         mvt_real x[3], uint32_t *inliers, int *n_inliers);

#ifdef __cplusplus
}
#endif

#endif /* MVT_TRI_H */
