#include "mvt_mask.h"

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
