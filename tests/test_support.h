/* Shared helpers for the C tests: a camera looking at a point, a deterministic RNG. */
#ifndef MVT_TEST_SUPPORT_H
#define MVT_TEST_SUPPORT_H

#include <math.h>
#include <string.h>

#include "mvt_camera.h"

/* Camera params at `pos` looking at `tgt` (z up, image y down), given intrinsics/distortion. */
static inline void test_look_at(mvt_camera_params_t *p, const double pos[3], const double tgt[3], double f,
                                double cx, double cy, const double dist5[5])
{
    memset(p, 0, sizeof(*p));
    double fw[3] = {tgt[0] - pos[0], tgt[1] - pos[1], tgt[2] - pos[2]};
    double n = sqrt(fw[0] * fw[0] + fw[1] * fw[1] + fw[2] * fw[2]);
    for (int i = 0; i < 3; i++) fw[i] /= n;
    double up[3] = {0, 0, 1};
    if (fabs(fw[2]) > 0.99) { up[1] = 1; up[2] = 0; }
    double x[3] = {fw[1] * up[2] - fw[2] * up[1], fw[2] * up[0] - fw[0] * up[2], fw[0] * up[1] - fw[1] * up[0]};
    n = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    for (int i = 0; i < 3; i++) x[i] /= n;
    double y[3] = {fw[1] * x[2] - fw[2] * x[1], fw[2] * x[0] - fw[0] * x[2], fw[0] * x[1] - fw[1] * x[0]};
    double R[9] = {x[0], x[1], x[2], y[0], y[1], y[2], fw[0], fw[1], fw[2]};
    /* Rodrigues vector of R (angle in (0, pi)) */
    double c = (R[0] + R[4] + R[8] - 1) / 2;
    c = c > 1 ? 1 : (c < -1 ? -1 : c);
    double th = acos(c);
    double r[3] = {R[7] - R[5], R[2] - R[6], R[3] - R[1]};
    double s = sin(th);
    if (s > 1e-6) {
        for (int i = 0; i < 3; i++) p->rvec[i] = (mvt_real)(r[i] * th / (2 * s));
    } else if (c > 0) {
        for (int i = 0; i < 3; i++) p->rvec[i] = 0;
    } else { /* angle pi: axis from the largest diagonal of (R + I) / 2 */
        int m = 0;
        for (int i = 1; i < 3; i++) if (R[i * 4] > R[m * 4]) m = i;
        double a[3];
        for (int i = 0; i < 3; i++) a[i] = (R[m * 3 + i] + (i == m ? 1.0 : 0.0)) / 2;
        const double an = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        for (int i = 0; i < 3; i++) p->rvec[i] = (mvt_real)(a[i] / an * th);
    }
    for (int i = 0; i < 3; i++) p->tvec[i] = (mvt_real)(-(R[i * 3] * pos[0] + R[i * 3 + 1] * pos[1] + R[i * 3 + 2] * pos[2]));
    double K[9] = {f, 0, cx, 0, f, cy, 0, 0, 1};
    for (int i = 0; i < 9; i++) p->camera_matrix[i] = (mvt_real)K[i];
    for (int i = 0; i < 5; i++) p->dist[i] = (mvt_real)(dist5 ? dist5[i] : 0.0);
    p->width = 768;
    p->height = 576;
    p->sigma_px = 2;
}

/* Five cameras around a 6 x 5 m room, as the simulator's SmartRoom. */
static inline int test_room_cameras(mvt_camera_t cams[5], int with_distortion)
{
    const double tgt[3] = {3.0, 2.5, 0.9};
    const double pos[5][3] = {{0.15, 0.15, 2.75}, {5.85, 0.15, 2.75}, {5.85, 4.85, 2.75}, {0.15, 4.85, 2.75}, {3.0, 2.5, 2.95}};
    const double d[5] = {-0.22, 0.06, 0.0005, -0.0004, -0.006};
    for (int k = 0; k < 5; k++) {
        mvt_camera_params_t p;
        const double down[3] = {3.0, 2.5, 0.0};
        test_look_at(&p, pos[k], k == 4 ? down : tgt, k == 4 ? 300.0 : 420.0, 383.5, 287.5, with_distortion ? d : NULL);
        if (mvt_cam_init(&cams[k], &p) != MVT_OK) return -1;
    }
    return 0;
}

/* xorshift64* uniform in [0, 1) and a Box-Muller normal: deterministic test noise. */
typedef struct { unsigned long long s; } test_rng_t;
static inline double test_uniform(test_rng_t *r)
{
    r->s ^= r->s >> 12; r->s ^= r->s << 25; r->s ^= r->s >> 27;
    return (double)((r->s * 2685821657736338717ULL) >> 11) * (1.0 / 9007199254740992.0);
}
static inline double test_normal(test_rng_t *r)
{
    double u1 = test_uniform(r), u2 = test_uniform(r);
    if (u1 < 1e-300) u1 = 1e-300;
    return sqrt(-2 * log(u1)) * cos(6.283185307179586 * u2);
}

#endif
