/*
 * mvt_trk_delete.c - confirmation and deletion of the tracker loop.
 *
 * A tentative track is confirmed after confirm_hits updated frames among the last confirm_window
 * and deleted after tentative_max_misses consecutive misses. A confirmed track that no camera
 * updated this frame is COASTING; it is deleted once unseen for coast_max_s, when its position
 * standard deviation exceeds max_pos_std_m on any axis, when it leaves the volume (plus margin),
 * or when its covariance cannot be repaired. Identities of deleted tracks are never reused.
 */
#include "mvt_trk.h"

static int popcount32(uint32_t x)
{
    int n = 0;
    while (x != 0u) {
        x &= x - 1u;
        n++;
    }
    return n;
}

void mvt_trk_delete(mvt_tracker_t *self, int64_t now_us)
{
    const mvt_tracker_config_t *c = &self->cfg;
    const uint32_t window = c->confirm_window >= 32 ? 0xffffffffu : ((1u << c->confirm_window) - 1u);
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0) {
            continue;
        }
        const int hit = tr->cameras_used != 0u;
        tr->hit_history = (tr->hit_history << 1) | (hit ? 1u : 0u);
        if (hit) {
            tr->misses = 0;
            tr->last_update_us = now_us;
        } else {
            tr->misses++;
        }
        int drop = 0;
        if (mvt_cv_repair(&tr->s, c->var_floor_m2) != MVT_OK) {
            self->counters.numeric_faults++;
            drop = 1;
        }
        const mvt_real *P = tr->s.P;
        const mvt_real var_max = c->max_pos_std_m * c->max_pos_std_m;
        const mvt_real unseen_s = (mvt_real)((double)(now_us - tr->last_update_us) * 1e-6);
        switch (tr->status) {
        case MVT_TRACK_TENTATIVE:
            if (tr->misses >= c->tentative_max_misses) {
                drop = 1;
            } else if (popcount32(tr->hit_history & window) >= c->confirm_hits) {
                tr->status = MVT_TRACK_CONFIRMED;
            }
            break;
        case MVT_TRACK_CONFIRMED:
        case MVT_TRACK_COASTING:
            tr->status = hit ? MVT_TRACK_CONFIRMED : MVT_TRACK_COASTING;
            if (unseen_s > c->coast_max_s) {
                drop = 1;
            }
            break;
        default:
            drop = 1;
            break;
        }
        if (P[0] > var_max || P[7] > var_max || P[14] > var_max || !mvt_trk_inside_volume(c, tr->s.x)) {
            drop = 1;
        }
        if (drop) {
            tr->id = 0;
            self->counters.deletions++;
        }
    }
}
