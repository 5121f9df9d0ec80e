#include "mvt_linalg.h"

#include <math.h>

const char *mvt_err_str(mvt_err_t err)
{
    switch (err) {
    case MVT_OK: return "ok";
    case MVT_ERR_INVALID: return "invalid argument";
    case MVT_ERR_NUMERIC: return "not positive definite";
    case MVT_ERR_BEHIND: return "behind camera";
    case MVT_ERR_FULL: return "capacity full";
    case MVT_ERR_NONFINITE: return "non-finite value";
    case MVT_ERR_GATED: return "outside gate";
    case MVT_ERR_DEGENERATE: return "degenerate geometry";
    }
    return "unknown error";
}

int mvt_la_all_finite(const mvt_real *x, int n)
{
    /* without an early exit, so that the compiler can test several at once (the common case is
     * that every one is finite, and n is small) */
    int ok = 1;
    for (int i = 0; i < n; i++) {
        ok &= isfinite(x[i]) != 0;
    }
    return ok;
}

mvt_err_t mvt_la_cholesky(int n, mvt_real *a)
{
    MVT_ASSERT(n > 0 && n <= MVT_LA_MAX_N);
    for (int j = 0; j < n; j++) {
        mvt_real d = a[j * n + j];
        for (int k = 0; k < j; k++) {
            d -= a[j * n + k] * a[j * n + k];
        }
        if (!(d > MVT_R(0.0)) || !isfinite(d)) {
            return MVT_ERR_NUMERIC;
        }
        const mvt_real ljj = MVT_SQRT(d);
        a[j * n + j] = ljj;
        for (int i = j + 1; i < n; i++) {
            mvt_real s = a[i * n + j];
            for (int k = 0; k < j; k++) {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / ljj;
        }
    }
    return MVT_OK;
}

void mvt_la_chol_solve(int n, const mvt_real *l, mvt_real *b)
{
    MVT_ASSERT(n > 0 && n <= MVT_LA_MAX_N);
    for (int i = 0; i < n; i++) { /* L y = b */
        mvt_real s = b[i];
        for (int k = 0; k < i; k++) {
            s -= l[i * n + k] * b[k];
        }
        b[i] = s / l[i * n + i];
    }
    for (int i = n - 1; i >= 0; i--) { /* L^T x = y */
        mvt_real s = b[i];
        for (int k = i + 1; k < n; k++) {
            s -= l[k * n + i] * b[k];
        }
        b[i] = s / l[i * n + i];
    }
}

mvt_err_t mvt_la_inv2_sym(const mvt_real s[3], mvt_real inv[3])
{
    const mvt_real det = s[0] * s[2] - s[1] * s[1];
    if (!(s[0] > MVT_R(0.0)) || !(det > MVT_R(0.0)) || !isfinite(det)) {
        return MVT_ERR_NUMERIC;
    }
    const mvt_real id = MVT_R(1.0) / det;
    inv[0] = s[2] * id;
    inv[1] = -s[1] * id;
    inv[2] = s[0] * id;
    return MVT_OK;
}

mvt_err_t mvt_la_inv3(const mvt_real a[9], mvt_real inv[9])
{
    const mvt_real c00 = a[4] * a[8] - a[5] * a[7];
    const mvt_real c01 = a[5] * a[6] - a[3] * a[8];
    const mvt_real c02 = a[3] * a[7] - a[4] * a[6];
    const mvt_real det = a[0] * c00 + a[1] * c01 + a[2] * c02;
    /* Hadamard: |det| <= product of the row norms; relative to it, det measures conditioning */
    mvt_real h = MVT_R(1.0);
    for (int r = 0; r < 3; r++) {
        h *= MVT_SQRT(a[r * 3] * a[r * 3] + a[r * 3 + 1] * a[r * 3 + 1] + a[r * 3 + 2] * a[r * 3 + 2]);
    }
    if (!isfinite(det) || !(h > MVT_R(0.0)) || MVT_FABS(det) <= MVT_R(1e2) * MVT_EPS * h) {
        return MVT_ERR_NUMERIC;
    }
    const mvt_real id = MVT_R(1.0) / det;
    inv[0] = c00 * id;
    inv[1] = (a[2] * a[7] - a[1] * a[8]) * id;
    inv[2] = (a[1] * a[5] - a[2] * a[4]) * id;
    inv[3] = c01 * id;
    inv[4] = (a[0] * a[8] - a[2] * a[6]) * id;
    inv[5] = (a[2] * a[3] - a[0] * a[5]) * id;
    inv[6] = c02 * id;
    inv[7] = (a[1] * a[6] - a[0] * a[7]) * id;
    inv[8] = (a[0] * a[4] - a[1] * a[3]) * id;
    return MVT_OK;
}

void mvt_la_rodrigues(const mvt_real rvec[3], mvt_real r[9])
{
    const mvt_real th2 = rvec[0] * rvec[0] + rvec[1] * rvec[1] + rvec[2] * rvec[2];
    const mvt_real th = MVT_SQRT(th2);
    mvt_real c, s, c1; /* cos, sin/th, (1-cos)/th^2 */
    if (th < MVT_R(1e-4)) { /* Taylor series keeps full precision near zero */
        c = MVT_R(1.0) - th2 * MVT_R(0.5);
        s = MVT_R(1.0) - th2 / MVT_R(6.0);
        c1 = MVT_R(0.5) - th2 / MVT_R(24.0);
    } else {
        c = MVT_COS(th);
        s = MVT_SIN(th) / th;
        c1 = (MVT_R(1.0) - c) / th2;
    }
    const mvt_real x = rvec[0], y = rvec[1], z = rvec[2];
    r[0] = c + c1 * x * x;
    r[1] = c1 * x * y - s * z;
    r[2] = c1 * x * z + s * y;
    r[3] = c1 * x * y + s * z;
    r[4] = c + c1 * y * y;
    r[5] = c1 * y * z - s * x;
    r[6] = c1 * x * z - s * y;
    r[7] = c1 * y * z + s * x;
    r[8] = c + c1 * z * z;
}
