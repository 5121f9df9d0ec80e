/*
 * mvt_trk.h - what the tracker's steps share (internal to the core): the estimation of one track
 * (mvt_trk_motion.c), its colour (mvt_trk_app.c), geometry and likelihood helpers (mvt_trk_geom.c).
 *
 * Each step reads and writes the tracker's per-frame workspaces; none allocates or prints.
 */
#ifndef MVT_TRK_H
#define MVT_TRK_H

#include "mvt_tracker.h"

/* Number of set bits (cameras in a mask). */
static inline int mvt_trk_popcount(uint32_t x)
{
    int n = 0;
    while (x != 0u) {
        x &= x - 1u;
        n++;
    }
    return n;
}

/* The lowest head top of a person standing, sitting or crouching, metres above the floor: a
 * silhouette's top lower than this is a leg fragment or a shadow on the floor, not a head. The
 * mask's tops measure only tracks whose head is at least this high (mvt_body_explain.c); the particle
 * filter's births use the same height (mvt_pft_config_t.birth_min_height_m, 1 m). */
#define MVT_TRK_MIN_HEAD_M MVT_R(1.0)

/* A head's top in a foreground mask (mvt_body_explain.c): half a head's width (m),
 * the band of image columns searched; a top narrower than MVT_TRK_TOP_MAX_WIDTH_M (m) in its first
 * rows (a wider one is a shoulder line or two heads side by side and says nothing of one head's
 * column); background for MVT_TRK_TOP_CLEAR_M (m) above it at its depth (a torso fragment under a
 * hole, or a shoulder's bump, has the head above it); and, since an outline has bumps a head's
 * width apart, nearer the prediction than a blob need be: chi-square 2 dof, 99 %. */
#define MVT_TRK_HEAD_HALFWIDTH_M MVT_R(0.11)
#define MVT_TRK_TOP_MAX_WIDTH_M MVT_R(0.3)
#define MVT_TRK_TOP_CLEAR_M MVT_R(0.3)
#define MVT_TRK_TOP_GATE_CHI2 MVT_R(9.21)

/* chi-square, 3 degrees of freedom, 99.9 %: a 3D estimate's gate (mvt_body_birth.c) */
#define MVT_TRK_GATE3 MVT_R(16.27)


/* Appearance (mvt_trk_app.c). A person's blobs do not all show their colour: a merged blob mixes two
 * people, a fragment shows only the legs, a shadow greys the mean. So a detection's chroma is the
 * person's, N(m, V I) with V = var (1 + 1/n) (the spread plus the mean's own uncertainty), with
 * probability 1 - MVT_TRK_APP_OUTLIER, and anywhere in the chroma disc (density 1 / pi)
 * otherwise. Its likelihood ratio against someone else's (or clutter's) blob, also anywhere in the
 * disc, is LR = (1 - eps) exp(-r^2 / 2V) / (2V) + eps, between eps and (1 - eps) / 2V + eps: an
 * odd colour can only cost -2 ln eps, however far it is. Measured on rendered scenes (blob chroma
 * of people's own detections against ground truth): spread per axis 0.08-0.34 (median 0.12-0.17),
 * people's means 0.11-0.94 apart (median 0.37-0.65), 10-32 % of a person's detections beyond three
 * robust standard deviations (docs/tracking.md, "Colour"). */
#define MVT_TRK_APP_OUTLIER MVT_R(0.2)
/* the spread a new person's colour is assumed to have until their own detections say (prior
 * weight MVT_TRK_APP_N0 detections), and the least it may shrink to (sensor noise), chroma units */
#define MVT_TRK_APP_SD0 MVT_R(0.15)
#define MVT_TRK_APP_N0 MVT_R(5.0)
#define MVT_TRK_APP_SD_MIN MVT_R(0.05)
/* the memory of the estimate, detections: about 2 s of 5 cameras, so that light that changes over a
 * room changes it, and a wrong person's few detections do not */
#define MVT_TRK_APP_NMAX MVT_R(250.0)

/* A detection's chroma from its hue and saturation; 0 when either is unknown or invalid. */
int mvt_trk_chroma(const mvt_detection_t *det, mvt_real a[2]);
/* The hue and saturation of an appearance's mean (the inverse of mvt_trk_chroma); -1 and -1 when
 * it has not been seen in colour. */
void mvt_trk_app_hue_sat(const mvt_app_t *app, mvt_real *hue, mvt_real *sat);
/* Resets an appearance to "not seen in colour". */
void mvt_trk_app_reset(mvt_app_t *app);
/* -2 ln LR of chroma a for appearance app (0 when app->n == 0), and its least value (a at m). */
mvt_real mvt_trk_app_cost(const mvt_app_t *app, const mvt_real a[2]);
mvt_real mvt_trk_app_cost_min(const mvt_app_t *app);
/* Adds a detection's chroma: weighted by the chance that it shows this person (the mixture above). */
void mvt_trk_app_update(mvt_app_t *app, const mvt_real a[2]);
/* A valid appearance (a checkpoint's): finite, m in the disc, var and n in range. */
int mvt_trk_app_ok(const mvt_app_t *app);

/* Mahalanobis distance squared of b from a, covariance S = Pa + Pb (3x3 each); < 0 if singular.
 * det (may be NULL) receives |S|. */
mvt_real mvt_trk_mahalanobis3(const mvt_real a[3], const mvt_real Pa[9], const mvt_real b[3], const mvt_real Pb[9],
                              mvt_real *det);

/* A blob's box (u0, v0, u1, v1) is usable: finite and not empty. */
int mvt_trk_box_ok(const mvt_real b[4]);
/* Image point uv lies in usable box b widened by slack_u, slack_v pixels. */
int mvt_trk_in_box(const mvt_real b[4], const mvt_real uv[2], mvt_real slack_u, mvt_real slack_v);
/* Boxes a and b (u0, v0, u1, v1) overlap. Written without short-circuits: each would be a branch
 * that the data decide, which the processor mispredicts often. */
static inline int mvt_trk_boxes_overlap(const mvt_real a[4], const mvt_real b[4])
{
    return (a[0] < b[2]) & (b[0] < a[2]) & (a[1] < b[3]) & (b[1] < a[3]);
}

/* The Gaussian density (1/px^2) of an innovation, N(y; 0, S); 0 when S is not positive definite. */
mvt_real mvt_trk_density(const mvt_pkf_innov_t *in);

/* The motion model's operations on a track (mvt_trk_motion.c): the single constant-velocity
 * filter on tr->s, or the IMM bank tr->imm with tr->s its combination. */
void mvt_trk_start(mvt_tracker_t *self, mvt_track_t *tr, const mvt_real x[3], const mvt_real cov[9], int64_t utime_us);
void mvt_trk_predict(mvt_tracker_t *self, mvt_track_t *tr, int64_t utime_us);
/* Within the per-camera pass (mvt_body.c) prediction and update keep only what projecting and
 * gating the next camera read: tr->s's x and the position block of its P (with an IMM bank the
 * velocity's covariance in tr->s is stale until mvt_trk_settle; the single filter is always whole).
 * in: the innovation against tr->s (mvt_pkf_innovation_from); extra_px2 as given to it (or NULL). */
void mvt_trk_predict_pos(mvt_tracker_t *self, mvt_track_t *tr, int64_t utime_us);
mvt_err_t mvt_trk_update_pkf(mvt_tracker_t *self, mvt_track_t *tr, int k, const mvt_pkf_innov_t *in,
                             const mvt_real *extra_px2);
/* The same for a head that shows (is not hidden behind another body) with probability `shown`
 * (0..1): the point is displaced (mvt_imm.h's impulsive noise) with prior 1 - shown (1 - p_outlier);
 * own_lr (> 0; 1: none) is other evidence's likelihood ratio of the person's head against displaced
 * (its blob's bottom: mvt_imm_update_view_lr). */
mvt_err_t mvt_trk_update_head(mvt_tracker_t *self, mvt_track_t *tr, int k, const mvt_pkf_innov_t *in,
                              const mvt_real *extra_px2, mvt_real shown, mvt_real own_lr);
void mvt_trk_settle(mvt_tracker_t *self, mvt_track_t *tr);
/* Camera k's head detection of tr at z (ideal pixels; in: its innovation, before any update;
 * gated: inside the gate). One beyond the gate that jumped off the view's last detection (further
 * than the head's picture moves in a frame, with both points' noise), which the view's memory took
 * for the head, while two other views place the person, begins a displacement of that view; one
 * beyond the gate that continues it (within its drift) keeps it, and two other views placing the
 * person confirm it. mvt_trk_update_head uses it as the view's memory while fewer views place the
 * person, its probability fading from the last confirmation as displacements end
 * (outlier_persist_s). */
void mvt_trk_onset_seen(mvt_tracker_t *self, mvt_track_t *tr, int k, const mvt_pkf_innov_t *in, const mvt_real z[2],
                        int gated);
/* After mvt_trk_update_head of camera k: the view's memory judged its detection displaced (the held
 * displacement continues; two other views placing the person confirm it) or not (it has ended). */
void mvt_trk_onset_judged(mvt_track_t *tr, int k);
/* mvt_trk_update_pixels within a camera's pass (position only, as mvt_trk_predict_pos) for a point
 * that is the body's with probability 1 - p_out (at least the motion model's p_outlier), else
 * anywhere within the outlier radius. */
mvt_err_t mvt_trk_update_pixels_robust(mvt_tracker_t *self, mvt_track_t *tr, const mvt_pkf_innov_t *in, mvt_real p_out);
mvt_err_t mvt_trk_update_point(mvt_tracker_t *self, mvt_track_t *tr, const mvt_real z[3], const mvt_real R[9]);
/* The triangulate-then-KF baseline's update (the paper's references [10, 18]): the views of obs
 * (n >= 2) that agree within thresh_px (mvt_tri_robust), their linear least-squares point and its
 * first-order covariance as one 3D measurement. *used: the inliers' camera bits. MVT_ERR_DEGENERATE
 * when no point comes of the views (fewer than two agree, parallel rays, behind a camera: nothing
 * changed); else the update's own error. */
mvt_err_t mvt_trk_update_triangulated(mvt_tracker_t *self, mvt_track_t *tr, const mvt_tri_obs_t *obs, int n,
                                      mvt_real thresh_px, uint32_t *used);
/* A whole (not position-only) update with a pixel innovation of any H on the position, without a
 * view's memory of displacement (the feet). */
mvt_err_t mvt_trk_update_pixels(mvt_tracker_t *self, mvt_track_t *tr, const mvt_pkf_innov_t *in);
mvt_err_t mvt_trk_truncate(mvt_tracker_t *self, mvt_track_t *tr, const mvt_real H[3], mvt_real value, mvt_real lo,
                           mvt_real hi);
mvt_err_t mvt_trk_truncate_ground(mvt_tracker_t *self, mvt_track_t *tr, const mvt_real H[3], mvt_real value,
                                  mvt_real extra_var, mvt_real lo, mvt_real hi);

/* Adds var (m^2) to the track's horizontal position variance along the unit vector H (H[2] = 0),
 * in every motion model: an estimate known to be wrong by about sqrt(var) there. */
void mvt_trk_widen_ground(mvt_tracker_t *self, mvt_track_t *tr, const mvt_real H[3], mvt_real var);
mvt_err_t mvt_trk_repair(mvt_tracker_t *self, mvt_track_t *tr);

/* The track's position is within the volume extended by volume.margin_m. */
int mvt_trk_inside_volume(const mvt_tracker_config_t *c, const mvt_real x[3]);

#endif /* MVT_TRK_H */
