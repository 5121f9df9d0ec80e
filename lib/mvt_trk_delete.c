/*
 * mvt_trk_delete.c - confirmation and deletion of the tracker loop.
 *
 * A frame "sees" a track when at least seen_min_views cameras updated it, or one did and the
 * position is still well determined (seen_max_std_m), or every camera whose picture holds its head
 * updated it (a person where fewer than seen_min_views cameras reach). A tentative track is
 * confirmed after confirm_hits seen frames among the last confirm_window
 * and deleted after tentative_max_misses consecutive misses. A confirmed track that no camera
 * updated this frame is COASTING; it is deleted once unseen for coast_max_s (or, hidden in other
 * tracks' blobs, once neither seen nor needed by their boxes for occluded_max_s), once contradicted
 * (its place in no blob another track took, in contra_views views) for contra_max_s, or for
 * MVT_TRK_FG_CONTRA times that where those views' masks show foreground at the place, when its position
 * standard deviation exceeds max_pos_std_m on any axis, when it leaves the volume (plus margin),
 * or when its covariance cannot be repaired. A track unseen for exit_coast_s near the volume's
 * side walls is deleted sooner (people leave through the sides; its identity is kept for recovery
 * all the same, since people also walk along walls). Of two tracks closer than
 * dup_dist_m in 3D (one person, two tracks), the one the cameras did not place is deleted, else
 * the younger, unless the cameras' evidence over time says one of them is nobody's
 * (delete_duplicates). Identities of deleted
 * tracks are never given to another person; a confirmed track deleted while its person may still
 * be in the room leaves its identity for recovery (mvt_trk_recover.c).
 */
#include <math.h>
#include <stddef.h>

#include "mvt_trk.h"

static int near_side_wall(const mvt_tracker_config_t *c, const mvt_real x[3])
{
    for (int i = 0; i < 2; i++) {
        if (x[i] < c->volume.min[i] + c->volume.exit_margin_m || x[i] > c->volume.max[i] - c->volume.exit_margin_m) {
            return 1;
        }
    }
    return 0;
}

/* Deletes one of every pair of live tracks closer than dup_dist_m: confirmed beats tentative; of two
 * confirmed (projective filters), one whose existence odds before this frame are more than
 * MVT_TRK_EXIST_LLR below the other's goes (a track that lived on hidden after its person left,
 * then was pulled onto someone: mvt_trk_existence); then a track the cameras placed this frame
 * (seen_min_views views) beats one they did not, then the older identity wins. Two tracks become duplicates when one was pulled onto the other's person (a
 * merged blob's top, a detection along one view's ray): the placed track is that person's, the one
 * that drifted there is not, and its own person (hidden, most often) may still be in the room, so
 * a confirmed victim leaves its identity for recovery (mvt_trk_recover.c). Measured on the masks'
 * connected components and rig 12's queue, docs/tracking.md. O(T^2). */
static void delete_duplicates(mvt_tracker_t *self, int64_t now_us)
{
    const mvt_real r2 = self->cfg.rules.dup_dist_m * self->cfg.rules.dup_dist_m;
    if (!(r2 > MVT_R(0.0))) {
        return;
    }
    const int min_views = mvt_trk_min_views(self);
    const int projective = self->cfg.filter == MVT_FILTER_PROJECTIVE; /* existence has detections' evidence */
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        mvt_track_t *a = &self->tracks[t];
        for (int u = t + 1; u < MVT_MAX_TARGETS && a->id != 0; u++) {
            mvt_track_t *b = &self->tracks[u];
            if (b->id == 0) {
                continue;
            }
            const mvt_real dx = a->s.x[0] - b->s.x[0], dy = a->s.x[1] - b->s.x[1], dz = a->s.x[2] - b->s.x[2];
            if (dx * dx + dy * dy + dz * dz >= r2) {
                continue;
            }
            const int a_conf = a->status != MVT_TRACK_TENTATIVE, b_conf = b->status != MVT_TRACK_TENTATIVE;
            const int a_hit = mvt_trk_popcount(a->cameras_used) >= min_views;
            const int b_hit = mvt_trk_popcount(b->cameras_used) >= min_views;
            int drop_a = a_conf != b_conf ? !a_conf : (a_hit != b_hit ? !a_hit : a->id > b->id);
            /* the existence odds before this frame's evidence (this frame's placement is above): one
             * track 99 times likelier to be a person's than the other is kept */
            const mvt_real odds_a = a->exist_llr - self->ev_llr[t], odds_b = b->exist_llr - self->ev_llr[u];
            if (a_conf && b_conf && projective && MVT_FABS(odds_a - odds_b) > MVT_TRK_EXIST_LLR) {
                drop_a = odds_a < odds_b; /* the cameras' long say beats this frame's */
            }
            mvt_track_t *victim = drop_a ? a : b;
            if (victim->status == MVT_TRACK_TENTATIVE) {
                mvt_trk_give_back(self, victim, now_us); /* a tentative holding a lost identity */
            } else {
                mvt_trk_lose(self, victim, now_us);
            }
            victim->id = 0;
            self->counters.deletions++;
            self->counters.duplicates_deleted++;
        }
    }
}

void mvt_trk_delete(mvt_tracker_t *self, int64_t now_us)
{
    const mvt_tracker_config_t *c = &self->cfg;
    const uint32_t window = c->rules.confirm_window >= 32 ? 0xffffffffu : ((1u << c->rules.confirm_window) - 1u);
    const int min_views = mvt_trk_min_views(self);
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0) {
            continue;
        }
        const int views = mvt_trk_popcount(tr->cameras_used);
        const mvt_real std2 = c->rules.seen_max_std_m * c->rules.seen_max_std_m;
        int hit = views >= min_views || (views >= 1 && tr->s.P[0] <= std2 && tr->s.P[7] <= std2 &&
                                               tr->s.P[14] <= std2);
        /* the frame's odds (p_detect): the views that saw the track against those that show its
         * place in no blob at all */
        const int refuted = tr->cameras_empty != 0u &&
                            mvt_trk_odds(self, tr->cameras_used, mvt_trk_popcount(tr->cameras_empty)) < MVT_R(0.0);
        hit = hit && !refuted;
        /* placed in 3D: the height it was seen at (seen_z) is what mvt_trk_hold_height holds */
        const int placed = hit;
        /* every camera whose picture holds the head updated the track: one view then sees it all
         * the same (a person where a single camera reaches, the height held to seen_z fixing the
         * point on its ray) */
        if (!hit && !refuted && self->visible[t] != 0u && (self->visible[t] & ~tr->cameras_used) == 0u) {
            hit = 1;
        }
        tr->hit_history = (tr->hit_history << 1) | (hit ? 1u : 0u);
        const int contradicted = refuted || (!hit && mvt_trk_popcount(tr->cameras_uncovered) >= c->rules.contra_views);
        if (!contradicted) {
            tr->last_consistent_us = now_us;
        }
        /* ... by views that show the place on background (or have no mask to tell) */
        if (!refuted && (hit || mvt_trk_popcount(tr->cameras_uncovered & ~tr->cameras_fg) < c->rules.contra_views)) {
            tr->last_unrefuted_us = now_us;
        }
        if (placed) {
            tr->seen_z = tr->s.x[2];
            tr->seen_zz = tr->s.P[14];
        }
        if (hit) {
            tr->misses = 0;
            tr->last_update_us = now_us;
            tr->last_explained_us = now_us;
            tr->last_needed_us = now_us;
        } else {
            tr->misses++;
            if (!contradicted && views + mvt_trk_popcount(tr->cameras_occluded) >= min_views) {
                tr->last_explained_us = now_us; /* hidden in other tracks' blobs, not lost */
                if (tr->need_llr > MVT_R(0.0)) {
                    tr->last_needed_us = now_us; /* ... and a blob needs the person */
                }
            }
        }
        uint64_t *reason = NULL; /* the counter of the deletion's reason */
        if (mvt_trk_repair(self, tr) != MVT_OK) {
            self->counters.numeric_faults++;
            reason = &self->counters.numeric_faults;
        }
        const mvt_real *P = tr->s.P;
        const mvt_real var_max = c->numerics.max_pos_std_m * c->numerics.max_pos_std_m;
        const mvt_real lost_s = mvt_us_to_s(now_us - tr->last_explained_us);
        const mvt_real unneeded_s = mvt_us_to_s(now_us - tr->last_needed_us);
        switch (tr->status) {
        case MVT_TRACK_TENTATIVE:
            /* existence: the evidence of the detections in its gates since the birth frame
             * (mvt_trk_assoc.c), a sequential test (Wald) with 1 % error either way */
            tr->exist_llr += self->ev_llr[t];
            if (tr->misses >= c->rules.tentative_max_misses || tr->exist_llr <= -MVT_TRK_EXIST_LLR) {
                reason = &self->counters.deleted_tentative;
            } else if (mvt_trk_popcount(tr->hit_history & window) >= c->rules.confirm_hits &&
                       tr->exist_llr >= MVT_TRK_EXIST_LLR) {
                mvt_trk_confirm(self, tr);
            }
            break;
        case MVT_TRACK_CONFIRMED:
        case MVT_TRACK_COASTING:
            tr->status = tr->cameras_used != 0u ? MVT_TRACK_CONFIRMED : MVT_TRACK_COASTING;
            tr->exist_llr += self->ev_llr[t];
            if (lost_s > c->rules.coast_max_s) {
                reason = &self->counters.deleted_unseen;
            } else if (unneeded_s > c->rules.occluded_max_s) {
                reason = &self->counters.deleted_occluded;
            } else if (mvt_us_to_s(now_us - tr->last_unrefuted_us) > c->rules.contra_max_s ||
                       mvt_us_to_s(now_us - tr->last_consistent_us) > MVT_TRK_FG_CONTRA * c->rules.contra_max_s) {
                reason = &self->counters.deleted_contradicted;
            } else if (lost_s > c->rules.exit_coast_s && near_side_wall(c, tr->s.x)) {
                reason = &self->counters.deleted_exit;
            }
            break;
        default:
            reason = &self->counters.numeric_faults;
            break;
        }
        if (reason == NULL && (P[0] > var_max || P[7] > var_max || P[14] > var_max)) {
            reason = &self->counters.deleted_uncertain;
        }
        if (reason == NULL && !mvt_trk_inside_volume(c, tr->s.x)) {
            reason = &self->counters.deleted_outside;
        }
        if (reason != NULL) {
            if (reason != &self->counters.numeric_faults) {
                (*reason)++;
            }
            if (tr->status == MVT_TRACK_TENTATIVE) {
                mvt_trk_give_back(self, tr, now_us);
            } else if (reason == &self->counters.deleted_unseen || reason == &self->counters.deleted_occluded ||
                       reason == &self->counters.deleted_contradicted || reason == &self->counters.deleted_exit) {
                mvt_trk_lose(self, tr, now_us); /* the person may still be here (one unseen by a wall
                                                    may walk along it); one whose place is unknown is
                                                    not kept */
            }
            tr->id = 0;
            self->counters.deletions++;
        }
    }
    delete_duplicates(self, now_us);
}
