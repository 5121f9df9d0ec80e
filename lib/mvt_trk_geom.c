/*
 * mvt_trk_geom.c - small geometric and likelihood helpers the tracker's steps share: blob boxes,
 * the tracked volume, a detection's likelihood density, and the distance between two 3D
 * estimates.
 */
#include <math.h>
#include <stddef.h>

#include "mvt_linalg.h"
#include "mvt_trk.h"

int mvt_trk_box_ok(const mvt_real b[4])
{
    return isfinite(b[0]) && isfinite(b[1]) && isfinite(b[2]) && isfinite(b[3]) && b[2] > b[0] && b[3] > b[1];
}

int mvt_trk_in_box(const mvt_real b[4], const mvt_real uv[2], mvt_real slack_u, mvt_real slack_v)
{
    return mvt_trk_box_ok(b) && uv[0] >= b[0] - slack_u && uv[0] <= b[2] + slack_u && uv[1] >= b[1] - slack_v &&
           uv[1] <= b[3] + slack_v;
}

int mvt_trk_inside_volume(const mvt_tracker_config_t *c, const mvt_real x[3])
{
    for (int i = 0; i < 3; i++) {
        if (!(x[i] >= c->volume.min[i] - c->volume.margin_m) || !(x[i] <= c->volume.max[i] + c->volume.margin_m)) {
            return 0;
        }
    }
    return 1;
}

mvt_real mvt_trk_density(const mvt_pkf_innov_t *in)
{
    const mvt_real det = in->S[0] * in->S[2] - in->S[1] * in->S[1];
    if (!(det > MVT_R(0.0)) || !(in->S[0] > MVT_R(0.0))) {
        return MVT_R(0.0);
    }
    return MVT_EXP(MVT_R(-0.5) * in->d2) / (MVT_R(6.2831853) * MVT_SQRT(det));
}

mvt_real mvt_trk_mahalanobis3(const mvt_real a[3], const mvt_real Pa[9], const mvt_real b[3], const mvt_real Pb[9],
                              mvt_real *det)
{
    mvt_real S[9], Si[9];
    for (int i = 0; i < 9; i++) {
        S[i] = Pa[i] + Pb[i];
    }
    if (mvt_la_inv3(S, Si) != MVT_OK) {
        return MVT_R(-1.0);
    }
    if (det != NULL) {
        *det = S[0] * (S[4] * S[8] - S[5] * S[7]) - S[1] * (S[3] * S[8] - S[5] * S[6]) +
               S[2] * (S[3] * S[7] - S[4] * S[6]);
    }
    const mvt_real d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    mvt_real q = MVT_R(0.0);
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            q += d[i] * Si[i * 3 + j] * d[j];
        }
    }
    return q;
}
