/*
 * mvt_camera.h - calibrated camera: OpenCV's pinhole + distortion model.
 *
 * Model (identical to cv::projectPoints): X_cam = R X_world + t; x = X/Z, y = Y/Z;
 * r2 = x^2 + y^2; radial = (1 + k1 r2 + k2 r2^2 + k3 r2^3) / (1 + k4 r2 + k5 r2^2 + k6 r2^3);
 * x_d = x radial + 2 p1 x y + p2 (r2 + 2 x^2); y_d = y radial + p1 (r2 + 2 y^2) + 2 p2 x y;
 * u = fx x_d + skew y_d + cx, v = fy y_d + cy. Pixels x right, y down, origin at the centre of
 * the top-left pixel as in OpenCV.
 *
 * "Ideal" pixels are the undistorted image: the same K applied to the undistorted normalised
 * point, i.e. the pinhole projection P = K [R | t].
 */
#ifndef MVT_CAMERA_H
#define MVT_CAMERA_H

#include "mvt_types.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Calibration as a rig file gives it. Copied by mvt_cam_init; the caller may discard it. */
typedef struct mvt_camera_params {
    mvt_real camera_matrix[9];  /* K, row-major: fx skew cx; 0 fy cy; 0 0 1 (pixels) */
    mvt_real dist[8];           /* k1 k2 p1 p2 k3 k4 k5 k6; missing entries are 0 */
    mvt_real rvec[3];           /* world -> camera rotation, Rodrigues vector, radians */
    mvt_real tvec[3];           /* world -> camera translation, metres */
    int width, height;          /* image size, pixels, 1..32767 */
    mvt_real sigma_px;          /* default 1-sigma pixel noise of detections, > 0 */
} mvt_camera_params_t;

/* A ready camera: derived quantities computed once by mvt_cam_init. */
typedef struct mvt_camera {
    mvt_real fx, fy, cx, cy, skew;  /* pixels */
    mvt_real dist[8];
    int has_dist;                   /* 0 when every coefficient is 0 (skip the model) */
    int has_rational;               /* 0 when k4 = k5 = k6 = 0 (no denominator) */
    mvt_real R[9];                  /* world -> camera rotation */
    mvt_real t[3];                  /* world -> camera translation, metres */
    mvt_real P[12];                 /* K [R | t], 3x4 row-major */
    mvt_real centre[3];             /* camera centre in the world, -R^T t, metres */
    int width, height;
    mvt_real sigma_px;
    mvt_real field_r2;              /* the model's field: normalised x^2 + y^2 up to where the radial
                                       map r -> r radial(r^2) stops increasing (a lens with k1 < 0
                                       folds farther points back into the image); 1e30 when it
                                       never folds within r = 20 (87 degrees off axis) */
} mvt_camera_t;

/* Checks the parameters (finite, fx, fy > 0, sizes > 0, sigma > 0, K's last row 0 0 1) and
 * fills cam. MVT_ERR_INVALID / MVT_ERR_NONFINITE on bad input (cam then unusable). */
mvt_err_t mvt_cam_init(mvt_camera_t *cam, const mvt_camera_params_t *params);

/* World -> camera frame: xc = R xw + t (metres). */
static inline void mvt_cam_to_camera(const mvt_camera_t *cam, const mvt_real xw[3], mvt_real xc[3])
{
    for (int i = 0; i < 3; i++) {
        xc[i] = cam->R[i * 3 + 0] * xw[0] + cam->R[i * 3 + 1] * xw[1] + cam->R[i * 3 + 2] * xw[2] + cam->t[i];
    }
}

/* The distortion model's value at a normalised point (mvt_cam_distort without the Jacobian;
 * inline for the particle filter's per-particle loops). */
static inline void mvt_cam_distort_value(const mvt_camera_t *cam, mvt_real x, mvt_real y, mvt_real xd[2])
{
    if (!cam->has_dist) {
        xd[0] = x;
        xd[1] = y;
        return;
    }
    const mvt_real *d = cam->dist;
    const mvt_real r2 = x * x + y * y;
    const mvt_real a = MVT_R(1.0) + r2 * (d[0] + r2 * (d[1] + r2 * d[4]));
    const mvt_real radial = cam->has_rational ? a / (MVT_R(1.0) + r2 * (d[5] + r2 * (d[6] + r2 * d[7]))) : a;
    xd[0] = x * radial + MVT_R(2.0) * d[2] * x * y + d[3] * (r2 + MVT_R(2.0) * x * x);
    xd[1] = y * radial + d[2] * (r2 + MVT_R(2.0) * y * y) + MVT_R(2.0) * d[3] * x * y;
}

/* Camera-frame depth Z of a world point, metres (> 0 in front of the camera). */
mvt_real mvt_cam_depth(const mvt_camera_t *cam, const mvt_real xw[3]);

/* Projects a world point to raw (distorted) pixels; jac (2x3 row-major, d(u,v)/d(X,Y,Z)) may be
 * NULL. MVT_ERR_BEHIND when the point is not in the camera's field: depth below 1 mm, or beyond
 * the radius where the distortion folds back (field_r2; such a point has no image, although the
 * polynomial would put it inside the picture). O(1). */
mvt_err_t mvt_cam_project(const mvt_camera_t *cam, const mvt_real xw[3], mvt_real uv[2],
                          mvt_real jac[6]);

/* Applies the distortion to a normalised point; jac (2x2, d(xd,yd)/d(x,y)) may be NULL. */
void mvt_cam_distort(const mvt_camera_t *cam, const mvt_real xn[2], mvt_real xd[2],
                     mvt_real jac[4]);

/* Raw pixels -> undistorted normalised coordinates (x = X/Z, y = Y/Z), by Newton iteration on
 * the distortion model (at most 20 iterations, each O(1)). MVT_ERR_NUMERIC when it does not
 * converge or lands beyond the fold (a pixel outside the model's invertible region). */
mvt_err_t mvt_cam_undistort(const mvt_camera_t *cam, const mvt_real uv[2], mvt_real xn[2]);

/* Normalised -> ideal (pinhole) pixels with the camera's K. */
void mvt_cam_normalised_to_ideal(const mvt_camera_t *cam, const mvt_real xn[2], mvt_real uv[2]);

/* Back-projected ray of a raw pixel: origin = camera centre, dir = unit world direction. */
mvt_err_t mvt_cam_ray(const mvt_camera_t *cam, const mvt_real uv[2], mvt_real origin[3],
                      mvt_real dir[3]);

#ifdef __cplusplus
}
#endif

#endif /* MVT_CAMERA_H */
