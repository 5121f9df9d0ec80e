/*
 * mvt_mask.h - one camera's foreground mask and hue/saturation image (docs/interfaces.md section 1).
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
 * not finite. The PKF's evidence that a person's place is empty in a view (mvt_body_vis.c).
 * O(r^2 / scale^2), stopping at the first foreground pixel. */
int mvt_mask_fg_near(const mvt_mask_t *mask, const mvt_real uv[2], mvt_real r);

/* The top of a head in the column band [u - half_w, u + half_w] (raw image pixels) between the
 * image rows v_lo <= v_hi: the first mask row of that range with a foreground pixel in the band,
 * provided the mask is background above it for clear_px raw pixels (or up to the picture's top),
 * across the band and one pixel beyond each end of the run of foreground through that pixel. So
 * not a slope rising out of the band (whose first row in the band would follow the band wherever
 * it is put), not a fragment under a head (a torso below a hole), not the inside of a silhouette
 * that goes on above the range. Its point, in the convention of a connected component's top
 * (tools/mvtrack_tools/render.py): top_uv[0] the mean image column of the foreground in that row
 * and the next, over the run and one pixel beyond each end; top_uv[1] the row's upper quarter.
 * A run wider than max_width_px raw pixels (a shoulder line, two heads side by side) says
 * nothing of one head's column: 0. Returns 1 with top_uv set, 0 when there is no such top, when it
 * is on the mask's first row or its run reaches the first or last column (a silhouette cut by the
 * picture's edge, whose outline may rise beyond it), when the mask is empty or an argument is not
 * finite or negative. The PKF's measurement of a head that a merged blob's reported top does not
 * show (mvt_body_explain.c).
 * O((half_w / scale + 1) * (v_hi - v_lo + clear_px) / scale + max_width_px / scale), no memory. */
int mvt_mask_top_in_band(const mvt_mask_t *mask, mvt_real u, mvt_real half_w, mvt_real v_lo, mvt_real v_hi,
                         mvt_real max_width_px, mvt_real clear_px, mvt_real top_uv[2]);

#ifdef __cplusplus
}
#endif

#endif /* MVT_MASK_H */
