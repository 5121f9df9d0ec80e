/*
 * status.c - MVTRACK_STATUS (mvtrack.status_t, about once a second) and the one-line logs of
 * camera events: what the daemon received, refused, shed and did since it started.
 */
#include "engine.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mvtrack_status_t.h"

static int cmp_float(const void *a, const void *b)
{
    const float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

static float percentile(float *v, int n, double p)
{
    if (n <= 0) {
        return 0.0f;
    }
    qsort(v, (size_t)n, sizeof(float), cmp_float);
    int i = (int)ceil(p * (double)n) - 1;
    i = i < 0 ? 0 : (i >= n ? n - 1 : i);
    return v[i];
}

void mvtd_publish_status(mvtd_t *d)
{
    const double now = mvtd_wall_s();
    const double period = now - d->last_status_wall_s;
    mvtrack_status_t st;
    memset(&st, 0, sizeof(st));
    mvtrack_camera_status_t cams[MVT_MAX_CAMERAS];
    st.utime = mvtd_wall_utime();
    st.uptime_s = (float)(now - d->start_wall_s);
    st.mode = (char *)d->mode_name;
    st.frames_processed = d->frames_processed;
    st.frame_sets_complete = (int64_t)d->assembler.counters.sets_complete;
    st.frame_sets_partial = (int64_t)d->assembler.counters.sets_partial;
    st.output_rate_hz = period > 0.0 ? (float)((double)(d->frames_processed - d->frames_at_last_status) / period) : 0.0f;
    d->frames_at_last_status = d->frames_processed;
    st.clock_jumps = (int32_t)d->assembler.counters.clock_jumps;
    st.time_gaps = (int32_t)d->assembler.counters.time_gaps;
    st.num_cameras = (int16_t)d->rig.num_cameras;
    st.cameras = cams;
    for (int k = 0; k < d->rig.num_cameras; k++) {
        cams[k].name = d->rig.names[k];
        cams[k].messages = d->cam_messages[k];
        cams[k].rate_hz =
            period > 0.0 ? (float)((double)(d->cam_messages[k] - d->cam_messages_at_last_status[k]) / period) : 0.0f;
        cams[k].last_message_age_s = d->cam_last_wall_s[k] > 0.0 ? (float)(now - d->cam_last_wall_s[k]) : -1.0f;
        cams[k].frames_missing = (int64_t)d->assembler.counters.missing[k];
        cams[k].active = (int8_t)((d->assembler.active >> k) & 1u);
        cams[k].went_down = (int32_t)d->assembler.counters.went_down[k];
        cams[k].came_back = (int32_t)d->assembler.counters.came_back[k];
        cams[k].counter_restarts = (int32_t)d->cam_counter_restarts[k];
        cams[k].shed = d->cam_shed[k];
        cams[k].clock_offset_ms = d->clock.n[k] > 0 ? (float)((double)d->clock.offset_us[k] * 1e-3) : 0.0f;
        cams[k].clock_tracks_lag_ms = (float)(d->clock.lag_us[k] * 1e-3);
        cams[k].clock_tracks_known = (int8_t)d->clock.lag_known[k];
        cams[k].clock_known = (int8_t)d->clock.confident[k];
        cams[k].clock_refused = d->clock.refused[k];
        d->cam_messages_at_last_status[k] = d->cam_messages[k];
    }
    st.rejected_undecodable = d->rej_undecodable;
    st.rejected_unknown_camera = d->rej_unknown_camera;
    st.rejected_bad_value = d->rej_bad_value + (int64_t)d->trk->counters.detections_nonfinite +
                            (int64_t)d->trk->counters.detections_undistort_failed;
    st.rejected_over_capacity = d->rej_over_capacity;
    st.rejected_time_backwards = d->rej_time_backwards;
    st.rejected_time_ahead = d->rej_time_ahead;
    st.rejected_late = d->rej_late;
    st.rejected_duplicate = d->rej_duplicate;
    st.rejected_clock = d->rej_clock;
    float tmp[MVTD_PROC_RING];
    const int n = d->n_proc < MVTD_PROC_RING ? d->n_proc : MVTD_PROC_RING;
    memcpy(tmp, d->proc_ms, (size_t)n * sizeof(float));
    st.proc_ms_p50 = percentile(tmp, n, 0.5);
    st.proc_ms_p99 = percentile(tmp, n, 0.99);
    st.proc_ms_max = n > 0 ? tmp[n - 1] : 0.0f;
    memcpy(tmp, d->latency_ms, (size_t)n * sizeof(float));
    st.latency_ms_p50 = percentile(tmp, n, 0.5);
    st.latency_ms_p99 = percentile(tmp, n, 0.99);
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        const mvt_track_t *tr = &d->trk->tracks[t];
        if (tr->id == 0) {
            continue;
        }
        if (tr->status == MVT_TRACK_TENTATIVE) {
            st.tracks_tentative++;
        } else if (tr->status == MVT_TRACK_CONFIRMED) {
            st.tracks_confirmed++;
        } else {
            st.tracks_coasting++;
        }
    }
    st.tracks_dropped_capacity = (int64_t)d->trk->counters.births_refused_full;
    const mvt_counters_t *c = &d->trk->counters;
    st.births = (int64_t)c->births;
    st.deleted_unlikely = (int64_t)c->deleted_unlikely;
    st.deleted_exit = (int64_t)c->deleted_exit;
    st.deleted_uncertain = (int64_t)c->deleted_uncertain;
    st.deleted_outside = (int64_t)c->deleted_outside;
    st.deleted_duplicate = (int64_t)c->duplicates_deleted;
    st.updates = (int64_t)c->updates;
    st.updates_feet = (int64_t)c->foot_updates;
    st.updates_mask_top = (int64_t)c->mask_top_updates;
    st.fragments = (int64_t)c->fragments;
    st.birth_candidates_dropped = (int64_t)c->birth_candidates_dropped;
    st.numeric_faults = (int64_t)c->numeric_faults;
    st.updates_occluded = (int64_t)c->occluded_updates;
    st.updates_exclusion = (int64_t)c->exclusion_updates;
    st.tracks_reacquired = (int64_t)c->reacquired;
    st.masks_decoded = d->masks_decoded;
    st.masks_rejected = d->masks_rejected;
    if (d->pf) {
        const mvt_pft_counters_t *pc = &d->pft->counters;
        st.views_without_mask = (int64_t)pc->views_without_mask;
        st.pf_resamples = (int64_t)pc->resamples;
        st.numeric_faults += (int64_t)pc->numeric_faults;
        /* the published tracks are the particle targets: count them, not the blob tracks */
        st.tracks_tentative = st.tracks_confirmed = st.tracks_coasting = 0;
        for (int t = 0; t < MVT_MAX_TARGETS; t++) {
            const mvt_pft_target_t *a = &d->pft->targets[t];
            if (a->id != 0) {
                st.tracks_confirmed += a->status == MVT_TRACK_CONFIRMED;
                st.tracks_coasting += a->status == MVT_TRACK_COASTING;
            }
        }
        st.births = (int64_t)pc->births;
        st.deleted_tentative = (int64_t)pc->deleted_tentative;
        st.deleted_unseen = (int64_t)pc->deleted_lost;
        st.deleted_outside = (int64_t)pc->deleted_outside;
        st.deleted_duplicate = (int64_t)pc->deleted_duplicate;
        st.tracks_dropped_capacity = (int64_t)pc->births_refused_full;
        st.identities_recovered = (int64_t)pc->identities_recovered;
    }
    st.shed_other_channels = d->cam_shed[d->rig.num_cameras];
    st.checkpoint_age_s = -1.0f;
    if (d->state_path != NULL) {
        mvtd_ckpt_stats(d, &st.checkpoints_written, &st.checkpoint_failures, &st.checkpoint_age_s);
    }
    st.restore = d->restore_note;
    PUBLISH(d, mvtrack_status_t, "MVTRACK_STATUS", &st);
    d->last_status_wall_s = now;
}


void mvtd_log_camera_events(mvtd_t *d)
{
    const mvtd_asm_counters_t *c = &d->assembler.counters;
    for (int k = 0; k < d->rig.num_cameras; k++) {
        if (c->went_down[k] != d->went_down_seen[k]) {
            d->went_down_seen[k] = c->went_down[k];
            mvtd_log(d, MVTD_LOG_CAMERA, "camera %s absent from %d frame sets: no longer waited for",
                     d->rig.names[k], MVTD_ASM_DOWN_SETS);
        }
        if (c->came_back[k] != d->came_back_seen[k]) {
            d->came_back_seen[k] = c->came_back[k];
            mvtd_log(d, MVTD_LOG_CAMERA, "camera %s is back", d->rig.names[k]);
        }
    }
    for (int k = 0; k < d->rig.num_cameras; k++) {
        /* a camera's clock off the others' (clock.h): said once when re-timed, once when refused */
        const int64_t off = d->clock.offset_us[k];
        const int64_t mag = off < 0 ? -off : off;
        const int level = !d->clock.confident[k] || mag <= MVTD_CLOCK_WARN_US ? 0 : (mag > MVTD_CLOCK_MAX_US ? 2 : 1);
        if (level > 0 && level != d->clock.warned[k] &&
            mvtd_log(d, MVTD_LOG_CLOCK,
                     level == 2 ? "camera %s: its clock is %+.1f ms off the other cameras' (from arrival times): "
                                  "beyond %.0f ms, its frames are refused"
                                : "camera %s: its clock is %+.1f ms off the other cameras' (from arrival times): its "
                                  "frames are re-timed (up to %.0f ms)",
                     d->rig.names[k], (double)off * 1e-3, (double)MVTD_CLOCK_MAX_US * 1e-3)) {
            d->clock.warned[k] = level; /* suppressed by the rate bound: said at a later call */
        }
        /* walking people late in its frames against the tracks (clock.h): said once */
        const double lag = d->clock.lag_us[k];
        if (d->clock.lag_over_since_us[k] != 0 && !d->clock.lag_warned[k] &&
            d->clock.motion_last_us - d->clock.lag_over_since_us[k] >= MVTD_CLOCK_MOTION_WARN_US &&
            mvtd_log(d, MVTD_LOG_CLOCK,
                     "camera %s: walking people in its frames are %+.0f ms (+-%.0f) %s the tracks: its detector or "
                     "network is that much %s than the others' (or its clock is off and its delay hides it), so its "
                     "frames are used that late; tracking holds, a little less precise",
                     d->rig.names[k], lag * 1e-3, d->clock.lag_se_us[k] * 1e-3, lag > 0 ? "behind" : "ahead of",
                     lag > 0 ? "slower" : "faster")) {
            d->clock.lag_warned[k] = 1;
        }
    }
    if (c->clock_jumps != d->clock_jumps_seen) {
        d->clock_jumps_seen = c->clock_jumps;
        mvtd_log(d, MVTD_LOG_TIME, "capture clock went back on every camera: time re-based (offset %lld us)",
                 (long long)d->assembler.offset_us);
    }
}
