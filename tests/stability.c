/*
 * stability.c - float against double over 10^6 filter steps (issue: "numerical stability in
 * float").
 *
 * One person walks a room for 11 hours of 25 fps frames seen by the five SmartRoom cameras (lens
 * distortion, +-3 ms capture jitter, 2 px noise, 5 % misses, each camera occluded for 0.5-3 s
 * about every 8 s, every camera blind for 1 s about every 200 s). Detections come from a double
 * generator with camera parameters rounded to float, so the float and double builds of the core
 * see bit-identical inputs; the filter is the core's: mvt_cv_predict_to, then the projective
 * update per camera in capture-time order, no gating (the two builds take the same path).
 *
 *   stability --write FILE   (float build) run, check P, write the positions
 *   stability --compare FILE (double build) run, check P, compare with FILE
 *   [--steps N] (default 1000000)
 *   [--imm]     the IMM (mvt_imm, default bank, robust updates) instead of the single filter:
 *               every model's P and the combination's are checked, mu must stay a distribution
 *
 * Checked at every step: P symmetric (|Pij - Pji| <= 1e-6 sqrt(Pii Pjj)) and positive definite
 * (Cholesky in double); with --compare, |x_float - x_double| <= 1 mm. Prints the figures; exit
 * status 1 on any violation.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mvt_imm.h"
#include "mvt_pkf.h"
#include "test_support.h"

#define NCAM 5

typedef struct {
    double K[9], dist[5], R[9], t[3];
} gen_cam_t;

static void rodrigues_d(const double r[3], double R[9])
{
    const double th = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    const double k[3] = {r[0] / th, r[1] / th, r[2] / th};
    const double c = cos(th), s = sin(th), v = 1 - c;
    R[0] = c + k[0] * k[0] * v;        R[1] = k[0] * k[1] * v - k[2] * s; R[2] = k[0] * k[2] * v + k[1] * s;
    R[3] = k[1] * k[0] * v + k[2] * s; R[4] = c + k[1] * k[1] * v;        R[5] = k[1] * k[2] * v - k[0] * s;
    R[6] = k[2] * k[0] * v - k[1] * s; R[7] = k[2] * k[1] * v + k[0] * s; R[8] = c + k[2] * k[2] * v;
}

/* OpenCV's model (k1 k2 p1 p2 k3) in double; 0 when behind the camera or outside the image. */
static int project_d(const gen_cam_t *g, const double X[3], double uv[2])
{
    double c[3];
    for (int i = 0; i < 3; i++) {
        c[i] = g->R[i * 3] * X[0] + g->R[i * 3 + 1] * X[1] + g->R[i * 3 + 2] * X[2] + g->t[i];
    }
    if (c[2] < 0.1) {
        return 0;
    }
    const double x = c[0] / c[2], y = c[1] / c[2], r2 = x * x + y * y;
    /* the lens's usable field: where the radial model is still clearly monotonic (beyond it the
     * core refuses to undistort, and which build refuses first would be a coin toss) */
    if (1 + 3 * g->dist[0] * r2 + 5 * g->dist[1] * r2 * r2 + 7 * g->dist[4] * r2 * r2 * r2 < 0.3) {
        return 0;
    }
    const double rad = 1 + g->dist[0] * r2 + g->dist[1] * r2 * r2 + g->dist[4] * r2 * r2 * r2;
    const double xd = x * rad + 2 * g->dist[2] * x * y + g->dist[3] * (r2 + 2 * x * x);
    const double yd = y * rad + g->dist[2] * (r2 + 2 * y * y) + 2 * g->dist[3] * x * y;
    uv[0] = g->K[0] * xd + g->K[1] * yd + g->K[2];
    uv[1] = g->K[4] * yd + g->K[5];
    return uv[0] >= 0 && uv[1] >= 0 && uv[0] <= 767 && uv[1] <= 575;
}

static void truth_at(double t, double x[3])
{
    x[0] = 3.0 + 1.9 * sin(0.11 * t) + 0.4 * sin(0.53 * t + 1.0);
    x[1] = 2.5 + 1.5 * sin(0.07 * t + 2.0) + 0.3 * sin(0.41 * t);
    x[2] = 1.7 + 0.03 * sin(11.0 * t);
}

/* Cholesky of the 6x6 P in double: 1 when positive definite. */
static int spd(const mvt_real *P, double *asym)
{
    double A[36];
    *asym = 0;
    for (int i = 0; i < 6; i++) {
        for (int j = 0; j < 6; j++) {
            A[i * 6 + j] = (double)P[i * 6 + j];
            const double s = sqrt(fabs((double)P[i * 7] * (double)P[j * 7]));
            const double d = fabs((double)P[i * 6 + j] - (double)P[j * 6 + i]) / (s > 0 ? s : 1);
            *asym = d > *asym ? d : *asym;
        }
    }
    for (int j = 0; j < 6; j++) {
        double d = A[j * 7];
        for (int k = 0; k < j; k++) d -= A[j * 6 + k] * A[j * 6 + k];
        if (!(d > 0)) return 0;
        d = sqrt(d);
        A[j * 7] = d;
        for (int i = j + 1; i < 6; i++) {
            double s = A[i * 6 + j];
            for (int k = 0; k < j; k++) s -= A[i * 6 + k] * A[j * 6 + k];
            A[i * 6 + j] = s / d;
        }
    }
    return 1;
}

int main(int argc, char **argv)
{
    const char *path = NULL;
    int compare = 0, use_imm = 0;
    long steps = 1000000;
    for (int i = 1; i < argc; i++) {
        if ((!strcmp(argv[i], "--write") || !strcmp(argv[i], "--compare")) && i + 1 < argc) {
            compare = !strcmp(argv[i], "--compare");
            path = argv[++i];
        } else if (!strcmp(argv[i], "--imm")) {
            use_imm = 1;
        } else if (!strcmp(argv[i], "--steps") && i + 1 < argc) {
            steps = strtol(argv[++i], NULL, 10);
        } else {
            fprintf(stderr, "usage: %s (--write FILE | --compare FILE) [--steps N] [--imm]\n", argv[0]);
            return 2;
        }
    }
    if (path == NULL || steps < 1) {
        fprintf(stderr, "usage: %s (--write FILE | --compare FILE) [--steps N] [--imm]\n", argv[0]);
        return 2;
    }
    FILE *fh = fopen(path, compare ? "rb" : "wb");
    if (fh == NULL) {
        perror(path);
        return 2;
    }
    /* the SmartRoom cameras, parameters rounded to float, the same in both builds */
    mvt_camera_t cams[NCAM];
    gen_cam_t gen[NCAM];
    {
        const double tgt[3] = {3.0, 2.5, 0.9}, down[3] = {3.0, 2.5, 0.0};
        const double pos[NCAM][3] = {{0.15, 0.15, 2.75}, {5.85, 0.15, 2.75}, {5.85, 4.85, 2.75}, {0.15, 4.85, 2.75},
                                     {3.0, 2.5, 2.95}};
        const double d[5] = {-0.22, 0.06, 0.0005, -0.0004, -0.006};
        for (int k = 0; k < NCAM; k++) {
            mvt_camera_params_t p;
            test_look_at(&p, pos[k], k == 4 ? down : tgt, k == 4 ? 300.0 : 420.0, 383.5, 287.5, d);
            double rv[3];
            for (int i = 0; i < 9; i++) p.camera_matrix[i] = (mvt_real)(float)p.camera_matrix[i];
            for (int i = 0; i < 5; i++) p.dist[i] = (mvt_real)(float)p.dist[i];
            for (int i = 0; i < 3; i++) {
                p.rvec[i] = (mvt_real)(float)p.rvec[i];
                p.tvec[i] = (mvt_real)(float)p.tvec[i];
                rv[i] = (double)p.rvec[i];
                gen[k].t[i] = (double)p.tvec[i];
            }
            for (int i = 0; i < 9; i++) gen[k].K[i] = (double)p.camera_matrix[i];
            for (int i = 0; i < 5; i++) gen[k].dist[i] = (double)p.dist[i];
            rodrigues_d(rv, gen[k].R);
            if (mvt_cam_init(&cams[k], &p) != MVT_OK) {
                fprintf(stderr, "camera %d rejected\n", k);
                return 2;
            }
        }
    }
    test_rng_t rng = {0x9e3779b97f4a7c15ULL};
    const mvt_real q[3] = {(mvt_real)0.5f, (mvt_real)0.5f, (mvt_real)0.05f};
    double x0[3];
    truth_at(0, x0);
    const mvt_real p0[3] = {(mvt_real)(float)x0[0], (mvt_real)(float)x0[1], (mvt_real)(float)x0[2]};
    const mvt_real c0[9] = {(mvt_real)0.01f, 0, 0, 0, (mvt_real)0.01f, 0, 0, 0, (mvt_real)0.01f};
    mvt_cv_state_t s;
    mvt_cv_init(&s, p0, c0, (mvt_real)1.0f, 0);
    mvt_imm_config_t icfg;
    mvt_imm_config_default(&icfg);
    mvt_imm_t imm;
    mvt_imm_init(&imm, &icfg, &s);
    long bad_mu = 0;
    int occluded_until[NCAM] = {0}, blind_until = 0;
    long bad_spd = 0, bad_sym = 0, bad_diff = 0, updates = 0, coasted = 0;
    double worst_asym = 0, worst_diff = 0, se = 0, worst_err = 0, max_std = 0;
    for (long n = 1; n <= steps; n++) {
        const int64_t t_us = n * 40000;
        if (test_uniform(&rng) < 1.0 / (25 * 200)) {
            blind_until = (int)n + 25;
        }
        /* capture times: +-3 ms jitter per camera, updates in time order */
        int64_t tk[NCAM];
        int order[NCAM];
        for (int k = 0; k < NCAM; k++) {
            tk[k] = t_us + (int64_t)((test_uniform(&rng) * 2 - 1) * 3000);
            order[k] = k;
            if (n >= occluded_until[k] && test_uniform(&rng) < 1.0 / (25 * 8)) {
                occluded_until[k] = (int)n + 12 + (int)(test_uniform(&rng) * 63);
            }
        }
        for (int i = 1; i < NCAM; i++) {
            for (int j = i; j > 0 && tk[order[j - 1]] > tk[order[j]]; j--) {
                const int tmp = order[j]; order[j] = order[j - 1]; order[j - 1] = tmp;
            }
        }
        int seen = 0;
        for (int oi = 0; oi < NCAM; oi++) {
            const int k = order[oi];
            double X[3], uv[2];
            truth_at((double)tk[k] * 1e-6, X);
            const double nu = test_normal(&rng) * 2.0, nv = test_normal(&rng) * 2.0;
            const int miss = test_uniform(&rng) < 0.05;
            if (n < blind_until || n < occluded_until[k] || miss || !project_d(&gen[k], X, uv)) {
                continue;
            }
            if (use_imm) {
                (void)mvt_imm_predict_to(&imm, &icfg, tk[k], &s);
            } else {
                (void)mvt_cv_predict_to(&s, tk[k], q);
            }
            const mvt_real z[2] = {(mvt_real)(float)(uv[0] + nu), (mvt_real)(float)(uv[1] + nv)};
            mvt_pkf_meas_t m;
            mvt_pkf_innov_t in;
            const mvt_real noise[4] = {(mvt_real)4.0f, 0, 0, (mvt_real)4.0f};
            if (mvt_pkf_meas_make(&cams[k], z, (mvt_real)2.0f, &m) == MVT_OK &&
                mvt_pkf_innovation(&s, &cams[k], MVT_PKF_JACOBIAN, &m, &in) == MVT_OK &&
                (use_imm ? mvt_imm_update(&imm, &icfg, 2, in.H, in.y, noise, &s) : mvt_pkf_update(&s, &in)) == MVT_OK) {
                updates++;
                seen++;
            } else if (getenv("STAB_DEBUG")) {
                fprintf(stderr, "step %ld cam %d: update refused\n", n, k);
            }
        }
        if (use_imm) {
            (void)mvt_imm_predict_to(&imm, &icfg, t_us + 5000, &s);
        } else {
            (void)mvt_cv_predict_to(&s, t_us + 5000, q);
        }
        coasted += seen == 0;
        double asym;
        if (!spd(s.P, &asym)) {
            if (bad_spd++ < 5) fprintf(stderr, "step %ld: P not positive definite\n", n);
        }
        if (use_imm) {
            double musum = 0;
            for (int j = 0; j < icfg.n; j++) {
                double aj;
                if (!spd(imm.m[j].P, &aj)) {
                    if (bad_spd++ < 5) fprintf(stderr, "step %ld: model %d's P not positive definite\n", n, j);
                }
                asym = aj > asym ? aj : asym;
                musum += (double)imm.mu[j];
                if (!(imm.mu[j] >= 0)) bad_mu++;
            }
            if (fabs(musum - 1.0) > 1e-4) bad_mu++;
        }
        worst_asym = asym > worst_asym ? asym : worst_asym;
        if (asym > 1e-6) bad_sym++;
        double X[3];
        truth_at((double)(t_us + 5000) * 1e-6, X);
        double e2 = 0;
        for (int i = 0; i < 3; i++) {
            e2 += ((double)s.x[i] - X[i]) * ((double)s.x[i] - X[i]);
            const double sd = sqrt((double)s.P[i * 7]);
            max_std = sd > max_std ? sd : max_std;
        }
        se += e2;
        worst_err = sqrt(e2) > worst_err ? sqrt(e2) : worst_err;
        double pos[3] = {(double)s.x[0], (double)s.x[1], (double)s.x[2]};
        if (!compare) {
            if (fwrite(pos, sizeof(pos), 1, fh) != 1) { perror(path); return 2; }
        } else {
            double other[3];
            if (fread(other, sizeof(other), 1, fh) != 1) { fprintf(stderr, "%s: short file\n", path); return 2; }
            const double d = sqrt((pos[0] - other[0]) * (pos[0] - other[0]) + (pos[1] - other[1]) * (pos[1] - other[1]) +
                                  (pos[2] - other[2]) * (pos[2] - other[2]));
            worst_diff = d > worst_diff ? d : worst_diff;
            if (d > 1e-3 && bad_diff++ < 5) fprintf(stderr, "step %ld: float and double differ by %.3g m\n", n, d);
        }
    }
    fclose(fh);
    printf("%s build (%zu-byte real): %ld steps, %ld camera updates, %ld steps with no view\n",
           sizeof(mvt_real) == 4 ? "float" : "double", sizeof(mvt_real), steps, updates, coasted);
    printf("  P not positive definite: %ld steps; worst relative asymmetry %.3g (%ld steps > 1e-6)\n", bad_spd,
           worst_asym, bad_sym);
    printf("  error vs truth: RMSE %.2f mm, worst %.1f mm; largest position std %.1f mm\n", 1e3 * sqrt(se / (double)steps),
           1e3 * worst_err, 1e3 * max_std);
    if (compare) {
        printf("  float vs double position: worst %.4f mm (%ld steps > 1 mm)\n", 1e3 * worst_diff, bad_diff);
    }
    if (use_imm) {
        printf("  IMM (%d models): model probabilities not a distribution: %ld steps\n", icfg.n, bad_mu);
    }
    return bad_spd == 0 && bad_sym == 0 && bad_diff == 0 && bad_mu == 0 ? 0 : 1;
}
