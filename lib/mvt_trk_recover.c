/*
 * mvt_trk_recover.c - identity recovery (mvt_trk.h): a person whose track was deleted while they
 * were still in the room, and who is born again soon after within walking reach, at the same head
 * height, keeps their identity.
 *
 * Why. A track is deleted on evidence that can be wrong for a moment: no camera placed it for
 * coast_max_s (a segmentation that lost a person standing still), it was hidden for
 * occluded_max_s with no blob needing it, or views showed its place empty for contra_max_s (its
 * estimate drifted off a hidden person), or it was unseen for exit_coast_s near a side wall (a
 * person walking along a wall, not out through it: three of the identity switches of the crowd
 * runs, docs/tracking.md). The person is then born again a few frames later under a new identity:
 * an identity switch that no association can prevent, because the old track no longer exists.
 * Tracks out of the volume and tracks too uncertain to have a place are not kept: their person is
 * gone or nowhere in particular. A confirmed duplicate is kept: it is the
 * track that drifted onto another's person (mvt_trk_delete.c), and its own may be hidden nearby.
 *
 * The test. A record keeps the deleted track's horizontal position x_l as the motion models
 * predicted it at the deletion, with its covariance P_l, and the head height (and its variance) of
 * the last frame the track was seen: while a track coasts, its height spreads with the models'
 * vertical noise, and the cue that tells two people apart would be lost. A birth at x_b
 * with covariance P_b, dt seconds after the track was last seen, is the same person when
 *     d^2 = (x_b - x_l)^T (P_l + P_b + W)^-1 (x_b - x_l) <= MVT_TRK_GATE3 (chi-square 3 dof, 99.9 %),
 * W = diag(v^2 dt^2, v^2 dt^2, h^2): the person walked at a speed of standard deviation
 * v = init_vel_std_ms per axis (the prior of a new track's speed) since anyone last saw them, and a
 * head's height stays within h = MVT_TRK_HEAD_SD_M. The time counts from the last frame seen, not
 * from the deletion: a track deleted as contradicted was not where its person was for the last
 * contra_max_s, and a standing person's motion model (its covariance grows a few millimetres a
 * second) says nothing about where they went (rig 11 from rendered video: a contradicted track
 * 0.4 m from its person's rebirth, 0.56 s after it last saw them, was 54 chi-square units away
 * when counted from the deletion, 1.0 from the last frame seen). Of several records in reach, the least d^2 plus the colour's -2 ln LR
 * (mvt_trk_app.c: the birth's detections against the record's colour) wins. The height is what
 * tells two people apart after a gap (re-acquisition uses the same cue).
 *
 * The identity goes to the birth at once (a track's identity never changes during its life) and
 * the record travels with the tentative track: if that track dies tentative (a ghost, not the
 * person) the record goes back to the store with its own deadline. Records are kept recover_s
 * after the deletion; when MVT_MAX_LOST are kept, the one nearest its deadline gives way.
 */
#include <math.h>
#include <string.h>

#include "mvt_trk.h"

/* The slot for a new record: a free or expired one, else the one nearest its deadline. */
static mvt_lost_t *free_record(mvt_tracker_t *self, int64_t now_us)
{
    mvt_lost_t *best = &self->lost[0];
    for (int i = 0; i < MVT_MAX_LOST; i++) {
        mvt_lost_t *r = &self->lost[i];
        if (r->id == 0 || r->until_us < now_us) {
            return r;
        }
        if (r->until_us < best->until_us) {
            best = r;
        }
    }
    return best;
}

/* What mvt_trk_lose would keep of a track, without keeping it. */
static void record_of(const mvt_track_t *tr, int64_t until_us, mvt_lost_t *r)
{
    memset(r, 0, sizeof(*r));
    r->id = tr->id;
    r->lost_us = tr->last_update_us; /* the person's whereabouts are unknown since */
    r->until_us = until_us;
    for (int i = 0; i < 2; i++) {
        r->x[i] = tr->s.x[i];
        for (int j = 0; j < 2; j++) {
            r->P[i * 3 + j] = tr->s.P[i * 6 + j];
        }
    }
    r->x[2] = tr->seen_z;
    r->P[8] = tr->seen_zz;
    r->app = tr->app;
}

void mvt_trk_lose(mvt_tracker_t *self, const mvt_track_t *tr, int64_t now_us)
{
    const mvt_real keep_s = self->cfg.rules.recover_s;
    if (!(keep_s > MVT_R(0.0)) || tr->id == 0) {
        return;
    }
    record_of(tr, now_us + (int64_t)(keep_s * MVT_R(1e6)), free_record(self, now_us));
}

void mvt_trk_give_back(mvt_tracker_t *self, mvt_track_t *tr, int64_t now_us)
{
    if (tr->held.id == 0 || tr->held.id != tr->id) {
        return;
    }
    if (tr->held.until_us >= now_us) {
        *free_record(self, now_us) = tr->held;
    }
    memset(&tr->held, 0, sizeof(tr->held));
}

void mvt_trk_confirm(mvt_tracker_t *self, mvt_track_t *tr)
{
    tr->status = MVT_TRACK_CONFIRMED;
    if (tr->held.id != 0) { /* the recovered identity is the track's own now */
        self->counters.identities_recovered++;
        memset(&tr->held, 0, sizeof(tr->held));
    }
}

/* Is a birth whose place is d2 (Mahalanobis, covariance S, |S| = det) from a record likelier that
 * record's person than a person new to the room, whose head may be anywhere in the tracked volume
 * (density 1 / V)? N(d2; S) > 1 / V, i.e. d2 + ln((2 pi)^3 |S|) < 2 ln V. The gate alone let a
 * record whose person nobody had placed for seconds reach across the room: its walking reach grows
 * init_vel_std_ms a second, so after 3 s a person entering by a door 2.4 m away was "in reach" and
 * took the identity (docs/tracking.md, "Deleted, then born again"). */
static int likelier_than_new(const mvt_tracker_config_t *c, mvt_real d2, mvt_real det)
{
    const mvt_real vol = (c->volume.max[0] - c->volume.min[0]) * (c->volume.max[1] - c->volume.min[1]) *
                         (c->volume.max[2] - c->volume.min[2]);
    if (!(det > MVT_R(0.0)) || !(vol > MVT_R(0.0))) {
        return 0;
    }
    return d2 + MVT_LOG(MVT_R(248.05021344239853) * det) < MVT_R(2.0) * MVT_LOG(vol); /* (2 pi)^3 */
}

/* The test above for a birth at x (covariance cov, colour obs) and record r at now_us: 0 when out of
 * reach (or singular), else 1 and in *score the d^2 plus the colour's -2 ln LR (may be < 0). */
static int record_test(const mvt_tracker_t *self, const mvt_lost_t *r, const mvt_real x[3], const mvt_real cov[9],
                       const mvt_app_obs_t *obs, int64_t now_us, mvt_real *score)
{
    const mvt_real v = self->cfg.init_vel_std_ms;
    const mvt_real dt = mvt_us_to_s(now_us - r->lost_us);
    mvt_real P[9];
    memcpy(P, r->P, sizeof(P));
    P[0] += v * v * dt * dt; /* + W */
    P[4] += v * v * dt * dt;
    P[8] += MVT_TRK_HEAD_SD_M * MVT_TRK_HEAD_SD_M;
    mvt_real det;
    const mvt_real d2 = mvt_trk_mahalanobis3(r->x, P, x, cov, &det);
    if (!(d2 >= MVT_R(0.0)) || d2 > MVT_TRK_GATE3 || !likelier_than_new(&self->cfg, d2, det)) {
        return 0;
    }
    /* the colour ranks the records in reach (-2 ln LR of the birth's detections against the record's
     * appearance); it does not refuse one: a birth's blobs in a crowd often mix two people's colour */
    *score = d2 + mvt_trk_app_obs_cost(&r->app, obs);
    return 1;
}

/* The record in reach of a birth at x with the least score (record_test; in *score_out), or -1. */
static int nearest_record(const mvt_tracker_t *self, const mvt_real x[3], const mvt_real cov[9],
                          const mvt_app_obs_t *obs, int64_t now_us, mvt_real *score_out)
{
    int best = -1;
    mvt_real best_score = MVT_R(0.0);
    for (int i = 0; i < MVT_MAX_LOST; i++) {
        const mvt_lost_t *r = &self->lost[i];
        if (r->id == 0 || r->until_us < now_us) {
            continue;
        }
        mvt_real score;
        if (record_test(self, r, x, cov, obs, now_us, &score) && (best < 0 || score < best_score)) {
            best_score = score;
            best = i;
        }
    }
    *score_out = best_score;
    return best;
}

void mvt_trk_release_contradicted(mvt_tracker_t *self, const mvt_real x[3], const mvt_real cov[9],
                                  const mvt_app_obs_t *obs, int64_t now_us)
{
    if (!(self->cfg.rules.recover_s > MVT_R(0.0))) {
        return;
    }
    int best = -1;
    mvt_real best_score = MVT_R(0.0);
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        const mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0 || tr->status == MVT_TRACK_TENTATIVE || tr->misses < 1 ||
            mvt_trk_popcount(tr->cameras_uncovered) < self->cfg.rules.contra_views) {
            continue; /* tentative, seen this frame, or not contradicted by contra_views views as
                         mvt_trk_delete has it (one view's empty place, which refutes a frame, is one
                         missed detection as often as a person gone) */
        }
        mvt_lost_t r;
        record_of(tr, now_us, &r);
        mvt_real score;
        if (record_test(self, &r, x, cov, obs, now_us, &score) && (best < 0 || score < best_score)) {
            best_score = score;
            best = t;
        }
    }
    mvt_real rec_score;
    if (best < 0 || (nearest_record(self, x, cov, obs, now_us, &rec_score) >= 0 && rec_score < best_score)) {
        return; /* none in reach, or a deleted track's record is nearer: recovery gives that one */
    }
    mvt_track_t *tr = &self->tracks[best];
    mvt_trk_lose(self, tr, now_us);
    tr->id = 0;
    self->counters.deleted_contradicted++;
    self->counters.deletions++;
}

int32_t mvt_trk_recover(mvt_tracker_t *self, const mvt_real x[3], const mvt_real cov[9], const mvt_app_obs_t *obs,
                        int64_t now_us, mvt_lost_t *held)
{
    mvt_real score;
    const int best = nearest_record(self, x, cov, obs, now_us, &score);
    if (best < 0) {
        return 0;
    }
    *held = self->lost[best];
    memset(&self->lost[best], 0, sizeof(self->lost[best]));
    return held->id;
}
