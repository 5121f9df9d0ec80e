/*
 * mvt_mask.h - one camera's foreground mask and hue/saturation image (CONTRACT section 1).
 *
 * The mask arrives as row-major run lengths alternating background, foreground, ... starting with
 * background, at the image resolution divided by an integer factor. This is the decoder of
 * untrusted input: every count, size and sum is checked before a byte is written.
 */
#ifndef MVT_MASK_H
#define MVT_MASK_H

#include "mvt_types.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mvt_mask {
    int width, height;                 /* mask pixels; 0 x 0 = no mask */
    int scale;                         /* image pixels per mask pixel along each axis, >= 1 */
    int has_colour;                    /* hue[] and sat[] are valid */
    int num_fg;                        /* foreground pixels */
    uint8_t fg[MVT_MAX_MASK_PIXELS];   /* 0 or 1, row-major */
    uint8_t hue[MVT_MAX_MASK_PIXELS];  /* 0..255 <-> [0, 1) */
    uint8_t sat[MVT_MAX_MASK_PIXELS];  /* 0..255 <-> [0, 1] */
} mvt_mask_t;

/* Decodes a mask of width x height (mask pixels) for an image of image_width x image_height.
 * runs: n_runs run lengths (>= 0, a first run of 0 allowed) summing to width * height exactly.
 * hue, sat: n_hs bytes each, n_hs 0 (no colour) or width * height. The image size must be the
 * mask size times one integer factor on both axes.
 * MVT_ERR_INVALID on any violation (size 0 or over MVT_MAX_MASK_PIXELS, non-integer or unequal
 * factors, negative run, sum mismatch, wrong n_hs, NULL with a non-zero count); mask is then
 * left empty (width = height = 0). O(width * height + n_runs); no memory beyond *mask. */
mvt_err_t mvt_mask_from_runs(mvt_mask_t *mask, int image_width, int image_height, int width, int height,
                             const int32_t *runs, int32_t n_runs, const uint8_t *hue, const uint8_t *sat,
                             int32_t n_hs);

/* 1 when a foreground pixel lies within r raw image pixels of the image point uv along each axis
 * (the square [u - r, u + r] x [v - r, v + r], at mask resolution the mask pixels it touches), 0
 * when none does, when the square misses the mask, or when the mask is empty (0 x 0) or uv or r is
 * not finite. The PKF's evidence that a person's place is empty in a view (mvt_trk_occl.c).
 * O(r^2 / scale^2), stopping at the first foreground pixel. */
int mvt_mask_fg_near(const mvt_mask_t *mask, const mvt_real uv[2], mvt_real r);

#ifdef __cplusplus
}
#endif

#endif /* MVT_MASK_H */
