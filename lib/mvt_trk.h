/*
 * mvt_trk.h - the steps of mvt_tracker_step, one module each (internal to the core).
 *
 * Each step reads and writes the tracker's per-frame workspaces; none allocates or prints.
 */
#ifndef MVT_TRK_H
#define MVT_TRK_H

#include "mvt_tracker.h"

/* The views that place a track in a frame (seen_min_views, at most the rig's cameras). */
static inline int mvt_trk_min_views(const mvt_tracker_t *self)
{
    return self->cfg.rules.seen_min_views < self->num_cameras ? self->cfg.rules.seen_min_views : self->num_cameras;
}

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

/* The spread of a person's head-top height over seconds (gait bob, posture), metres: the height
 * cue of re-acquisition and of identity recovery. */
#define MVT_TRK_HEAD_SD_M MVT_R(0.04)
/* A track that fewer than two views place keeps its height within this many standard deviations
 * of the height last placed (mvt_trk_hold_height). */
#define MVT_TRK_HEIGHT_BAND MVT_R(3.0)
/* The lowest head top of a person standing, sitting or crouching, metres above the floor: a
 * silhouette's top lower than this is a leg fragment or a shadow on the floor, not a head. The
 * mask's tops measure only tracks whose head is at least this high (mvt_trk_occl.c); the particle
 * filter's births use the same height (mvt_pft_config_t.birth_min_height_m, 1 m). */
#define MVT_TRK_MIN_HEAD_M MVT_R(1.0)

/* A head's top in a foreground mask (mvt_trk_occl.c, mvt_body_explain.c): half a head's width (m),
 * the band of image columns searched; a top narrower than MVT_TRK_TOP_MAX_WIDTH_M (m) in its first
 * rows (a wider one is a shoulder line or two heads side by side and says nothing of one head's
 * column); background for MVT_TRK_TOP_CLEAR_M (m) above it at its depth (a torso fragment under a
 * hole, or a shoulder's bump, has the head above it); and, since an outline has bumps a head's
 * width apart, nearer the prediction than a blob need be: chi-square 2 dof, 99 %. */
#define MVT_TRK_HEAD_HALFWIDTH_M MVT_R(0.11)
#define MVT_TRK_TOP_MAX_WIDTH_M MVT_R(0.3)
#define MVT_TRK_TOP_CLEAR_M MVT_R(0.3)
#define MVT_TRK_TOP_GATE_CHI2 MVT_R(9.21)

/* How long the boxes' evidence for a hidden person is remembered (need_llr), s: a second of frames
 * outweighs one noisy box edge, and a person who left stops being needed within a few seconds. */
#define MVT_TRK_NEED_MEMORY_S MVT_R(1.0)
/* A track contradicted only by views whose foreground mask holds something at its place (its head
 * in foreground, in no blob another track took) is deleted after this many times contra_max_s; one
 * that views show on background, after contra_max_s. Foreground there is what a person merged into
 * a blob looks like when the track's prediction has left the blob's band, and it lasts as long as
 * the people stay merged; background is what an absent person looks like (docs/tracking.md,
 * "Empty places"). */
#define MVT_TRK_FG_CONTRA MVT_R(2.0)
/* chi-square, 3 degrees of freedom, 99.9 %: the gate of both */
#define MVT_TRK_GATE3 MVT_R(16.27)

/* A tentative track is confirmed only when its detections since birth are this much likelier
 * (log) from a person than from clutter, and deleted when they are this much likelier from clutter:
 * ln(99), a sequential test with 1 % error either way. In ordinary clutter a person's first frame
 * after the birth passes it; in a flood of false alarms a ghost's random detections do not. */
#define MVT_TRK_EXIST_LLR MVT_R(4.595)
/* A confirmed track's existence (exist_llr, the log odds that its person is there) is a two-state
 * Markov chain that switches each way at rate 1 / MVT_TRK_EXIST_MEMORY_S: what the cameras said a
 * minute ago is forgotten, and before a frame's evidence the odds lie within +-ln(1500) at 25 fps, so
 * that a track seen for a long time is not beyond the reach of what the cameras say now
 * (mvt_trk_existence). */
#define MVT_TRK_EXIST_MEMORY_S MVT_R(60.0)
/* Time over which the rate of births tried is averaged for their prior odds (mvt_trk_init.c), s */
#define MVT_TRK_BIRTH_RATE_S MVT_R(1.0)

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
/* A birth candidate's colour: the chroma of its inlier detections that carry one. */
typedef struct mvt_app_obs {
    int n;
    mvt_real a[MVT_MAX_CAMERAS][2];
} mvt_app_obs_t;
/* Sum of mvt_trk_app_cost over obs (independent views): what the colour says against app. */
mvt_real mvt_trk_app_obs_cost(const mvt_app_t *app, const mvt_app_obs_t *obs);
/* A valid appearance (a checkpoint's): finite, m in the disc, var and n in range. */
int mvt_trk_app_ok(const mvt_app_t *app);

/* Mahalanobis distance squared of b from a, covariance S = Pa + Pb (3x3 each); < 0 if singular.
 * det (may be NULL) receives |S|. */
mvt_real mvt_trk_mahalanobis3(const mvt_real a[3], const mvt_real Pa[9], const mvt_real b[3], const mvt_real Pb[9],
                              mvt_real *det);

/* Identity recovery (mvt_trk_recover.c). A confirmed track deleted while its person may still be
 * in the room (unseen, hidden too long, contradicted) leaves its identity, position and covariance
 * for recover_s. A birth within reach of such a record (the Mahalanobis distance
 * of the birth's point from the record, the record's covariance grown by walking pace times the
 * time since, heights compared with MVT_TRK_HEAD_SD_M) takes the nearest record's identity; a
 * tentative track that dies gives it back, one that is confirmed (mvt_trk_confirm, which sets the
 * status) keeps it. O(MVT_MAX_LOST) each. */
void mvt_trk_confirm(mvt_tracker_t *self, mvt_track_t *tr);
void mvt_trk_lose(mvt_tracker_t *self, const mvt_track_t *tr, int64_t now_us);
void mvt_trk_give_back(mvt_tracker_t *self, mvt_track_t *tr, int64_t now_us);
int32_t mvt_trk_recover(mvt_tracker_t *self, const mvt_real x[3], const mvt_real cov[9], const mvt_app_obs_t *obs,
                        int64_t now_us, mvt_lost_t *held);
/* Before a birth at x: a confirmed track that no camera placed this frame and whose place at least
 * contra_views views show in no blob another track took (contradicted, not yet deleted; one view's
 * empty place is as often one missed detection) and which passes the record test for x is deleted
 * into a record (counted as contradicted), unless a kept record is nearer; mvt_trk_recover then
 * gives its identity to the birth. Without it the birth came first and recovery could not act.
 * O(MVT_MAX_TARGETS + MVT_MAX_LOST). */
void mvt_trk_release_contradicted(mvt_tracker_t *self, const mvt_real x[3], const mvt_real cov[9],
                                  const mvt_app_obs_t *obs, int64_t now_us);

/* Hypothesise + associate for camera k (tracks already predicted to the camera's capture time):
 * fills assign[t] with the detection that updates track t (or -1) and merged[t] with 1 when that
 * detection is shared with unresolved tracks (its covariance is widened by merge_cov[t]). Marks
 * the assigned detections used. O(T * D) gating + O(cluster^2 * (cluster + D)) assignment. */
void mvt_trk_associate(mvt_tracker_t *self, const mvt_view_t *view, int k, int assign[MVT_MAX_TARGETS],
                       uint8_t merged[MVT_MAX_TARGETS]);

/* Occlusion hypotheses for camera k after associate (view: its detections and boxes, assign: as
 * filled by mvt_trk_associate): confirmed tracks left without a detection whose predicted head
 * lies in the box of a blob another track took are constrained to that box's column band and
 * marked in cameras_occluded. O(T * D). */
void mvt_trk_occlusion(mvt_tracker_t *self, const mvt_view_t *view, int k, const int assign[MVT_MAX_TARGETS]);

/* What a camera's blobs say of a head at x: */
typedef enum mvt_trk_evidence {
    MVT_TRK_NO_INFO = 0, /* outside the camera's field or picture (slack_px from the border) */
    MVT_TRK_COVERED = 1, /* inside a blob's box widened by slack_px: seen, or hidden in that blob */
    MVT_TRK_EMPTY = 2    /* in the picture and in no blob: that camera shows nobody there */
} mvt_trk_evidence_t;

/* A blob's box (u0, v0, u1, v1) is usable: finite and not empty. */
int mvt_trk_box_ok(const mvt_real b[4]);
/* Image point uv lies in usable box b widened by slack_u, slack_v pixels. */
int mvt_trk_in_box(const mvt_real b[4], const mvt_real uv[2], mvt_real slack_u, mvt_real slack_v);

/* The predicted heads of the seen (confirmed or coasting) tracks in camera k (the frame's
 * predictions, pred), raw pixels, with three standard deviations of the prediction and the pixel
 * noise: heads[i] = [u, v, margin u, margin v] of track who[i]. Returns their number. O(T). */
int mvt_trk_seen_heads(const mvt_tracker_t *self, int k, mvt_real heads[][4], int16_t who[]);

/* The view's evidence on a head at x (call only for a view with boxes). O(D). */
mvt_trk_evidence_t mvt_trk_view_evidence(const mvt_tracker_t *self, const mvt_view_t *view, int k,
                                         const mvt_real x[3], mvt_real slack_px);

/* The slack (pixels) around a birth candidate's image point: the birth radius of camera k. */
mvt_real mvt_trk_birth_radius_px(const mvt_tracker_t *self, int k);

/* Per observed camera, this frame's evidence weights (ev_boxes, ev_support, ev_empty, ev_clutter): a detection
 * within the birth radius of a place weighs ln((p_detect + (1 - p_detect) q) / q) for a person
 * there, q the chance that clutter puts one there (Poisson, from the view's detection count and
 * picture area, clamped to [0.01, 0.95]); a place in no blob weighs ln(1 - p_detect) (views with
 * boxes only: a view without boxes never shows a place empty). O(C D). */
void mvt_trk_evidence_weights(mvt_tracker_t *self, const mvt_frame_t *frame);

/* The Gaussian density (1/px^2) of an innovation, N(y; 0, S); 0 when S is not positive definite. */
mvt_real mvt_trk_density(const mvt_pkf_innov_t *in);

/* The existence evidence of a confirmed track (ev_llr, integrated PDA with visibility) that camera k
 * updated with innovation in: ln(1 - p_detect + p_detect N(in) / clutter density). */
mvt_real mvt_trk_detected_llr(const mvt_tracker_t *self, int k, const mvt_pkf_innov_t *in);

/* Before a frame's evidence: every confirmed track's existence odds through the chain of
 * MVT_TRK_EXIST_MEMORY_S over dt seconds. O(T). */
void mvt_trk_existence(mvt_tracker_t *self, mvt_real dt);

/* The log odds "a person is there" of a place that the cameras in support detect and `empty`
 * views show in no blob: the support weights less the two weakest (any two rays that meet make a
 * candidate, so two views prove nothing), plus empty * ev_empty. O(C). */
mvt_real mvt_trk_odds(const mvt_tracker_t *self, uint32_t support, int empty);

/* Exclusion after the frame's updates: every confirmed track seen in fewer than seen_min_views
 * cameras is kept exclusion_m (horizontally) from every track seen in at least that many. O(T^2). */
void mvt_trk_exclusion(mvt_tracker_t *self);

/* After the frame's updates: a confirmed track seen in fewer than seen_min_views cameras keeps its
 * head height within MVT_TRK_HEIGHT_BAND standard deviations of the height last seen (seen_z,
 * its variance plus MVT_TRK_HEAD_SD_M squared). O(T). */
void mvt_trk_hold_height(mvt_tracker_t *self);

/* Confirmation, coasting and deletion after the frame's updates. O(T). */
void mvt_trk_delete(mvt_tracker_t *self, int64_t now_us);

/* Births from detections no track used that agree in >= birth_min_views views. order[] are the
 * observed cameras. O(C^2 D^2) cheap epipolar tests + O(candidates * C * D). */
void mvt_trk_initiate(mvt_tracker_t *self, const mvt_frame_t *frame, const int order[], int n_order);

/* Multi-view candidates from the free detections of this frame (>= birth_min_views views, birth
 * odds >= 1) into self->cand, best first (most views, then least reprojection error). count: 1
 * to count refuted and dropped candidates (births), 0 not to (a second look in the same frame). */
void mvt_trk_candidates(mvt_tracker_t *self, const mvt_frame_t *frame, const int order[], int n_order, int count);

/* A candidate's point: robust triangulation (>= birth_min_views inliers, inside the volume) and
 * its first-order covariance; inliers: bit i for cand->cam[i]. 1 on success. */
int mvt_trk_cand_point(mvt_tracker_t *self, const mvt_birth_cand_t *cand, mvt_real x[3], mvt_real cov[9],
                       uint32_t *inliers);

/* Re-acquisition before the per-camera association (mvt_trk_reacq.c). O(C^2 D^2 + T^2 (T + D)). */
void mvt_trk_reacquire(mvt_tracker_t *self, const mvt_frame_t *frame, const int order[], int n_order);

/* The motion model's operations on a track (mvt_trk_motion.c): the single constant-velocity
 * filter on tr->s, or the IMM bank tr->imm with tr->s its combination. */
void mvt_trk_start(mvt_tracker_t *self, mvt_track_t *tr, const mvt_real x[3], const mvt_real cov[9], int64_t utime_us);
void mvt_trk_predict(mvt_tracker_t *self, mvt_track_t *tr, int64_t utime_us);
/* Within the per-camera loop (step_projective) prediction and update keep only what projecting and
 * gating the next camera read: tr->s's x and the position block of its P (with an IMM bank the
 * velocity's covariance in tr->s is stale until mvt_trk_settle; the single filter is always whole).
 * in: the innovation against tr->s (mvt_pkf_innovation_from); extra_px2 as given to it (or NULL). */
void mvt_trk_predict_pos(mvt_tracker_t *self, mvt_track_t *tr, int64_t utime_us);
mvt_err_t mvt_trk_update_pkf(mvt_tracker_t *self, mvt_track_t *tr, int k, const mvt_pkf_innov_t *in,
                             const mvt_real *extra_px2);
/* The same for a head that shows (is not hidden behind another body) with probability `shown`
 * (0..1): the point is displaced (mvt_imm.h's impulsive noise) with prior 1 - shown (1 - p_outlier). */
mvt_err_t mvt_trk_update_head(mvt_tracker_t *self, mvt_track_t *tr, int k, const mvt_pkf_innov_t *in,
                              const mvt_real *extra_px2, mvt_real shown);
void mvt_trk_settle(mvt_tracker_t *self, mvt_track_t *tr);
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
/* The estimate tr->s predicted to utime_us into out, the track unchanged. */
void mvt_trk_predicted(const mvt_tracker_t *self, const mvt_track_t *tr, int64_t utime_us, mvt_cv_state_t *out);

/* The track's position is within the volume extended by volume.margin_m. */
int mvt_trk_inside_volume(const mvt_tracker_config_t *c, const mvt_real x[3]);

#endif /* MVT_TRK_H */
