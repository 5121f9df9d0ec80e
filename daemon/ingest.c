/*
 * ingest.c - one DETECTIONS_<camera> message, from its bytes to the frame assembler: the wire
 * check, decoding, validation against the rig, the choice of detections over capacity, the mask.
 * Everything refused is counted (status.c) and logged at a bounded rate. Trust model:
 * docs/trust-model.md.
 */
#include "engine.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mvtrack_camera_frame_t.h"

/* Two mask buffers per camera: the one the open frame set references is never overwritten. */
static mvt_mask_t g_masks[MVT_MAX_CAMERAS][2];

static const mvt_mask_t *decode_mask(mvtd_t *d, int cam, const mvtrack_camera_frame_t *m)
{
    const mvt_view_t *open_view = &d->assembler.frame.views[cam];
    const int in_open = d->assembler.open && (d->assembler.present & (1u << cam)) != 0u;
    const int bank = in_open && open_view->mask == &g_masks[cam][0] ? 1 : 0;
    mvt_mask_t *mask = &g_masks[cam][bank];
    if (mvt_mask_from_runs(mask, m->width, m->height, m->mask_width, m->mask_height, m->runs, m->num_runs, m->hue,
                           m->saturation, m->num_hs) != MVT_OK) {
        d->masks_rejected++;
        mvtd_log(d, MVTD_LOG_BAD_VALUE,
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

/* Admission (live only: a log is processed whole). A camera sends one message per frame; a channel
 * that sends more than MVTD_FLOOD_FACTOR x the frame rate within one second of wall time is
 * flooding (a detector in a loop, a replay at line rate, an attack): its messages beyond that are
 * shed before any decoding, and all of them for every following second that is still over the
 * bound. The camera then counts as down, so the frame sets of the others neither wait for it nor
 * are split by its times; it is back one quiet second later. Costs O(cameras) string compares per
 * message. Returns 1 to shed. */
static int shed(mvtd_t *d, const char *channel, double now)
{
    int slot = d->rig.num_cameras; /* channels of no rig camera share one bound */
    if (strncmp(channel, "DETECTIONS_", 11) == 0) {
        const int k = mvt_rig_find(&d->rig, channel + 11);
        slot = k >= 0 ? k : slot;
    }
    const int32_t bound = (int32_t)(MVTD_FLOOD_FACTOR * d->rig.frame_rate + 0.5);
    if (now - d->cam_window_s[slot] >= 1.0) {
        d->cam_flooding[slot] = d->cam_window_n[slot] > bound;
        d->cam_window_s[slot] = now;
        d->cam_window_n[slot] = 0;
    }
    d->cam_window_n[slot] += d->cam_window_n[slot] < INT32_MAX;
    if (!d->cam_flooding[slot] && d->cam_window_n[slot] <= bound) {
        return 0;
    }
    d->cam_shed[slot]++;
    mvtd_log(d, MVTD_LOG_SHED, "%s sends more than %d messages a second: shed (%lld so far)", channel, bound,
             (long long)d->cam_shed[slot]);
    return 1;
}

void mvtd_handle(mvtd_t *d, const char *channel, const void *data, uint32_t size)
{
    if (!d->offline && shed(d, channel, mvtd_wall_s())) {
        return;
    }
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
        mvtd_log(d, MVTD_LOG_UNDECODABLE, "undecodable message on %s (%u bytes) skipped", channel,
                 (unsigned)size);
        return;
    }
    const int cam = mvt_rig_find(&d->rig, m.camera != NULL ? m.camera : "");
    if (cam < 0) {
        d->rej_unknown_camera++;
        mvtd_log(d, MVTD_LOG_UNKNOWN_CAMERA, "message on %s names camera '%s', not in the rig: skipped", channel,
                 m.camera != NULL ? m.camera : "");
        mvtrack_camera_frame_t_decode_cleanup(&m);
        return;
    }
    if (m.utime < 0 || m.utime > MVTD_MAX_UTIME) {
        d->rej_bad_value++; /* time arithmetic (offsets, frame periods) stays far from overflow */
        mvtd_log(d, MVTD_LOG_BAD_VALUE, "camera %s: utime %lld outside 0..2^60 us: skipped", d->rig.names[cam],
                 (long long)m.utime);
        mvtrack_camera_frame_t_decode_cleanup(&m);
        return;
    }
    const mvt_camera_params_t *p = &d->rig.params[cam];
    if (m.width != p->width || m.height != p->height) {
        d->rej_bad_value++;
        mvtd_log(d, MVTD_LOG_BAD_VALUE, "camera %s sends %dx%d images, the rig says %dx%d: skipped", d->rig.names[cam],
                 m.width, m.height, p->width, p->height);
        mvtrack_camera_frame_t_decode_cleanup(&m);
        return;
    }
    if (!d->offline) {
        /* live: the camera's clock against the others' (clock.h) */
        int64_t t = m.utime;
        const mvtd_clock_verdict_t cv =
            mvtd_clock_observe(&d->clock, cam, m.utime, mvtd_wall_utime(), d->assembler.half_period_us, &t);
        if (cv != MVTD_CLOCK_ACCEPT) { /* said once per camera by mvtd_log_camera_events */
            d->rej_clock++;
            mvtrack_camera_frame_t_decode_cleanup(&m);
            return;
        }
        m.utime = t;
    }
    mvtd_ckpt_first_message(d, m.utime); /* --state: restore or refuse, once */
    if (d->cam_messages[cam] > 0 && m.frame < d->cam_last_frame[cam]) {
        d->cam_counter_restarts[cam]++; /* harmless: frame sets are built from utime alone */
        mvtd_log(d, MVTD_LOG_CAMERA, "camera %s: frame counter went from %lld to %lld (restarted)",
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
            mvtd_log(d, MVTD_LOG_BAD_VALUE, "camera %s: detection with non-finite or absurd coordinates dropped",
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
        mvtd_log(d, MVTD_LOG_CAPACITY,
                 "camera %s: %d detections, capacity MVT_MAX_DETECTIONS=%d: kept each track's nearest, then the "
                 "highest scores",
                 d->rig.names[cam], m.num_detections, MVT_MAX_DETECTIONS);
    }
    for (int i = 0; i < kept; i++) {
        v->det[i] = in[idx[i]];
    }
    v->num_detections = kept;
    v->num_offered = n_in; /* the clutter density counts what was dropped too */
    v->mask = NULL;
    if (m.mask_width != 0 || m.mask_height != 0) { /* every mode: the PKF reads empty places from it */
        v->mask = decode_mask(d, cam, &m);
    }
    mvtrack_camera_frame_t_decode_cleanup(&m);

    const double now = mvtd_wall_s();
    d->last_accept_wall_s = now;
    const mvtd_asm_result_t r = mvtd_asm_add(&d->assembler, cam, v, now);
    switch (r) {
    case MVTD_ASM_ACCEPTED:
        d->cam_messages[cam]++;
        d->cam_last_wall_s[cam] = now;
        break;
    case MVTD_ASM_LATE:
        d->rej_late++;
        mvtd_log(d, MVTD_LOG_TIME, "camera %s: message at utime %lld arrived after its frame set: skipped",
                 d->rig.names[cam], (long long)v->utime_us);
        break;
    case MVTD_ASM_DUPLICATE:
        d->rej_duplicate++;
        mvtd_log(d, MVTD_LOG_TIME, "camera %s: duplicate message at utime %lld skipped", d->rig.names[cam],
                 (long long)v->utime_us);
        break;
    case MVTD_ASM_BACKWARDS:
        d->rej_time_backwards++;
        mvtd_log(d, MVTD_LOG_TIME, "camera %s: utime %lld earlier than its previous message: skipped",
                 d->rig.names[cam], (long long)v->utime_us);
        break;
    case MVTD_ASM_AHEAD:
        d->rej_time_ahead++;
        mvtd_log(d, MVTD_LOG_TIME,
                 "camera %s: utime %lld far ahead of the other cameras: skipped (accepted once every camera "
                 "agrees)",
                 d->rig.names[cam], (long long)v->utime_us);
        break;
    }
}
