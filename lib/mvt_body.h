/*
 * mvt_body.h - one model of a person: the steps of a frame, one file each
 * (internal to the core; docs/tracking.md gives the reasoning).
 *
 * A person is a head top at (x, y, z) over a body that stands on the floor, 2 body.halfwidth_m wide.
 * Its silhouette in a camera is the box around the projections (lens included) of the head's and
 * the feet's left and right edges. A blob that a camera reports is one of: the head of a person
 * (its top is the head's top; a merged blob's top is the top-most head it holds), a fragment of a
 * person's silhouette (its top lies inside a tracked body, below that body's head), or clutter.
 * Each track carries the log odds that its person is in the volume; the cameras' evidence moves
 * them as the integrated PDA does (Musicki, Evans and Stankovic, IEEE TAC 39(6), 1994), each camera
 * with the detection probability of that head in that picture; confirmation and deletion are
 * thresholds on them.
 *
 * One frame (mvt_body_step, in mvt_body.c; no step calls another, each reads what the previous
 * wrote in the workspace mvt_body_ws_t and nothing older):
 *   existence    survival over dt: a person leaves at rate 1 / stay_s, near a side wall at
 *                1 / exit_s more; after an outage (MVT_BODY_GAP_FRAMES) every shown track sleeps
 *   per observed camera, in capture-time order:
 *     predict     each track's estimate to the camera's capture time (mvt_trk_motion.c)
 *     visibility  mvt_body_vis.c: each track's predicted head and silhouette; the probability that
 *                 the camera reports the head: p_detect inside the picture, less where the silhouette
 *                 of a body likely present covers it (hidden, or merged under that body's top),
 *                 unless the camera's mask shows background there
 *     explain     mvt_body_explain.c: per camera, a global assignment of blobs to heads on the
 *                 likelihood ratio of head against clutter; a blob left over whose top lies on a
 *                 tracked silhouette past its head, or by its feet, is that body's fragment when
 *                 its fragment density beats clutter; a head in another body's blob is hosted;
 *                 a shown head no blob reports is the mask's top in its column; the rest unexplained
 *     update      mvt_body_update.c: a head (a blob's, or the mask's top) updates its track (PKF),
 *                 weighed by its blob's bottom where that shows the feet, which then update it too;
 *                 a hosted head's column stays in its host's box, whose edges that only its body
 *                 makes measure it; the existence takes the camera's evidence: detected (against
 *                 clutter and other bodies' fragments), hosted (with the merged box's edges), missed with a fragment
 *                 of the body in view (no evidence), or missed; the camera's clutter rate,
 *                 detection probability and fragment rate are learnt
 *   triangulate  kf only (MVT_FILTER_TRIANGULATE, the baseline): the heads the cameras placed,
 *                triangulated, update the track as one point; the update step above then placed
 *                heads without updating, and left the mask's tops, the hosts' edges and the feet
 *                (per-view pixel measurements, the projective filter's) out
 *   one view     mvt_body_update.c: a track fewer than two views placed keeps the person's height
 *                (the last two views gave); each camera learns its feet from people two views placed
 *   birth        mvt_body_birth.c: each unexplained blob is the seed of a candidate: its head ray
 *                with the prior on head height, its feet where visible, then every other camera's
 *                unexplained blobs (or their absence where the head would show); a candidate is
 *                born when its odds of a person against clutter allow, best first; the births and
 *                the labels of tracks that lost their person are paired all at once
 *   prune        mvt_body_prune.c: deletion by existence, uncertainty and the volume; two bodies
 *                cannot overlap (closer than body.halfwidth_m, the estimates are one person's);
 *                the status from the existence
 */
#ifndef MVT_BODY_H
#define MVT_BODY_H

#include "mvt_trk.h"

/* A camera's clutter rate (false blobs per frame) is a running mean over this time, s. */
#define MVT_BODY_CLUTTER_S MVT_R(10.0)
/* A shown track whose existence fell under population.exist_delete sleeps this long, s, before its label is
 * given up: a person lost in a knot who walks out elsewhere, or hidden longer than the existence
 * lasts, is found again under their own label (mvt_body_birth.c, heir_of). */
#define MVT_BODY_DORMANT_S MVT_R(3.0)
/* The person's height: a track fewer than two views place this frame keeps its head within this
 * many spreads of the height two views last gave it, the spread being that estimate's and a walking
 * head's bob (MVT_BODY_HEAD_BOB_M, m). */
#define MVT_BODY_HEIGHT_BAND MVT_R(3.0)
#define MVT_BODY_HEAD_BOB_M MVT_R(0.04)
/* The heights two views give a track are remembered over about this time, s (a few strides): how
 * far they wandered beyond a walking head's bob is how little the last one is known to be its
 * person's, which a lost label's heir is compared with (mvt_body_birth.c). */
#define MVT_BODY_HEIGHT_MEMORY_S MVT_R(1.0)
/* A camera's detection probability (a visible head reported inside its gate) is a running mean
 * over this time, s, of its likely-present tracks' hits, within MVT_BODY_PD_MIN..MVT_BODY_PD_MAX:
 * misses come in runs (a bad segmentation, a burst of noise) that independent frames at the
 * configured p_detect would take as proof of absence. */
#define MVT_BODY_PD_S MVT_R(30.0)
#define MVT_BODY_PD_MIN MVT_R(0.3)
#define MVT_BODY_PD_MAX MVT_R(0.98)
/* The probability that a head another body hides or merges with (mvt_body_shown) still shows as a
 * blob top of its own: a segmentation that cuts bodies at the neck or between two people shows
 * them, one that keeps each region whole does not. Learnt per camera like the detection
 * probability (hidden heads likely present that took a blob, per p_detect), from this prior and
 * floor up to MVT_BODY_P_SHOWN_HIDDEN_MAX. */
#define MVT_BODY_P_SHOWN_HIDDEN MVT_R(0.02)
#define MVT_BODY_P_SHOWN_HIDDEN_MAX MVT_R(0.9)
/* How much a body's width in the picture differs from the model's 2 body.halfwidth_m, relative to
 * it: people's shoulders differ by about this much, and where two tracked people stand is known to
 * a few centimetres. Whether two silhouettes touch (mvt_body_touch) is then a probability that
 * falls smoothly over the last few pixels of the gap, not a step at one pixel. */
#define MVT_BODY_WIDTH_SD MVT_R(0.15)
/* The probability that a camera's foreground mask shows background all around a visible head of a
 * person who is there (clothes and hair the colour of the background behind them, a segmentation
 * that lost the person): a head missed where the mask is empty weighs this, not the plain miss's
 * 1 - p, against the person. Learnt per camera from the heads of people two other views placed the
 * frame before (running mean over MVT_BODY_PD_S), from this prior, which is also its floor (a
 * mask is never trusted more than that), up to MVT_BODY_P_BG_MAX. */
#define MVT_BODY_P_BG MVT_R(0.01)
#define MVT_BODY_P_BG_MIN MVT_BODY_P_BG
#define MVT_BODY_P_BG_MAX MVT_R(0.5)
/* A blob's lowest point is the body's point on the floor nearest the camera: this far (m) from the
 * head's vertical toward the camera. Legs and feet are narrower than shoulders, so for a standing
 * or walking person it is less than the body's half width. Learnt per camera from the feet of
 * people whom two views place (their heads fix the place): the running mean of the
 * offset of the feet's floor point along the camera's direction, MVT_BODY_FOOT_AHEAD_N samples
 * long, from this prior and within 0..MVT_BODY_FOOT_AHEAD_MAX_M. */
#define MVT_BODY_FOOT_AHEAD_M MVT_R(0.1)
#define MVT_BODY_FOOT_AHEAD_MAX_M MVT_R(0.4)
#define MVT_BODY_FOOT_AHEAD_N MVT_R(200.0)
/* The same samples' spread about that mean is the feet's spread in that camera (a stride, a shadow,
 * the detector's edge), from the body's prior foot_sd_m, within MVT_BODY_FOOT_SD_MIN_M (a foot's
 * own size) and MVT_BODY_FOOT_AHEAD_MAX_M. */
#define MVT_BODY_FOOT_SD_MIN_M MVT_R(0.03)
/* The probability that a blob's bottom, where nothing cuts it, is the person's feet (not a shadow,
 * a blob merged with the floor's reflection, legs the colour of the floor): the prior of each
 * camera's rate, learnt from the same people as the share of their bottoms that land within
 * -MVT_BODY_FOOT_AHEAD_MAX_M..2 MVT_BODY_FOOT_AHEAD_MAX_M of their head's vertical, never under
 * MVT_BODY_P_FEET_MIN (clothes the colour of the floor in every view may hide most feet) nor over
 * MVT_BODY_PD_MAX. */
#define MVT_BODY_P_FEET MVT_R(0.9)
#define MVT_BODY_P_FEET_MIN MVT_R(0.05)
/* A blob's box within this many pixels of the picture's edge is cut by it. */
#define MVT_BODY_EDGE_PX MVT_R(2.0)
/* A merged blob's edge that one body's silhouette alone puts there measures that edge of the body
 * when it lies within this many squared standard deviations of it (chi-square, 1 dof, 99.7 %). */
#define MVT_BODY_EDGE_GATE MVT_R(9.0)
/* A time without frames longer than this many of the rig's typical intervals (and than a person
 * takes to walk a body's width) is an outage: nobody watched (mvt_body_step). */
#define MVT_BODY_GAP_FRAMES MVT_R(4.0)
/* A fragment's top lies at least this share of the silhouette's height below the head's top (a
 * blob at the head's own height beside it is not the body's). */
#define MVT_BODY_FRAGMENT_BELOW MVT_R(0.08)

/* How far from the feet (m) a person's shadow or reflection on the floor reaches: background
 * subtraction keeps it as foreground, attached to the body's blob or a blob of its own. */
#define MVT_BODY_SHADOW_M MVT_R(0.7)

/* The blobs a body's silhouette (with its shadow) breaks into per camera and frame besides the one
 * its head tops (holes, cuts, clothes the colour of the background, a shadow apart), anywhere on
 * the silhouette (mvt_body_fragment_of): a running mean over MVT_BODY_CLUTTER_S of each camera's
 * fragments per body likely present, from this prior, never under the floor (a segmentation that
 * has not broken a body for a while still may). */
#define MVT_BODY_FRAGMENTS_PRIOR MVT_R(0.3)
#define MVT_BODY_FRAGMENTS_MIN MVT_R(0.01)

/* The entries of a silhouette's axis (mvt_body_axis). */
#define MVT_BODY_AXIS_N 6

/* Probability p in (0, 1) as log odds, and back. */
mvt_real mvt_body_logit(mvt_real p);
mvt_real mvt_body_prob(mvt_real lo);

/* Track tr's person's height from now on: z, variance zz (its estimate starts again there). */
void mvt_body_height_start(mvt_track_t *tr, mvt_real z, mvt_real zz);

/* The silhouette of a body with head top x in camera cam: box (u0 v0 u1 v1, raw pixels) around the
 * projections of the head's and feet's edges, the head's own projection, and (foot, may be NULL)
 * the floor point under the head's, or the head's where the floor is not in front of the camera
 * (mvt_body_axis_at's foot). With head_given, head already holds x's projection (the Jacobian
 * prediction's, mvt_pkf_predict_obs) and is not projected again. 0 when the head is not in front of
 * the camera (box and head unset). O(1): six projections, five with head_given. */
int mvt_body_silhouette(const mvt_tracker_t *self, const mvt_camera_t *cam, const mvt_real x[3], mvt_real box[4],
                        mvt_real head[2], int head_given, mvt_real foot[2]);

/* The silhouette as the body's axis in the picture, thickened: axis = head u v, the floor point
 * under it u v, half the body's width at mid height (px), and MVT_BODY_SHADOW_M at the feet's depth
 * (px; 0 when the feet are not in front of the camera), all raw pixels. 0 when the head is not in
 * front of the camera. O(1). */
int mvt_body_axis(const mvt_tracker_t *self, const mvt_camera_t *cam, const mvt_real x[3], mvt_real axis[MVT_BODY_AXIS_N]);
/* The same, the head's projection `head` given, and the floor point's `foot` as mvt_body_silhouette
 * gives it (NULL: projected here). */
int mvt_body_axis_at(const mvt_tracker_t *self, const mvt_camera_t *cam, const mvt_real x[3], const mvt_real head[2],
                     const mvt_real foot[2], mvt_real axis[MVT_BODY_AXIS_N]);

/* The probability that two silhouettes touch in the picture (one blob, or one hiding the other):
 * that the gap between their axes is under their summed half widths, each half width spread by
 * MVT_BODY_WIDTH_SD of itself; 1 where the axes cross. */
mvt_real mvt_body_touch(const mvt_real a[MVT_BODY_AXIS_N], const mvt_real b[MVT_BODY_AXIS_N]);

/* Image point uv lies on the silhouette (within its half width of the axis) and at least
 * MVT_BODY_FRAGMENT_BELOW of the axis' length below the head: a fragment's top. */
int mvt_body_on_body_below_head(const mvt_real axis[MVT_BODY_AXIS_N], const mvt_real uv[2]);

/* Image point uv, a blob's top, is a fragment of the body with silhouette axis: on the body below
 * the head (mvt_body_on_body_below_head), or on the floor by the feet, within MVT_BODY_SHADOW_M at
 * their depth of their image (the body's shadow or reflection, which background subtraction keeps
 * as foreground and which, seen from above, may be the top of the body's blob). O(1). */
int mvt_body_fragment_of(const mvt_real axis[MVT_BODY_AXIS_N], const mvt_real uv[2]);

/* A box (u0 v0 u1 v1, px) outside which mvt_body_fragment_of(axis, .) is 0: the thickened axis'
 * box and the floor disc's. O(1). */
void mvt_body_fragment_bounds(const mvt_real axis[MVT_BODY_AXIS_N], mvt_real box[4]);

/* The area (px^2) over which the fragments of the body with silhouette axis lie: the thickened
 * axis and the floor by the feet (mvt_body_fragment_of). O(1). */
mvt_real mvt_body_silhouette_area(const mvt_real axis[MVT_BODY_AXIS_N]);

/* The density (1/px^2) of camera k's fragments of track t's body (likely present) at image point
 * uv: its fragments per frame (the camera's learnt rate) over its silhouette's area, times its
 * existence; 0 off the silhouette. O(1). */
mvt_real mvt_body_fragment_density(const mvt_tracker_t *self, int k, int t, const mvt_real uv[2]);
/* That density where uv lies on the silhouette: 0 where the body may have no fragments. O(1). */
mvt_real mvt_body_fragment_scale(const mvt_tracker_t *self, int k, int t);
/* Track t's body may have fragments in camera k (it is tracked, awake, likely present and shows
 * there): mvt_body_fragment_density is 0 everywhere otherwise. */
int mvt_body_fragment_possible(const mvt_tracker_t *self, int k, int t);

/* Image point uv lies on the silhouette: within its half width and slack_px of the axis. */
int mvt_body_on_silhouette(const mvt_real axis[MVT_BODY_AXIS_N], const mvt_real uv[2], mvt_real slack_px);

/* The head x lies within volume.exit_margin_m of the volume's side walls: where people leave. */
int mvt_body_near_side_wall(const mvt_tracker_config_t *c, const mvt_real x[3]);

/* Pixel uv lies in camera cam's picture. */
int mvt_body_in_picture(const mvt_camera_t *cam, const mvt_real uv[2]);

/* Camera k's clutter density: false blobs per frame over the picture's area, 1/px^2: the learnt
 * rate, or this frame's blobs beyond the heads it may show when they are more (a flood of false
 * alarms begins in one frame; a running mean would take seconds to believe it). */
mvt_real mvt_body_clutter_density(const mvt_tracker_t *self, int k);

/* The feet of blob det of camera k, when its bottom is visible: not within MVT_BODY_EDGE_PX of the
 * picture's edge, and its box overlapping no silhouette (this camera's, ws.sil) of a body likely
 * present other than track `self_t` (-1: none is the blob's own): a nearer or merged body would
 * hide or be the bottom; and its ray meeting no static occluder before the floor (furniture's edge
 * would be the bottom). uv receives the bottom's centre. 1 when visible. O(T + occluders). */
int mvt_body_feet_visible(const mvt_tracker_t *self, int k, const mvt_detection_t *det, int self_t, mvt_real uv[2]);

/* The innovation of feet seen at uv (raw pixels) in camera k against state s: the blob's lowest
 * point is the body's edge nearest the camera on the floor, (x, y, 0) moved body.halfwidth_m toward
 * the camera, with the feet's spread (body.foot_sd_m at their depth) added to the
 * pixel noise. MVT_ERR_* as mvt_pkf_innovation. */
mvt_err_t mvt_body_feet_innovation(const mvt_tracker_t *self, const mvt_cv_state_t *s, int k, const mvt_real uv[2],
                                   mvt_pkf_innov_t *in);

/* The chance that camera k shows a head with silhouette axis (mvt_body_axis) as a blob top of its
 * own, given the bodies tracked there (ws.axis of this camera; track self_t, or -1, excluded):
 * every body more likely present than not whose silhouette touches this one (mvt_body_touch's
 * probability) and whose head is higher in the picture makes the blob's top its own (a nearer body
 * hides the head, or the two merge into one blob), and lowers the chance toward camera k's learnt
 * rate of hidden heads shown (from MVT_BODY_P_SHOWN_HIDDEN) by its existence times that
 * probability. O(T). */
mvt_real mvt_body_shown(const mvt_tracker_t *self, int k, const mvt_real axis[MVT_BODY_AXIS_N], int self_t);

/* Detection d of camera k, at innovation in from track t's prediction, lies in the track's gate:
 * the chi-square test on the innovation (MVT_GATE_CHI2), or the paper's projected ellipsoid
 * (MVT_GATE_PAPER, mvt_pkf_paper_distance within paper.delta). */
int mvt_body_gated(const mvt_tracker_t *self, int t, int k, int d, const mvt_pkf_innov_t *in);

/* The density (1/px^2) of a head's detection at innovation in, as the motion model weighs it
 * (mvt_imm.h): the person's, N(y; 0, S), with probability 1 - p_outlier where it is in the track's
 * gate (gated: mvt_body_gated), and displaced anywhere within outlier_radius_px with p_outlier. 0
 * beyond both. */
mvt_real mvt_body_head_density(const mvt_tracker_t *self, const mvt_pkf_innov_t *in, int gated);

/* The steps (see above). */
void mvt_body_existence(mvt_tracker_t *self, mvt_real dt);
void mvt_body_visibility(mvt_tracker_t *self, const mvt_view_t *view, int k);

/* The line from o along dir, for s in (0, s_max), passes through one of the rig's static occluders
 * (mvt_volume_t). O(occluders). */
int mvt_body_occluded(const mvt_tracker_t *self, const mvt_real o[3], const mvt_real dir[3], mvt_real s_max);

/* Camera cam's line of sight to x passes through a static occluder before reaching it. */
int mvt_body_behind_occluder(const mvt_tracker_t *self, const mvt_camera_t *cam, const mvt_real x[3]);

/* Camera k's mask (where it sent one) shows background all around the head predicted at p (within
 * half a head's width, three of the detector's sigmas and two of the prediction's spreads). */
int mvt_body_head_on_background(const mvt_tracker_t *self, const mvt_view_t *view, int k, const mvt_pkf_pred_t *p);
void mvt_body_explain(mvt_tracker_t *self, const mvt_view_t *view, int k);
void mvt_body_update(mvt_tracker_t *self, const mvt_view_t *view, int k, mvt_real dt);
void mvt_body_triangulate(mvt_tracker_t *self);
void mvt_body_regather(mvt_tracker_t *self, mvt_real dt);
void mvt_body_one_view(mvt_tracker_t *self, const mvt_frame_t *frame);
void mvt_body_birth(mvt_tracker_t *self, const mvt_frame_t *frame, const int order[], int n_order, mvt_real dt);
void mvt_body_prune(mvt_tracker_t *self);

/* The whole frame (after mvt_tracker_step has prepared the measurements and the camera order). */
void mvt_body_step(mvt_tracker_t *self, const mvt_frame_t *frame, const int order[], int n_order, mvt_real dt);

#endif /* MVT_BODY_H */
