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

/* The run of foreground through column c of mask row r: [*a, *b]. */
static void run_through(const mvt_mask_t *mask, int r, int c, int *a, int *b)
{
    const uint8_t *row = &mask->fg[(size_t)r * (size_t)mask->width];
    int lo = c, hi = c;
    while (lo > 0 && row[lo - 1] != 0u) {
        lo--;
    }
    while (hi + 1 < mask->width && row[hi + 1] != 0u) {
        hi++;
    }
    *a = lo;
    *b = hi;
}

int mvt_mask_top_in_band(const mvt_mask_t *mask, mvt_real u, mvt_real half_w, mvt_real v_lo, mvt_real v_hi,
                         mvt_real max_width_px, mvt_real clear_px, mvt_real top_uv[2])
{
    MVT_ASSERT(mask != NULL && top_uv != NULL);
    int c0, c1, r0, r1;
    const mvt_real vm = MVT_R(0.5) * (v_lo + v_hi), vr = MVT_R(0.5) * (v_hi - v_lo);
    if (mask->width < 1 || mask->height < 1 || mask->scale < 1 || !isfinite(u) || !isfinite(half_w) ||
        !isfinite(v_lo) || !isfinite(v_hi) || !isfinite(max_width_px) || !isfinite(clear_px) || half_w < MVT_R(0.0) ||
        !(vr >= MVT_R(0.0)) || !(clear_px >= MVT_R(0.0)) || !isfinite(vm) || !isfinite(vr) ||
        !span(u, half_w, mask->scale, mask->width, &c0, &c1) || !span(vm, vr, mask->scale, mask->height, &r0, &r1)) {
        return 0;
    }
    const mvt_real s = (mvt_real)mask->scale;
    const mvt_real clear_rows = clear_px / s < (mvt_real)mask->height ? clear_px / s : (mvt_real)mask->height;
    const int n_clear = (int)clear_rows + 1; /* >= 1: at least the row above */
    int r = r0, c = c1 + 1;
    for (; r <= r1; r++) {
        const uint8_t *row = &mask->fg[(size_t)r * (size_t)mask->width];
        for (c = c0; c <= c1 && row[c] == 0u; c++) {
        }
        if (c <= c1) {
            break;
        }
    }
    if (r > r1 || r < 1) {
        return 0; /* none, or at the picture's top edge (a head cut by it) */
    }
    int a, b;
    run_through(mask, r, c, &a, &b);
    if ((mvt_real)(b - a + 1) * s > max_width_px || a == 0 || b == mask->width - 1) {
        return 0; /* too wide for a head, or cut by the picture's side (a slope may go on beyond) */
    }
    /* a top: background above it, across the band and beside the run's ends, for n_clear rows (or
     * up to the picture's top). Otherwise it is a slope rising out of the band (whose first row in
     * the band would follow the band wherever it is put), or a fragment under a head (a torso
     * under a hole), or the inside of a silhouette that goes on above the range. */
    int x0 = a - 1 < c0 ? a - 1 : c0, x1 = b + 1 > c1 ? b + 1 : c1;
    x0 = x0 > 0 ? x0 : 0;
    x1 = x1 < mask->width - 1 ? x1 : mask->width - 1;
    for (int y = r - 1; y >= 0 && y >= r - n_clear; y--) {
        const uint8_t *up = &mask->fg[(size_t)y * (size_t)mask->width];
        for (int x = x0; x <= x1; x++) {
            if (up[x] != 0u) {
                return 0;
            }
        }
    }
    /* the column: the mean of the foreground in this row and the next over the run and a pixel
     * beside each end (a head widens by about that much a row; further on, the next row may
     * already be a neighbour's shoulder) */
    const uint8_t *row = &mask->fg[(size_t)r * (size_t)mask->width];
    const uint8_t *next = r + 1 < mask->height ? row + mask->width : row;
    mvt_real sum = MVT_R(0.0);
    int n = 0;
    for (int x = a > 0 ? a - 1 : 0; x <= b + 1 && x < mask->width; x++) {
        if (row[x] != 0u || next[x] != 0u) {
            sum += (mvt_real)x;
            n++;
        }
    }
    top_uv[0] = (sum / (mvt_real)n + MVT_R(0.5)) * s - MVT_R(0.5);
    top_uv[1] = (mvt_real)r * s - MVT_R(0.5) + MVT_R(0.25) * s;
    return 1;
}
