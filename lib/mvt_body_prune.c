/*
 * mvt_body_prune.c - the end of a frame: which tracks end, which are one person, and each track's
 * status, all from the model.
 *
 * A track ends when its existence falls under population.exist_delete (the cameras say nobody is there, or
 * its person walked out through a wall): one that was shown confirmed first sleeps (dormant, unseen
 * and unshown) MVT_BODY_DORMANT_S, its label kept for the person found again nearby, unless it is
 * by a side wall and its velocity carries it out through that wall (its person left; one walking
 * along the wall sleeps like any other). It ends too
 * when its horizontal position is spread wider than
 * max_pos_std_m (nobody has seen it for long: it is nowhere in particular), or when it leaves the
 * volume widened by volume.margin_m.
 * Bodies do not overlap: a track no camera placed this frame is kept a body's width from those the
 * cameras placed and from likelier unplaced ones (a truncation along their horizontal separation;
 * between two tracks both shown, an estimate the truncation finds wholly inside the other body is
 * widened by the overlap first).
 * Two heads closer than body.halfwidth_m horizontally, one of them placed this frame, are one person (two bodies cannot stand
 * inside each other): the track with the likelier estimate (the higher existence) goes on with its
 * own identity, or with the other's when only the other was shown confirmed. The other label, when
 * it was shown, sleeps as a lost one does (one of the two tracks had taken the wrong person).
 * Status: confirmed from the frame the existence first reaches population.exist_confirm, for as long as it
 * stays above one half (more likely there than not; coasting when no camera saw the head this
 * frame); tentative otherwise: a track that drops under one half keeps its identity and is shown
 * confirmed again when its evidence returns.
 * Cost O(T^2); memory: none.
 */
#include "mvt_body.h"

#include <math.h>
#include <string.h>

static void end_track(mvt_tracker_t *self, mvt_track_t *tr, uint64_t *reason)
{
    (*reason)++;
    self->counters.deletions++;
    memset(tr, 0, sizeof(*tr));
}

/* Track tr's label waits, unseen and unshown, for its person found again (heir_of,
 * mvt_body_birth.c); asleep since now. */
static void fall_asleep(const mvt_tracker_t *self, mvt_track_t *tr)
{
    tr->dormant = 1;
    tr->status = MVT_TRACK_TENTATIVE;
    tr->last_update_us = self->last_utime_us;
}

/* A track by a side wall whose velocity carries it out through that wall (faster than a tenth of
 * walking pace): its person left. */
static int heading_out(const mvt_tracker_config_t *c, const mvt_track_t *tr)
{
    const mvt_real m = c->volume.exit_margin_m, v = MVT_R(0.1) * c->init_vel_std_ms;
    const mvt_real *x = tr->s.x;
    return (x[0] < c->volume.min[0] + m && x[3] < -v) || (x[0] > c->volume.max[0] - m && x[3] > v) ||
           (x[1] < c->volume.min[1] + m && x[4] < -v) || (x[1] > c->volume.max[1] - m && x[4] > v);
}

static int shown(const mvt_track_t *tr)
{
    return tr->status == MVT_TRACK_CONFIRMED || tr->status == MVT_TRACK_COASTING;
}

void mvt_body_prune(mvt_tracker_t *self)
{
    const mvt_tracker_config_t *c = &self->cfg;
    const mvt_real lo_delete = mvt_body_logit(c->population.exist_delete);
    const mvt_real lo_confirm = mvt_body_logit(c->population.exist_confirm);
    const mvt_real max_var = c->numerics.max_pos_std_m * c->numerics.max_pos_std_m;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0) {
            continue;
        }
        if (mvt_trk_repair(self, tr) != MVT_OK) {
            self->counters.numeric_faults++;
            end_track(self, tr, &self->counters.deleted_uncertain);
        } else if (tr->dormant) {
            if (mvt_us_to_s(self->last_utime_us - tr->last_update_us) > MVT_BODY_DORMANT_S) {
                end_track(self, tr, &self->counters.deleted_unlikely);
            }
        } else if (!(tr->exist_lo >= lo_delete)) {
            if (tr->was_shown && !heading_out(c, tr)) {
                fall_asleep(self, tr);
            } else if (tr->was_shown) {
                end_track(self, tr, &self->counters.deleted_exit); /* walked out */
            } else {
                end_track(self, tr, &self->counters.deleted_unlikely);
            }
        } else if (!(tr->s.P[0] <= max_var) || !(tr->s.P[7] <= max_var)) {
            end_track(self, tr, &self->counters.deleted_uncertain);
        } else if (!mvt_trk_inside_volume(c, tr->s.x)) {
            end_track(self, tr, &self->counters.deleted_outside);
        }
    }
    /* bodies do not overlap: a track no camera placed this frame (hidden, or missed) is kept a
     * body's width (2 body.halfwidth_m, horizontally) from every track a camera placed and from
     * every likelier one nobody placed; its height stays as it is (a ground-plane truncation) */
    const mvt_real width = MVT_R(2.0) * c->body.halfwidth_m;
    for (int a = 0; a < MVT_MAX_TARGETS; a++) {
        mvt_track_t *ta = &self->tracks[a];
        if (ta->id == 0 || ta->cameras_used != 0u || ta->dormant) {
            continue;
        }
        for (int b = 0; b < MVT_MAX_TARGETS; b++) {
            const mvt_track_t *tb = &self->tracks[b];
            if (b == a || tb->id == 0 || !(tb->exist_lo > MVT_R(0.0)) || tb->dormant ||
                (tb->cameras_used == 0u && !(tb->exist_lo > ta->exist_lo))) {
                continue; /* only the placed, or the likelier of two unplaced, holds its ground */
            }
            const mvt_real dx = ta->s.x[0] - tb->s.x[0], dy = ta->s.x[1] - tb->s.x[1];
            const mvt_real dist = MVT_SQRT(dx * dx + dy * dy);
            if (!(dist < width) || !(dist > MVT_R(1e-6))) {
                continue;
            }
            const mvt_real H[3] = {dx / dist, dy / dist, MVT_R(0.0)};
            const mvt_real var_b = H[0] * H[0] * tb->s.P[0] + MVT_R(2.0) * H[0] * H[1] * tb->s.P[1] + H[1] * H[1] * tb->s.P[7];
            const mvt_real base = H[0] * tb->s.x[0] + H[1] * tb->s.x[1];
            mvt_err_t err = mvt_trk_truncate_ground(self, ta, H, base + dist, var_b, base + width, base + MVT_R(1e3));
            if (err == MVT_ERR_NUMERIC && ta->was_shown && tb->was_shown) {
                /* two people both shown, the unplaced one's estimate inside the other's body with
                 * next to no mass outside it: its estimate is wrong by about the overlap (it has
                 * coasted on a velocity nobody measured), not the person gone; its horizontal
                 * spread along the separation widens by the overlap, then the bodies part */
                const mvt_real over = width - dist;
                mvt_trk_widen_ground(self, ta, H, over * over);
                err = mvt_trk_truncate_ground(self, ta, H, base + dist, var_b, base + width, base + MVT_R(1e3));
            }
            if (err == MVT_OK) {
                self->counters.exclusion_updates++;
            }
        }
    }
    const mvt_real sep2 = c->body.halfwidth_m * c->body.halfwidth_m;
    for (int a = 0; a < MVT_MAX_TARGETS; a++) {
        for (int b = a + 1; b < MVT_MAX_TARGETS && self->tracks[a].id != 0; b++) {
            mvt_track_t *ta = &self->tracks[a], *tb = &self->tracks[b];
            if (tb->id == 0 || ta->dormant || tb->dormant || (ta->cameras_used == 0u && tb->cameras_used == 0u)) {
                continue; /* two estimates nobody placed that drift together are kept apart above */
            }
            const mvt_real dx = ta->s.x[0] - tb->s.x[0], dy = ta->s.x[1] - tb->s.x[1];
            if (!(dx * dx + dy * dy < sep2)) {
                continue;
            }
            /* one person: the likelier estimate, with its identity unless only the other's was shown */
            mvt_track_t *keep = ta->exist_lo >= tb->exist_lo ? ta : tb;
            const mvt_track_t *other = keep == ta ? tb : ta;
            const mvt_track_t *named = !shown(keep) && shown(other) ? other : keep;
            mvt_track_t *drop = keep == ta ? tb : ta;
            const int32_t id = named->id;
            const int32_t status = shown(ta) || shown(tb) ? MVT_TRACK_CONFIRMED : MVT_TRACK_TENTATIVE;
            keep->id = id;
            keep->status = status;
            keep->was_shown |= drop->was_shown;
            keep->cameras_used |= drop->cameras_used;
            if (drop->was_shown && named == keep) {
                /* two bodies cannot stand inside each other, so one of the two tracks followed the
                 * wrong person here; which one the model cannot tell, and the other label is no
                 * evidence that its person left: it sleeps like any lost one, for its person found
                 * again nearby */
                fall_asleep(self, drop);
            } else {
                end_track(self, drop, &self->counters.duplicates_deleted);
            }
        }
    }
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0 || tr->dormant) {
            continue;
        }
        if (tr->exist_lo >= lo_confirm || (shown(tr) && tr->exist_lo > MVT_R(0.0))) {
            tr->status = tr->cameras_used != 0u ? MVT_TRACK_CONFIRMED : MVT_TRACK_COASTING;
            tr->was_shown = 1;
        } else {
            tr->status = MVT_TRACK_TENTATIVE;
        }
        if (tr->cameras_used != 0u) {
            tr->last_update_us = self->last_utime_us;
        }
    }
}
