/*
 * mvt_pf.h - 3D particle filter weighted directly by motion masks and colour (second paper).
 *
 * Building blocks of one target's bootstrap filter; mvt_pft runs them for every target.
 *   likelihood image  D = max(g_sigma * M, p_B) (Eq. 8) per camera and frame, quantised to 8 bits
 *                     and shared by every target; hue/saturation stay in the mask
 *   predict           constant velocity (Eq. 14 / 15), isotropic Gaussian noise
 *   weight            sum over cameras of log D at each particle's projection, plus with colour the
 *                     log of Eq. 11 and Eq. 13 (circular hue distance min(|dH|, 1 - |dH|), not the
 *                     printed 1/2 - |dH|), all from 256-entry tables. Two particle models:
 *                       point   (the paper) a particle is a point of the body, scored where it projects
 *                       column  a particle is a hypothesis of the head top; each camera scores the
 *                               vertical segment under it (head, torso, legs on foreground) and a
 *                               point above it (on background), colour at the torso point
 *   estimate          weighted mean, covariance, the P_H volume (axis-aligned box of the fewest
 *                     heaviest particles accumulating P_H), head height, hue and saturation
 *   resample          systematic, when the effective sample size falls below a threshold
 * Random numbers: PCG32 (O'Neill 2014), seeded; identical seeds give identical runs.
 * No allocation: the caller owns every pool, image and workspace.
 */
#ifndef MVT_PF_H
#define MVT_PF_H

#include "mvt_camera.h"
#include "mvt_mask.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Largest blur radius in mask pixels (3 sigma); larger sigmas are clamped to it. */
#define MVT_PF_MAX_RADIUS 24
/* The likelihood level that is evidence neither way (D = 1/2): a point outside a camera's image
 * or on pixels another target has claimed. */
#define MVT_PF_LEVEL_UNKNOWN 128u
/* Rows a blur workspace can flag (mask height is at most the image height, < 32768). */
#define MVT_PF_MAX_ROWS (MVT_MAX_MASK_PIXELS < 32768 ? MVT_MAX_MASK_PIXELS : 32768)

typedef struct mvt_rng {
    uint64_t state, inc;
} mvt_rng_t;

/* Seeds a PCG32 generator; stream selects one of 2^63 independent sequences. O(1). */
void mvt_rng_seed(mvt_rng_t *rng, uint64_t seed, uint64_t stream);
uint32_t mvt_rng_u32(mvt_rng_t *rng);
/* Uniform in [0, 1). */
mvt_real mvt_rng_uniform(mvt_rng_t *rng);
/* Two independent standard normal numbers (Box-Muller, no rejection loop). */
void mvt_rng_normal2(mvt_rng_t *rng, mvt_real out[2]);

/* The measurement model (Eq. 8, 11, 13). */
typedef struct mvt_pf_model {
    mvt_real sigma_px;  /* motion blur sigma at full image resolution, pixels, > 0; default 4 */
    mvt_real p_b;       /* background probability of D, (0, 1); default 0.2 */
    mvt_real sigma_h;   /* hue noise, (0, 0.5]; default 0.05 */
    mvt_real sigma_s;   /* saturation noise, (0, 1]; default 0.1 */
    mvt_real h_b, s_b;  /* background levels of Eq. 11 and 13, [0, 1); default 0.1, 0.1 */
} mvt_pf_model_t;

/* Tables derived once from a model (mvt_pf_tables_init). */
typedef struct mvt_pf_tables {
    mvt_real log_d[256];   /* log(max(l / 255, p_B)) */
    mvt_real log_bg[256];  /* log(max(1 - l / 255, p_B)): a point expected on background */
    mvt_real log_h[129];   /* log of Eq. 11 at circular hue distance k / 256 */
    mvt_real log_s[256];   /* log of Eq. 13 at saturation distance k / 255 */
    mvt_real log_colour_background; /* log(h_B s_B): colour term where the mask is background */
    uint8_t d_floor;       /* quantised p_B */
} mvt_pf_tables_t;

/* Fills the tables; MVT_ERR_INVALID when a model parameter is outside its range. O(640). */
mvt_err_t mvt_pf_tables_init(mvt_pf_tables_t *tab, const mvt_pf_model_t *model);

/* One camera's motion likelihood image for this frame. */
typedef struct mvt_pf_image {
    int width, height, scale;       /* 0 x 0: no mask from this camera this frame */
    const mvt_mask_t *mask;         /* hue / saturation source (the caller's, valid for the frame) */
    uint8_t d[MVT_MAX_MASK_PIXELS]; /* round(255 max(g * M, p_B)), row-major */
} mvt_pf_image_t;

/* Index of the mask pixel holding raw image pixel (u, v), or -1 outside the mask. O(1). */
static inline int mvt_pf_image_index(const mvt_pf_image_t *img, mvt_real u, mvt_real v)
{
    const mvt_real mu = (u + MVT_R(0.5)) / (mvt_real)img->scale, mv = (v + MVT_R(0.5)) / (mvt_real)img->scale;
    if (!(mu >= MVT_R(0.0) && mv >= MVT_R(0.0) && mu < (mvt_real)img->width && mv < (mvt_real)img->height)) {
        return -1;
    }
    return (int)mv * img->width + (int)mu;
}

/* Blur workspace (shared by every camera, one at a time). */
typedef struct mvt_pf_blur_ws {
    uint16_t h[MVT_MAX_MASK_PIXELS];   /* horizontal pass */
    uint8_t row_any[MVT_PF_MAX_ROWS];  /* row of the horizontal pass has foreground */
} mvt_pf_blur_ws_t;

/* Builds D from mask (NULL or empty: img marked absent) with a discrete Gaussian of
 * sigma_px / scale mask pixels, radius ceil(3 sigma) <= MVT_PF_MAX_RADIUS, zero outside the mask,
 * separable and in fixed point (error below 1/255 + 1e-4 against the exact convolution).
 * O(width * height * (2 radius + 1)) worst case; rows without foreground near them cost O(width). */
void mvt_pf_image_build(mvt_pf_image_t *img, const mvt_mask_t *mask, const mvt_pf_tables_t *tab,
                        mvt_real sigma_px, mvt_pf_blur_ws_t *ws);

/* Normalised-coordinate window of a camera's image (plus a margin): particles outside it are not
 * projected through the lens model, whose polynomial can fold far-away points back into the image. */
typedef struct mvt_pf_fov {
    mvt_real x_min, x_max, y_min, y_max;
} mvt_pf_fov_t;

/* From the undistorted image border (32 points per side) widened by margin (fraction of the
 * size). A border point the model cannot invert narrows nothing: the pinhole bound is used. */
void mvt_pf_fov_init(mvt_pf_fov_t *fov, const mvt_camera_t *cam, mvt_real margin);

/* Where the world point xw falls in camera cam's likelihood image: 1 on foreground (above
 * halfway from the floor to 1, as the weighting's support counts it), 0 on background, -1 unseen
 * (no image this frame, behind the camera, outside the lens model's window or the mask). O(1). */
int mvt_pf_point_on_fg(const mvt_camera_t *cam, const mvt_pf_fov_t *fov, const mvt_pf_image_t *img,
                       const mvt_pf_tables_t *tab, const mvt_real xw[3]);

/* One target's particles, structure of arrays. */
typedef struct mvt_pf_pool {
    int n;                                   /* particles, 1..MVT_MAX_PARTICLES */
    mvt_real x[MVT_MAX_PARTICLES], y[MVT_MAX_PARTICLES], z[MVT_MAX_PARTICLES];    /* m */
    mvt_real vx[MVT_MAX_PARTICLES], vy[MVT_MAX_PARTICLES], vz[MVT_MAX_PARTICLES]; /* m/s */
    mvt_real h[MVT_MAX_PARTICLES], s[MVT_MAX_PARTICLES]; /* colour state, [0, 1) and [0, 1] */
    mvt_real w[MVT_MAX_PARTICLES];           /* log weight while weighting; normalised after */
} mvt_pf_pool_t;

/* Process noise of the constant-velocity model (continuous white noise on each state). */
typedef struct mvt_pf_noise {
    mvt_real pos_m2s;    /* position diffusion, m^2/s, >= 0: std sqrt(pos_m2s dt) per axis */
    mvt_real vel_m2s3;   /* velocity diffusion, m^2/s^3, >= 0 */
    mvt_real colour_1s;  /* hue and saturation diffusion, 1/s, >= 0 */
    mvt_real z_renew;    /* probability per prediction that a particle's height is drawn anew,
                            uniform in [z_min, z_max], with zero vertical velocity, [0, 1] */
    mvt_real z_min, z_max; /* m */
    mvt_real pos_z_m2s;  /* vertical position diffusion, m^2/s, >= 0 */
    mvt_real vel_z_m2s3; /* vertical velocity diffusion, m^2/s^3, >= 0 */
} mvt_pf_noise_t;

/* x += v dt + noise, v += noise (horizontal and vertical diffusions apart), colour += noise (hue wrapped, saturation clamped to [0, 1]); then
 * with probability z_renew the height is drawn anew. A particle is a point of the person's body,
 * not one material point: which body point it is has no memory, and a random walk alone would
 * take thousands of frames to spread the cloud over a body's height. dt_s >= 0. O(n). */
void mvt_pf_predict(mvt_pf_pool_t *pool, mvt_real dt_s, const mvt_pf_noise_t *noise, mvt_rng_t *rng);

/* The column model's body: where, under a head-top hypothesis at height z, each camera looks. */
typedef struct mvt_pf_body {
    mvt_real above_m;    /* a point this far above the top should be background, > 0; default 0.06 */
    mvt_real head_m;     /* a point this far under the top should be foreground (the head), > 0;
                            default 0.06 */
    mvt_real torso_frac; /* torso point at this fraction of z (colour is scored here), (0, 1);
                            default 0.7 */
    mvt_real legs_frac;  /* legs point at this fraction of z, (0, 1); default 0.3 */
    mvt_real min_top_m;  /* lowest head top (mvt_pft reflects hypotheses below it: a shadow on the
                            floor is a perfect column of height ~0, and the legs of two people
                            one of height ~0.9 m), >= 0; default 1.1 (a seated adult's head is
                            higher) */
    mvt_real face_m;     /* a second point this far under the top should be foreground too (the
                            face), >= 0, 0: none; default 0.16. With one head point, a hypothesis
                            far above the head costs only that point: the likelihood along z had a
                            plateau above the head 1.6 nats under its peak (5 cameras), and tall
                            people's heights ran off to it; with the face point it is 5-6 nats */
    mvt_real clear_m;    /* the column from clear_m / 3 to clear_m above the top should be
                            background as well, >= 0, 0: not scored; default 0.9. Scored once, at the
                            largest D of three points clear_m / 3 apart: a "top" on the legs under
                            a hole (a shirt the colour of the wall) has the rest of the body above
                            it, and that fragment otherwise scored as well as the true top */
} mvt_pf_body_t;

/* Pixels that other targets already explain (mvt_pft shares each camera's pixels out between its
 * targets). Per mask pixel: 0 when no other target's silhouette covers it, else the quantised
 * camera depth of the nearest one that does (mvt_pf_claim_depth). */
typedef struct mvt_pf_claims {
    int width, height;                  /* as the camera's image this frame; 0 x 0: no claims */
    uint8_t depth[MVT_MAX_MASK_PIXELS]; /* row-major */
} mvt_pf_claims_t;

/* Depth step of the claims, m: depths 0..12.7 m are told apart, farther ones are all "far". */
#define MVT_PF_CLAIM_STEP_M MVT_R(0.05)

/* 1 + floor(z / MVT_PF_CLAIM_STEP_M), in 1..255. O(1). */
static inline uint8_t mvt_pf_claim_depth(mvt_real z)
{
    const mvt_real q = z / MVT_PF_CLAIM_STEP_M;
    return (uint8_t)(q >= MVT_R(254.0) ? 255 : (q > MVT_R(0.0) ? 1 + (int)q : 1));
}

/* Adds to pool->w exponent times each camera's log-likelihood (images with width 0 are skipped).
 * body NULL (point model): log D at the particle's pixel. body set (column model): log D at the
 * head, face (when face_m > 0), torso and legs points plus log max(1 - D, p_B) at the point above
 * the top and (clear_m > 0) at the largest D of the three points higher up. With colour (use_colour and the camera's mask has colour), the scored point (point model: the
 * particle; column model: the torso point) adds on foreground the log of Eq. 11 x Eq. 13 at its
 * pixel, on background log(h_B s_B). A point outside the image or behind the camera reads D = 1/2:
 * the camera saw nothing there (as background it pulled every column a camera sees only in part,
 * head above the image or feet below it, into the image and onto the body's lower half; measured
 * on rendered video, docs/particle-filter.md). Its colour term is log(h_B s_B).
 * claims (may be NULL; else one per camera, width 0 for none): a point on a pixel another target
 * explains reads D = 1/2 whatever the mask says. Another silhouette makes that pixel foreground
 * whether or not this target is there too, so it is evidence neither way (the likelihood ratio of
 * a union of silhouettes). Its colour is scored only when this target's point is the nearer
 * (otherwise log(h_B s_B)): the nearer body is the one whose colour the camera sees.
 * on_fg[k] (may be NULL) receives, per camera, the fraction of particles (unweighted) whose
 * particle (column model: head point) has D above the midpoint between p_B and 1 on a pixel no
 * other target claims; hidden[k] (may be NULL) the fraction whose point (column model: head point)
 * the view cannot judge: on a claimed pixel (another target explains what it sees) or outside the
 * image.
 * O(n * num_cams) projections (column model: 4 to 8 per particle and camera). */
void mvt_pf_weight(mvt_pf_pool_t *pool, const mvt_camera_t *cams, const mvt_pf_fov_t *fovs,
                   const mvt_pf_image_t *images, int num_cams, const mvt_pf_tables_t *tab, int use_colour,
                   const mvt_pf_body_t *body, mvt_real exponent, const mvt_pf_claims_t *claims,
                   mvt_real on_fg[], mvt_real hidden[]);

/* Turns log weights into normalised weights (max-subtracted, so no underflow to all zeros) and
 * returns the effective sample size 1 / sum(w^2), in [1, n]. A pool whose log weights are not all
 * finite gets uniform weights and returns 0 (the caller counts a numeric fault). O(n). */
mvt_real mvt_pf_normalise(mvt_pf_pool_t *pool);

typedef struct mvt_pf_estimate {
    mvt_real mean[3], vel[3];   /* weighted means, m and m/s */
    mvt_real cov[6];            /* weighted position covariance xx xy xz yy yz zz, m^2 */
    mvt_real box_min[3], box_max[3]; /* axis-aligned box of the P_H volume */
    int box_count;              /* particles in the P_H set */
    mvt_real head_z;            /* weighted quantile head_quantile of z, m */
    mvt_real hue, saturation;   /* weighted circular mean of h, mean of s */
} mvt_pf_estimate_t;

/* Estimates from normalised weights. order: workspace of n entries. p_h in (0, 1], head_quantile
 * in [0, 1] (0: head_z is the mean z, for particles that are head hypotheses). O(n log n) (one or
 * two heap sorts, no recursion). */
void mvt_pf_estimate(const mvt_pf_pool_t *pool, mvt_real p_h, mvt_real head_quantile,
                     uint16_t order[MVT_MAX_PARTICLES], mvt_pf_estimate_t *est);

/* Systematic resampling into scratch, then copied back; weights become 1/n. O(n). */
void mvt_pf_resample(mvt_pf_pool_t *pool, mvt_rng_t *rng, mvt_pf_pool_t *scratch);

#ifdef __cplusplus
}
#endif

#endif /* MVT_PF_H */
