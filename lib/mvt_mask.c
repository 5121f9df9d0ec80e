#include "mvt_mask.h"

#include <math.h>
#include <string.h>

static mvt_err_t reject(mvt_mask_t *mask)
{
    mask->width = 0;
    mask->height = 0;
    mask->scale = 0;
    mask->has_colour = 0;
    mask->num_fg = 0;
    return MVT_ERR_INVALID;
}

mvt_err_t mvt_mask_from_runs(mvt_mask_t *mask, int image_width, int image_height, int width, int height,
                             const int32_t *runs, int32_t n_runs, const uint8_t *hue, const uint8_t *sat,
                             int32_t n_hs)
{
    MVT_ASSERT(mask != NULL);
    if (width < 1 || height < 1 || image_width < 1 || image_height < 1 || width > MVT_MAX_MASK_PIXELS ||
        height > MVT_MAX_MASK_PIXELS / width) {
        return reject(mask);
    }
    const int n_pix = width * height;
    if (image_width % width != 0 || image_height % height != 0 ||
        image_width / width != image_height / height) {
        return reject(mask);
    }
    if (n_runs < 0 || (n_runs > 0 && runs == NULL) || (n_hs != 0 && n_hs != n_pix) ||
        (n_hs != 0 && (hue == NULL || sat == NULL))) {
        return reject(mask);
    }
    /* check before writing: every run >= 0 and the sum exactly n_pix (no overflow: stop early) */
    int64_t sum = 0;
    for (int32_t i = 0; i < n_runs; i++) {
        if (runs[i] < 0) {
            return reject(mask);
        }
        sum += runs[i];
        if (sum > n_pix) {
            return reject(mask);
        }
    }
    if (sum != n_pix) {
        return reject(mask);
    }
    int pos = 0, num_fg = 0;
    for (int32_t i = 0; i < n_runs; i++) {
        const uint8_t value = (uint8_t)(i & 1);
        memset(mask->fg + pos, value, (size_t)runs[i]);
        pos += runs[i];
        num_fg += value ? runs[i] : 0;
    }
    if (n_hs != 0) {
        memcpy(mask->hue, hue, (size_t)n_pix);
        memcpy(mask->sat, sat, (size_t)n_pix);
    }
    mask->width = width;
    mask->height = height;
    mask->scale = image_width / width;
    mask->has_colour = n_hs != 0;
    mask->num_fg = num_fg;
    return MVT_OK;
}

/* The mask pixel range [lo, hi] that raw image coordinates [a - r, a + r] touch, clamped to
 * [0, n - 1]; 0 when it misses. Clamped in mvt_real before the conversion, so no r overflows. */
static int span(mvt_real a, mvt_real r, int scale, int n, int *lo, int *hi)
{
    const mvt_real s = (mvt_real)scale;
    mvt_real l = (a - r) / s, h = (a + r) / s;
    if (!(h >= MVT_R(0.0)) || !(l < (mvt_real)n)) {
        return 0;
    }
    l = l > MVT_R(0.0) ? l : MVT_R(0.0);
    h = h < (mvt_real)(n - 1) ? h : (mvt_real)(n - 1);
    *lo = (int)l; /* l, h >= 0: the conversion truncates down */
    *hi = (int)h;
    return 1;
}

int mvt_mask_fg_near(const mvt_mask_t *mask, const mvt_real uv[2], mvt_real r)
{
    MVT_ASSERT(mask != NULL && uv != NULL);
    int u0, u1, v0, v1;
    if (mask->width < 1 || mask->height < 1 || mask->scale < 1 || !isfinite(uv[0]) || !isfinite(uv[1]) ||
        !isfinite(r) || r < MVT_R(0.0) || !span(uv[0], r, mask->scale, mask->width, &u0, &u1) ||
        !span(uv[1], r, mask->scale, mask->height, &v0, &v1)) {
        return 0;
    }
    for (int v = v0; v <= v1; v++) {
        const uint8_t *row = &mask->fg[(size_t)v * (size_t)mask->width];
        for (int u = u0; u <= u1; u++) {
            if (row[u] != 0u) {
                return 1;
            }
        }
    }
    return 0;
}
