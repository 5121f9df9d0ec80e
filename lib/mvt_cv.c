#include "mvt_cv.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "mvt_linalg.h"

void mvt_cv_init(mvt_cv_state_t *s, const mvt_real pos[3], const mvt_real pos_cov[9], mvt_real vel_var,
                 int64_t utime_us)
{
    MVT_ASSERT(s != NULL);
    memset(s, 0, sizeof(*s));
    for (int i = 0; i < 3; i++) {
        s->x[i] = pos[i];
        for (int j = 0; j < 3; j++) {
            s->P[i * 6 + j] = pos_cov[i * 3 + j];
        }
        s->P[(i + 3) * 6 + (i + 3)] = vel_var;
    }
    s->utime_us = utime_us;
}

mvt_err_t mvt_cv_predict(mvt_cv_state_t *s, mvt_real dt, const mvt_real q[3])
{
    if (!(dt >= MVT_R(0.0)) || !isfinite(dt)) {
        return MVT_ERR_INVALID;
    }
    mvt_real *P = s->P;
    for (int i = 0; i < 3; i++) {
        s->x[i] += dt * s->x[i + 3];
    }
    /* P' = F P F^T with F = [I dt I; 0 I], by 3x3 blocks A = Ppp, B = Ppv, C = Pvv:
     * A' = A + dt (B + B^T) + dt^2 C, B' = B + dt C, C' = C. */
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            const mvt_real c = P[(i + 3) * 6 + (j + 3)];
            P[i * 6 + j] += dt * (P[i * 6 + (j + 3)] + P[(i + 3) * 6 + j]) + dt * dt * c;
        }
    }
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            P[i * 6 + (j + 3)] += dt * P[(i + 3) * 6 + (j + 3)];
            P[(j + 3) * 6 + i] = P[i * 6 + (j + 3)];
        }
    }
    const mvt_real dt2 = dt * dt;
    for (int i = 0; i < 3; i++) {
        P[i * 6 + i] += q[i] * dt2 * dt / MVT_R(3.0);
        P[i * 6 + (i + 3)] += q[i] * dt2 * MVT_R(0.5);
        P[(i + 3) * 6 + i] = P[i * 6 + (i + 3)];
        P[(i + 3) * 6 + (i + 3)] += q[i] * dt;
    }
    return MVT_OK;
}

mvt_err_t mvt_cv_predict_to(mvt_cv_state_t *s, int64_t utime_us, const mvt_real q[3])
{
    if (utime_us <= s->utime_us) {
        return MVT_OK;
    }
    const mvt_err_t err = mvt_cv_predict(s, mvt_us_to_s(utime_us - s->utime_us), q);
    if (err == MVT_OK) {
        s->utime_us = utime_us;
    }
    return err;
}

/* m = 2 (a camera's pixel rows, the hot path) written out: the same operations in the same order as
 * the general loop below, so the result is bit for bit the same, unrolled. */
static void joseph_hp2(mvt_real *P, const mvt_real *hpP, const mvt_real *S, const mvt_real *k)
{
    mvt_real ks0[6], ks1[6];
    for (int i = 0; i < 6; i++) {
        mvt_real a0 = -hpP[i];
        a0 += k[i * 2 + 0] * S[0];
        a0 += k[i * 2 + 1] * S[2];
        mvt_real a1 = -hpP[6 + i];
        a1 += k[i * 2 + 0] * S[1];
        a1 += k[i * 2 + 1] * S[3];
        ks0[i] = a0;
        ks1[i] = a1;
    }
    for (int i = 0; i < 6; i++) {
        for (int j = i; j < 6; j++) {
            mvt_real v = P[i * 6 + j];
            v += ks0[i] * k[j * 2 + 0] - k[i * 2 + 0] * hpP[j];
            v += ks1[i] * k[j * 2 + 1] - k[i * 2 + 1] * hpP[6 + j];
            P[i * 6 + j] = v;
            P[j * 6 + i] = v;
        }
    }
}

void mvt_cv_joseph_hp(mvt_cv_state_t *s, int m, const mvt_real *hpP, const mvt_real *S, const mvt_real *k)
{
    MVT_ASSERT(m >= 1 && m <= 3);
    mvt_real *P = s->P;
    if (m == 2) {
        joseph_hp2(P, hpP, S, k);
        return;
    }
    /* Joseph form (I - K H) P (I - K H)^T + K R K^T, expanded as
     *   P - K (H P) - (H P)^T K^T + K S K^T,   S = H P H^T + R,
     * which is the same polynomial in K: valid for any gain and, like the product form, only
     * second-order sensitive to errors in K. Upper triangle computed and mirrored, so P stays
     * exactly symmetric. ~130 flops for m = 2. */
    mvt_real ks[6][3]; /* K S - (H P)^T */
    for (int i = 0; i < 6; i++) {
        for (int b = 0; b < m; b++) {
            mvt_real acc = -hpP[b * 6 + i];
            for (int a = 0; a < m; a++) {
                acc += k[i * m + a] * S[a * m + b];
            }
            ks[i][b] = acc;
        }
    }
    for (int i = 0; i < 6; i++) {
        for (int j = i; j < 6; j++) {
            mvt_real v = P[i * 6 + j];
            for (int b = 0; b < m; b++) {
                v += ks[i][b] * k[j * m + b] - k[i * m + b] * hpP[b * 6 + j];
            }
            P[i * 6 + j] = v;
            P[j * 6 + i] = v;
        }
    }
}

void mvt_cv_joseph(mvt_cv_state_t *s, int m, const mvt_real *hp, const mvt_real *k, const mvt_real *r)
{
    MVT_ASSERT(m >= 1 && m <= 3);
    const mvt_real *P = s->P;
    mvt_real hpP[3 * 6]; /* H P (m x 6) */
    for (int a = 0; a < m; a++) {
        for (int j = 0; j < 6; j++) {
            hpP[a * 6 + j] = hp[a * 3 + 0] * P[0 * 6 + j] + hp[a * 3 + 1] * P[1 * 6 + j] + hp[a * 3 + 2] * P[2 * 6 + j];
        }
    }
    mvt_real S[9];
    for (int a = 0; a < m; a++) {
        for (int b = 0; b < m; b++) {
            S[a * m + b] = hpP[a * 6 + 0] * hp[b * 3 + 0] + hpP[a * 6 + 1] * hp[b * 3 + 1] + hpP[a * 6 + 2] * hp[b * 3 + 2] +
                           r[a * m + b];
        }
    }
    mvt_cv_joseph_hp(s, m, hpP, S, k);
}

mvt_err_t mvt_cv_update_point(mvt_cv_state_t *s, const mvt_real z[3], const mvt_real R[9], mvt_real gate_chi2,
                              mvt_real *d2_out)
{
    if (!mvt_la_all_finite(z, 3) || !mvt_la_all_finite(R, 9)) {
        return MVT_ERR_NONFINITE;
    }
    mvt_real S[9], y[3], w[3];
    for (int i = 0; i < 3; i++) {
        y[i] = z[i] - s->x[i];
        for (int j = 0; j < 3; j++) {
            S[i * 3 + j] = s->P[i * 6 + j] + R[i * 3 + j];
        }
    }
    if (mvt_la_cholesky(3, S) != MVT_OK) {
        return MVT_ERR_NUMERIC;
    }
    memcpy(w, y, sizeof(w));
    mvt_la_chol_solve(3, S, w); /* w = S^-1 y */
    const mvt_real d2 = y[0] * w[0] + y[1] * w[1] + y[2] * w[2];
    if (d2_out != NULL) {
        *d2_out = d2;
    }
    if (gate_chi2 > MVT_R(0.0) && d2 > gate_chi2) {
        return MVT_ERR_GATED;
    }
    /* K = P[:, 0:3] S^-1 : solve S k_i = P[i, 0:3]^T for each state row i. */
    mvt_real k[18];
    for (int i = 0; i < 6; i++) {
        mvt_real row[3] = {s->P[i * 6 + 0], s->P[i * 6 + 1], s->P[i * 6 + 2]};
        mvt_la_chol_solve(3, S, row);
        for (int a = 0; a < 3; a++) {
            k[i * 3 + a] = row[a];
        }
    }
    for (int i = 0; i < 6; i++) {
        s->x[i] += k[i * 3 + 0] * y[0] + k[i * 3 + 1] * y[1] + k[i * 3 + 2] * y[2];
    }
    static const mvt_real hp[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    mvt_cv_joseph(s, 3, hp, k, R);
    return MVT_OK;
}

mvt_err_t mvt_cv_repair(mvt_cv_state_t *s, mvt_real var_floor)
{
    mvt_real *P = s->P;
    if (!mvt_la_all_finite(s->x, 6) || !mvt_la_all_finite(P, 36)) {
        return MVT_ERR_NUMERIC;
    }
    for (int i = 0; i < 6; i++) {
        for (int j = i + 1; j < 6; j++) {
            const mvt_real m = MVT_R(0.5) * (P[i * 6 + j] + P[j * 6 + i]);
            P[i * 6 + j] = m;
            P[j * 6 + i] = m;
        }
        if (P[i * 6 + i] < var_floor) {
            P[i * 6 + i] = var_floor;
        }
    }
    mvt_real a[9];
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            a[i * 3 + j] = P[i * 6 + j];
        }
    }
    return mvt_la_cholesky(3, a);
}

/* Mass, mean and variance of the standard normal truncated to [a, b] (a < b). The mass comes from
 * erfc on the side of the tails, so a band far out in one tail keeps its relative precision; a
 * band narrow against the unit prior falls back to the uniform limit (mean at the density-weighted
 * centre, variance width^2 / 12), where the closed form cancels catastrophically. */
static void truncated_std_normal(mvt_real a, mvt_real b, mvt_real *mass, mvt_real *mean, mvt_real *var)
{
    const mvt_real r2 = MVT_R(0.70710678118654752);
    const mvt_real inv_sqrt_2pi = MVT_R(0.39894228040143268);
    mvt_real z;
    if (a >= MVT_R(0.0)) {
        z = MVT_R(0.5) * (MVT_ERFC(a * r2) - MVT_ERFC(b * r2));
    } else if (b <= MVT_R(0.0)) {
        z = MVT_R(0.5) * (MVT_ERFC(-b * r2) - MVT_ERFC(-a * r2));
    } else {
        z = MVT_R(1.0) - MVT_R(0.5) * (MVT_ERFC(b * r2) + MVT_ERFC(-a * r2));
    }
    *mass = z;
    const mvt_real w = b - a;
    if (w < MVT_R(0.05)) {
        const mvt_real c = MVT_R(0.5) * (a + b);
        *var = w * w / MVT_R(12.0);
        *mean = c - c * *var; /* the density's slope tilts the uniform: d log phi / dx = -x */
        return;
    }
    const mvt_real pa = inv_sqrt_2pi * MVT_EXP(MVT_R(-0.5) * a * a);
    const mvt_real pb = inv_sqrt_2pi * MVT_EXP(MVT_R(-0.5) * b * b);
    const mvt_real m = (pa - pb) / z;
    mvt_real v = MVT_R(1.0) + (a * pa - b * pb) / z - m * m;
    if (!(v > MVT_R(1e-6))) { /* rounding: never negative, never a spike */
        const mvt_real u = w * w / MVT_R(12.0);
        v = u < MVT_R(1.0) ? u : MVT_R(1.0);
    }
    *mean = m;
    *var = v < MVT_R(1.0) ? v : MVT_R(1.0);
}

mvt_err_t mvt_cv_truncate(mvt_cv_state_t *s, const mvt_real H[3], mvt_real value, mvt_real lo, mvt_real hi,
                          mvt_real *mass)
{
    return mvt_cv_truncate_ex(s, H, value, MVT_R(0.0), lo, hi, mass);
}

static mvt_err_t truncate(mvt_cv_state_t *s, const mvt_real H[3], mvt_real value, mvt_real extra_var, mvt_real lo,
                          mvt_real hi, int keep_height, mvt_real *mass);

mvt_err_t mvt_cv_truncate_ex(mvt_cv_state_t *s, const mvt_real H[3], mvt_real value, mvt_real extra_var, mvt_real lo,
                             mvt_real hi, mvt_real *mass)
{
    return truncate(s, H, value, extra_var, lo, hi, 0, mass);
}

mvt_err_t mvt_cv_truncate_ground(mvt_cv_state_t *s, const mvt_real H[3], mvt_real value, mvt_real extra_var,
                                 mvt_real lo, mvt_real hi, mvt_real *mass)
{
    return truncate(s, H, value, extra_var, lo, hi, 1, mass);
}

static mvt_err_t truncate(mvt_cv_state_t *s, const mvt_real H[3], mvt_real value, mvt_real extra_var, mvt_real lo,
                          mvt_real hi, int keep_height, mvt_real *mass)
{
    if (mass != NULL) {
        *mass = MVT_R(0.0);
    }
    if (!isfinite(lo) || !isfinite(hi) || !(lo < hi) || !isfinite(value) || !(extra_var >= MVT_R(0.0)) ||
        !isfinite(extra_var)) {
        return MVT_ERR_INVALID;
    }
    const mvt_real *P = s->P;
    mvt_real hpP[6], k[6];
    for (int j = 0; j < 6; j++) {
        hpP[j] = H[0] * P[0 * 6 + j] + H[1] * P[1 * 6 + j] + H[2] * P[2 * 6 + j];
    }
    const mvt_real s2 = hpP[0] * H[0] + hpP[1] * H[1] + hpP[2] * H[2] + extra_var;
    if (!(s2 > MVT_R(0.0)) || !isfinite(s2)) {
        return MVT_ERR_NUMERIC;
    }
    const mvt_real sd = MVT_SQRT(s2);
    mvt_real z, m, v;
    truncated_std_normal((lo - value) / sd, (hi - value) / sd, &z, &m, &v);
    if (mass != NULL) {
        *mass = z;
    }
    if (!(z >= MVT_R(1e-6))) {
        return MVT_ERR_NUMERIC;
    }
    const mvt_real gain = MVT_R(1.0) - v; /* K = (s2 - v') / s2 of the equivalent measurement */
    if (!(gain > MVT_R(1e-4))) {
        return MVT_OK; /* the band is wide open around the prior: nothing learnt */
    }
    /* equivalent measurement: R = s2 v' / (s2 - v'), S = s2 + R = s2 / gain, and the innovation y
     * with value + K y = value + sd m, i.e. y = sd m / gain */
    const mvt_real S = s2 / gain;
    const mvt_real y = sd * m / gain;
    for (int i = 0; i < 6; i++) {
        k[i] = keep_height && (i == 2 || i == 5) ? MVT_R(0.0) : hpP[i] / S;
        s->x[i] += k[i] * y;
    }
    mvt_cv_joseph_hp(s, 1, hpP, &S, k); /* Joseph form: right for any gain, the zeroed rows too */
    return MVT_OK;
}
