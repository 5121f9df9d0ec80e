#include "mvt_pkf.h"

#include <math.h>
#include <string.h>

#include "mvt_linalg.h"

mvt_err_t mvt_pkf_meas_make(const mvt_camera_t *cam, const mvt_real uv[2], mvt_real sigma_px, mvt_pkf_meas_t *out)
{
    if (!mvt_la_all_finite(uv, 2) || !isfinite(sigma_px)) {
        return MVT_ERR_NONFINITE;
    }
    if (!(sigma_px > MVT_R(0.0))) {
        return MVT_ERR_INVALID;
    }
    const mvt_err_t err = mvt_cam_undistort(cam, uv, out->xn);
    if (err != MVT_OK) {
        return err;
    }
    out->raw[0] = uv[0];
    out->raw[1] = uv[1];
    mvt_cam_normalised_to_ideal(cam, out->xn, out->ideal);
    out->var_px2 = sigma_px * sigma_px;
    return MVT_OK;
}

mvt_err_t mvt_pkf_predict_obs(const mvt_cv_state_t *s, const mvt_camera_t *cam, mvt_pkf_lin_t lin,
                              mvt_pkf_pred_t *out)
{
    const mvt_real *x = s->x;
    mvt_real tc[3];
    mvt_cam_to_camera(cam, x, tc);
    out->lin = lin;
    out->depth_m = tc[2];
    if (lin == MVT_PKF_JACOBIAN) {
        const mvt_err_t err = mvt_cam_project(cam, x, out->h, out->H);
        if (err != MVT_OK) {
            return err;
        }
    } else {
        /* Eq. 18: H = alpha P_k (pixel rows), alpha = 1 / (P_k^3 . s) */
        const mvt_real *P = cam->P;
        const mvt_real w = P[8] * x[0] + P[9] * x[1] + P[10] * x[2] + P[11];
        if (!(w > MVT_R(1e-3))) {
            return MVT_ERR_BEHIND;
        }
        const mvt_real alpha = MVT_R(1.0) / w;
        const mvt_real cu = lin == MVT_PKF_PAPER_CENTRED ? cam->cx : MVT_R(0.0);
        const mvt_real cv = lin == MVT_PKF_PAPER_CENTRED ? cam->cy : MVT_R(0.0);
        for (int c = 0; c < 3; c++) {
            out->H[c] = alpha * (P[c] - cu * P[8 + c]);
            out->H[3 + c] = alpha * (P[4 + c] - cv * P[8 + c]);
        }
        out->h[0] = alpha * (P[0] * x[0] + P[1] * x[1] + P[2] * x[2] + P[3]);
        out->h[1] = alpha * (P[4] * x[0] + P[5] * x[1] + P[6] * x[2] + P[7]);
    }
    mvt_real hp[6];
    mvt_pkf_hph(out->H, s->P, hp, out->hph);
    return MVT_OK;
}

void mvt_pkf_hph(const mvt_real H[6], const mvt_real P[36], mvt_real hp[6], mvt_real hph[3])
{
    for (int a = 0; a < 2; a++) {
        for (int c = 0; c < 3; c++) {
            hp[a * 3 + c] = H[a * 3 + 0] * P[0 * 6 + c] + H[a * 3 + 1] * P[1 * 6 + c] + H[a * 3 + 2] * P[2 * 6 + c];
        }
    }
    if (hph != NULL) {
        hph[0] = hp[0] * H[0] + hp[1] * H[1] + hp[2] * H[2];
        hph[1] = hp[0] * H[3] + hp[1] * H[4] + hp[2] * H[5];
        hph[2] = hp[3] * H[3] + hp[4] * H[4] + hp[5] * H[5];
    }
}

mvt_err_t mvt_pkf_innovation_from(const mvt_pkf_pred_t *pred, const mvt_pkf_meas_t *meas,
                                  const mvt_real *extra_px2, mvt_pkf_innov_t *out)
{
    const mvt_real *z = pred->lin == MVT_PKF_JACOBIAN ? meas->raw : meas->ideal;
    out->y[0] = z[0] - pred->h[0];
    out->y[1] = z[1] - pred->h[1];
    for (int i = 0; i < 6; i++) {
        out->H[i] = pred->H[i];
    }
    out->r = meas->var_px2;
    out->S[0] = pred->hph[0] + out->r;
    out->S[1] = pred->hph[1];
    out->S[2] = pred->hph[2] + out->r;
    if (extra_px2 != NULL) {
        out->S[0] += extra_px2[0];
        out->S[1] += extra_px2[1];
        out->S[2] += extra_px2[2];
    }
    return mvt_pkf_innov_d2(out);
}

mvt_err_t mvt_pkf_innov_d2(mvt_pkf_innov_t *in)
{
    mvt_real si[3];
    if (mvt_la_inv2_sym(in->S, si) != MVT_OK) {
        return MVT_ERR_NUMERIC;
    }
    in->d2 = in->y[0] * (si[0] * in->y[0] + si[1] * in->y[1]) + in->y[1] * (si[1] * in->y[0] + si[2] * in->y[1]);
    if (!isfinite(in->d2)) {
        return MVT_ERR_NUMERIC;
    }
    return MVT_OK;
}

mvt_err_t mvt_pkf_innovation(const mvt_cv_state_t *s, const mvt_camera_t *cam, mvt_pkf_lin_t lin,
                             const mvt_pkf_meas_t *meas, mvt_pkf_innov_t *out)
{
    mvt_pkf_pred_t pred;
    const mvt_err_t err = mvt_pkf_predict_obs(s, cam, lin, &pred);
    if (err != MVT_OK) {
        return err;
    }
    return mvt_pkf_innovation_from(&pred, meas, NULL, out);
}

mvt_err_t mvt_pkf_update(mvt_cv_state_t *s, const mvt_pkf_innov_t *in)
{
    mvt_real si[3];
    if (mvt_la_inv2_sym(in->S, si) != MVT_OK) {
        return MVT_ERR_NUMERIC;
    }
    /* H P (2x6) once; K = (H P)^T S^-1 since P is symmetric */
    const mvt_real *P = s->P;
    const mvt_real *H = in->H;
    mvt_real hpP[12], k[12];
    for (int j = 0; j < 6; j++) {
        hpP[j] = H[0] * P[0 * 6 + j] + H[1] * P[1 * 6 + j] + H[2] * P[2 * 6 + j];
        hpP[6 + j] = H[3] * P[0 * 6 + j] + H[4] * P[1 * 6 + j] + H[5] * P[2 * 6 + j];
    }
    for (int i = 0; i < 6; i++) {
        k[i * 2 + 0] = hpP[i] * si[0] + hpP[6 + i] * si[1];
        k[i * 2 + 1] = hpP[i] * si[1] + hpP[6 + i] * si[2];
        s->x[i] += k[i * 2 + 0] * in->y[0] + k[i * 2 + 1] * in->y[1];
    }
    const mvt_real S[4] = {in->S[0], in->S[1], in->S[1], in->S[2]};
    mvt_cv_joseph_hp(s, 2, hpP, S, k);
    return MVT_OK;
}

mvt_err_t mvt_pkf_paper_distance(const mvt_cv_state_t *s, const mvt_camera_t *cam, const mvt_real var_m2[3],
                                 mvt_real gamma, const mvt_pkf_meas_t *meas, mvt_real *dist)
{
    /* Computed in normalised camera coordinates (K is an affine map of the image plane, so the
     * normalised conic distance is the same). The outline is the cone of rays from the camera
     * centre tangent to the ellipsoid: with u the ellipsoid's centre in the camera frame and
     * Ei = R diag(1 / (gamma var)) R^T its shape's inverse there, a ray w meets the ellipsoid iff
     * (w^T Ei u)^2 >= (w^T Ei w)(u^T Ei u - 1), so the outline's point conic is
     * C = (u^T Ei u - 1) Ei - (Ei u)(Ei u)^T (negative inside). This is the inverse of the dual
     * quadric's projection up to scale, without inverting that nearly rank-one matrix: a head-sized
     * ellipsoid a few metres away would lose it to float rounding. */
    const mvt_real *R = cam->R;
    const mvt_real *c = s->x;
    mvt_real tc[3]; /* camera-frame position of c */
    mvt_cam_to_camera(cam, c, tc);
    if (!(tc[2] > MVT_R(1e-3))) {
        return MVT_ERR_BEHIND;
    }
    mvt_real inv_e[3];
    for (int k = 0; k < 3; k++) {
        const mvt_real e = gamma * var_m2[k];
        if (!(e > MVT_R(0.0))) {
            return MVT_ERR_NUMERIC;
        }
        inv_e[k] = MVT_R(1.0) / e;
    }
    mvt_real ei[9];
    for (int a = 0; a < 3; a++) {
        for (int b = 0; b < 3; b++) {
            mvt_real acc = MVT_R(0.0);
            for (int k = 0; k < 3; k++) {
                acc += R[a * 3 + k] * inv_e[k] * R[b * 3 + k];
            }
            ei[a * 3 + b] = acc;
        }
    }
    mvt_real v[3];
    for (int a = 0; a < 3; a++) {
        v[a] = ei[a * 3] * tc[0] + ei[a * 3 + 1] * tc[1] + ei[a * 3 + 2] * tc[2];
    }
    const mvt_real sq = tc[0] * v[0] + tc[1] * v[1] + tc[2] * v[2] - MVT_R(1.0);
    if (!(sq > MVT_R(0.0))) {
        return MVT_ERR_NUMERIC; /* the camera is inside the ellipsoid */
    }
    mvt_real cc[9];
    for (int a = 0; a < 3; a++) {
        for (int b = 0; b < 3; b++) {
            cc[a * 3 + b] = sq * ei[a * 3 + b] - v[a] * v[b];
        }
    }
    /* conic: x^T A x + 2 b^T x + c0 = 0 -> (x - x0)^T A (x - x0) = k, x0 = -A^-1 b */
    const mvt_real a[3] = {cc[0], MVT_R(0.5) * (cc[1] + cc[3]), cc[4]};
    const mvt_real b[2] = {MVT_R(0.5) * (cc[2] + cc[6]), MVT_R(0.5) * (cc[5] + cc[7])};
    const mvt_real det = a[0] * a[2] - a[1] * a[1];
    if (!(det > MVT_R(0.0)) || !isfinite(det)) {
        return MVT_ERR_NUMERIC; /* not an ellipse: the ellipsoid reaches the camera plane */
    }
    const mvt_real x0 = -(a[2] * b[0] - a[1] * b[1]) / det;
    const mvt_real y0 = -(a[0] * b[1] - a[1] * b[0]) / det;
    const mvt_real k = a[0] * x0 * x0 + MVT_R(2.0) * a[1] * x0 * y0 + a[2] * y0 * y0 - cc[8];
    if (!(MVT_FABS(k) > MVT_R(0.0)) || !isfinite(k)) {
        return MVT_ERR_NUMERIC;
    }
    /* the detection in normalised pinhole coordinates (from the ideal pixels: K^-1) */
    const mvt_real yn = (meas->ideal[1] - cam->cy) / cam->fy;
    const mvt_real xn = (meas->ideal[0] - cam->cx - cam->skew * yn) / cam->fx;
    /* measured from the outline's own centre x0 (Eq. 25 writes psi(s), the projected centre of
     * the ellipsoid, which under perspective is not the outline's centre): dist <= 1 exactly
     * when the detection lies inside the projected ellipsoid */
    const mvt_real du = xn - x0;
    const mvt_real dv = yn - y0;
    const mvt_real m2 = (a[0] * du * du + MVT_R(2.0) * a[1] * du * dv + a[2] * dv * dv) / k;
    if (!(m2 >= MVT_R(0.0)) || !isfinite(m2)) {
        return MVT_ERR_NUMERIC;
    }
    *dist = MVT_SQRT(m2);
    return MVT_OK;
}
