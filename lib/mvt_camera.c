#include "mvt_camera.h"

#include <math.h>
#include <string.h>

#include "mvt_linalg.h"

/* Where the radial map g(r) = r radial(r^2) first stops increasing, scanned in steps of 1/256 up to
 * r = 20 (5120 evaluations, once per camera). Tangential terms are left out: they are 1e-3 of the
 * radial ones in real calibrations and do not fold. */
static mvt_real field_r2(const mvt_camera_t *cam)
{
    const mvt_real step = MVT_R(1.0) / MVT_R(256.0);
    mvt_real prev = MVT_R(0.0);
    for (int i = 1; i <= 20 * 256; i++) {
        const mvt_real r = step * (mvt_real)i;
        const mvt_real r2 = r * r;
        const mvt_real *d = cam->dist;
        const mvt_real a = MVT_R(1.0) + r2 * (d[0] + r2 * (d[1] + r2 * d[4]));
        const mvt_real b = MVT_R(1.0) + r2 * (d[5] + r2 * (d[6] + r2 * d[7]));
        const mvt_real g = cam->has_rational ? r * a / b : r * a;
        if (!(g > prev) || !(b > MVT_R(0.0))) {
            const mvt_real rf = r - step;
            return rf * rf;
        }
        prev = g;
    }
    return MVT_R(1e30);
}

mvt_err_t mvt_cam_init(mvt_camera_t *cam, const mvt_camera_params_t *p)
{
    MVT_ASSERT(cam != NULL && p != NULL);
    memset(cam, 0, sizeof(*cam));
    if (!mvt_la_all_finite(p->camera_matrix, 9) || !mvt_la_all_finite(p->dist, 8) ||
        !mvt_la_all_finite(p->rvec, 3) || !mvt_la_all_finite(p->tvec, 3) ||
        !isfinite(p->sigma_px)) {
        return MVT_ERR_NONFINITE;
    }
    const mvt_real *k = p->camera_matrix;
    if (!(k[0] > MVT_R(0.0)) || !(k[4] > MVT_R(0.0)) || MVT_FABS(k[3]) > MVT_EPS ||
        MVT_FABS(k[6]) > MVT_EPS || MVT_FABS(k[7]) > MVT_EPS ||
        MVT_FABS(k[8] - MVT_R(1.0)) > MVT_R(1e-6) || p->width < 1 || p->height < 1 ||
        p->width > 32767 || p->height > 32767 || !(p->sigma_px > MVT_R(0.0))) {
        return MVT_ERR_INVALID;
    }
    cam->fx = k[0];
    cam->skew = k[1];
    cam->cx = k[2];
    cam->fy = k[4];
    cam->cy = k[5];
    cam->has_dist = 0;
    for (int i = 0; i < 8; i++) {
        cam->dist[i] = p->dist[i];
        if (MVT_FABS(p->dist[i]) > MVT_R(0.0)) {
            cam->has_dist = 1;
            cam->has_rational |= i >= 5;
        }
    }
    mvt_la_rodrigues(p->rvec, cam->R);
    memcpy(cam->t, p->tvec, sizeof(cam->t));
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++) {
            cam->P[r * 4 + c] = k[r * 3 + 0] * cam->R[0 * 3 + c] + k[r * 3 + 1] * cam->R[1 * 3 + c] +
                                k[r * 3 + 2] * cam->R[2 * 3 + c];
        }
        cam->P[r * 4 + 3] = k[r * 3 + 0] * cam->t[0] + k[r * 3 + 1] * cam->t[1] + k[r * 3 + 2] * cam->t[2];
    }
    for (int i = 0; i < 3; i++) {
        cam->centre[i] = -(cam->R[0 * 3 + i] * cam->t[0] + cam->R[1 * 3 + i] * cam->t[1] +
                           cam->R[2 * 3 + i] * cam->t[2]);
    }
    cam->width = p->width;
    cam->height = p->height;
    cam->sigma_px = p->sigma_px;
    cam->field_r2 = cam->has_dist ? field_r2(cam) : MVT_R(1e30);
    return MVT_OK;
}

mvt_real mvt_cam_depth(const mvt_camera_t *cam, const mvt_real xw[3])
{
    return cam->R[6] * xw[0] + cam->R[7] * xw[1] + cam->R[8] * xw[2] + cam->t[2];
}

void mvt_cam_distort(const mvt_camera_t *cam, const mvt_real xn[2], mvt_real xd[2], mvt_real jac[4])
{
    mvt_cam_distort_value(cam, xn[0], xn[1], xd);
    if (jac == NULL) {
        return;
    }
    if (!cam->has_dist) {
        jac[0] = MVT_R(1.0);
        jac[1] = MVT_R(0.0);
        jac[2] = MVT_R(0.0);
        jac[3] = MVT_R(1.0);
        return;
    }
    const mvt_real *d = cam->dist;
    const mvt_real x = xn[0], y = xn[1];
    const mvt_real r2 = x * x + y * y;
    const mvt_real a = MVT_R(1.0) + r2 * (d[0] + r2 * (d[1] + r2 * d[4]));
    const mvt_real b = cam->has_rational ? MVT_R(1.0) + r2 * (d[5] + r2 * (d[6] + r2 * d[7])) : MVT_R(1.0);
    const mvt_real radial = cam->has_rational ? a / b : a;
    const mvt_real p1 = d[2], p2 = d[3];
    const mvt_real da = d[0] + r2 * (MVT_R(2.0) * d[1] + MVT_R(3.0) * r2 * d[4]);
    mvt_real drad = da; /* d radial / d r2 */
    if (cam->has_rational) {
        const mvt_real db = d[5] + r2 * (MVT_R(2.0) * d[6] + MVT_R(3.0) * r2 * d[7]);
        drad = (da * b - a * db) / (b * b);
    }
    jac[0] = radial + MVT_R(2.0) * x * x * drad + MVT_R(2.0) * p1 * y + MVT_R(6.0) * p2 * x;
    jac[1] = MVT_R(2.0) * x * y * drad + MVT_R(2.0) * p1 * x + MVT_R(2.0) * p2 * y;
    jac[2] = jac[1];
    jac[3] = radial + MVT_R(2.0) * y * y * drad + MVT_R(6.0) * p1 * y + MVT_R(2.0) * p2 * x;
}

mvt_err_t mvt_cam_project(const mvt_camera_t *cam, const mvt_real xw[3], mvt_real uv[2], mvt_real jac[6])
{
    const mvt_real *R = cam->R;
    mvt_real xc[3];
    mvt_cam_to_camera(cam, xw, xc);
    if (!(xc[2] > MVT_R(1e-3))) {
        return MVT_ERR_BEHIND;
    }
    const mvt_real iz = MVT_R(1.0) / xc[2];
    const mvt_real xn[2] = {xc[0] * iz, xc[1] * iz};
    if (!(xn[0] * xn[0] + xn[1] * xn[1] <= cam->field_r2)) {
        return MVT_ERR_BEHIND; /* beyond the fold: no image (and NaN never passes) */
    }
    mvt_real xd[2], jd[4];
    mvt_cam_distort(cam, xn, xd, jac != NULL ? jd : NULL);
    uv[0] = cam->fx * xd[0] + cam->skew * xd[1] + cam->cx;
    uv[1] = cam->fy * xd[1] + cam->cy;
    if (jac != NULL) {
        /* d(u,v)/d(xd,yd) * d(xd,yd)/d(x,y) */
        const mvt_real a00 = cam->fx * jd[0] + cam->skew * jd[2];
        const mvt_real a01 = cam->fx * jd[1] + cam->skew * jd[3];
        const mvt_real a10 = cam->fy * jd[2];
        const mvt_real a11 = cam->fy * jd[3];
        /* d(x,y)/d(Xc) = [iz 0 -x iz; 0 iz -y iz], then * R */
        mvt_real b[6];
        b[0] = a00 * iz;
        b[1] = a01 * iz;
        b[2] = -(a00 * xn[0] + a01 * xn[1]) * iz;
        b[3] = a10 * iz;
        b[4] = a11 * iz;
        b[5] = -(a10 * xn[0] + a11 * xn[1]) * iz;
        for (int r = 0; r < 2; r++) {
            for (int c = 0; c < 3; c++) {
                jac[r * 3 + c] = b[r * 3 + 0] * R[0 * 3 + c] + b[r * 3 + 1] * R[1 * 3 + c] +
                                 b[r * 3 + 2] * R[2 * 3 + c];
            }
        }
    }
    return MVT_OK;
}

mvt_err_t mvt_cam_undistort(const mvt_camera_t *cam, const mvt_real uv[2], mvt_real xn[2])
{
    if (!mvt_la_all_finite(uv, 2)) {
        return MVT_ERR_NONFINITE;
    }
    /* invert K */
    const mvt_real yd = (uv[1] - cam->cy) / cam->fy;
    const mvt_real xdd = (uv[0] - cam->cx - cam->skew * yd) / cam->fx;
    xn[0] = xdd;
    xn[1] = yd;
    if (!cam->has_dist) {
        return MVT_OK;
    }
    /* Newton on distort(x) = xd, started at x = xd. */
    const mvt_real tol = MVT_R(1e-3) * MVT_R(1e-3) / (cam->fx * cam->fx); /* (1e-3 px)^2 */
    for (int it = 0; it < 20; it++) {
        mvt_real f[2], j[4];
        mvt_cam_distort(cam, xn, f, j);
        const mvt_real rx = f[0] - xdd, ry = f[1] - yd;
        const mvt_real det = j[0] * j[3] - j[1] * j[2];
        if (!(MVT_FABS(det) > MVT_R(1e-9)) || !isfinite(det)) {
            return MVT_ERR_NUMERIC;
        }
        const mvt_real dx = (j[3] * rx - j[1] * ry) / det;
        const mvt_real dy = (j[0] * ry - j[2] * rx) / det;
        xn[0] -= dx;
        xn[1] -= dy;
        if (dx * dx + dy * dy < tol) {
            break;
        }
    }
    mvt_real f[2];
    mvt_cam_distort(cam, xn, f, NULL);
    const mvt_real ex = (f[0] - xdd) * cam->fx, ey = (f[1] - yd) * cam->fy;
    if (!(ex * ex + ey * ey < MVT_R(0.01)) || !mvt_la_all_finite(xn, 2) || /* 0.1 px */
        !(xn[0] * xn[0] + xn[1] * xn[1] <= cam->field_r2)) {
        return MVT_ERR_NUMERIC;
    }
    return MVT_OK;
}

void mvt_cam_normalised_to_ideal(const mvt_camera_t *cam, const mvt_real xn[2], mvt_real uv[2])
{
    uv[0] = cam->fx * xn[0] + cam->skew * xn[1] + cam->cx;
    uv[1] = cam->fy * xn[1] + cam->cy;
}

mvt_err_t mvt_cam_ray(const mvt_camera_t *cam, const mvt_real uv[2], mvt_real origin[3], mvt_real dir[3])
{
    mvt_real xn[2];
    const mvt_err_t err = mvt_cam_undistort(cam, uv, xn);
    if (err != MVT_OK) {
        return err;
    }
    const mvt_real dc[3] = {xn[0], xn[1], MVT_R(1.0)};
    mvt_real n2 = MVT_R(0.0);
    for (int i = 0; i < 3; i++) { /* R^T dc */
        dir[i] = cam->R[0 * 3 + i] * dc[0] + cam->R[1 * 3 + i] * dc[1] + cam->R[2 * 3 + i] * dc[2];
        n2 += dir[i] * dir[i];
        origin[i] = cam->centre[i];
    }
    const mvt_real in = MVT_R(1.0) / MVT_SQRT(n2);
    for (int i = 0; i < 3; i++) {
        dir[i] *= in;
    }
    return MVT_OK;
}
