/*
 * mvt_trk_reacq.c - re-acquisition of tracks that were lost for a while (mvt_trk.h).
 *
 * The per-camera association decides camera by camera, in the image, and updates the track after
 * each camera. That is right while a track is well localised. After a second or more without
 * updates (a long occlusion, the daemon's restart) its predicted position is uncertain by more
 * than the distance between neighbours, and the first camera's choice decides for all the others.
 * Here the decision is taken once, for all cameras together: the frame's detections are
 * triangulated into multi-view points (the births' machinery), and the lost tracks are assigned
 * to those points jointly (Hungarian) by the distance of each prediction to each point. The
 * detections of an assigned point are then reserved for its track in every camera; the
 * per-camera updates that follow use them, so each measurement still updates the filter once.
 *
 * The distance. Horizontally, the constant-velocity prediction and its covariance. Vertically, a
 * person's head height is an identity cue that the constant-velocity model throws away over a
 * gap (its white acceleration lets the height wander by q_z t^3 / 3: 0.2 m after 1.3 s with the
 * default q_z), while a walking or standing person's head stays within a few centimetres of its
 * height (gait). The height is compared unextrapolated, with the track's variance plus
 * MVT_TRK_HEAD_SD_M squared.
 */
#include <string.h>

#include "mvt_assoc.h"
#include "mvt_linalg.h"
#include "mvt_trk.h"


mvt_real mvt_trk_mahalanobis3(const mvt_real a[3], const mvt_real Pa[9], const mvt_real b[3], const mvt_real Pb[9],
                              mvt_real *det)
{
    mvt_real S[9], Si[9];
    for (int i = 0; i < 9; i++) {
        S[i] = Pa[i] + Pb[i];
    }
    if (mvt_la_inv3(S, Si) != MVT_OK) {
        return MVT_R(-1.0);
    }
    if (det != NULL) {
        *det = S[0] * (S[4] * S[8] - S[5] * S[7]) - S[1] * (S[3] * S[8] - S[5] * S[6]) +
               S[2] * (S[3] * S[7] - S[4] * S[6]);
    }
    const mvt_real d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    mvt_real q = MVT_R(0.0);
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            q += d[i] * Si[i * 3 + j] * d[j];
        }
    }
    return q;
}

/* Each live track's position and its position covariance predicted to utime, once per frame,
 * into rq_tx/rq_tP (the tracks themselves are not changed). */
static void predict_all(mvt_tracker_t *self, int64_t utime)
{
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        if (self->tracks[t].id == 0) {
            continue;
        }
        mvt_cv_state_t s;
        mvt_trk_predicted(self, &self->tracks[t], utime, &s);
        for (int i = 0; i < 3; i++) {
            self->rq_tx[t][i] = s.x[i];
            for (int j = 0; j < 3; j++) {
                self->rq_tP[t][i * 3 + j] = s.P[i * 6 + j];
            }
        }
    }
}

/* A lost track's prediction for re-acquisition: horizontally the constant-velocity one; the
 * height the track's own (not extrapolated), its variance plus the head's spread. */
static void lost_prediction(const mvt_tracker_t *self, int t, mvt_real x[3], mvt_real P[9])
{
    const mvt_track_t *tr = &self->tracks[t];
    for (int i = 0; i < 3; i++) {
        x[i] = self->rq_tx[t][i];
        for (int j = 0; j < 3; j++) {
            P[i * 3 + j] = i < 2 && j < 2 ? self->rq_tP[t][i * 3 + j] : MVT_R(0.0);
        }
    }
    x[2] = tr->s.x[2];
    P[8] = tr->s.P[2 * 6 + 2] + MVT_TRK_HEAD_SD_M * MVT_TRK_HEAD_SD_M;
}

/* The distinct candidates of this frame, best first: none shares a detection with a better one. */
static int distinct_points(mvt_tracker_t *self)
{
    memset(self->claimed, 0, sizeof(self->claimed));
    int n = 0;
    for (int i = 0; i < self->num_cand && n < MVT_MAX_DETECTIONS; i++) {
        mvt_birth_cand_t *c = &self->cand[i];
        int free_all = 1;
        for (int v = 0; v < c->n && free_all; v++) {
            free_all = !self->claimed[c->cam[v]][c->det[v]];
        }
        uint32_t inl = 0;
        if (!free_all || !mvt_trk_cand_point(self, c, self->rq_x[n], self->rq_cov[n], &inl)) {
            continue;
        }
        int m = 0;
        for (int v = 0; v < c->n; v++) {
            self->claimed[c->cam[v]][c->det[v]] = 1;
            if (inl & (1u << v)) { /* keep only the inliers, in place */
                c->cam[m] = c->cam[v];
                c->det[m] = c->det[v];
                m++;
            }
        }
        c->n = (int16_t)m;
        self->rq_cand[n++] = (int16_t)i;
    }
    return n;
}

void mvt_trk_reacquire(mvt_tracker_t *self, const mvt_frame_t *frame, const int order[], int n_order)
{
    const mvt_tracker_config_t *c = &self->cfg;
    self->reacq_any = 0; /* reacq_det is read only when set */
    /* the lost tracks: confirmed (or coasting), horizontal std above half the closest spacing */
    const mvt_real lost_var = MVT_R(0.25) * c->rules.birth_min_sep_m * c->rules.birth_min_sep_m;
    if (!(lost_var > MVT_R(0.0))) {
        return;
    }
    predict_all(self, frame->utime_us);
    int rows[MVT_MAX_TARGETS];
    uint8_t lost[MVT_MAX_TARGETS];
    int n_rows = 0;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        const mvt_track_t *tr = &self->tracks[t];
        lost[t] = tr->id != 0 && tr->status != MVT_TRACK_TENTATIVE &&
                  (self->rq_tP[t][0] > lost_var || self->rq_tP[t][4] > lost_var);
        if (lost[t]) {
            rows[n_rows++] = t;
        }
    }
    if (n_rows == 0) {
        return;
    }
    mvt_trk_candidates(self, frame, order, n_order, 0);
    const int n_pts = distinct_points(self);
    /* a point inside the gate of a track that is not lost is that track's person */
    int cols[MVT_MAX_DETECTIONS];
    int n_cols = 0;
    for (int i = 0; i < n_pts; i++) {
        int taken = 0;
        for (int t = 0; t < MVT_MAX_TARGETS && !taken; t++) {
            const mvt_track_t *tr = &self->tracks[t];
            if (tr->id == 0 || lost[t]) {
                continue;
            }
            const mvt_real d2 = mvt_trk_mahalanobis3(self->rq_tx[t], self->rq_tP[t], self->rq_x[i], self->rq_cov[i], NULL);
            taken = d2 >= MVT_R(0.0) && d2 <= MVT_TRK_GATE3;
        }
        if (!taken) {
            cols[n_cols++] = i;
        }
    }
    const int ncol = n_cols + n_rows;
    if (n_cols == 0 || ncol > MVT_ASSOC_MAX_COLS || n_rows > MVT_ASSOC_MAX_ROWS) {
        return;
    }
    /* rows: the lost tracks; columns: the points, then one "not here" per row */
    for (int r = 0; r < n_rows; r++) {
        mvt_real x[3], P[9];
        lost_prediction(self, rows[r], x, P);
        mvt_real *row = &self->cl_cost[r * ncol];
        for (int j = 0; j < n_cols; j++) {
            const int i = cols[j];
            const mvt_real d2 = mvt_trk_mahalanobis3(x, P, self->rq_x[i], self->rq_cov[i], NULL);
            row[j] = d2 >= MVT_R(0.0) && d2 <= MVT_TRK_GATE3 ? d2 : MVT_R(-1.0);
        }
        for (int j = 0; j < n_rows; j++) {
            row[n_cols + j] = j == r ? MVT_TRK_GATE3 : MVT_R(-1.0);
        }
    }
    for (int t = 0; t < MVT_MAX_TARGETS; t++) { /* only now: the common frame has no lost track */
        for (int k = 0; k < MVT_MAX_CAMERAS; k++) {
            self->reacq_det[t][k] = -1;
        }
    }
    int assign[MVT_MAX_TARGETS];
    if (mvt_assoc_solve(self->cl_cost, n_rows, ncol, ncol, assign, &self->assoc_ws) != MVT_OK) {
        return;
    }
    for (int r = 0; r < n_rows; r++) {
        if (assign[r] < 0 || assign[r] >= n_cols) {
            continue;
        }
        const mvt_birth_cand_t *cd = &self->cand[self->rq_cand[cols[assign[r]]]];
        for (int v = 0; v < cd->n; v++) {
            self->reacq_det[rows[r]][cd->cam[v]] = cd->det[v];
        }
        self->reacq_any = 1;
        self->counters.reacquired++;
    }
}
