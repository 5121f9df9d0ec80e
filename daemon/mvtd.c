/*
 * mvtd.c - the daemon's engine (see mvtd.h; CONTRACT section 3).
 *
 * LCM in: DETECTIONS_.* (mvtrack.camera_frame_t). LCM out: TRACKS (mvtrack.tracks_t) every
 * processed frame set, MVTRACK_STATUS (mvtrack.status_t) about once a second, and in pf modes
 * optionally MVTRACK_PARTICLES. The tracking maths live in lib/; this file is transport,
 * validation and bookkeeping. Trust model: docs/trust-model.md.
 */
#define _GNU_SOURCE /* signalfd, timerfd */
#include "mvtd.h"

#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/signalfd.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include "mvtrack_camera_frame_t.h"
#include "mvtrack_particles_t.h"
#include "mvtrack_status_t.h"
#include "mvtrack_tracks_t.h"

typedef mvtd_t daemon_state_t;

/* Without LCM output (fuzzing, soak) messages are still encoded, into this buffer. */
static uint8_t g_encode_buf[1 << 22];

#define PUBLISH(d, T, channel, msg)                                                                \
    do {                                                                                           \
        if ((d)->lcm_out != NULL) {                                                                \
            T##_publish((d)->lcm_out, channel, msg);                                               \
        } else {                                                                                   \
            const int n_ = T##_encode(g_encode_buf, 0, (int)sizeof(g_encode_buf), msg);          \
            (d)->bytes_encoded += n_ > 0 ? n_ : 0;                                                 \
        }                                                                                          \
    } while (0)

static double wall_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static int64_t wall_utime(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

/* stderr at a bounded rate: one line per class per second, with the count of suppressed lines. */
static void log_limited(daemon_state_t *d, enum mvtd_log_class cls, const char *fmt, ...)
{
    const double now = wall_s();
    if (d->quiet || now - d->log_last_s[cls] < 1.0) {
        d->log_suppressed[cls]++;
        return;
    }
    d->log_last_s[cls] = now;
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "mvtrackd: ");
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    if (d->log_suppressed[cls] > 0) {
        fprintf(stderr, " (+%lld similar suppressed)", (long long)d->log_suppressed[cls]);
        d->log_suppressed[cls] = 0;
    }
    fputc('\n', stderr);
}

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

void mvtd_publish_status(daemon_state_t *d)
{
    const double now = wall_s();
    const double period = now - d->last_status_wall_s;
    mvtrack_status_t st;
    memset(&st, 0, sizeof(st));
    mvtrack_camera_status_t cams[MVT_MAX_CAMERAS];
    st.utime = wall_utime();
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
    st.deleted_tentative = (int64_t)c->deleted_tentative;
    st.deleted_unseen = (int64_t)c->deleted_unseen;
    st.deleted_exit = (int64_t)c->deleted_exit;
    st.deleted_uncertain = (int64_t)c->deleted_uncertain;
    st.deleted_outside = (int64_t)c->deleted_outside;
    st.deleted_duplicate = (int64_t)c->duplicates_deleted;
    st.updates = (int64_t)c->updates;
    st.updates_merged_withheld = (int64_t)c->merged_ambiguous;
    st.updates_merged_shared = (int64_t)c->merged_updates;
    st.birth_candidates_dropped = (int64_t)c->birth_candidates_dropped;
    st.numeric_faults = (int64_t)c->numeric_faults;
    st.updates_occluded = (int64_t)c->occluded_updates;
    st.updates_exclusion = (int64_t)c->exclusion_updates;
    st.updates_merged_top = (int64_t)c->merged_top;
    st.deleted_occluded = (int64_t)c->deleted_occluded;
    st.deleted_contradicted = (int64_t)c->deleted_contradicted;
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
        st.deleted_unseen = (int64_t)pc->deleted_lost;
        st.deleted_outside = (int64_t)pc->deleted_outside;
        st.deleted_duplicate = (int64_t)pc->deleted_duplicate;
        st.tracks_dropped_capacity = (int64_t)pc->births_refused_full;
    }
    PUBLISH(d, mvtrack_status_t, "MVTRACK_STATUS", &st);
    d->last_status_wall_s = now;
}

/* A systematic sample of publish_particles particles per target (weights renormalised). */
static void publish_particles(daemon_state_t *d, int64_t utime)
{
    static int32_t ids[MVT_MAX_TARGETS * MVT_MAX_PARTICLES];
    static float px[MVT_MAX_TARGETS * MVT_MAX_PARTICLES], py[MVT_MAX_TARGETS * MVT_MAX_PARTICLES],
        pz[MVT_MAX_TARGETS * MVT_MAX_PARTICLES];
    static float wt[MVT_MAX_TARGETS * MVT_MAX_PARTICLES];
    int n = 0;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        const mvt_pft_target_t *a = &d->pft->targets[t];
        if (a->id == 0) {
            continue;
        }
        const mvt_pf_pool_t *p = &a->pool;
        const int m = d->publish_particles < p->n ? d->publish_particles : p->n;
        const int first = n;
        double sum = 0.0;
        for (int j = 0; j < m; j++) {
            const int i = (int)((long long)j * p->n / m);
            ids[n] = a->id;
            px[n] = (float)p->x[i];
            py[n] = (float)p->y[i];
            pz[n] = (float)p->z[i];
            wt[n] = (float)p->w[i];
            sum += (double)p->w[i];
            n++;
        }
        for (int j = first; j < n && sum > 0.0; j++) {
            wt[j] = (float)((double)wt[j] / sum);
        }
    }
    mvtrack_particles_t msg;
    msg.utime = utime;
    msg.num_particles = n;
    msg.id = ids;
    msg.x = px;
    msg.y = py;
    msg.z = pz;
    msg.weight = wt;
    PUBLISH(d, mvtrack_particles_t, "MVTRACK_PARTICLES", &msg);
}

/* Cameras that went down or came back, and clock re-basings, since the last call: one line each. */
static void log_camera_events(daemon_state_t *d)
{
    const mvtd_asm_counters_t *c = &d->assembler.counters;
    for (int k = 0; k < d->rig.num_cameras; k++) {
        if (c->went_down[k] != d->went_down_seen[k]) {
            d->went_down_seen[k] = c->went_down[k];
            log_limited(d, MVTD_LOG_CAMERA, "camera %s absent from %d frame sets: no longer waited for",
                        d->rig.names[k], MVTD_ASM_DOWN_SETS);
        }
        if (c->came_back[k] != d->came_back_seen[k]) {
            d->came_back_seen[k] = c->came_back[k];
            log_limited(d, MVTD_LOG_CAMERA, "camera %s is back", d->rig.names[k]);
        }
    }
    if (c->clock_jumps != d->clock_jumps_seen) {
        d->clock_jumps_seen = c->clock_jumps;
        log_limited(d, MVTD_LOG_TIME, "capture clock went back on every camera: time re-based (offset %lld us)",
                    (long long)d->assembler.offset_us);
    }
}

static void on_frame(void *ctx, mvt_frame_t *frame, int complete)
{
    daemon_state_t *d = ctx;
    (void)complete;
    const double t0 = wall_s();
    const mvt_err_t err =
        d->pf ? mvt_pft_step(d->pft, frame, &d->output) : mvt_tracker_step(&d->tracker, frame, &d->output);
    if (err != MVT_OK) {
        log_limited(d, MVTD_LOG_TRACKER, "frame at utime %lld skipped: %s", (long long)frame->utime_us, mvt_err_str(err));
        return;
    }
    mvtrack_track_t tracks[MVT_MAX_TARGETS];
    mvtrack_tracks_t msg;
    const int64_t capture_utime = d->output.utime_us - d->assembler.offset_us; /* the cameras' clock */
    msg.utime = capture_utime;
    msg.frame = d->frames_processed;
    msg.num_tracks = (int16_t)d->output.num_tracks;
    msg.tracks = tracks;
    for (int i = 0; i < d->output.num_tracks; i++) {
        const mvt_track_out_t *o = &d->output.tracks[i];
        mvtrack_track_t *m = &tracks[i];
        m->id = o->id;
        m->status = (int8_t)o->status;
        for (int a = 0; a < 3; a++) {
            m->position[a] = (float)o->pos_m[a];
            m->velocity[a] = (float)o->vel_ms[a];
            m->extent_min[a] = (float)o->extent_min[a];
            m->extent_max[a] = (float)o->extent_max[a];
        }
        for (int a = 0; a < 6; a++) {
            m->position_covariance[a] = (float)o->cov_m2[a];
        }
        m->cameras_used = (int32_t)o->cameras_used;
        m->hue = (float)o->hue;
        m->saturation = (float)o->saturation;
    }
    msg.publish_utime = wall_utime();
    PUBLISH(d, mvtrack_tracks_t, "TRACKS", &msg);
    if (d->pf && d->publish_particles > 0) {
        publish_particles(d, capture_utime);
    }
    d->frames_processed++;
    const double t1 = wall_s();
    const int slot = d->n_proc % MVTD_PROC_RING;
    d->proc_ms[slot] = (float)((t1 - t0) * 1e3);
    d->latency_ms[slot] = (float)((t1 - d->last_accept_wall_s) * 1e3);
    d->n_proc++;
    log_camera_events(d);
    if (d->trk->counters.births_refused_full > d->tracker_births_full_seen) {
        d->tracker_births_full_seen = d->trk->counters.births_refused_full;
        log_limited(d, MVTD_LOG_CAPACITY, "track capacity MVT_MAX_TARGETS=%d full: %llu births refused so far",
                    MVT_MAX_TARGETS, (unsigned long long)d->trk->counters.births_refused_full);
    }
}

/* Two mask buffers per camera: the one the open frame set references is never overwritten. */
static mvt_mask_t g_masks[MVT_MAX_CAMERAS][2];

static const mvt_mask_t *decode_mask(daemon_state_t *d, int cam, const mvtrack_camera_frame_t *m)
{
    const mvt_view_t *open_view = &d->assembler.frame.views[cam];
    const int in_open = d->assembler.open && (d->assembler.present & (1u << cam)) != 0u;
    const int bank = in_open && open_view->mask == &g_masks[cam][0] ? 1 : 0;
    mvt_mask_t *mask = &g_masks[cam][bank];
    if (mvt_mask_from_runs(mask, m->width, m->height, m->mask_width, m->mask_height, m->runs, m->num_runs, m->hue,
                           m->saturation, m->num_hs) != MVT_OK) {
        d->masks_rejected++;
        log_limited(d, MVTD_LOG_BAD_VALUE,
                    "camera %s: mask %dx%d with %d runs and %d hue/saturation bytes rejected (runs must sum to the "
                    "mask, the image must be an integer multiple of it, at most %d pixels)",
                    d->rig.names[cam], m->mask_width, m->mask_height, m->num_runs, m->num_hs, MVT_MAX_MASK_PIXELS);
        return NULL;
    }
    d->masks_decoded++;
    return mask;
}

/* Big-endian wire reader over an untrusted buffer: every read checks the bytes are there. */
typedef struct wire {
    const uint8_t *p;
    uint32_t left;
} wire_t;

static int wire_skip(wire_t *w, uint64_t n)
{
    if (n > w->left) {
        return -1;
    }
    w->p += n;
    w->left -= (uint32_t)n;
    return 0;
}

static int wire_int(wire_t *w, int bytes, int64_t *out)
{
    if ((uint32_t)bytes > w->left) {
        return -1;
    }
    uint64_t v = 0;
    for (int i = 0; i < bytes; i++) {
        v = (v << 8) | w->p[i];
    }
    const uint64_t sign = 1ull << (8 * bytes - 1);
    *out = (int64_t)((v ^ sign) - sign); /* sign-extend */
    w->p += bytes;
    w->left -= (uint32_t)bytes;
    return 0;
}

/* Walks a camera_frame_t message as laid out on the wire (lcmtypes/camera_frame_t.lcm): checks the
 * fingerprint, that every count is non-negative, and that every array, and the camera string with
 * its terminating NUL, lies inside the message. lcm-gen's decoder trusts the counts (it allocates what they say
 * before checking the bytes exist, leaks what it allocated when a later field fails, and leaves a
 * string of length 0 or without its NUL unterminated), so it only ever sees messages that passed
 * this: what it allocates is then bounded by the message's own size. */
int mvtd_frame_wire_check(const void *data, uint32_t size)
{
    wire_t w = {data, size};
    int64_t v, n;
    if (wire_int(&w, 8, &v) != 0 || v != __mvtrack_camera_frame_t_get_hash() || wire_int(&w, 8, &v) != 0 ||
        wire_int(&w, 8, &v) != 0) {
        return -1; /* fingerprint, utime, frame */
    }
    if (wire_int(&w, 4, &n) != 0 || n < 1 || n > (int64_t)w.left || w.p[n - 1] != 0 || wire_skip(&w, (uint64_t)n) != 0) {
        return -1; /* camera name: length with its NUL, and the NUL present */
    }
    if (wire_int(&w, 2, &v) != 0 || wire_int(&w, 2, &v) != 0 || wire_int(&w, 2, &n) != 0 || n < 0 ||
        wire_skip(&w, (uint64_t)n * 10u * 4u) != 0) {
        return -1; /* width, height, detections of 10 floats each */
    }
    if (wire_int(&w, 2, &v) != 0 || wire_int(&w, 2, &v) != 0 || wire_int(&w, 4, &n) != 0 || n < 0 ||
        wire_skip(&w, (uint64_t)n * 4u) != 0) {
        return -1; /* mask size, runs */
    }
    if (wire_int(&w, 4, &n) != 0 || n < 0 || wire_skip(&w, (uint64_t)n * 2u) != 0) {
        return -1; /* hue and saturation bytes */
    }
    return 0;
}

void mvtd_handle(daemon_state_t *d, const char *channel, const void *data, uint32_t size)
{
    mvtrack_camera_frame_t m;
    memset(&m, 0, sizeof(m));
    if (size > (uint32_t)INT32_MAX || mvtd_frame_wire_check(data, size) != 0 ||
        mvtrack_camera_frame_t_decode(data, 0, (int)size, &m) < 0) {
        /* (a decode failure after the wire check would be an LCM change: free what it allocated;
         * fields it never reached are still NULL from the memset) */
        free(m.camera);
        free(m.detections);
        free(m.runs);
        free(m.hue);
        free(m.saturation);
        d->rej_undecodable++;
        log_limited(d, MVTD_LOG_UNDECODABLE, "undecodable message on %s (%u bytes) skipped", channel,
                    (unsigned)size);
        return;
    }
    const int cam = mvtd_rig_find(&d->rig, m.camera != NULL ? m.camera : "");
    if (cam < 0) {
        d->rej_unknown_camera++;
        log_limited(d, MVTD_LOG_UNKNOWN_CAMERA, "message on %s names camera '%s', not in the rig: skipped", channel,
                    m.camera != NULL ? m.camera : "");
        mvtrack_camera_frame_t_decode_cleanup(&m);
        return;
    }
    if (m.utime < 0 || m.utime > MVTD_MAX_UTIME) {
        d->rej_bad_value++; /* time arithmetic (offsets, frame periods) stays far from overflow */
        log_limited(d, MVTD_LOG_BAD_VALUE, "camera %s: utime %lld outside 0..2^60 us: skipped", d->rig.names[cam],
                    (long long)m.utime);
        mvtrack_camera_frame_t_decode_cleanup(&m);
        return;
    }
    const mvt_camera_params_t *p = &d->rig.params[cam];
    if (m.width != p->width || m.height != p->height) {
        d->rej_bad_value++;
        log_limited(d, MVTD_LOG_BAD_VALUE, "camera %s sends %dx%d images, the rig says %dx%d: skipped", d->rig.names[cam],
                    m.width, m.height, p->width, p->height);
        mvtrack_camera_frame_t_decode_cleanup(&m);
        return;
    }
    if (d->cam_messages[cam] > 0 && m.frame < d->cam_last_frame[cam]) {
        d->cam_counter_restarts[cam]++; /* harmless: frame sets are built from utime alone */
        log_limited(d, MVTD_LOG_CAMERA, "camera %s: frame counter went from %lld to %lld (restarted)",
                    d->rig.names[cam], (long long)d->cam_last_frame[cam], (long long)m.frame);
    }
    d->cam_last_frame[cam] = m.frame;
    mvt_view_t *v = &d->scratch_view;
    v->observed = 1;
    v->utime_us = m.utime;
    /* valid detections first (a flood is cut at MVTD_MAX_INPUT_DETECTIONS, counted), then, over
     * the core's capacity, the core chooses: each track's nearest gated detection, then scores */
    mvt_detection_t *in = d->input_dets;
    int n_in = 0;
    for (int i = 0; i < m.num_detections; i++) {
        const mvtrack_detection_t *s = &m.detections[i];
        if (!isfinite(s->u) || !isfinite(s->v) || !isfinite(s->sigma_px) || fabsf(s->u) > 1e6f ||
            fabsf(s->v) > 1e6f) {
            d->rej_bad_value++;
            log_limited(d, MVTD_LOG_BAD_VALUE, "camera %s: detection with non-finite or absurd coordinates dropped",
                        d->rig.names[cam]);
            continue;
        }
        if (n_in == MVTD_MAX_INPUT_DETECTIONS) {
            d->rej_over_capacity++;
            continue;
        }
        mvt_detection_t *o = &in[n_in++];
        o->u = (mvt_real)s->u;
        o->v = (mvt_real)s->v;
        o->sigma_px = (mvt_real)s->sigma_px;
        o->score = (mvt_real)s->score;
        o->hue = (mvt_real)s->hue;
        o->saturation = (mvt_real)s->saturation;
        const int box_ok = isfinite(s->bbox[0]) && isfinite(s->bbox[1]) && isfinite(s->bbox[2]) &&
                           isfinite(s->bbox[3]) && s->bbox[2] > s->bbox[0] && s->bbox[3] > s->bbox[1] &&
                           fabsf(s->bbox[0]) < 1e6f && fabsf(s->bbox[1]) < 1e6f && fabsf(s->bbox[2]) < 1e6f &&
                           fabsf(s->bbox[3]) < 1e6f;
        for (int j = 0; j < 4; j++) {
            o->box[j] = box_ok ? (mvt_real)s->bbox[j] : (mvt_real)0; /* unknown: explains no occlusion */
        }
    }
    int idx[MVT_MAX_DETECTIONS];
    const int kept = mvt_tracker_select(d->trk, cam, in, n_in, idx);
    if (n_in > kept) {
        d->rej_over_capacity += n_in - kept;
        log_limited(d, MVTD_LOG_CAPACITY,
                    "camera %s: %d detections, capacity MVT_MAX_DETECTIONS=%d: kept each track's nearest, then the "
                    "highest scores",
                    d->rig.names[cam], m.num_detections, MVT_MAX_DETECTIONS);
    }
    for (int i = 0; i < kept; i++) {
        v->det[i] = in[idx[i]];
    }
    v->num_detections = kept;
    v->mask = NULL;
    if (d->pf && (m.mask_width != 0 || m.mask_height != 0)) {
        v->mask = decode_mask(d, cam, &m);
    }
    mvtrack_camera_frame_t_decode_cleanup(&m);

    const double now = wall_s();
    d->last_accept_wall_s = now;
    const mvtd_asm_result_t r = mvtd_asm_add(&d->assembler, cam, v, now);
    switch (r) {
    case MVTD_ASM_ACCEPTED:
        d->cam_messages[cam]++;
        d->cam_last_wall_s[cam] = now;
        break;
    case MVTD_ASM_LATE:
        d->rej_late++;
        log_limited(d, MVTD_LOG_TIME, "camera %s: message at utime %lld arrived after its frame set: skipped",
                    d->rig.names[cam], (long long)v->utime_us);
        break;
    case MVTD_ASM_DUPLICATE:
        d->rej_duplicate++;
        log_limited(d, MVTD_LOG_TIME, "camera %s: duplicate message at utime %lld skipped", d->rig.names[cam],
                    (long long)v->utime_us);
        break;
    case MVTD_ASM_BACKWARDS:
        d->rej_time_backwards++;
        log_limited(d, MVTD_LOG_TIME, "camera %s: utime %lld earlier than its previous message: skipped",
                    d->rig.names[cam], (long long)v->utime_us);
        break;
    case MVTD_ASM_AHEAD:
        d->rej_time_ahead++;
        log_limited(d, MVTD_LOG_TIME,
                    "camera %s: utime %lld far ahead of the other cameras: skipped (accepted once every camera "
                    "agrees)",
                    d->rig.names[cam], (long long)v->utime_us);
        break;
    }
}

static void on_detections(const lcm_recv_buf_t *rbuf, const char *channel, void *ctx)
{
    mvtd_handle(ctx, channel, rbuf->data, rbuf->data_size);
}

static void usage(FILE *f)
{
    fprintf(f,
            "usage: mvtrackd --rig RIG.yaml [--in URL] [--out URL] [--mode MODE] [options]\n"
            "\n"
            "Fuses per-camera detections (LCM channels DETECTIONS_<camera>, mvtrack.camera_frame_t)\n"
            "into 3D tracks published on TRACKS (mvtrack.tracks_t) every frame set, and its health\n"
            "on MVTRACK_STATUS (mvtrack.status_t) about once a second.\n"
            "\n"
            "  --rig FILE          camera rig, OpenCV FileStorage YAML (required)\n"
            "  --in URL            LCM input (default %s);\n"
            "                      'file://LOG.lcm?speed=0' processes a log as fast as possible and\n"
            "                      exits 0 at its end\n"
            "  --out URL           LCM output (default: the input URL; required for file:// input,\n"
            "                      e.g. 'file://OUT.lcm?mode=w')\n"
            "  --mode MODE         pkf (default): projective Kalman filter fusing every camera's pixels\n"
            "                                     directly in 3D, linearised with the projection's\n"
            "                                     Jacobian (the EKF form; measured best, see README)\n"
            "                      ekf          same as pkf\n"
            "                      pkf-paper    the paper's literal H (Eq. 18), OpenCV pixel origin\n"
            "                      pkf-centred  Eq. 18 with pixels centred on the principal point\n"
            "                      kf           baseline: triangulate per frame, then a 3D Kalman filter\n"
            "                      pf           particle filter per person weighted by the cameras'\n"
            "                                   foreground masks, and their hue/saturation when sent\n"
            "                                   (MS+C; MS when a camera sends no colour); needs masks\n"
            "                      pf-ms        the same, motion masks only (colour ignored)\n"
            "  --particles N       pf: particles per person, 16..%d (default %d)\n"
            "  --exclusion M       two people's heads are at least M metres apart horizontally\n"
            "                      (default 0.5 in pf modes, 0.4 otherwise; 0 = off). pf: particles\n"
            "                      closer to another person's centre are penalised, so two filters\n"
            "                      cannot share one body (0: the paper's independent filters); other\n"
            "                      modes: a track seen by fewer than two cameras is kept this far\n"
            "                      from the others\n"
            "  --occlusion box|off a confirmed track a camera did not update although it lies inside\n"
            "                      the box of a blob given to another track is hidden there: box\n"
            "                      (default) keeps it in the box's columns and alive; off: missed\n"
            "  --particle-model column|point\n"
            "                      pf: column (default): a particle is a head-top hypothesis, each\n"
            "                      camera scores the body under it and the background above it;\n"
            "                      point: the paper's, a particle is a point of the body\n"
            "  --seed N            pf: random number seed (default 1); same seed, same output\n"
            "  --publish-particles N\n"
            "                      pf: publish N particles per person on MVTRACK_PARTICLES\n"
            "                      (mvtrack.particles_t; default 0 = none)\n",
            MVTD_DEFAULT_URL, MVT_MAX_PARTICLES, MVT_MAX_PARTICLES);
    fprintf(f,
            "  --gate chi2|paper   association gate: innovation chi-square (default) or the paper's\n"
            "                      projected ellipsoid (Eq. 22-26)\n"
            "  --gate-chi2 X       chi-square threshold, 2 dof (default 13.8)\n"
            "  --q QX,QY,QZ        process noise, white-acceleration density m^2/s^3 per axis\n"
            "                      (default 0.5,0.5,0.05; tools/mvtrack learn-q estimates it)\n"
            "  --sigma-px X        pixel noise for cameras without sigma_px in the rig (default 2)\n"
            "  --deadline-ms X     live mode: process an incomplete frame set this long after its\n"
            "                      first message (default 20)\n"
            "  --merge P           a detection inside the gates of two tracks that one camera cannot\n"
            "                      tell apart (a merged blob): neither (default: update neither),\n"
            "                      share (update both, covariance widened), off (one-to-one only),\n"
            "                      top (the detector's rule: the higher head gets it when the order\n"
            "                      is clear, otherwise neither)\n"
            "  --verbose           print a line per status period\n"
            "  --help              this text\n"
            "\n"
            "Exit status: 0 after SIGINT/SIGTERM or at the end of a file:// log; 2 on bad arguments\n"
            "or rig; 1 when LCM cannot be opened.\n");
}

static int parse_q(const char *s, mvt_real q[3])
{
    double a, b, c;
    char extra;
    if (sscanf(s, "%lf,%lf,%lf%c", &a, &b, &c, &extra) != 3 || !(a > 0) || !(b > 0) || !(c > 0) || !isfinite(a) ||
        !isfinite(b) || !isfinite(c)) {
        return -1;
    }
    q[0] = (mvt_real)a;
    q[1] = (mvt_real)b;
    q[2] = (mvt_real)c;
    return 0;
}

static int parse_pos(const char *s, double *out)
{
    char *end = NULL;
    errno = 0;
    const double v = strtod(s, &end);
    if (errno != 0 || end == s || *end != '\0' || !(v > 0.0) || !isfinite(v)) {
        return -1;
    }
    *out = v;
    return 0;
}

/* Parses a positive option value; prints why not and returns -1 on failure. */
static int option_pos(const char *opt_name, const char *arg, double *out)
{
    if (parse_pos(arg, out) != 0) {
        fprintf(stderr, "mvtrackd: %s needs a positive number, got '%s'\n", opt_name, arg);
        return -1;
    }
    return 0;
}

/* Parses an integer option in [lo, hi]; prints why not and returns -1 on failure. */
static int option_int(const char *opt_name, const char *arg, long lo, long hi, long *out)
{
    char *end = NULL;
    errno = 0;
    const long v = strtol(arg, &end, 10);
    if (errno != 0 || end == arg || *end != '\0' || v < lo || v > hi) {
        fprintf(stderr, "mvtrackd: %s needs an integer in %ld..%ld, got '%s'\n", opt_name, lo, hi, arg);
        return -1;
    }
    *out = v;
    return 0;
}

/* Index of arg among names, or -1 after printing the allowed values. */
static int option_choice(const char *opt_name, const char *arg, const char *const names[], int n)
{
    for (int i = 0; i < n; i++) {
        if (strcmp(arg, names[i]) == 0) {
            return i;
        }
    }
    fprintf(stderr, "mvtrackd: unknown %s '%s' (", opt_name, arg);
    for (int i = 0; i < n; i++) {
        fprintf(stderr, "%s%s", i ? ", " : "", names[i]);
    }
    fprintf(stderr, ")\n");
    return -1;
}

int mvtd_configure(daemon_state_t *d, int argc, char **argv)
{
    const char *rig_path = NULL, *in_url = MVTD_DEFAULT_URL, *out_url = NULL, *mode = "pkf", *gate = "chi2",
               *merge = "neither", *occlusion = "box", *particle_model = "column";
    double sigma_px = 2.0, deadline_ms = 20.0, gate_chi2 = 13.8;
    mvt_real q[3] = {MVT_R(0.5), MVT_R(0.5), MVT_R(0.05)};
    static const struct option opts[] = {
        {"rig", required_argument, 0, 'r'},      {"in", required_argument, 0, 'i'},
        {"out", required_argument, 0, 'o'},      {"mode", required_argument, 0, 'm'},
        {"gate", required_argument, 0, 'g'},     {"gate-chi2", required_argument, 0, 'c'},
        {"q", required_argument, 0, 'q'},        {"sigma-px", required_argument, 0, 's'},
        {"deadline-ms", required_argument, 0, 'd'}, {"verbose", no_argument, 0, 'v'},
        {"merge", required_argument, 0, 'M'},    {"help", no_argument, 0, 'h'},
        {"occlusion", required_argument, 0, 'O'},
        {"particles", required_argument, 0, 'P'}, {"exclusion", required_argument, 0, 'X'},
        {"seed", required_argument, 0, 'S'},     {"publish-particles", required_argument, 0, 'Q'},
        {"particle-model", required_argument, 0, 'B'}, {0, 0, 0, 0}};
    int opt;
    optind = 1; /* callable more than once (tests, fuzzer) */
    long particles = MVT_MAX_PARTICLES, seed = 1, publish_particles = 0;
    double exclusion_m = -1.0; /* mode-dependent default */
    while ((opt = getopt_long(argc, argv, "r:i:o:m:g:c:q:s:d:M:O:vhP:X:S:Q:B:", opts, NULL)) != -1) {
        switch (opt) {
        case 'r': rig_path = optarg; break;
        case 'i': in_url = optarg; break;
        case 'o': out_url = optarg; break;
        case 'm': mode = optarg; break;
        case 'g': gate = optarg; break;
        case 'M': merge = optarg; break;
        case 'O': occlusion = optarg; break;
        case 'B': particle_model = optarg; break;
        case 'c':
            if (option_pos("--gate-chi2", optarg, &gate_chi2) != 0) {
                return 2;
            }
            break;
        case 'q':
            if (parse_q(optarg, q) != 0) {
                fprintf(stderr, "mvtrackd: --q needs three positive numbers QX,QY,QZ, got '%s'\n", optarg);
                return 2;
            }
            break;
        case 's':
            if (option_pos("--sigma-px", optarg, &sigma_px) != 0) {
                return 2;
            }
            break;
        case 'd':
            if (option_pos("--deadline-ms", optarg, &deadline_ms) != 0) {
                return 2;
            }
            break;
        case 'P':
            if (option_int("--particles", optarg, 16, MVT_MAX_PARTICLES, &particles) != 0) {
                return 2;
            }
            break;
        case 'S':
            if (option_int("--seed", optarg, 0, 2147483647L, &seed) != 0) {
                return 2;
            }
            break;
        case 'Q':
            if (option_int("--publish-particles", optarg, 0, MVT_MAX_PARTICLES, &publish_particles) != 0) {
                return 2;
            }
            break;
        case 'X': {
            char *end = NULL;
            exclusion_m = strtod(optarg, &end);
            if (end == optarg || *end != '\0' || !(exclusion_m >= 0.0) || exclusion_m > 10.0) {
                fprintf(stderr, "mvtrackd: --exclusion needs metres in [0, 10], got '%s'\n", optarg);
                return 2;
            }
            break;
        }
        case 'v': d->verbose = 1; break;
        case 'h': usage(stdout); return 0;
        default: usage(stderr); return 2;
        }
    }
    if (optind < argc) {
        fprintf(stderr, "mvtrackd: unexpected argument '%s'\n", argv[optind]);
        usage(stderr);
        return 2;
    }
    if (rig_path == NULL) {
        fprintf(stderr, "mvtrackd: --rig is required\n");
        usage(stderr);
        return 2;
    }
    mvt_tracker_config_t cfg;
    mvt_tracker_config_default(&cfg);
    static const char *const modes[] = {"pkf", "ekf", "pkf-paper", "pkf-centred", "kf", "pf", "pf-ms"};
    static const char *const gates[] = {"chi2", "paper"};
    static const char *const merges[] = {"neither", "share", "off", "top"};
    static const char *const particle_models[] = {"column", "point"};
    const int mi = option_choice("--mode", mode, modes, 7);
    const int gi = option_choice("--gate", gate, gates, 2);
    const int ri = option_choice("--merge", merge, merges, 4);
    const int bi = option_choice("--particle-model", particle_model, particle_models, 2);
    static const char *const occlusions[] = {"box", "off"};
    const int oi = option_choice("--occlusion", occlusion, occlusions, 2);
    if (mi < 0 || gi < 0 || ri < 0 || bi < 0 || oi < 0) {
        return 2;
    }
    static const mvt_pkf_lin_t mode_lin[] = {MVT_PKF_JACOBIAN, MVT_PKF_JACOBIAN, MVT_PKF_PAPER,
                                             MVT_PKF_PAPER_CENTRED, MVT_PKF_JACOBIAN, MVT_PKF_JACOBIAN,
                                             MVT_PKF_JACOBIAN};
    cfg.lin = mode_lin[mi];
    cfg.filter = mi == 4 ? MVT_FILTER_TRIANGULATE : MVT_FILTER_PROJECTIVE;
    cfg.gate = gi == 0 ? MVT_GATE_CHI2 : MVT_GATE_PAPER;
    static const mvt_merge_t merge_of[] = {MVT_MERGE_NEITHER, MVT_MERGE_SHARE, MVT_MERGE_OFF, MVT_MERGE_TOP};
    cfg.merge = merge_of[ri];
    cfg.gate_chi2 = (mvt_real)gate_chi2;
    cfg.occlusion = oi == 0;
    if (exclusion_m < 0.0) { /* measured defaults: docs/particle-filter.md, docs/tracking.md */
        exclusion_m = mi >= 5 ? 0.5 : 0.4;
    }
    cfg.exclusion_m = (mvt_real)exclusion_m;
    memcpy(cfg.q_m2s3, q, sizeof(q));
    d->mode_name = mode;

    char err[512];
    if (mvtd_rig_load(rig_path, sigma_px, &d->rig, err, sizeof(err)) != 0) {
        fprintf(stderr, "mvtrackd: %s\n", err);
        return 2;
    }
    if (!d->rig.volume_given) {
        fprintf(stderr, "mvtrackd: rig has no volume_min/volume_max; using the camera centres' box\n");
    }
    for (int i = 0; i < 3; i++) {
        cfg.volume_min[i] = (mvt_real)d->rig.volume_min[i];
        cfg.volume_max[i] = (mvt_real)d->rig.volume_max[i];
    }
    mvt_camera_t cams[MVT_MAX_CAMERAS];
    for (int k = 0; k < d->rig.num_cameras; k++) {
        if (mvt_cam_init(&cams[k], &d->rig.params[k]) != MVT_OK) {
            fprintf(stderr, "mvtrackd: camera %s: invalid calibration\n", d->rig.names[k]);
            return 2;
        }
    }
    d->pf = mi >= 5;
    d->publish_particles = (int)publish_particles;
    d->trk = &d->tracker;
    if (d->pf) {
        static mvt_pft_t pft; /* ~1.5 MB at the default capacities: static, not on the stack */
        mvt_pft_config_t pcfg;
        mvt_pft_config_default(&pcfg);
        pcfg.det = cfg;
        /* the particle filter's blob tracker only proposes births: it keeps the lifecycle its
         * figures were measured with (docs/particle-filter.md); exclusion is the particles' own */
        pcfg.det.occlusion = 0;
        pcfg.det.exclusion_m = 0;
        pcfg.num_particles = (int)particles;
        pcfg.use_colour = mi == 5;
        pcfg.column = bi == 0;
        pcfg.exclusion_m = (mvt_real)exclusion_m;
        pcfg.seed = (uint64_t)seed;
        if (mvt_pft_init(&pft, &pcfg, cams, d->rig.num_cameras) != MVT_OK) {
            fprintf(stderr, "mvtrackd: invalid particle-filter configuration\n");
            return 2;
        }
        d->pft = &pft;
        d->trk = &pft.det;
    } else if (mvt_tracker_init(&d->tracker, &cfg, cams, d->rig.num_cameras) != MVT_OK) {
        fprintf(stderr, "mvtrackd: invalid tracker configuration\n");
        return 2;
    }
    d->offline = strncmp(in_url, "file://", 7) == 0;
    if (out_url == NULL) {
        if (d->offline) {
            fprintf(stderr, "mvtrackd: file:// input needs --out (a log opened for reading cannot publish)\n");
            return 2;
        }
        out_url = in_url;
    }
    d->in_url = in_url;
    d->out_url = out_url;
    d->deadline_s = deadline_ms * 1e-3;
    mvtd_asm_init(&d->assembler, d->rig.num_cameras, d->rig.frame_rate, on_frame, d);
    d->start_wall_s = wall_s();
    d->last_status_wall_s = d->start_wall_s;
    return MVTD_CONTINUE;
}

static lcm_subscription_t *g_sub;

/* Multicast input without recv_buf_size gets 4 MB: a frame set of foreground masks is a few
 * hundred UDP fragments, more than a default socket buffer holds while the tracker works. */
static const char *with_recv_buf(const char *url)
{
    static char buf[1024];
    if (strncmp(url, "udpm://", 7) != 0 || strstr(url, "recv_buf_size=") != NULL ||
        strlen(url) + 32 >= sizeof(buf)) {
        return url;
    }
    snprintf(buf, sizeof(buf), "%s%crecv_buf_size=4194304", url, strchr(url, '?') != NULL ? '&' : '?');
    return buf;
}

int mvtd_open(daemon_state_t *d)
{
    if (strcmp(d->out_url, d->in_url) == 0) {
        d->out_url = d->in_url = with_recv_buf(d->in_url);
    } else {
        d->in_url = with_recv_buf(d->in_url);
    }
    d->lcm_in = lcm_create(d->in_url);
    if (d->lcm_in == NULL) {
        fprintf(stderr, "mvtrackd: cannot open LCM input '%s'\n", d->in_url);
        return 1;
    }
    if (strcmp(d->out_url, d->in_url) == 0) {
        d->lcm_out = d->lcm_in;
    } else {
        d->lcm_out = lcm_create(d->out_url);
        if (d->lcm_out == NULL) {
            fprintf(stderr, "mvtrackd: cannot open LCM output '%s'\n", d->out_url);
            lcm_destroy(d->lcm_in);
            d->lcm_in = NULL;
            return 1;
        }
    }
    g_sub = lcm_subscribe(d->lcm_in, "DETECTIONS_.*", on_detections, d);
    if (!d->offline) {
        lcm_subscription_set_queue_capacity(g_sub, 256);
    }
    fprintf(stderr, "mvtrackd: %d cameras, mode %s, in %s, out %s\n", d->rig.num_cameras, d->mode_name, d->in_url,
            d->out_url);
    return MVTD_CONTINUE;
}

void mvtd_tick(daemon_state_t *d)
{
    if (!d->offline) {
        mvtd_asm_poll(&d->assembler, wall_s(), d->deadline_s);
    }
    if (wall_s() - d->last_status_wall_s >= 1.0) {
        mvtd_publish_status(d);
        if (d->verbose) {
            fprintf(stderr, "mvtrackd: %lld frames, %lld complete, %lld partial\n", (long long)d->frames_processed,
                    (long long)d->assembler.counters.sets_complete, (long long)d->assembler.counters.sets_partial);
        }
    }
}

static int run_offline(daemon_state_t *d, int sig_fd)
{
    while (lcm_handle(d->lcm_in) == 0) {
        mvtd_tick(d);
        struct signalfd_siginfo si;
        if (read(sig_fd, &si, sizeof(si)) == (ssize_t)sizeof(si)) {
            break; /* SIGINT/SIGTERM: stop reading the log */
        }
    }
    return 0;
}

/* Arms the one-shot deadline timer for the open frame set (disarms it when none is open). */
static void arm_deadline(daemon_state_t *d, int timer_fd)
{
    struct itimerspec its;
    memset(&its, 0, sizeof(its));
    const double dl = mvtd_asm_time_to_deadline(&d->assembler, wall_s(), d->deadline_s);
    if (dl > -1e29) {
        const double w = dl > 1e-6 ? dl : 1e-6; /* zero would disarm */
        its.it_value.tv_sec = (time_t)w;
        its.it_value.tv_nsec = (long)((w - (double)its.it_value.tv_sec) * 1e9);
    }
    timerfd_settime(timer_fd, 0, &its, NULL);
}

/* Live: one poll() over the LCM socket, the signals (signalfd), the frame-set deadline and the
 * status period (timerfds). Every wake-up drains LCM completely before anything else. */
static int run_live(daemon_state_t *d, int sig_fd)
{
    const int deadline_fd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
    const int status_fd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
    if (deadline_fd < 0 || status_fd < 0) {
        perror("mvtrackd: timerfd_create");
        return 1;
    }
    const struct itimerspec second = {{1, 0}, {1, 0}};
    timerfd_settime(status_fd, 0, &second, NULL);
    struct pollfd pfd[4] = {{lcm_get_fileno(d->lcm_in), POLLIN, 0}, {sig_fd, POLLIN, 0}, {deadline_fd, POLLIN, 0},
                            {status_fd, POLLIN, 0}};
    int rc = 0;
    for (;;) {
        arm_deadline(d, deadline_fd);
        const int pr = poll(pfd, 4, -1);
        if (pr < 0) {
            if (errno == EINTR) {
                continue;
            }
            perror("mvtrackd: poll");
            rc = 1;
            break;
        }
        if (pfd[0].revents & POLLIN) {
            while (lcm_handle_timeout(d->lcm_in, 0) > 0) { /* drain everything queued */
            }
        }
        uint64_t expirations;
        if (pfd[2].revents & POLLIN) {
            (void)read(deadline_fd, &expirations, sizeof(expirations));
        }
        if (pfd[3].revents & POLLIN) {
            (void)read(status_fd, &expirations, sizeof(expirations));
        }
        mvtd_tick(d);
        if (pfd[1].revents & POLLIN) {
            struct signalfd_siginfo si;
            if (read(sig_fd, &si, sizeof(si)) == (ssize_t)sizeof(si)) {
                fprintf(stderr, "mvtrackd: %s: finishing the frame in hand\n", strsignal((int)si.ssi_signo));
                break;
            }
        }
    }
    close(deadline_fd);
    close(status_fd);
    return rc;
}

int mvtd_run(daemon_state_t *d)
{
    sigset_t mask;
    sigemptyset(&mask);
    sigaddset(&mask, SIGINT);
    sigaddset(&mask, SIGTERM);
    sigprocmask(SIG_BLOCK, &mask, NULL);
    signal(SIGPIPE, SIG_IGN);
    const int sig_fd = signalfd(-1, &mask, SFD_NONBLOCK | SFD_CLOEXEC);
    if (sig_fd < 0) {
        perror("mvtrackd: signalfd");
        return 1;
    }
    const int rc = d->offline ? run_offline(d, sig_fd) : run_live(d, sig_fd);
    close(sig_fd);
    return rc;
}

void mvtd_finish(daemon_state_t *d)
{
    mvtd_asm_flush(&d->assembler); /* the frame in hand */
    mvtd_publish_status(d);
    if (!d->quiet) {
        fprintf(stderr,
                "mvtrackd: done: %lld frames (%llu complete, %llu partial); rejected: %lld undecodable, %lld unknown "
                "camera, %lld bad value, %lld over capacity, %lld time backwards, %lld late, %lld duplicate\n",
                (long long)d->frames_processed, (unsigned long long)d->assembler.counters.sets_complete,
                (unsigned long long)d->assembler.counters.sets_partial, (long long)d->rej_undecodable,
                (long long)d->rej_unknown_camera, (long long)d->rej_bad_value, (long long)d->rej_over_capacity,
                (long long)d->rej_time_backwards, (long long)d->rej_late, (long long)d->rej_duplicate);
    }
    if (d->lcm_in != NULL) {
        lcm_unsubscribe(d->lcm_in, g_sub);
        if (d->lcm_out != d->lcm_in) {
            lcm_destroy(d->lcm_out);
        }
        lcm_destroy(d->lcm_in);
        d->lcm_in = d->lcm_out = NULL;
    }
}
