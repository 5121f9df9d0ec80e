/*
 * track.c - one frame set from the assembler: the tracker's step, then TRACKS (and, in pf modes,
 * MVTRACK_PARTICLES). The tracking maths live in lib/.
 */
#include "engine.h"

#include <math.h>
#include <string.h>

#include "mvtrack_particles_t.h"
#include "mvtrack_tracks_t.h"

uint8_t g_mvtd_encode_buf[1 << 22];

/* A systematic sample of publish_particles particles per target (weights renormalised). */
static void publish_particles(mvtd_t *d, int64_t utime)
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

/* Live: what the tracks say of each camera's clock (clock.h). For every confirmed track walking
 * (over 0.3 m/s) that two other cameras updated this frame (so it does not follow this one), its
 * residual in the camera (the nearest detection minus its head projected at the view's time)
 * against its head's image velocity, where nothing else is near enough to be taken for it: no
 * other detection and no other track's head within twice the gate. The gate is 30 px plus 0.15 s
 * of the head's image motion (a lag of up to 0.15 s is seen whole). Whether this camera's own
 * detection updated the track is not asked: the tracker refuses the detections a lag displaces
 * most, and keeping only the ones it took would shrink the measured lag. */
static void clock_from_tracks(mvtd_t *d, const mvt_frame_t *frame)
{
    const mvt_output_t *out = &d->output;
    for (int k = 0; k < d->rig.num_cameras; k++) {
        const mvt_view_t *v = &frame->views[k];
        if (!v->observed || v->num_detections == 0) {
            continue;
        }
        const mvt_camera_t *cam = &d->trk->cams[k];
        const double dt = (double)(v->utime_us - out->utime_us) * 1e-6;
        mvt_real uv[MVT_MAX_TARGETS][2];
        double udot[MVT_MAX_TARGETS][2]; /* the head's image velocity, px/s */
        int seen[MVT_MAX_TARGETS];
        for (int i = 0; i < out->num_tracks; i++) {
            const mvt_track_out_t *o = &out->tracks[i];
            mvt_real x[3], jac[6];
            for (int a = 0; a < 3; a++) {
                x[a] = o->pos_m[a] + o->vel_ms[a] * (mvt_real)dt;
            }
            seen[i] = mvt_cam_project(cam, x, uv[i], jac) == MVT_OK;
            for (int r = 0; r < 2 && seen[i]; r++) {
                udot[i][r] = (double)(jac[3 * r] * o->vel_ms[0] + jac[3 * r + 1] * o->vel_ms[1] + jac[3 * r + 2] * o->vel_ms[2]);
            }
        }
        for (int i = 0; i < out->num_tracks; i++) {
            const mvt_track_out_t *o = &out->tracks[i];
            const double speed = hypot((double)o->vel_ms[0], (double)o->vel_ms[1]);
            const int others = __builtin_popcount(o->cameras_used & ~(1u << k));
            if (!seen[i] || o->status != MVT_TRACK_CONFIRMED || others < 2 || speed < 0.3) {
                continue;
            }
            const double gate = 30.0 + 0.15 * hypot(udot[i][0], udot[i][1]);
            double best = HUGE_VAL, second = HUGE_VAL;
            int bi = -1;
            for (int j = 0; j < v->num_detections; j++) {
                const double e = hypot((double)(v->det[j].u - uv[i][0]), (double)(v->det[j].v - uv[i][1]));
                if (e < best) {
                    second = best;
                    best = e;
                    bi = j;
                } else if (e < second) {
                    second = e;
                }
            }
            int alone = bi >= 0 && best < gate && second > 2.0 * gate;
            for (int j = 0; j < out->num_tracks && alone; j++) {
                if (j != i && seen[j] && hypot((double)(uv[j][0] - uv[i][0]), (double)(uv[j][1] - uv[i][1])) < 2.0 * gate) {
                    alone = 0;
                }
            }
            if (alone) {
                const double r[2] = {(double)(v->det[bi].u - uv[i][0]), (double)(v->det[bi].v - uv[i][1])};
                mvtd_clock_motion_sample(&d->clock, k, r, udot[i]);
            }
        }
    }
    mvtd_clock_motion_frame(&d->clock, out->utime_us);
}

void mvtd_on_frame(void *ctx, mvt_frame_t *frame, int complete)
{
    mvtd_t *d = ctx;
    (void)complete;
    const double t0 = mvtd_wall_s();
    const mvt_err_t err =
        d->pf ? mvt_pft_step(d->pft, frame, &d->output) : mvt_tracker_step(&d->tracker, frame, &d->output);
    if (err != MVT_OK) {
        mvtd_log(d, MVTD_LOG_TRACKER, "frame at utime %lld skipped: %s", (long long)frame->utime_us, mvt_err_str(err));
        return;
    }
    (void)mvtd_ckpt_ids(d); /* identities leased on disk before they are published (--state) */
    if (!d->offline) {
        clock_from_tracks(d, frame);
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
    msg.publish_utime = mvtd_wall_utime();
    PUBLISH(d, mvtrack_tracks_t, "TRACKS", &msg);
    if (d->pf && d->publish_particles > 0) {
        publish_particles(d, capture_utime);
    }
    d->frames_processed++;
    if (!d->offline && d->frames_processed % (d->pf ? MVTD_CKPT_FRAMES_PF : MVTD_CKPT_FRAMES) == 0) {
        mvtd_ckpt_save(d, 0); /* --state: handed to the writer thread, which takes it to disk */
    }
    const double t1 = mvtd_wall_s();
    const int slot = d->n_proc % MVTD_PROC_RING;
    d->proc_ms[slot] = (float)((t1 - t0) * 1e3);
    d->latency_ms[slot] = (float)((t1 - d->last_accept_wall_s) * 1e3);
    d->n_proc++;
    mvtd_log_camera_events(d);
    if (d->trk->counters.births_refused_full > d->tracker_births_full_seen) {
        d->tracker_births_full_seen = d->trk->counters.births_refused_full;
        mvtd_log(d, MVTD_LOG_CAPACITY, "track capacity MVT_MAX_TARGETS=%d full: %llu births refused so far",
                 MVT_MAX_TARGETS, (unsigned long long)d->trk->counters.births_refused_full);
    }
}
