#include "mvt_imm.h"

#include <math.h>
#include <string.h>

#include "mvt_linalg.h"

#define ALL3(k) {(k), (k), (k)}
#define WALKS {MVT_MOTION_CV, MVT_MOTION_CV, MVT_MOTION_STILL}
#define RISES {MVT_MOTION_STILL, MVT_MOTION_STILL, MVT_MOTION_CV}

void mvt_imm_config_default(mvt_imm_config_t *c)
{
    memset(c, 0, sizeof(*c));
    enum { BANK = 4 };
    const mvt_imm_model_t bank[BANK] = {
        {ALL3(MVT_MOTION_STILL), {MVT_R(2.5e-5), MVT_R(2.5e-5), MVT_R(2.5e-5)}, MVT_R(0.2)},
        {WALKS, {MVT_R(0.3), MVT_R(0.3), MVT_R(4e-4)}, MVT_R(0.3)},
        {ALL3(MVT_MOTION_CV), {MVT_R(3.0), MVT_R(3.0), MVT_R(0.1)}, MVT_R(1.5)},
        {RISES, {MVT_R(2.5e-5), MVT_R(2.5e-5), MVT_R(1.0)}, MVT_R(1.3)},
    };
    c->n = MVT_IMM_MODELS < BANK ? MVT_IMM_MODELS : BANK;
    c->p_outlier = MVT_R(0.1);
    c->outlier_radius_px = MVT_R(150.0);
    c->outlier_persist_s = MVT_R(0.5);
    c->outlier_drift_px2_s = MVT_R(400.0);
    for (int j = 0; j < c->n; j++) {
        c->model[j] = bank[j];
    }
}

void mvt_imm_config_single(mvt_imm_config_t *c, const mvt_real q[3])
{
    memset(c, 0, sizeof(*c));
    c->n = 1;
    c->outlier_radius_px = MVT_R(150.0); /* p_outlier 0: the single filter is the plain PKF */
    for (int i = 0; i < 3; i++) {
        c->model[0].kind[i] = MVT_MOTION_CV;
        c->model[0].q[i] = q[i];
    }
}

int mvt_imm_model_is(const mvt_imm_model_t *m, mvt_motion_kind_t k)
{
    return m->kind[0] == k && m->kind[1] == k && m->kind[2] == k;
}

mvt_err_t mvt_imm_config_check(const mvt_imm_config_t *c)
{
    if (c->n < 1 || c->n > MVT_IMM_MODELS) {
        return MVT_ERR_INVALID;
    }
    for (int j = 0; j < c->n; j++) {
        const mvt_imm_model_t *m = &c->model[j];
        for (int i = 0; i < 3; i++) {
            if ((m->kind[i] != MVT_MOTION_CV && m->kind[i] != MVT_MOTION_STILL) || !(m->q[i] > MVT_R(0.0)) ||
                !isfinite(m->q[i])) {
                return MVT_ERR_INVALID;
            }
        }
        if (!(m->leave_hz >= MVT_R(0.0)) || !isfinite(m->leave_hz)) {
            return MVT_ERR_INVALID;
        }
    }
    if (!(c->p_outlier >= MVT_R(0.0) && c->p_outlier < MVT_R(1.0)) ||
        !(c->outlier_radius_px > MVT_R(0.0)) || !isfinite(c->outlier_radius_px) ||
        !(c->outlier_persist_s >= MVT_R(0.0)) || !isfinite(c->outlier_persist_s) ||
        !(c->outlier_drift_px2_s >= MVT_R(0.0)) || !isfinite(c->outlier_drift_px2_s)) {
        return MVT_ERR_INVALID;
    }
    return MVT_OK;
}

void mvt_imm_stationary(const mvt_imm_config_t *c, mvt_real mu[MVT_IMM_MODELS])
{
    /* Leaving j at rate r_j for any other model alike: the balance pi_j r_j = sum_{i != j}
     * pi_i r_i / (n - 1) holds for pi_j r_j constant, so pi_j is proportional to 1 / r_j. */
    int any_zero = 0;
    for (int j = 0; j < c->n; j++) {
        any_zero |= !(c->model[j].leave_hz > MVT_R(0.0));
    }
    mvt_real sum = MVT_R(0.0);
    for (int j = 0; j < c->n; j++) {
        mu[j] = any_zero ? MVT_R(1.0) : MVT_R(1.0) / c->model[j].leave_hz;
        sum += mu[j];
    }
    for (int j = 0; j < c->n; j++) {
        mu[j] /= sum;
    }
}

void mvt_imm_init(mvt_imm_t *imm, const mvt_imm_config_t *c, const mvt_cv_state_t *s)
{
    memset(imm, 0, sizeof(*imm));
    for (int j = 0; j < c->n; j++) {
        imm->m[j] = *s;
    }
    mvt_imm_stationary(c, imm->mu);
}

/* One model's prediction over dt. Its CV axes: mvt_cv_predict. Its STILL axes, a head that holds
 * along them: x_p' = x_p + w_p, x_v' = w_v, w_p ~ N(0, q dt), w_v ~ N(0, q / 1 s). The still axes'
 * velocity rows are cleared first, so that the CV transform leaves them alone. */
static void predict_model(mvt_cv_state_t *s, mvt_real dt, const mvt_imm_model_t *m)
{
    if (mvt_imm_model_is(m, MVT_MOTION_CV)) {
        (void)mvt_cv_predict(s, dt, m->q);
        return;
    }
    mvt_real *P = s->P;
    mvt_real qcv[3];
    int any_cv = 0;
    for (int i = 0; i < 3; i++) {
        qcv[i] = MVT_R(0.0);
        if (m->kind[i] == MVT_MOTION_CV) {
            qcv[i] = m->q[i];
            any_cv = 1;
            continue;
        }
        s->x[i + 3] = MVT_R(0.0);
        for (int j = 0; j < 6; j++) {
            P[(i + 3) * 6 + j] = MVT_R(0.0);
            P[j * 6 + (i + 3)] = MVT_R(0.0);
        }
    }
    if (any_cv) {
        (void)mvt_cv_predict(s, dt, qcv);
    }
    for (int i = 0; i < 3; i++) {
        if (m->kind[i] == MVT_MOTION_STILL) {
            P[i * 6 + i] += m->q[i] * dt;
            P[(i + 3) * 6 + (i + 3)] = m->q[i];
        }
    }
}

/* The position and its covariance block (six numbers) of the combination, written out */
static void combine_position(const mvt_imm_t *imm, int n, mvt_cv_state_t *s)
{
    mvt_real x0 = MVT_R(0.0), x1 = MVT_R(0.0), x2 = MVT_R(0.0);
    for (int j = 0; j < n; j++) {
        const mvt_real mu = imm->mu[j];
        const mvt_real *xj = imm->m[j].x;
        x0 += mu * xj[0];
        x1 += mu * xj[1];
        x2 += mu * xj[2];
    }
    mvt_real p00 = MVT_R(0.0), p01 = MVT_R(0.0), p02 = MVT_R(0.0), p11 = MVT_R(0.0), p12 = MVT_R(0.0),
             p22 = MVT_R(0.0);
    for (int j = 0; j < n; j++) {
        const mvt_real mu = imm->mu[j];
        const mvt_real *xj = imm->m[j].x, *Pj = imm->m[j].P;
        const mvt_real d0 = xj[0] - x0, d1 = xj[1] - x1, d2 = xj[2] - x2;
        const mvt_real m0 = mu * d0, m1 = mu * d1, m2 = mu * d2;
        p00 += mu * Pj[0] + m0 * d0;
        p01 += mu * Pj[1] + m0 * d1;
        p02 += mu * Pj[2] + m0 * d2;
        p11 += mu * Pj[7] + m1 * d1;
        p12 += mu * Pj[8] + m1 * d2;
        p22 += mu * Pj[14] + m2 * d2;
    }
    s->x[0] = x0;
    s->x[1] = x1;
    s->x[2] = x2;
    mvt_real *P = s->P;
    P[0] = p00;
    P[1] = P[6] = p01;
    P[2] = P[12] = p02;
    P[7] = p11;
    P[8] = P[13] = p12;
    P[14] = p22;
}

/* The combination into s: in full (nb = 6), or only the position and its covariance block (nb = 3;
 * the velocity and the rest of s->P left as they were). */
static void combine(const mvt_imm_t *imm, const mvt_imm_config_t *c, mvt_cv_state_t *s, int nb)
{
    const int n = c->n;
    s->utime_us = imm->m[0].utime_us;
    if (n == 1) {
        memcpy(s->x, imm->m[0].x, sizeof(s->x));
        memcpy(s->P, imm->m[0].P, sizeof(s->P));
        return;
    }
    if (nb == 3) {
        combine_position(imm, n, s);
        return;
    }
    /* into locals first: s may not alias the bank, but the compiler cannot know */
    mvt_real x[6], P[36];
    for (int i = 0; i < 6; i++) {
        x[i] = MVT_R(0.0);
    }
    for (int i = 0; i < 36; i++) {
        P[i] = MVT_R(0.0);
    }
    for (int j = 0; j < n; j++) {
        const mvt_real mu = imm->mu[j];
        const mvt_real *xj = imm->m[j].x;
        for (int i = 0; i < 6; i++) {
            x[i] += mu * xj[i];
        }
    }
    for (int j = 0; j < n; j++) {
        const mvt_real mu = imm->mu[j];
        const mvt_real *xj = imm->m[j].x;
        const mvt_real *Pj = imm->m[j].P;
        mvt_real d[6], md[6];
        for (int i = 0; i < 6; i++) {
            d[i] = xj[i] - x[i];
            md[i] = mu * d[i];
        }
        for (int a = 0; a < 6; a++) {
            for (int b = a; b < 6; b++) {
                P[a * 6 + b] += mu * Pj[a * 6 + b] + md[a] * d[b];
            }
        }
    }
    for (int a = 0; a < 6; a++) {
        s->x[a] = x[a];
        for (int b = a; b < 6; b++) {
            s->P[a * 6 + b] = P[a * 6 + b];
            s->P[b * 6 + a] = P[a * 6 + b];
        }
    }
}

void mvt_imm_combine(const mvt_imm_t *imm, const mvt_imm_config_t *c, mvt_cv_state_t *s)
{
    combine(imm, c, s, 6);
}

/* The upper nb x nb block of a mixed covariance, sum_i w_i M_i - e e^T, mirrored. Inlined with nb
 * constant, and summed over the whole capacity (weight 0 past n), so that the compiler unrolls it. */
static inline void mix_block(mvt_real *P, int nb, const mvt_real *w, mvt_real (*M)[36], const mvt_real *e)
{
    for (int a = 0; a < nb; a++) {
        for (int b = a; b < nb; b++) {
            mvt_real acc = -e[a] * e[b];
            for (int i = 0; i < MVT_IMM_MODELS; i++) {
                acc += w[i] * M[i][a * 6 + b];
            }
            P[a * 6 + b] = acc;
            P[b * 6 + a] = acc;
        }
    }
}

static mvt_err_t predict_to(mvt_imm_t *imm, const mvt_imm_config_t *c, int64_t utime_us, mvt_cv_state_t *s, int nb)
{
    const int n = c->n;
    if (utime_us <= imm->m[0].utime_us) {
        return MVT_OK;
    }
    const mvt_real dt = mvt_us_to_s(utime_us - imm->m[0].utime_us);
    if (!(dt >= MVT_R(0.0)) || !isfinite(dt)) {
        return MVT_ERR_INVALID;
    }
    if (n > 1) {
        /* transition probabilities over dt: p[i][j] = P(model j at the end | model i at the start) */
        mvt_real p[MVT_IMM_MODELS][MVT_IMM_MODELS];
        for (int i = 0; i < n; i++) {
            const mvt_real stay = MVT_EXP(-c->model[i].leave_hz * dt);
            for (int j = 0; j < n; j++) {
                p[i][j] = i == j ? stay : (MVT_R(1.0) - stay) / (mvt_real)(n - 1);
            }
        }
        /* Mixing: model j starts from x0j = sum_i w_ij x_i, P0j = sum_i w_ij (P_i + (x_i - x0j)(...)^T).
         * Written about the combination xbar, with d_i = x_i - xbar and e_j = x0j - xbar (so
         * sum_i w_ij d_i = e_j): P0j = sum_i w_ij (P_i + d_i d_i^T) - e_j e_j^T. The bracket is
         * built once per model instead of once per pair, and the spreads stay small numbers (no
         * cancellation in float). The sums run over the whole capacity (weight 0 past n) so that the
         * compiler unrolls them. */
        enum { K = MVT_IMM_MODELS };
        mvt_real xbar[6] = {MVT_R(0.0), MVT_R(0.0), MVT_R(0.0), MVT_R(0.0), MVT_R(0.0), MVT_R(0.0)};
        for (int i = 0; i < n; i++) {
            for (int a = 0; a < 6; a++) {
                xbar[a] += imm->mu[i] * imm->m[i].x[a];
            }
        }
        mvt_real d[K][6];
        mvt_real M[K][36]; /* upper triangle */
        memset(d, 0, sizeof(d));
        memset(M, 0, sizeof(M));
        for (int i = 0; i < n; i++) {
            const mvt_real *xi = imm->m[i].x, *Pi = imm->m[i].P;
            for (int a = 0; a < 6; a++) {
                d[i][a] = xi[a] - xbar[a];
            }
            for (int a = 0; a < 6; a++) {
                for (int b = a; b < 6; b++) {
                    M[i][a * 6 + b] = Pi[a * 6 + b] + d[i][a] * d[i][b];
                }
            }
        }
        mvt_real cbar[K], w[K][K]; /* w[j][i]: mixing weight of model i into model j */
        for (int j = 0; j < n; j++) {
            mvt_real cj = MVT_R(0.0);
            for (int i = 0; i < n; i++) {
                cj += p[i][j] * imm->mu[i];
            }
            cbar[j] = cj;
            for (int i = 0; i < K; i++) {
                w[j][i] = i >= n ? MVT_R(0.0)
                          : cj > MVT_R(0.0) ? p[i][j] * imm->mu[i] / cj
                                            : (i == j ? MVT_R(1.0) : MVT_R(0.0));
            }
        }
        /* every model's old state is in d and M: the mixed ones are written in place */
        for (int j = 0; j < n; j++) {
            const mvt_real *wj = w[j];
            mvt_cv_state_t *mj = &imm->m[j];
            mvt_real e[6];
            for (int a = 0; a < 6; a++) {
                mvt_real acc = MVT_R(0.0);
                for (int i = 0; i < K; i++) {
                    acc += wj[i] * d[i][a];
                }
                e[a] = acc;
                mj->x[a] = xbar[a] + acc;
            }
            /* a standing model's prediction sets its velocity rows: only its position block is mixed */
            mix_block(mj->P, mvt_imm_model_is(&c->model[j], MVT_MOTION_STILL) ? 3 : 6, wj, M, e);
        }
        mvt_real sum = MVT_R(0.0);
        for (int j = 0; j < n; j++) {
            sum += cbar[j];
        }
        for (int j = 0; j < n; j++) {
            imm->mu[j] = cbar[j] / sum;
        }
    }
    for (int j = 0; j < n; j++) {
        mvt_cv_state_t *mj = &imm->m[j];
        predict_model(mj, dt, &c->model[j]);
        mj->utime_us = utime_us;
    }
    combine(imm, c, s, nb);
    return MVT_OK;
}

mvt_err_t mvt_imm_predict_to(mvt_imm_t *imm, const mvt_imm_config_t *c, int64_t utime_us, mvt_cv_state_t *s)
{
    return predict_to(imm, c, utime_us, s, 6);
}

mvt_err_t mvt_imm_predict_to_pos(mvt_imm_t *imm, const mvt_imm_config_t *c, int64_t utime_us, mvt_cv_state_t *s)
{
    return predict_to(imm, c, utime_us, s, 3);
}

/* Per model: the innovation, its covariance and inverse, and the gain rows. */
typedef struct imm_upd {
    mvt_real hpP[18]; /* H P_j, m x 6 (pixel update: its whitened rows L^-1 H P_j) */
    mvt_real S[9];    /* m x m (pixel update: 1 / d0, 1 / d1 of S = L D L^T) */
    mvt_real Si[9];   /* (not used by the pixel update) */
    mvt_real y[3];    /* (pixel update: whitened, L^-1 y) */
    mvt_real g;       /* Gaussian likelihood N(y; 0, S) */
    int nx;           /* state rows the measurement reaches: 3 for a standing model (P_pv = 0) */
} imm_upd_t;

/* The point update (m = 3, --mode kf's triangulated point): the general form. The pixel update
 * (m = 2) is MVT_IMM_PIXEL_UPDATE below. */
static int innovation(const mvt_cv_state_t *mj, const mvt_cv_state_t *s, int m, const mvt_real *H, const mvt_real *y,
                      const mvt_real *noise, int nx, imm_upd_t *u)
{
    const mvt_real *P = mj->P;
    const mvt_real dx[3] = {mj->x[0] - s->x[0], mj->x[1] - s->x[1], mj->x[2] - s->x[2]};
    u->nx = nx;
    for (int a = 0; a < m; a++) {
        const mvt_real *h = &H[a * 3];
        u->y[a] = y[a] - (h[0] * dx[0] + h[1] * dx[1] + h[2] * dx[2]);
        for (int b = 0; b < nx; b++) {
            u->hpP[a * 6 + b] = h[0] * P[0 * 6 + b] + h[1] * P[1 * 6 + b] + h[2] * P[2 * 6 + b];
        }
    }
    for (int a = 0; a < m; a++) {
        for (int b = a; b < m; b++) {
            const mvt_real *h = &H[b * 3];
            const mvt_real v = u->hpP[a * 6 + 0] * h[0] + u->hpP[a * 6 + 1] * h[1] + u->hpP[a * 6 + 2] * h[2] +
                               MVT_R(0.5) * (noise[a * m + b] + noise[b * m + a]);
            u->S[a * m + b] = v;
            u->S[b * m + a] = v;
        }
    }
    mvt_real l[9];
    memcpy(l, u->S, sizeof(l));
    if (mvt_la_cholesky(3, l) != MVT_OK) {
        return 0;
    }
    mvt_real det = MVT_R(1.0);
    for (int a = 0; a < 3; a++) {
        det *= l[a * 3 + a] * l[a * 3 + a];
    }
    for (int a = 0; a < 3; a++) { /* columns of S^-1 */
        mvt_real e[3] = {MVT_R(0.0), MVT_R(0.0), MVT_R(0.0)};
        e[a] = MVT_R(1.0);
        mvt_la_chol_solve(3, l, e);
        for (int b = 0; b < 3; b++) {
            u->Si[b * 3 + a] = e[b];
        }
    }
    mvt_real d2;
    d2 = MVT_R(0.0);
    for (int a = 0; a < m; a++) {
        for (int b = 0; b < m; b++) {
            d2 += u->y[a] * u->Si[a * m + b] * u->y[b];
        }
    }
    const mvt_real norm = MVT_R(15.749609945722419) * MVT_SQRT(det); /* (2 pi)^(3/2) sqrt(det S) */
    u->g = MVT_EXP(MVT_R(-0.5) * d2) / norm;
    return isfinite(d2) && isfinite(u->g) && d2 >= MVT_R(0.0);
}

/* x += w K y; P += w (Joseph increment) + w (1 - w) (K y)(K y)^T over the first nx rows: the
 * Kalman update for w = 1, and for 0 < w < 1 the update with a detection that is right with
 * probability w (the PDA filter's one-measurement form). */
static void apply(mvt_cv_state_t *mj, int m, const imm_upd_t *u, mvt_real w)
{
    const int nx = u->nx;
    mvt_real k[6][3], ks[6][3], d[6];
    for (int i = 0; i < nx; i++) {
        d[i] = MVT_R(0.0);
        for (int a = 0; a < m; a++) {
            mvt_real acc = MVT_R(0.0);
            for (int b = 0; b < m; b++) {
                acc += u->hpP[b * 6 + i] * u->Si[b * m + a];
            }
            k[i][a] = acc;
            d[i] += acc * u->y[a];
        }
        mj->x[i] += w * d[i];
        for (int b = 0; b < m; b++) {
            mvt_real acc = -u->hpP[b * 6 + i];
            for (int a = 0; a < m; a++) {
                acc += k[i][a] * u->S[a * m + b];
            }
            ks[i][b] = acc;
        }
    }
    const mvt_real spread = w * (MVT_R(1.0) - w);
    mvt_real *P = mj->P;
    for (int i = 0; i < nx; i++) {
        for (int j = i; j < nx; j++) {
            mvt_real inc = MVT_R(0.0);
            for (int b = 0; b < m; b++) {
                inc += ks[i][b] * k[j][b] - k[i][b] * u->hpP[b * 6 + j];
            }
            const mvt_real v = P[i * 6 + j] + w * inc + spread * d[i] * d[j];
            P[i * 6 + j] = v;
            P[j * 6 + i] = v;
        }
    }
}

/* The pixel update (m = 2), the IMM's hot path (every camera, every model), written out for a fixed
 * number of state rows so that the compiler unrolls it. With S = L D L^T (L unit lower triangular,
 * l = S01 / S00, D = diag(S00, det S / S00)) and v = L^-1 H P_j, z = L^-1 y (whitened rows):
 *   K y = v0 z0 / d0 + v1 z1 / d1,   K S K^T = v0 v0^T / d0 + v1 v1^T / d1,   y^T S^-1 y = z0^2 / d0 + z1^2 / d1.
 * The same update as innovation() and apply() (agreement in tests/test_oracle.cpp); the covariance's
 * change, robust term included, is a rank-two form in (v0, v1): 2 multiply-adds per element of the
 * triangle, where the expanded Joseph form of apply() takes 12 flops. */
#define MVT_IMM_PIXEL_UPDATE(NAME, NX)                                                                                \
    static int NAME##_innov(const mvt_cv_state_t *mj, const mvt_cv_state_t *s, const mvt_real *H, const mvt_real *y,  \
                            const mvt_real *noise, imm_upd_t *u)                                                      \
    {                                                                                                                 \
        const mvt_real *P = mj->P;                                                                                    \
        const mvt_real dx0 = mj->x[0] - s->x[0], dx1 = mj->x[1] - s->x[1], dx2 = mj->x[2] - s->x[2];                  \
        u->nx = NX;                                                                                                   \
        for (int a = 0; a < 2; a++) {                                                                                 \
            const mvt_real *h = &H[a * 3];                                                                            \
            u->y[a] = y[a] - (h[0] * dx0 + h[1] * dx1 + h[2] * dx2);                                                  \
            for (int b = 0; b < NX; b++) {                                                                            \
                u->hpP[a * 6 + b] = h[0] * P[b] + h[1] * P[6 + b] + h[2] * P[12 + b];                                 \
            }                                                                                                         \
        }                                                                                                             \
        const mvt_real s00 = u->hpP[0] * H[0] + u->hpP[1] * H[1] + u->hpP[2] * H[2] + noise[0];                       \
        const mvt_real s01 = u->hpP[0] * H[3] + u->hpP[1] * H[4] + u->hpP[2] * H[5] +                                 \
                             MVT_R(0.5) * (noise[1] + noise[2]);                                                      \
        const mvt_real s11 = u->hpP[6] * H[3] + u->hpP[7] * H[4] + u->hpP[8] * H[5] + noise[3];                       \
        if (!(s00 > MVT_R(0.0)) || !isfinite(s00)) {                                                                  \
            return 0;                                                                                                 \
        }                                                                                                             \
        const mvt_real i0 = MVT_R(1.0) / s00;                                                                        \
        const mvt_real l = s01 * i0;                                                                                 \
        const mvt_real d1 = s11 - l * s01;                                                                            \
        if (!(d1 > MVT_R(0.0)) || !isfinite(d1)) {                                                                    \
            return 0;                                                                                                 \
        }                                                                                                             \
        const mvt_real i1 = MVT_R(1.0) / d1;                                                                         \
        u->S[0] = i0;                                                                                                \
        u->S[1] = i1;                                                                                                \
        const mvt_real z1 = u->y[1] - l * u->y[0];                                                                    \
        u->y[1] = z1;                                                                                                 \
        for (int b = 0; b < NX; b++) {                                                                                \
            u->hpP[6 + b] -= l * u->hpP[b];                                                                           \
        }                                                                                                             \
        const mvt_real d2 = u->y[0] * u->y[0] * i0 + z1 * z1 * i1;                                                   \
        u->g = MVT_EXP(MVT_R(-0.5) * d2) * MVT_SQRT(i0 * i1) * MVT_R(0.15915494309189535); /* 1 / (2 pi) */          \
        return isfinite(d2) && d2 >= MVT_R(0.0);                                                                      \
    }                                                                                                                 \
    /* x += w K y; P += -w K S K^T + w (1 - w) (K y)(K y)^T */                                                        \
    static void NAME##_apply(mvt_cv_state_t *mj, const imm_upd_t *u, mvt_real w)                                     \
    {                                                                                                                \
        /* K y = c0 v0 + c1 v1, so the whole change of P is a quadratic form in (v0, v1):                            \
         * P -= [v0 v1] A [v0 v1]^T, A = w diag(i0, i1) - w (1 - w) c c^T (2 flops per element) */                   \
        mvt_real v0[NX], v1[NX]; /* copies: the stores into P below cannot be taken for writes to them */        \
        for (int i = 0; i < NX; i++) {                                                                               \
            v0[i] = u->hpP[i];                                                                                       \
            v1[i] = u->hpP[6 + i];                                                                                   \
        }                                                                                                            \
        const mvt_real i0 = u->S[0], i1 = u->S[1];                                                                   \
        const mvt_real c0 = u->y[0] * i0, c1 = u->y[1] * i1;                                                         \
        const mvt_real spread = w * (MVT_R(1.0) - w);                                                                \
        const mvt_real a00 = w * i0 - spread * c0 * c0, a01 = -spread * c0 * c1, a11 = w * i1 - spread * c1 * c1;    \
        mvt_real t0[NX], t1[NX];                                                                                     \
        for (int i = 0; i < NX; i++) {                                                                               \
            mj->x[i] += w * (v0[i] * c0 + v1[i] * c1);                                                               \
            t0[i] = a00 * v0[i] + a01 * v1[i];                                                                       \
            t1[i] = a01 * v0[i] + a11 * v1[i];                                                                       \
        }                                                                                                            \
        mvt_real *P = mj->P;                                                                                         \
        _Pragma("GCC unroll 6") for (int i = 0; i < NX; i++) {                                                       \
            _Pragma("GCC unroll 6") for (int j = i; j < NX; j++) {                                                   \
                const mvt_real v = P[i * 6 + j] - (v0[i] * t0[j] + v1[i] * t1[j]);                                   \
                P[i * 6 + j] = v;                                                                                    \
                P[j * 6 + i] = v;                                                                                    \
            }                                                                                                        \
        }                                                                                                            \
    }

MVT_IMM_PIXEL_UPDATE(px6, 6)
MVT_IMM_PIXEL_UPDATE(px3, 3)

/* The density of y under "the view's last displacement continues": N(y - view->y; 0, S_c) with
 * S_c = S + noise + drift dt I, S the combined estimate's innovation covariance H P H^T + noise (the
 * estimate's spread and this detection's noise), plus the last detection's noise and the
 * displacement's wander; times the prior probability of continuing. 0 when nothing is known or
 * persistence is off. */
static mvt_real continuing(const mvt_imm_config_t *c, const mvt_real *y, const mvt_real *noise, const mvt_real S[3],
                           const mvt_imm_view_t *view, const mvt_cv_state_t *s, mvt_real *prior)
{
    *prior = MVT_R(0.0);
    if (view == NULL || !(c->outlier_persist_s > MVT_R(0.0)) || !(view->p > MVT_R(0.0)) ||
        s->utime_us < view->utime_us) {
        return MVT_R(0.0);
    }
    const mvt_real dt = (mvt_real)(s->utime_us - view->utime_us) * MVT_R(1e-6);
    *prior = view->p * MVT_EXP(-dt / c->outlier_persist_s);
    const mvt_real drift = c->outlier_drift_px2_s * dt;
    const mvt_real s00 = S[0] + noise[0] + drift;
    const mvt_real s01 = S[1] + MVT_R(0.5) * (noise[1] + noise[2]);
    const mvt_real s11 = S[2] + noise[3] + drift;
    const mvt_real det = s00 * s11 - s01 * s01;
    if (!(det > MVT_R(0.0)) || !isfinite(det)) {
        *prior = MVT_R(0.0);
        return MVT_R(0.0);
    }
    const mvt_real e0 = y[0] - view->y[0], e1 = y[1] - view->y[1];
    const mvt_real d2 = (s11 * e0 * e0 - MVT_R(2.0) * s01 * e0 * e1 + s00 * e1 * e1) / det;
    return MVT_EXP(MVT_R(-0.5) * d2) / (MVT_R(6.283185307179586) * MVT_SQRT(det));
}

static mvt_err_t update(mvt_imm_t *imm, const mvt_imm_config_t *c, int m, const mvt_real *H, const mvt_real *y,
                        const mvt_real *noise, mvt_cv_state_t *s, int nb, const mvt_real *S_view,
                        mvt_imm_view_t *view, mvt_real own_lr)
{
    MVT_ASSERT(m == 2 || m == 3);
    const int n = c->n;
    imm_upd_t u[MVT_IMM_MODELS];
    /* first every model's innovation, so that a failure changes nothing */
    for (int j = 0; j < n; j++) {
        const int still = mvt_imm_model_is(&c->model[j], MVT_MOTION_STILL);
        int ok;
        if (m == 2) {
            ok = still ? px3_innov(&imm->m[j], s, H, y, noise, &u[j]) : px6_innov(&imm->m[j], s, H, y, noise, &u[j]);
        } else {
            ok = innovation(&imm->m[j], s, m, H, y, noise, still ? 3 : 6, &u[j]);
        }
        if (!ok) {
            return MVT_ERR_NUMERIC;
        }
    }
    /* a pixel detection is the person's with probability 1 - p_outlier, else displaced anywhere
     * within outlier_radius_px (density 1 / (pi r^2)) */
    const mvt_real eps = m == 2 ? c->p_outlier : MVT_R(0.0);
    /* ... or, with the view's memory, displaced as in its last detection (continuing) */
    mvt_real p_cont = MVT_R(0.0);
    const mvt_real g_cont = eps > MVT_R(0.0) ? continuing(c, y, noise, S_view, view, s, &p_cont) : MVT_R(0.0);
    const mvt_real right = (MVT_R(1.0) - eps) * (MVT_R(1.0) - p_cont) * own_lr;
    const mvt_real clutter =
        eps > MVT_R(0.0)
            ? eps * (MVT_R(1.0) - p_cont) / (MVT_R(3.14159265358979) * c->outlier_radius_px * c->outlier_radius_px) +
                  p_cont * g_cont
            : MVT_R(0.0);
    mvt_real like[MVT_IMM_MODELS], sum = MVT_R(0.0);
    for (int j = 0; j < n; j++) {
        like[j] = right * u[j].g + clutter;
        sum += imm->mu[j] * like[j];
    }
    if (view != NULL && eps > MVT_R(0.0)) {
        const mvt_real pd = sum > MVT_R(0.0) && isfinite(sum) ? clutter / sum : MVT_R(1.0);
        view->p = pd < MVT_R(1.0) ? pd : MVT_R(1.0);
        view->y[0] = y[0];
        view->y[1] = y[1];
        view->utime_us = s->utime_us;
    }
    for (int j = 0; j < n; j++) {
        const mvt_real w = like[j] > MVT_R(0.0) ? right * u[j].g / like[j] : MVT_R(0.0);
        const mvt_real wj = eps > MVT_R(0.0) ? w : MVT_R(1.0);
        if (m != 2) {
            apply(&imm->m[j], m, &u[j], wj);
        } else if (u[j].nx == 3) {
            px3_apply(&imm->m[j], &u[j], wj);
        } else {
            px6_apply(&imm->m[j], &u[j], wj);
        }
    }
    if (n > 1) {
        if (sum > MVT_R(0.0) && isfinite(sum)) {
            for (int j = 0; j < n; j++) {
                imm->mu[j] = imm->mu[j] * like[j] / sum;
            }
        } /* else: every model equally far off (likelihoods underflow), no evidence either way */
    }
    combine(imm, c, s, nb);
    return MVT_OK;
}

mvt_err_t mvt_imm_update(mvt_imm_t *imm, const mvt_imm_config_t *c, int m, const mvt_real *H, const mvt_real *y,
                         const mvt_real *noise, mvt_cv_state_t *s)
{
    return update(imm, c, m, H, y, noise, s, 6, NULL, NULL, MVT_R(1.0));
}

mvt_err_t mvt_imm_update_pos(mvt_imm_t *imm, const mvt_imm_config_t *c, int m, const mvt_real *H, const mvt_real *y,
                             const mvt_real *noise, mvt_cv_state_t *s)
{
    return update(imm, c, m, H, y, noise, s, 3, NULL, NULL, MVT_R(1.0));
}

mvt_err_t mvt_imm_update_view(mvt_imm_t *imm, const mvt_imm_config_t *c, const mvt_real *H, const mvt_real *y,
                              const mvt_real *noise, const mvt_real S[3], mvt_imm_view_t *view, mvt_cv_state_t *s)
{
    return update(imm, c, 2, H, y, noise, s, 3, S, view, MVT_R(1.0));
}

mvt_err_t mvt_imm_update_view_lr(mvt_imm_t *imm, const mvt_imm_config_t *c, const mvt_real *H, const mvt_real *y,
                                 const mvt_real *noise, const mvt_real S[3], mvt_imm_view_t *view, mvt_real own_lr,
                                 mvt_cv_state_t *s)
{
    return update(imm, c, 2, H, y, noise, s, 3, S, view, own_lr);
}

static mvt_err_t truncate_models(mvt_imm_t *imm, const mvt_imm_config_t *c, const mvt_real H[3], mvt_real value,
                                 mvt_real extra_var, mvt_real lo, mvt_real hi, mvt_cv_state_t *s, int ground)
{
    const int n = c->n;
    mvt_imm_t tmp = *imm;
    for (int j = 0; j < n; j++) {
        const mvt_real *xj = tmp.m[j].x;
        const mvt_real vj = value + H[0] * (xj[0] - s->x[0]) + H[1] * (xj[1] - s->x[1]) + H[2] * (xj[2] - s->x[2]);
        const mvt_err_t err = ground ? mvt_cv_truncate_ground(&tmp.m[j], H, vj, extra_var, lo, hi, NULL)
                                     : mvt_cv_truncate_ex(&tmp.m[j], H, vj, extra_var, lo, hi, NULL);
        if (err != MVT_OK) {
            return err;
        }
    }
    *imm = tmp;
    mvt_imm_combine(imm, c, s);
    return MVT_OK;
}

mvt_err_t mvt_imm_truncate(mvt_imm_t *imm, const mvt_imm_config_t *c, const mvt_real H[3], mvt_real value,
                           mvt_real extra_var, mvt_real lo, mvt_real hi, mvt_cv_state_t *s)
{
    return truncate_models(imm, c, H, value, extra_var, lo, hi, s, 0);
}

mvt_err_t mvt_imm_truncate_ground(mvt_imm_t *imm, const mvt_imm_config_t *c, const mvt_real H[3], mvt_real value,
                                  mvt_real extra_var, mvt_real lo, mvt_real hi, mvt_cv_state_t *s)
{
    return truncate_models(imm, c, H, value, extra_var, lo, hi, s, 1);
}

mvt_err_t mvt_imm_repair(mvt_imm_t *imm, const mvt_imm_config_t *c, mvt_cv_state_t *s, mvt_real var_floor)
{
    for (int j = 0; j < c->n; j++) {
        const mvt_err_t err = mvt_cv_repair(&imm->m[j], var_floor);
        if (err != MVT_OK) {
            return err;
        }
    }
    mvt_imm_combine(imm, c, s);
    return mvt_cv_repair(s, var_floor);
}
