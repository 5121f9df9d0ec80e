#include "mvt_tri.h"

#include <math.h>
#include <string.h>

#include "mvt_linalg.h"

#define MVT_TRI_HUGE MVT_R(1e9)

/* Accumulates one view's two rows of A X = b (scaled to pixels) into the normal equations. */
static void add_rows(const mvt_camera_t *cam, const mvt_tri_obs_t *o, mvt_real w, mvt_real ata[9], mvt_real atb[3])
{
    const mvt_real *R = cam->R;
    const mvt_real *t = cam->t;
    for (int r = 0; r < 2; r++) {
        const mvt_real f = r == 0 ? cam->fx : cam->fy;
        mvt_real a[3];
        for (int c = 0; c < 3; c++) {
            a[c] = f * (o->xn[r] * R[6 + c] - R[r * 3 + c]);
        }
        const mvt_real b = f * (t[r] - o->xn[r] * t[2]);
        for (int i = 0; i < 3; i++) {
            for (int j = 0; j < 3; j++) {
                ata[i * 3 + j] += w * a[i] * a[j];
            }
            atb[i] += w * a[i] * b;
        }
    }
}

static mvt_err_t solve_normal(mvt_real ata[9], mvt_real atb[3], mvt_real x[3])
{
    /* condition guard: smallest pivot relative to the trace */
    const mvt_real tr = ata[0] + ata[4] + ata[8];
    if (!(tr > MVT_R(0.0)) || mvt_la_cholesky(3, ata) != MVT_OK) {
        return MVT_ERR_DEGENERATE;
    }
    const mvt_real pmin = ata[8] < ata[4] ? (ata[8] < ata[0] ? ata[8] : ata[0]) : (ata[4] < ata[0] ? ata[4] : ata[0]);
    if (pmin * pmin < MVT_R(1e-7) * tr) {
        return MVT_ERR_DEGENERATE;
    }
    mvt_la_chol_solve(3, ata, atb);
    memcpy(x, atb, 3 * sizeof(mvt_real));
    return mvt_la_all_finite(x, 3) ? MVT_OK : MVT_ERR_DEGENERATE;
}

static int in_front(const mvt_camera_t *cams, const mvt_tri_obs_t *obs, int n, const mvt_real x[3])
{
    for (int k = 0; k < n; k++) {
        if (!(mvt_cam_depth(&cams[obs[k].cam], x) > MVT_R(1e-2))) {
            return 0;
        }
    }
    return 1;
}

mvt_err_t mvt_tri_linear(const mvt_camera_t *cams, const mvt_tri_obs_t *obs, int n, mvt_real x[3])
{
    if (n < 2) {
        return MVT_ERR_DEGENERATE;
    }
    mvt_real ata[9] = {0}, atb[3] = {0};
    for (int k = 0; k < n; k++) {
        add_rows(&cams[obs[k].cam], &obs[k], MVT_R(1.0), ata, atb);
    }
    const mvt_err_t err = solve_normal(ata, atb, x);
    if (err != MVT_OK) {
        return err;
    }
    return in_front(cams, obs, n, x) ? MVT_OK : MVT_ERR_BEHIND;
}

mvt_err_t mvt_tri_refine(const mvt_camera_t *cams, const mvt_tri_obs_t *obs, int n, int iters, mvt_real x[3])
{
    MVT_ASSERT(iters >= 0 && iters <= 10);
    for (int it = 0; it < iters; it++) {
        mvt_real jtj[9] = {0}, jtr[3] = {0};
        for (int k = 0; k < n; k++) {
            const mvt_camera_t *cam = &cams[obs[k].cam];
            mvt_real xc[3];
            mvt_cam_to_camera(cam, x, xc);
            if (!(xc[2] > MVT_R(1e-2))) {
                return MVT_ERR_BEHIND;
            }
            const mvt_real iz = MVT_R(1.0) / xc[2];
            const mvt_real px[2] = {xc[0] * iz, xc[1] * iz};
            for (int r = 0; r < 2; r++) {
                const mvt_real f = r == 0 ? cam->fx : cam->fy;
                const mvt_real w = f * f / obs[k].var_px2;
                mvt_real j[3];
                for (int c = 0; c < 3; c++) {
                    j[c] = iz * (cam->R[r * 3 + c] - px[r] * cam->R[6 + c]);
                }
                const mvt_real res = obs[k].xn[r] - px[r];
                for (int a = 0; a < 3; a++) {
                    for (int b = 0; b < 3; b++) {
                        jtj[a * 3 + b] += w * j[a] * j[b];
                    }
                    jtr[a] += w * j[a] * res;
                }
            }
        }
        mvt_real dx[3];
        if (solve_normal(jtj, jtr, dx) != MVT_OK) {
            return MVT_ERR_DEGENERATE;
        }
        for (int i = 0; i < 3; i++) {
            x[i] += dx[i];
        }
        if (dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2] < MVT_R(1e-12)) {
            break;
        }
    }
    return in_front(cams, obs, n, x) ? MVT_OK : MVT_ERR_BEHIND;
}

mvt_real mvt_tri_reproj_px(const mvt_camera_t *cams, const mvt_tri_obs_t *o, const mvt_real x[3])
{
    const mvt_camera_t *cam = &cams[o->cam];
    mvt_real xc[3];
    mvt_cam_to_camera(cam, x, xc);
    if (!(xc[2] > MVT_R(1e-2))) {
        return MVT_TRI_HUGE;
    }
    const mvt_real ex = cam->fx * (o->xn[0] - xc[0] / xc[2]);
    const mvt_real ey = cam->fy * (o->xn[1] - xc[1] / xc[2]);
    return MVT_SQRT(ex * ex + ey * ey);
}

mvt_err_t mvt_tri_covariance(const mvt_camera_t *cams, const mvt_tri_obs_t *obs, int n, const mvt_real x[3],
                             mvt_real cov[9])
{
    mvt_real info[9] = {0};
    for (int k = 0; k < n; k++) {
        const mvt_camera_t *cam = &cams[obs[k].cam];
        mvt_real xc[3];
        mvt_cam_to_camera(cam, x, xc);
        if (!(xc[2] > MVT_R(1e-2))) {
            return MVT_ERR_BEHIND;
        }
        const mvt_real iz = MVT_R(1.0) / xc[2];
        for (int r = 0; r < 2; r++) {
            const mvt_real f = r == 0 ? cam->fx : cam->fy;
            const mvt_real pr = xc[r] * iz;
            mvt_real j[3];
            for (int c = 0; c < 3; c++) {
                j[c] = f * iz * (cam->R[r * 3 + c] - pr * cam->R[6 + c]);
            }
            for (int a = 0; a < 3; a++) {
                for (int b = 0; b < 3; b++) {
                    info[a * 3 + b] += j[a] * j[b] / obs[k].var_px2;
                }
            }
        }
    }
    if (mvt_la_inv3(info, cov) != MVT_OK) {
        return MVT_ERR_DEGENERATE;
    }
    return MVT_OK;
}

static mvt_real max_error(const mvt_camera_t *cams, const mvt_tri_obs_t *obs, int n, const mvt_real x[3])
{
    mvt_real e = MVT_R(0.0);
    for (int k = 0; k < n; k++) {
        const mvt_real ek = mvt_tri_reproj_px(cams, &obs[k], x);
        e = ek > e ? ek : e;
    }
    return e;
}

mvt_err_t mvt_tri_robust(const mvt_camera_t *cams, const mvt_tri_obs_t *obs, int n, mvt_real thresh_px, mvt_real x[3],
                         uint32_t *inliers_out, int *n_inliers_out)
{
    MVT_ASSERT(n <= MVT_MAX_CAMERAS);
    if (n < 2) {
        return MVT_ERR_DEGENERATE;
    }
    mvt_real xa[3];
    if (mvt_tri_linear(cams, obs, n, xa) == MVT_OK && mvt_tri_refine(cams, obs, n, 3, xa) == MVT_OK &&
        max_error(cams, obs, n, xa) <= thresh_px) {
        memcpy(x, xa, sizeof(xa));
        if (inliers_out != NULL) {
            *inliers_out = (n >= 32) ? 0xffffffffu : ((1u << n) - 1u);
        }
        if (n_inliers_out != NULL) {
            *n_inliers_out = n;
        }
        return MVT_OK;
    }
    /* Hypotheses from every pair of views; keep the largest consensus. */
    int best_count = 0;
    mvt_real best_err = MVT_TRI_HUGE;
    uint32_t best_mask = 0;
    for (int a = 0; a < n; a++) {
        for (int b = a + 1; b < n; b++) {
            const mvt_tri_obs_t pair[2] = {obs[a], obs[b]};
            mvt_real xp[3];
            if (mvt_tri_linear(cams, pair, 2, xp) != MVT_OK) {
                continue;
            }
            uint32_t mask = 0;
            int count = 0;
            mvt_real sum = MVT_R(0.0);
            for (int k = 0; k < n; k++) {
                const mvt_real e = mvt_tri_reproj_px(cams, &obs[k], xp);
                if (e <= thresh_px) {
                    mask |= 1u << k;
                    count++;
                    sum += e;
                }
            }
            if (count >= 2 && (count > best_count || (count == best_count && sum < best_err))) {
                best_count = count;
                best_err = sum;
                best_mask = mask;
            }
        }
    }
    if (best_count < 2) {
        return MVT_ERR_DEGENERATE;
    }
    mvt_tri_obs_t in[MVT_MAX_CAMERAS];
    int m = 0;
    for (int k = 0; k < n; k++) {
        if (best_mask & (1u << k)) {
            in[m++] = obs[k];
        }
    }
    mvt_err_t err = mvt_tri_linear(cams, in, m, xa);
    if (err == MVT_OK) {
        err = mvt_tri_refine(cams, in, m, 3, xa);
    }
    if (err != MVT_OK) {
        return err;
    }
    memcpy(x, xa, sizeof(xa));
    if (inliers_out != NULL) {
        *inliers_out = best_mask;
    }
    if (n_inliers_out != NULL) {
        *n_inliers_out = m;
    }
    return MVT_OK;
}
