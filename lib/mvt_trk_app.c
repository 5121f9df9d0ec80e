/*
 * mvt_trk_app.c - a person's appearance from the colour of their blobs (mvt_trk.h).
 *
 * Where the detector sends each blob's mean hue and saturation (detection_t), geometry is
 * not the only thing that tells two people apart. Two people passing at half a metre have gates
 * that hold both heads in most views, and an identity is lost the moment the assignment
 * prefers the wrong one by a few pixels; their shirts rarely agree.
 *
 * The model is one chroma point per person, a = s (cos 2 pi h, sin 2 pi h): grey clothes lie
 * near the centre of the disc, where a hue is noise, and saturated ones on its rim. A person's
 * detections scatter about their mean m (the view shows more shirt or more trousers, the light
 * changes across the room) with a spread the track learns from its own detections, starting from
 * MVT_TRK_APP_SD0 with the weight of MVT_TRK_APP_N0 detections. A share MVT_TRK_APP_OUTLIER of
 * them carries someone else's colour (a merged blob, a fragment, a shadow): each detection is
 * weighted by the chance that it shows the person (the mixture's posterior), so such detections
 * neither pull the mean nor widen the spread, and their cost is bounded (-2 ln eps).
 *
 * The tracker learns it from the blobs that are a track's head alone in their blob
 * (mvt_body_update.c) and reports it (track_t.hue, saturation); association does not weigh it
 * (measured: with clothes the background's colour it pulled tracks onto the wrong blobs;
 * docs/results.md, "Colour"). The cost below is what weighing it would use.
 */
#include <math.h>
#include <string.h>

#include "mvt_trk.h"

#define TWO_PI MVT_R(6.283185307179586)

int mvt_trk_chroma(const mvt_detection_t *det, mvt_real a[2])
{
    const mvt_real h = det->hue, s = det->saturation;
    if (!(h >= MVT_R(0.0) && h <= MVT_R(1.0)) || !(s >= MVT_R(0.0) && s <= MVT_R(1.0))) {
        return 0; /* unknown (< 0), out of range or NaN */
    }
    a[0] = s * MVT_COS(TWO_PI * h);
    a[1] = s * MVT_SIN(TWO_PI * h);
    return 1;
}

void mvt_trk_app_hue_sat(const mvt_app_t *app, mvt_real *hue, mvt_real *sat)
{
    *hue = MVT_R(-1.0);
    *sat = MVT_R(-1.0);
    if (!(app->n > MVT_R(0.0))) {
        return;
    }
    const mvt_real *m = app->m;
    mvt_real h = MVT_ATAN2(m[1], m[0]) / TWO_PI;
    h = h < MVT_R(0.0) ? h + MVT_R(1.0) : h;
    *hue = h < MVT_R(1.0) ? h : MVT_R(0.0);
    const mvt_real s = MVT_SQRT(m[0] * m[0] + m[1] * m[1]);
    *sat = s < MVT_R(1.0) ? s : MVT_R(1.0);
}

void mvt_trk_app_reset(mvt_app_t *app)
{
    app->m[0] = MVT_R(0.0);
    app->m[1] = MVT_R(0.0);
    app->var = MVT_TRK_APP_SD0 * MVT_TRK_APP_SD0;
    app->n = MVT_R(0.0);
}

/* The predictive variance per axis of a new detection's chroma. */
static mvt_real predictive_var(const mvt_app_t *app)
{
    return app->var * (MVT_R(1.0) + MVT_R(1.0) / app->n);
}

/* LR of a detection at squared chroma distance r2 (the mixture in mvt_trk.h). */
static mvt_real likelihood_ratio(mvt_real r2, mvt_real V)
{
    const mvt_real eps = MVT_TRK_APP_OUTLIER;
    return (MVT_R(1.0) - eps) * MVT_EXP(MVT_R(-0.5) * r2 / V) / (MVT_R(2.0) * V) + eps;
}

mvt_real mvt_trk_app_cost(const mvt_app_t *app, const mvt_real a[2])
{
    if (!(app->n > MVT_R(0.0))) {
        return MVT_R(0.0);
    }
    const mvt_real d0 = a[0] - app->m[0], d1 = a[1] - app->m[1];
    return MVT_R(-2.0) * MVT_LOG(likelihood_ratio(d0 * d0 + d1 * d1, predictive_var(app)));
}

mvt_real mvt_trk_app_cost_min(const mvt_app_t *app)
{
    if (!(app->n > MVT_R(0.0))) {
        return MVT_R(0.0);
    }
    return MVT_R(-2.0) * MVT_LOG(likelihood_ratio(MVT_R(0.0), predictive_var(app)));
}

void mvt_trk_app_update(mvt_app_t *app, const mvt_real a[2])
{
    const mvt_real d0 = a[0] - app->m[0], d1 = a[1] - app->m[1];
    const mvt_real r2 = d0 * d0 + d1 * d1;
    mvt_real w = MVT_R(1.0); /* the first detection shows the person: it made the track */
    if (app->n > MVT_R(0.0)) {
        const mvt_real lr = likelihood_ratio(r2, predictive_var(app));
        w = (lr - MVT_TRK_APP_OUTLIER) / lr; /* P(this person's colour | a) */
    }
    mvt_real n = app->n + w;
    if (n > MVT_TRK_APP_NMAX) {
        n = MVT_TRK_APP_NMAX;
    }
    if (!(n > MVT_R(0.0))) {
        return;
    }
    const mvt_real g = w / n;
    app->m[0] += g * d0;
    app->m[1] += g * d1;
    if (app->n > MVT_R(0.0)) {
        /* the spread (Welford's sum, weighted): the prior's MVT_TRK_APP_N0 detections at
         * MVT_TRK_APP_SD0, then the person's own; a first detection has no deviation to add */
        const mvt_real gv = w / (n - MVT_R(1.0) + MVT_TRK_APP_N0);
        const mvt_real var = app->var + gv * (MVT_R(0.5) * r2 * (MVT_R(1.0) - g) - app->var);
        const mvt_real floor = MVT_TRK_APP_SD_MIN * MVT_TRK_APP_SD_MIN;
        app->var = var > floor ? var : floor;
    }
    app->n = n;
}

int mvt_trk_app_ok(const mvt_app_t *app)
{
    const mvt_real floor = MVT_TRK_APP_SD_MIN * MVT_TRK_APP_SD_MIN;
    const mvt_real r2 = app->m[0] * app->m[0] + app->m[1] * app->m[1];
    return isfinite(app->m[0]) && isfinite(app->m[1]) && r2 <= MVT_R(1.0001) && app->var >= floor * MVT_R(0.999) &&
           app->var <= MVT_R(1.0) && app->n >= MVT_R(0.0) && app->n <= MVT_TRK_APP_NMAX;
}
