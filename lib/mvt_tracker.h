/*
 * mvt_tracker.h - multi-view 3D tracker: the per-frame loop over the core's components.
 *
 * One call per frame set, one model of a person (mvt_body.h, docs/tracking.md), one module per step:
 *   predict      mvt_body.c: every track's motion models to the frame (mvt_imm)
 *   visibility   mvt_body_vis.c: each track's silhouette and detection probability per camera
 *                (field of view, nearer bodies, the rig's static occluders)
 *   explain      mvt_body_explain.c: each blob as a head, a fragment of a body, a merged blob
 *                of several people or clutter, by likelihood (Hungarian method, mvt_assoc)
 *   update       mvt_body_update.c: state (mvt_pkf, or mvt_tri + mvt_cv for the triangulating
 *                baseline) and existence
 *   birth        mvt_body_birth.c: unexplained blobs in any number of views, with a prior on
 *                head height; a lost label goes to the person found where it was lost
 *   prune        mvt_body_prune.c: existence under its threshold, duplicates, the volume's walls
 * The caller owns the mvt_tracker_t (sizeof(mvt_tracker_t) bytes); nothing is allocated, nothing
 * is printed. Identities count up from 1 and are never given to another person (they wrap only
 * after 2^31 births).
 *
 * Filters (mvt_tracker_config_t.filter):
 *   MVT_FILTER_PROJECTIVE   each camera's pixels update the 3D state directly (PKF family;
 *                           linearisation in .lin, gate in .gate)
 *   MVT_FILTER_TRIANGULATE  the baseline of the PKF paper: per frame triangulate the point from
 *                           the views (robustly), then a 6-state constant-velocity Kalman update
 */
#ifndef MVT_TRACKER_H
#define MVT_TRACKER_H

#include "mvt_assoc.h"
#include "mvt_camera.h"
#include "mvt_cv.h"
#include "mvt_imm.h"
#include "mvt_pkf.h"
#include "mvt_tri.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mvt_filter {
    MVT_FILTER_PROJECTIVE = 0,
    MVT_FILTER_TRIANGULATE = 1
} mvt_filter_t;

typedef enum mvt_gate {
    MVT_GATE_CHI2 = 0,  /* innovation y^T S^-1 y <= numerics.gate_chi2 (2 dof per camera) */
    MVT_GATE_PAPER = 1  /* Eq. 22-26: distance to the projected ellipsoid <= paper_delta */
} mvt_gate_t;

enum { MVT_TRACK_TENTATIVE = 1, MVT_TRACK_CONFIRMED = 2, MVT_TRACK_COASTING = 3 };

/* The paper's gate (MVT_GATE_PAPER, Eq. 22-26). */
typedef struct mvt_paper_gate {
    mvt_real gamma;             /* Eq. 23 gamma; default 6 */
    mvt_real var_m2[3];         /* Eq. 23 per-axis variance of the frame-to-frame position change
                                   (the paper's "Q learnt from ground truth"); default 0.04^2 m^2 */
    mvt_real delta;             /* Eq. 26 threshold on the normalised distance; default 1 */
} mvt_paper_gate_t;

/* The room: where people are tracked and where they leave it. */
typedef struct mvt_volume {
    mvt_real min[3];            /* tracked volume, metres (rig file) */
    mvt_real max[3];
    mvt_real margin_m;          /* births and tracks may be this far outside; default 0.5 */
    mvt_real exit_margin_m;     /* the band along the volume's side walls through which people
                                   leave, m: a track there may walk out (population.exit_s);
                                   >= 0, default 0.5 */
    int num_occluders;          /* static occluders the rig declares, 0..MVT_MAX_OCCLUDERS; default 0 */
    mvt_real occluder_min[MVT_MAX_OCCLUDERS > 0 ? MVT_MAX_OCCLUDERS : 1][3]; /* each an axis-aligned
                                   box (a desk, a shelf, a pillar), metres, max > min on every
                                   axis: a camera whose line of sight to a head passes through one
                                   does not see that head, and a blob's bottom whose ray meets one
                                   before the floor is its edge, not feet (the body model) */
    mvt_real occluder_max[MVT_MAX_OCCLUDERS > 0 ? MVT_MAX_OCCLUDERS : 1][3];
} mvt_volume_t;

/* A person's body, the size prior of a head top over a body standing on the floor. */
typedef struct mvt_body_prior {
    mvt_real halfwidth_m;       /* half a person's width: a hidden head lies at least this far
                                   inside the blob's side edges, and two heads closer than it are
                                   one person's; >= 0, default 0.2 */
    mvt_real head_height_m;     /* mean head-top height of a standing adult, m, 1..2.5; default 1.70 */
    mvt_real head_height_sd_m;  /* its spread over people and postures a newcomer has, m, 0.02..0.5;
                                   default 0.15 */
    mvt_real foot_sd_m;         /* a blob's bottom-centre (the feet) about the point under the head
                                   top, horizontal standard deviation, m (stride, lean), 0.01..0.5;
                                   default 0.12 */
} mvt_body_prior_t;

/* The people as the model counts them: how often a camera reports one, how many false blobs it
 * sends, how often people come and go, and how sure a track must be to be shown or ended. */
typedef struct mvt_population {
    mvt_real p_detect;          /* the prior of each camera's probability of reporting a
                                   visible head, which it learns online (MVT_BODY_PD_S); (0, 1),
                                   default 0.9 */
    mvt_real clutter_per_frame; /* a camera's false blobs per frame before it
                                   has been watched (then learnt online over MVT_BODY_CLUTTER_S),
                                   0.01..100; default 0.5 */
    mvt_real birth_per_s;       /* ... people entering the tracked volume per second, on average,
                                   1e-4..10; default 0.1 */
    mvt_real stay_s;            /* ... mean time a person stays in the volume, s, > 0; default 600 */
    mvt_real exit_s;            /* ... mean time a person within volume.exit_margin_m of a side
                                   wall takes to walk out, s, > 0; default 2 */
    mvt_real exist_confirm;     /* ... probability of existence that confirms a track, (0.5, 1);
                                   default 0.9 */
    mvt_real exist_delete;      /* ... under which a track is deleted, (0, 0.5); default 0.01 */
} mvt_population_t;

/* The estimator's bounds: what the filter itself can tell, not what people are. */
typedef struct mvt_numerics {
    mvt_real gate_chi2;         /* chi-square gate, 2 dof; default 13.8 (0.1 % false rejection) */
    mvt_real max_pos_std_m;     /* a track whose position std exceeds this is deleted; default 1.0
                                   (it is nowhere in particular any more) */
    mvt_real var_floor_m2;      /* covariance diagonal floor; default 1e-10 */
} mvt_numerics_t;

typedef struct mvt_tracker_config {
    /* mode selectors */
    mvt_filter_t filter;        /* default MVT_FILTER_PROJECTIVE */
    mvt_pkf_lin_t lin;          /* default MVT_PKF_JACOBIAN */
    mvt_gate_t gate;            /* default MVT_GATE_CHI2 */
    /* the physical model */
    mvt_imm_config_t motion;    /* the motion models (mvt_imm.h): default mvt_imm_config_default,
                                   an IMM of standing, walking and manoeuvring people that needs no
                                   tuning; mvt_imm_config_single(q) is the single constant-velocity
                                   filter with white-acceleration density q (m^2/s^3 per axis) */
    mvt_volume_t volume;        /* the room */
    mvt_body_prior_t body;      /* a person's size */
    mvt_population_t population; /* detection, clutter, births, stays, exits, belief */
    mvt_real init_vel_std_ms;   /* velocity std of a new track, m/s; default 1.0 (also how far a
                                   person who was lost may have walked) */
    mvt_numerics_t numerics;    /* the estimator's bounds: gate, uncertainty, floor */
    /* other lifecycles and gates */
    mvt_paper_gate_t paper;     /* MVT_GATE_PAPER's parameters */
} mvt_tracker_config_t;

/* One detection as the core needs it (raw distorted pixels). */
typedef struct mvt_detection {
    mvt_real u, v;        /* pixels */
    mvt_real sigma_px;    /* <= 0: the camera's default */
    mvt_real score;       /* [0, 1] */
    mvt_real hue, saturation; /* < 0 unknown */
    mvt_real box[4];      /* the blob's box x_min, y_min, x_max, y_max in raw pixels; unknown
                             (all zero) unless finite with x_max > x_min and y_max > y_min */
} mvt_detection_t;

/* What one camera delivered for this frame set. */
typedef struct mvt_view {
    int observed;         /* 0: the camera did not report (not observed, not "saw nothing") */
    int64_t utime_us;     /* capture time */
    int num_detections;   /* 0..MVT_MAX_DETECTIONS (larger is counted and clamped) */
    int num_offered;      /* how many the camera sent, when the caller kept num_detections of them
                             (mvt_tracker_select); <= num_detections: none dropped. The view's
                             clutter density counts them all: the kept ones are each track's nearest,
                             so a flood's density must not be read from what was kept */
    mvt_detection_t det[MVT_MAX_DETECTIONS];
    const struct mvt_mask *mask; /* foreground mask and colour, or NULL; owned by the caller and
                                    valid until the frame is processed. mvt_pft weighs its particles
                                    by it; the PKF tracker reads from it whether a place is empty */
} mvt_view_t;

typedef struct mvt_frame {
    int64_t utime_us;     /* the time the output refers to (>= every view's utime) */
    mvt_view_t views[MVT_MAX_CAMERAS]; /* indexed like the rig's cameras */
} mvt_frame_t;

typedef struct mvt_track_out {
    int32_t id;
    int32_t status;             /* MVT_TRACK_* */
    mvt_real pos_m[3];
    mvt_real vel_ms[3];
    mvt_real cov_m2[6];         /* xx xy xz yy yz zz */
    uint32_t cameras_used;      /* bit k: camera k updated the track this frame */
    mvt_real extent_min[3];     /* position -/+ 2 sigma */
    mvt_real extent_max[3];
    mvt_real hue, saturation;   /* < 0 unknown */
} mvt_track_out_t;

typedef struct mvt_output {
    int64_t utime_us;
    int num_tracks;
    mvt_track_out_t tracks[MVT_MAX_TARGETS];
} mvt_output_t;

/* Counters of what the tracker refused or repaired. Never reset by the library. */
typedef struct mvt_counters {
    uint64_t frames;
    uint64_t frames_time_backwards;   /* frame utime earlier than the previous one: skipped */
    uint64_t detections_over_capacity;/* beyond MVT_MAX_DETECTIONS: dropped */
    uint64_t detections_nonfinite;    /* NaN / Inf coordinates or sigma: dropped */
    uint64_t detections_undistort_failed; /* outside the lens model's invertible region */
    uint64_t views_unknown_camera;    /* observed views beyond the rig's camera count */
    uint64_t updates;                 /* camera updates applied */
    uint64_t gated_out;               /* track-camera pairs whose best detection failed the gate */
    uint64_t behind_camera;           /* track-camera pairs skipped: point behind the camera */
    uint64_t numeric_faults;          /* covariance repaired or track dropped as non-PD */
    uint64_t births;
    uint64_t births_refused_full;     /* MVT_MAX_TARGETS reached */
    uint64_t deletions;               /* all deletions; by reason: */
    uint64_t deleted_exit;            /*   walked out through a side wall (population.exit_s) */
    uint64_t deleted_uncertain;       /*   position std above numerics.max_pos_std_m */
    uint64_t deleted_outside;         /*   left the volume (plus margin) */
    uint64_t duplicates_deleted;      /*   a second track on one person, never shown (a shown
                                             one sleeps: mvt_body_prune.c) */
    uint64_t birth_candidates_dropped;/* multi-view birth candidates beyond MVT_MAX_BIRTH_CANDIDATES */
    uint64_t occluded_updates;        /* track-camera pairs explained as hidden in another body's
                                         blob and constrained to its box */
    uint64_t exclusion_updates;       /* tracks kept a body's width from a better-placed one */
    uint64_t reacquired;              /* lost labels given to the person found where they were lost
                                         (mvt_body_birth.c) */
    uint64_t deleted_unlikely;        /*   existence fell under population.exist_delete */
    uint64_t fragments;               /* blobs explained as a fragment of a
                                         tracked body (no update, no birth) */
    uint64_t foot_updates;            /* updates with a blob's visible feet */
    uint64_t mask_top_updates;        /* track-camera updates with the top of the foreground in the
                                         track's own column, where no blob's reported top showed
                                         the head (views with masks; mvt_body_update.c) */
} mvt_counters_t;

/* A person's appearance as the blobs' colour shows it (mvt_trk_app.c): the blob's mean hue h and
 * saturation s as a chroma point a = s (cos 2 pi h, sin 2 pi h) in the unit disc (grey clothes sit
 * near the centre, where hue means nothing), its mean m over the detections given to the track, and
 * the spread var (per axis) of those detections about it. n = 0: not seen in colour yet. */
typedef struct mvt_app {
    mvt_real m[2];
    mvt_real var;               /* per axis, chroma units^2 */
    mvt_real n;                 /* detections behind m (weighted, at most MVT_TRK_APP_NMAX) */
} mvt_app_t;

/* One view's detections of a track beyond what the filter's memory holds (mvt_trk_onset_seen):
 * where its last head detection lay, and a displacement of that view seen to begin (the detection
 * jumped off the head while two other views placed the person), which stands in for the view's
 * memory while fewer views place the person. */
typedef struct mvt_trk_onset {
    mvt_real head[2];     /* the view's last head detection of the track, ideal pixels */
    mvt_real y[2];        /* the displacement's last offset from the predicted head, px */
    mvt_real p;           /* P(displaced) when two other views last placed the person */
    mvt_real seen_s;      /* its last detection, seconds after that */
    int64_t confirmed_us; /* that time; 0: no displacement held */
} mvt_trk_onset_t;

typedef struct mvt_track {
    int32_t id;                 /* 0: free slot */
    int32_t status;
    mvt_cv_state_t s;           /* the estimate: the motion models' combination */
    mvt_imm_t imm;              /* each motion model's estimate and probability */
    uint32_t cameras_used;      /* this frame */
    int64_t last_update_us;     /* last frame seen */
    mvt_real seen_z, seen_zz;   /* head height and its variance the last frame seen: a coasting
                                   track's height spreads with the motion models' vertical noise,
                                   a person's does not (a lost label's heir is compared with this) */
    mvt_real z_mean, z_var;     /* the heights two views gave it, over about the last
                                   MVT_BODY_HEIGHT_MEMORY_S: their running mean and variance (a
                                   walking head's bob, and beyond it a track whose height was not its
                                   person's: one that slid down onto a piece of a body) */
    mvt_app_t app;              /* its appearance (blobs with colour only) */
    uint32_t cameras_placed;      /* this frame: cameras whose detection updated the track as
                                     the person's (not judged displaced) */
    uint32_t cameras_placed_prev; /* ... the frame before */
    mvt_imm_view_t view[MVT_MAX_CAMERAS]; /* per camera: was its last detection displaced, and by
                                             how much (mvt_imm_update_view) */
    uint32_t heads;             /* this frame: cameras with a head detection of it (explain's) */
    uint32_t heads_prev;        /* ... the frame before */
    mvt_trk_onset_t onset[MVT_MAX_CAMERAS]; /* per camera: its last head, a displacement seen to begin */
    mvt_real exist_lo;          /* log odds that its person is in the volume */
    int32_t dormant;            /* 1 when its existence fell under population.exist_delete
                                   after it was shown: its label waits MVT_BODY_DORMANT_S for the
                                   person to be found again (mvt_body_birth.c), unseen and unshown */
    int32_t was_shown;          /* 1 once it has been shown confirmed */
    mvt_real one_view_s;        /* seconds since two or more views last placed it
                                   in one frame (since its birth when none ever did) */
    mvt_real agree_s;           /* seconds its displaced heads agreed on a point elsewhere, less
                                   the seconds they did not, never below 0 (mvt_body_regather) */
} mvt_track_t;

/* Multi-view birth candidates examined per frame (the best are kept; the excess is counted). */
#ifndef MVT_MAX_BIRTH_CANDIDATES
#define MVT_MAX_BIRTH_CANDIDATES 128
#endif
#if MVT_MAX_BIRTH_CANDIDATES < 1 || MVT_MAX_BIRTH_CANDIDATES > 4096
#error "MVT_MAX_BIRTH_CANDIDATES must be in 1..4096"
#endif

/* The body model's workspace (mvt_body.h): what one camera's pass computes for its steps, and
 * the frame's birth material. Rebuilt every frame; nothing in it outlives the frame. */
typedef struct mvt_body_cand {
    mvt_real x[3];                      /* head top, m */
    mvt_real P[9];                      /* its covariance */
    mvt_real lo;                        /* log odds of a new person against clutter */
    int16_t det[MVT_MAX_CAMERAS];       /* the detection of each camera it explains, or -1 */
} mvt_body_cand_t;

/* A track's label and what was known of its person when a candidate took it (mvt_body_birth.c). */
typedef struct mvt_body_label {
    int32_t id;
    int32_t status;
    int32_t was_shown;
    int32_t dormant;
    mvt_app_t app;
    mvt_real seen_z, seen_zz;
    mvt_real exist_lo;
    mvt_real x[3];     /* the estimate it carried, and its covariance widened by walking pace's reach */
    mvt_real P[9];
} mvt_body_label_t;

typedef struct mvt_body_ws {
    mvt_real sil[MVT_MAX_CAMERAS][MVT_MAX_TARGETS][4]; /* each track's predicted silhouette box in
                                                          each camera (u0 v0 u1 v1, raw px); u1 < u0:
                                                          not in that picture */
    mvt_real axis[MVT_MAX_CAMERAS][MVT_MAX_TARGETS][6]; /* ... and its axis: head u v, the point
                                                           under it on the floor u v, half the
                                                           body's width at mid height and the
                                                           shadow's reach at the feet, raw px */
    mvt_real head[MVT_MAX_TARGETS][2];  /* this camera: predicted head, raw px */
    mvt_real pd[MVT_MAX_TARGETS];       /* this camera: probability that the head is reported */
    int16_t assign[MVT_MAX_TARGETS];    /* this camera: the detection that is the track's head, -1 */
    int16_t frag[MVT_MAX_TARGETS];      /* this camera: a detection that is a fragment of it, -1 */
    int16_t host[MVT_MAX_TARGETS];      /* this camera: a merged blob that holds it under another
                                           track's head, -1 */
    int16_t owner[MVT_MAX_DETECTIONS];  /* this camera: the track a detection belongs to, or -1 */
    mvt_pkf_meas_t top[MVT_MAX_TARGETS]; /* this camera: the head as a top of the foreground mask in
                                            its own column, where no blob is its head */
    uint8_t top_ok[MVT_MAX_TARGETS];    /* ... found */
    uint8_t on_bg[MVT_MAX_TARGETS];     /* this camera: its mask shows background all around the
                                           predicted head (mvt_body_vis.c) */
    mvt_real frag_dens[MVT_MAX_DETECTIONS]; /* this camera: density (1/px^2) of the bodies' fragments
                                               at each blob's top */
    uint8_t free_det[MVT_MAX_CAMERAS][MVT_MAX_DETECTIONS]; /* this frame: 1 explained by no track
                                                              (clutter or a newcomer), 2 given to a
                                                              track as its head beyond the gate (a
                                                              merged blob topped by someone else);
                                                              either may seed a birth */
    int16_t head_of[MVT_MAX_CAMERAS][MVT_MAX_DETECTIONS];  /* this frame: the track whose head the
                                                              blob is, or -1 */
    mvt_body_cand_t cand[MVT_MAX_BIRTH_CANDIDATES];
    int num_cand;
    mvt_body_label_t heirs[MVT_MAX_TARGETS]; /* this frame, before its births: the labels of the tracks
                                                that lost their person, with what they knew */
    int16_t heir_slot[MVT_MAX_TARGETS];      /* ... and the slot of each */
    int num_heirs;
    int16_t born_cand[MVT_MAX_TARGETS];      /* this frame's births: each one's candidate, */
    int16_t born_own[MVT_MAX_TARGETS];       /* and the label whose slot it took, or -1 */
    mvt_real clutter_now[MVT_MAX_CAMERAS]; /* this frame: each camera's blobs beyond the tracked
                                              heads it may show (a lower bound of its clutter) */
} mvt_body_ws_t;

typedef struct mvt_tracker {
    mvt_tracker_config_t cfg;
    int num_cameras;
    mvt_camera_t cams[MVT_MAX_CAMERAS];
    mvt_track_t tracks[MVT_MAX_TARGETS];
    int32_t next_id;
    int64_t last_utime_us;
    int have_time;
    mvt_counters_t counters;
    /* per-frame workspaces (no state carried between frames) */
    mvt_pkf_meas_t meas[MVT_MAX_CAMERAS][MVT_MAX_DETECTIONS];
    uint8_t meas_ok[MVT_MAX_CAMERAS][MVT_MAX_DETECTIONS];
    mvt_real chroma[MVT_MAX_CAMERAS][MVT_MAX_DETECTIONS][2]; /* the detection's colour (mvt_app_t) */
    uint8_t chroma_ok[MVT_MAX_CAMERAS][MVT_MAX_DETECTIONS];  /* ... sent and valid */
    int num_meas[MVT_MAX_CAMERAS];
    mvt_pkf_pred_t pred[MVT_MAX_TARGETS];    /* this camera: each track's predicted head */
    uint8_t pred_ok[MVT_MAX_TARGETS];        /* ... made */
    mvt_real cl_cost[MVT_ASSOC_MAX_ROWS * MVT_ASSOC_MAX_COLS]; /* a cost matrix for mvt_assoc */
    mvt_assoc_ws_t assoc_ws;
    /* what the tracker learns of each camera (persisted) */
    mvt_real clutter_n[MVT_MAX_CAMERAS]; /* each camera's false blobs per
                                            frame, learnt (mvt_body.c) */
    mvt_real p_detect_k[MVT_MAX_CAMERAS]; /* ... and its detection probability of a visible head,
                                             learnt (mvt_body_update.c); 0: not yet */
    mvt_real foot_ahead_k[MVT_MAX_CAMERAS]; /* ... how far toward it from the head's vertical a blob's
                                               lowest point lies on the floor, m, learnt
                                               (mvt_body_update.c); 0: not yet */
    mvt_real foot_var_k[MVT_MAX_CAMERAS]; /* ... the spread of those distances, m^2, learnt
                                             (mvt_body_update.c); 0: not yet */
    mvt_real p_feet_k[MVT_MAX_CAMERAS];   /* ... and the chance that a blob's bottom where feet may
                                             show is the feet, learnt (mvt_body_update.c); 0: not
                                             yet */
    mvt_real p_hidden_k[MVT_MAX_CAMERAS]; /* ... and the chance that a head another body hides or
                                             merges shows as a blob top of its own, learnt
                                             (mvt_body_update.c); 0: not yet */
    mvt_real frag_n[MVT_MAX_CAMERAS];     /* ... and the fragments it shows per body likely present
                                             per frame, learnt (mvt_body.c); 0: not yet */
    mvt_real p_bg_k[MVT_MAX_CAMERAS];     /* ... and the chance that its mask shows background all
                                             around a visible head, learnt (mvt_body_update.c); 0: not
                                             yet */
    mvt_real frame_dt_s;                  /* the typical time between frames, s
                                             (mvt_body.c); 0: not yet. Not persisted */
    mvt_body_ws_t body;         /* the body model's workspace */
} mvt_tracker_t;

/* Fills cfg with the documented defaults (volume: a 10 m cube around the origin, z >= 0). */
void mvt_tracker_config_default(mvt_tracker_config_t *cfg);

/* Checks cfg (ranges above) and the cameras, and resets the tracker. num_cameras 1..MVT_MAX_CAMERAS.
 * MVT_ERR_INVALID on a bad configuration. */
mvt_err_t mvt_tracker_init(mvt_tracker_t *self, const mvt_tracker_config_t *cfg, const mvt_camera_t *cams,
                           int num_cameras);

/* Processes one frame set and fills out (may be NULL). Worst case O(C * T^2 * (T + D)) for the
 * explanation (one assignment per camera) plus O(C^2 * D^2) for births (each free blob's candidate
 * gathers every other view's blobs), with C cameras, T tracks, D detections per camera.
 * MVT_ERR_INVALID (counted, state unchanged) when frame->utime_us is earlier than the last frame. */
mvt_err_t mvt_tracker_step(mvt_tracker_t *self, const mvt_frame_t *frame, mvt_output_t *out);

/* Chooses which of n_in > MVT_MAX_DETECTIONS detections of camera cam to keep (a flood of false
 * alarms must not push out the detections that feed existing tracks): first, for every track,
 * the detection nearest to its predicted image point inside the chi-square gate, then the rest
 * by decreasing score (ties: input order). keep[] receives up to MVT_MAX_DETECTIONS input indices
 * in increasing order; returns how many (n_in - that = dropped). Does not change the tracker.
 * Cost O(T * n_in + n_in * MVT_MAX_DETECTIONS); memory: the caller's keep[] and in[] only. */
int mvt_tracker_select(const mvt_tracker_t *self, int cam, const mvt_detection_t *in, int n_in,
                       int keep[MVT_MAX_DETECTIONS]);

/* What a tracker carries from one frame to the next, and nothing else: its tracks, the next
 * identity, its clock, its counters and what it learnt of each camera (the configuration and
 * cameras come from the caller, the
 * workspaces are rebuilt every frame). Pointer-free and fixed-size, so a caller may store it as
 * bytes (a daemon's checkpoint) and give it back to a tracker built with the same configuration. */
typedef struct mvt_tracker_persist {
    mvt_track_t tracks[MVT_MAX_TARGETS];
    int32_t next_id;
    int32_t have_time;
    int64_t last_utime_us;
    mvt_counters_t counters;
    mvt_real clutter_n[MVT_MAX_CAMERAS];
    mvt_real p_detect_k[MVT_MAX_CAMERAS];
    mvt_real p_hidden_k[MVT_MAX_CAMERAS];
    mvt_real foot_ahead_k[MVT_MAX_CAMERAS];
    mvt_real foot_var_k[MVT_MAX_CAMERAS];
    mvt_real p_feet_k[MVT_MAX_CAMERAS];
    mvt_real frag_n[MVT_MAX_CAMERAS];
    mvt_real p_bg_k[MVT_MAX_CAMERAS];
} mvt_tracker_persist_t;

/* Copies the persistent part of the tracker into out (padding zeroed: equal states give equal
 * bytes). O(MVT_MAX_TARGETS). */
void mvt_tracker_save(const mvt_tracker_t *self, mvt_tracker_persist_t *out);

/* Restores a saved state into a tracker initialised with the same configuration and cameras.
 * The state is checked whole before anything is copied: identities positive, unique and below
 * next_id, statuses known, states finite with a positive-definite covariance, every time at or
 * before the saved clock. MVT_ERR_INVALID leaves the tracker unchanged.
 * unobserved_us >= 0 is time during which nobody watched (the process was down): the tracks'
 * "last seen" clocks move forward by it, so an outage does not use up a sleeping label's wait;
 * the filters still predict across the whole time (their covariance grows with it).
 * O(MVT_MAX_TARGETS). */
mvt_err_t mvt_tracker_resume(mvt_tracker_t *self, const mvt_tracker_persist_t *p, int64_t unobserved_us);

/* Identities given from now on are >= first (> 0): a caller that cannot restore a state but knows
 * which identities were used before (a daemon restarted without its checkpoint) keeps them
 * unique. Never lowers the counter. */
void mvt_tracker_reserve_ids(mvt_tracker_t *self, int32_t first);

/* Fills out with the current tracks (no processing). */
void mvt_tracker_output(const mvt_tracker_t *self, int64_t utime_us, mvt_output_t *out);

#ifdef __cplusplus
}
#endif

#endif /* MVT_TRACKER_H */
