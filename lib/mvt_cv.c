#include "mvt_cv.h"

#include <math.h>
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
    const mvt_err_t err = mvt_cv_predict(s, (mvt_real)((double)(utime_us - s->utime_us) * 1e-6), q);
    if (err == MVT_OK) {
        s->utime_us = utime_us;
    }
    return err;
}

void mvt_cv_joseph(mvt_cv_state_t *s, int m, const mvt_real *hp, const mvt_real *k, const mvt_real *r)
{
    MVT_ASSERT(m >= 1 && m <= 3);
    mvt_real *P = s->P;
    /* KH is 6x6 with only its first 3 columns non-zero: kh[i][c] = sum_a K[i][a] Hp[a][c]. */
    mvt_real kh[6][3];
    for (int i = 0; i < 6; i++) {
        for (int c = 0; c < 3; c++) {
            mvt_real acc = MVT_R(0.0);
            for (int a = 0; a < m; a++) {
                acc += k[i * m + a] * hp[a * 3 + c];
            }
            kh[i][c] = acc;
        }
    }
    /* B = (I - KH) P */
    mvt_real b[36];
    for (int i = 0; i < 6; i++) {
        for (int j = 0; j < 6; j++) {
            b[i * 6 + j] = P[i * 6 + j] - kh[i][0] * P[0 * 6 + j] - kh[i][1] * P[1 * 6 + j] -
                           kh[i][2] * P[2 * 6 + j];
        }
    }
    /* P = B (I - KH)^T + K R K^T, upper triangle then mirrored (exactly symmetric). */
    mvt_real kr[6 * 3];
    for (int i = 0; i < 6; i++) {
        for (int a = 0; a < m; a++) {
            mvt_real acc = MVT_R(0.0);
            for (int c = 0; c < m; c++) {
                acc += k[i * m + c] * r[c * m + a];
            }
            kr[i * 3 + a] = acc;
        }
    }
    for (int i = 0; i < 6; i++) {
        for (int j = i; j < 6; j++) {
            mvt_real v = b[i * 6 + j] - b[i * 6 + 0] * kh[j][0] - b[i * 6 + 1] * kh[j][1] -
                         b[i * 6 + 2] * kh[j][2];
            for (int a = 0; a < m; a++) {
                v += kr[i * 3 + a] * k[j * m + a];
            }
            P[i * 6 + j] = v;
            P[j * 6 + i] = v;
        }
    }
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
