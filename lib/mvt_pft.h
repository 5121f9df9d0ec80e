/*
 * mvt_pft.h - multi-target tracking with one 3D particle filter per person (second paper).
 *
 * Per frame set:
 *   images    each camera's motion likelihood image from its mask (mvt_pf_image_build), once,
 *             shared by all targets
 *   propose   the blob-level tracker (mvt_tracker, detections derived from the masks) runs
 *             alongside; a confirmed blob track farther than birth_sep_m from every particle
 *             target proposes a birth. It never moves a particle target.
 *   filter    per target: constant-velocity prediction, an exclusion prior (particles inside
 *             another target's body, horizontally within exclusion_m of its predicted centre, lose
 *             up to exclusion_log of log weight: two filters cannot both explain one person's
 *             pixels), the per-camera motion and colour likelihoods, normalisation, estimates,
 *             systematic resampling when ESS < ess_fraction * n
 *   lifecycle a camera supports a target when at least support_fraction of its particles project
 *             onto foreground; a target supported by fewer than support_min_views cameras (capped
 *             by the cameras that sent masks) for lost_s is deleted; so is one that leaves the
 *             volume (plus margin) or comes within dup_dist_m (horizontally) of a stronger target.
 *             A new target stays TENTATIVE until supported in confirm_frames frames and is deleted
 *             when unsupported for tentative_lost_s meanwhile (blob-level ghosts die there)
 * Output per target: position = the weighted mean (column model: particles are head tops) or
 * the mean x, y with the head height found by scanning the masks down the column above it (point
 * model: the particles fill the body, the tracked point is the head top), velocity,
 * particle covariance, the P_H volume's box as extent, the colour estimate (MS+C).
 * Identities count up from 1, never reused. The caller owns the mvt_pft_t.
 */
#ifndef MVT_PFT_H
#define MVT_PFT_H

#include "mvt_pf.h"
#include "mvt_tracker.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mvt_pft_config {
    mvt_tracker_config_t det;   /* the blob-level tracker proposing births (mvt_tracker_config_default) */
    mvt_pf_model_t model;       /* likelihoods: sigma_px 4, p_b 0.2, sigma_h 0.05, sigma_s 0.1,
                                   h_b 0.5, s_b 0.5 */
    mvt_pf_noise_t noise;       /* pos 0.02 m^2/s, vel 1.0 m^2/s^3, colour 0.005 1/s, z_renew 0.2
                                   over z 0..2.2 m (point model only; the column model never
                                   renews heights), vertical pos 0.002 m^2/s and vel 0.1 m^2/s^3
                                   (column model: a head top moves up and down a tenth as much as
                                   sideways; the point model diffuses isotropically) */
    int column;                 /* 1 (default): column model, a particle is a head-top hypothesis
                                   scored along the body under it (mvt_pf_weight); 0: the paper's
                                   point model, a particle is a point of the body */
    mvt_pf_body_t body;         /* column model: above 0.06 m, head 0.06 m, torso 0.7, legs 0.3,
                                   lowest top 1.1 m, face 0.16 m, clear 0.9 m */
    int num_particles;          /* per target, 16..MVT_MAX_PARTICLES; default MVT_MAX_PARTICLES */
    int use_colour;             /* 1 (default): MS+C for cameras that send hue/saturation; 0: MS */
    mvt_real lik_exponent;      /* each camera's log-likelihood is multiplied by this, (0, 1]: the
                                   cameras' masks are not independent views of one point; default 1 */
    mvt_real ess_fraction;      /* resample when ESS < ess_fraction * n; (0, 1], default 0.5 */
    mvt_real p_h;               /* probability of the bounding volume, (0, 1]; default 0.95 */
    mvt_real head_quantile;     /* point model: z quantile reported as the head height, (0, 1];
                                   default 0.97 (the column model reports the mean) */
    mvt_real exclusion_m;       /* >= 0 (0: off, the paper's independent filters); default 0.5 */
    mvt_real exclusion_log;     /* >= 0; default 8 */
    mvt_real birth_sep_m;       /* > 0; default 0.5 */
    mvt_real birth_min_height_m;/* a blob track lower than this (a fragment: legs, a shadow) proposes
                                   no birth; default 1.0 (standing people) */
    mvt_real birth_xy_std_m;    /* initial horizontal spread (column model: also the head
                                   height's), > 0; default 0.1 */
    mvt_real dup_dist_m;        /* >= 0; default 0.2 */
    mvt_real support_fraction;  /* (0, 1]; default 0.25 */
    int support_min_views;      /* >= 1; default 2 */
    mvt_real lost_s;            /* > 0; default 0.5 (1.0 before the face point and shared pixels: a
                                   target lingered 1 s after its person left through a door) */
    int confirm_frames;         /* a new target is TENTATIVE until supported in this many frames,
                                   >= 1; default 5 */
    mvt_real tentative_lost_s;  /* a tentative target unsupported this long is deleted, > 0;
                                   default 0.2 */
    int share_pixels;           /* 1 (default): each camera's pixels are shared out between the
                                   targets (mvt_pf_claims_t): the targets are weighted one after
                                   another, strongest first (strength with this frame's
                                   evidence folded in: where the predicted body falls on
                                   foreground; then confirmed before tentative, then the
                                   older), and each one's
                                   silhouette at its new estimate claims its pixels for the targets
                                   after it; a camera where most of a target's head hypotheses are
                                   on claimed pixels cannot tell whether it is there (hidden), and
                                   hidden views do not count against it; 0: independent targets
                                   (every target reads every pixel) */
    mvt_real body_radius_m;     /* share_pixels: a target's silhouette is the image box of a
                                   vertical cylinder of this radius from the floor to its head
                                   top, > 0; default 0.25 (shoulders) */
    mvt_real recover_s;         /* identity recovery: a target deleted as lost keeps its identity this
                                   long for a new target born from the blob track it was following
                                   (the blob tracker kept the person; the filter lost them); >= 0,
                                   default 3; 0: off */
    uint64_t seed;              /* random number seed; default 1 */
} mvt_pft_config_t;

typedef struct mvt_pft_target {
    int32_t id;                 /* 0: free slot */
    int32_t status;             /* MVT_TRACK_TENTATIVE (fewer than confirm_frames supported frames
                                   since birth), _CONFIRMED (supported this frame) or _COASTING */
    int32_t supported_frames;   /* since birth, saturating at confirm_frames */
    uint32_t cameras_used;      /* supporting cameras this frame */
    int64_t last_supported_us;
    int32_t blob_id;            /* the confirmed blob track it coincides with (0: none yet) */
    int64_t recover_until_us;   /* tentative with a recovered identity: until when it may give it
                                   back; 0 otherwise */
    mvt_real ess;               /* effective sample size this frame, before resampling */
    mvt_real strength;          /* share of the cameras that could see it which supported it,
                                   smoothed over about 1 s (exponential, from 0 at birth): the
                                   order pixels are shared out in, and who stays of two duplicates */
    mvt_pf_estimate_t est;
    mvt_pf_pool_t pool;
} mvt_pft_target_t;

typedef struct mvt_pft_counters {
    uint64_t frames;
    uint64_t frames_time_backwards;
    uint64_t views_without_mask;     /* observed views that carried no mask */
    uint64_t births;
    uint64_t births_refused_full;    /* MVT_MAX_TARGETS reached */
    uint64_t deleted_lost;
    uint64_t deleted_tentative;      /* never confirmed */
    uint64_t deleted_outside;
    uint64_t deleted_duplicate;
    uint64_t identities_recovered;   /* targets confirmed with a lost target's identity */
    uint64_t views_hidden;           /* target-views where the head was behind a nearer target's pixels or outside the image */
    uint64_t resamples;
    uint64_t numeric_faults;         /* non-finite weights: reset to uniform */
} mvt_pft_counters_t;

typedef struct mvt_pft {
    mvt_pft_config_t cfg;
    mvt_tracker_t det;
    mvt_pf_fov_t fovs[MVT_MAX_CAMERAS];
    mvt_pf_tables_t tab;
    mvt_rng_t rng;
    mvt_pft_target_t targets[MVT_MAX_TARGETS];
    int32_t next_id;
    struct {                    /* identities of targets lost recently (recover_s) */
        int32_t id, blob_id;
        int64_t until_us;
    } lost[MVT_MAX_TARGETS];
    int64_t last_utime_us;
    int have_time;
    mvt_pft_counters_t counters;
    /* per-frame workspaces */
    mvt_pf_image_t images[MVT_MAX_CAMERAS];
    mvt_pf_blur_ws_t blur;
    mvt_pf_pool_t scratch;
    uint16_t order[MVT_MAX_PARTICLES];
    mvt_output_t det_out;
    mvt_real centre[MVT_MAX_TARGETS][3];  /* targets' predicted centres for the exclusion prior */
    mvt_pf_claims_t claims[MVT_MAX_CAMERAS]; /* share_pixels: what the targets weighted so far explain */
    int16_t rank[MVT_MAX_TARGETS];        /* share_pixels: the order the targets are weighted in */
    mvt_real rank_key[MVT_MAX_TARGETS];   /* share_pixels: strength with this frame's evidence (ranking) */
} mvt_pft_t;

/* Documented defaults (det: mvt_tracker_config_default). */
void mvt_pft_config_default(mvt_pft_config_t *cfg);

/* Checks cfg and the cameras, resets. MVT_ERR_INVALID on a bad configuration. */
mvt_err_t mvt_pft_init(mvt_pft_t *self, const mvt_pft_config_t *cfg, const mvt_camera_t *cams, int num_cameras);

/* One frame set; views may carry masks (mvt_view_t.mask). Cost per frame:
 * O(sum of mask pixels * (2 r + 1)) for the images + O(T * n * C) weighting + O(T * n log n)
 * estimates + the blob tracker's. MVT_ERR_INVALID (counted, state unchanged) when time goes back. */
mvt_err_t mvt_pft_step(mvt_pft_t *self, const mvt_frame_t *frame, mvt_output_t *out);

/* The particle filter's persistent part (see mvt_tracker_persist_t): its targets with their
 * particles, identities, the identities kept for recovery, the random generator, clock, counters,
 * and the blob tracker's own. */
typedef struct mvt_pft_persist {
    mvt_tracker_persist_t det;
    mvt_pft_target_t targets[MVT_MAX_TARGETS];
    int32_t next_id;
    int32_t have_time;
    int64_t last_utime_us;
    struct {
        int32_t id, blob_id;
        int64_t until_us;
    } lost[MVT_MAX_TARGETS];
    mvt_rng_t rng;
    mvt_pft_counters_t counters;
} mvt_pft_persist_t;

void mvt_pft_save(const mvt_pft_t *self, mvt_pft_persist_t *out);

/* As mvt_tracker_resume: the whole state is checked first (pool sizes equal to the configured
 * num_particles, particles and weights finite, weights normalised, identities unique), then
 * copied; unobserved_us moves the targets' support and recovery clocks. */
mvt_err_t mvt_pft_resume(mvt_pft_t *self, const mvt_pft_persist_t *p, int64_t unobserved_us);

/* Published identities (the targets') and the blob tracker's from now on are >= first. */
void mvt_pft_reserve_ids(mvt_pft_t *self, int32_t first);

#ifdef __cplusplus
}
#endif

#endif /* MVT_PFT_H */
