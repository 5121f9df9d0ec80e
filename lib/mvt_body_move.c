/*
 * mvt_body_move.c - a person who walked away from their track: the views that judged the head
 * displaced, taken together.
 *
 * Each camera's update (mvt_body_update.c) weighs a head's blob against the motion model's
 * displaced point (an occluded head, a merged blob's top): a blob far from the prediction moves the
 * estimate little, and a displacement that lasts is expected to go on. That is right for one view
 * at a time. It is wrong when the person walked off while the estimate stayed (it believed them
 * still, and a view along whose ray they walk kept placing it): then two or more views judge
 * their head's blob displaced, each on its own, while together they place the head elsewhere.
 *
 * After every camera's pass, each track likely present whose head's blob two or more views judged
 * displaced (beyond the chi-square gate) is tested against the hypothesis that its person is where
 * those blobs meet: an estimate started from the track's, widened by walking pace over
 * MVT_BODY_MOVE_S (how long an estimate may lag its person unnoticed) and holding the person's
 * height, updated with the displaced views' blobs, then with its other blobs. The likelihood of
 * all the track's head blobs (mvt_body_head_density: the person's with 1 - p_outlier, displaced
 * anywhere near with p_outlier) under each place decides, the new place's taken sequentially (its
 * wider prior pays for itself). Where the new place wins with two displaced views inside its gate,
 * and no other body likely present stands within a body's width of it (two bodies cannot
 * overlap), the track starts again there: the same person, with its label, existence, colour and
 * height.
 * Cost O(T C) projections; memory: none beyond the tracker.
 */
#include "mvt_body.h"

#include <math.h>
#include <stddef.h>

static mvt_real log_density(const mvt_tracker_t *self, const mvt_pkf_innov_t *in)
{
    const mvt_real g = mvt_body_head_density(self, in);
    return MVT_LOG(g > MVT_R(1e-30) ? g : MVT_R(1e-30));
}

/* Track t's head blob in each observed camera this frame (-1 where none), the log likelihood of
 * them all at its estimate, and which the estimate judges displaced (bits). */
static mvt_real blobs_at_estimate(const mvt_tracker_t *self, const mvt_frame_t *frame, int t, int16_t blob[],
                                  uint32_t *displaced)
{
    const mvt_track_t *tr = &self->tracks[t];
    mvt_real ll = MVT_R(0.0);
    *displaced = 0u;
    for (int k = 0; k < self->num_cameras; k++) {
        blob[k] = -1;
        if (!frame->views[k].observed) {
            continue;
        }
        for (int d = 0; d < self->num_meas[k] && blob[k] < 0; d++) {
            blob[k] = self->body.head_of[k][d] == t ? (int16_t)d : (int16_t)-1;
        }
        mvt_pkf_pred_t pred;
        mvt_pkf_innov_t in;
        if (blob[k] < 0 || mvt_pkf_predict_obs(&tr->s, &self->cams[k], MVT_PKF_JACOBIAN, &pred) != MVT_OK ||
            mvt_pkf_innovation_from(&pred, &self->meas[k][blob[k]], NULL, &in) != MVT_OK) {
            blob[k] = -1;
            continue;
        }
        ll += log_density(self, &in);
        if (!(in.d2 <= self->cfg.numerics.gate_chi2)) {
            *displaced |= 1u << k;
        }
    }
    return ll;
}

/* The track's head started from its estimate widened by walking pace over MVT_BODY_MOVE_S and at
 * the person's height, updated with the displaced views' blobs first, then the others': the log
 * likelihood of them all, sequentially; *placed the views inside the gate, *n_displaced how many
 * of them are displaced ones. */
static mvt_real blobs_moved(const mvt_tracker_t *self, const mvt_frame_t *frame, const mvt_track_t *tr,
                            const int16_t blob[], uint32_t displaced, mvt_cv_state_t *s, uint32_t *placed,
                            int *n_displaced)
{
    const mvt_real reach = self->cfg.init_vel_std_ms * MVT_BODY_MOVE_S;
    mvt_real x[3], P[9];
    const int at[9] = {0, 1, 2, 6, 7, 8, 12, 13, 14};
    for (int i = 0; i < 3; i++) {
        x[i] = tr->s.x[i];
    }
    for (int i = 0; i < 9; i++) {
        P[i] = tr->s.P[at[i]];
    }
    P[0] += reach * reach;
    P[4] += reach * reach;
    if (tr->seen_zz > MVT_R(0.0)) {
        x[2] = tr->seen_z;
        P[2] = P[5] = P[6] = P[7] = MVT_R(0.0);
        P[8] = tr->seen_zz + MVT_BODY_HEAD_BOB_M * MVT_BODY_HEAD_BOB_M;
    }
    mvt_cv_init(s, x, P, self->cfg.init_vel_std_ms * self->cfg.init_vel_std_ms, frame->utime_us);
    mvt_real ll = MVT_R(0.0);
    *placed = 0u;
    *n_displaced = 0;
    for (int pass = 0; pass < 2; pass++) {
        for (int k = 0; k < self->num_cameras; k++) {
            const int first = (displaced >> k) & 1u;
            if (blob[k] < 0 || first != (pass == 0)) {
                continue;
            }
            mvt_pkf_pred_t pred;
            mvt_pkf_innov_t in;
            if (mvt_pkf_predict_obs(s, &self->cams[k], MVT_PKF_JACOBIAN, &pred) != MVT_OK ||
                mvt_pkf_innovation_from(&pred, &self->meas[k][blob[k]], NULL, &in) != MVT_OK) {
                return -INFINITY;
            }
            ll += log_density(self, &in);
            if (in.d2 <= self->cfg.numerics.gate_chi2 && mvt_pkf_update(s, &in) == MVT_OK) {
                *placed |= 1u << k;
                *n_displaced += first;
            }
        }
    }
    return ll;
}

/* The observed views in which a head at x lies on some blob (inside its box, the head's own
 * spread about its top allowed): where a body there shows. */
static int views_on_blobs(const mvt_tracker_t *self, const mvt_frame_t *frame, const mvt_real x[3])
{
    const mvt_real in_head[3] = {x[0], x[1], x[2] - MVT_R(0.1)};
    int n = 0;
    for (int k = 0; k < self->num_cameras; k++) {
        mvt_real uv[2];
        if (!frame->views[k].observed || mvt_cam_project(&self->cams[k], in_head, uv, NULL) != MVT_OK) {
            continue;
        }
        const mvt_real slack = MVT_R(2.0) * self->cams[k].sigma_px;
        for (int d = 0; d < self->num_meas[k]; d++) {
            if (mvt_trk_in_box(frame->views[k].det[d].box, uv, slack, slack)) {
                n++;
                break;
            }
        }
    }
    return n;
}

/* No other body likely present within a body's width of x (horizontally). */
static int room_for(const mvt_tracker_t *self, int t, const mvt_real x[3])
{
    const mvt_real sep = MVT_R(2.0) * self->cfg.body.halfwidth_m;
    for (int j = 0; j < MVT_MAX_TARGETS; j++) {
        const mvt_track_t *o = &self->tracks[j];
        if (j == t || o->id == 0 || o->dormant || !(o->exist_lo > MVT_R(0.0))) {
            continue;
        }
        const mvt_real dx = o->s.x[0] - x[0], dy = o->s.x[1] - x[1];
        if (dx * dx + dy * dy < sep * sep) {
            return 0;
        }
    }
    return 1;
}

void mvt_body_move(mvt_tracker_t *self, const mvt_frame_t *frame)
{
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0 || tr->dormant || !(tr->exist_lo > MVT_R(0.0))) {
            continue;
        }
        int16_t blob[MVT_MAX_CAMERAS];
        uint32_t displaced;
        const mvt_real ll_here = blobs_at_estimate(self, frame, t, blob, &displaced);
        if (mvt_trk_popcount(displaced) < 2) {
            continue;
        }
        mvt_cv_state_t s;
        uint32_t placed;
        int n_displaced;
        const mvt_real ll_there = blobs_moved(self, frame, tr, blob, displaced, &s, &placed, &n_displaced);
        const mvt_real dx = s.x[0] - tr->s.x[0], dy = s.x[1] - tr->s.x[1], w = MVT_R(2.0) * self->cfg.body.halfwidth_m;
        if (n_displaced < 2 || !(dx * dx + dy * dy > w * w) || !(ll_there > ll_here) || !room_for(self, t, s.x) ||
            !(views_on_blobs(self, frame, s.x) > views_on_blobs(self, frame, tr->s.x))) {
            continue;
        }
        mvt_real P[9];
        const int at[9] = {0, 1, 2, 6, 7, 8, 12, 13, 14};
        for (int i = 0; i < 9; i++) {
            P[i] = s.P[at[i]];
        }
        mvt_trk_start(self, tr, s.x, P, frame->utime_us);
        for (int k = 0; k < self->num_cameras; k++) {
            if ((placed >> k) & 1u) {
                tr->view[k].p = MVT_R(0.0); /* its blob is the head's again */
            }
        }
        tr->cameras_used |= placed;
        tr->cameras_placed = placed;
        self->counters.reacquired++;
    }
}
