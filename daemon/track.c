/*
 * track.c - one frame set from the assembler: the tracker's step, then TRACKS (and, in pf modes,
 * MVTRACK_PARTICLES). The tracking maths live in lib/.
 */
#include "engine.h"

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
