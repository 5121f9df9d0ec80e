/*
 * mvtrack-soak - the daemon's engine fed the equivalent of a long run offline, reporting memory
 * and per-frame time as it goes (issue "a daemon for the long run").
 *
 * A changing population walks the rig's volume (people arrive at random, stay about a minute,
 * leave); every frame each camera's detections (projected through the rig's lens model, pixel
 * noise, misses, false alarms) are encoded as mvtrack.camera_frame_t and handed to the same
 * handler LCM calls in mvtrackd, in a shuffled camera order. Now and then a camera stops for a
 * few seconds, a camera restarts its frame counter, a garbage or duplicate message arrives, and
 * once the capture clock jumps back. TRACKS and MVTRACK_STATUS are encoded, not sent.
 *
 * Prints one JSON line per window (RSS, frame time p50/p99/max, tracks) and a summary line:
 * RSS after warm-up vs at the end, and the least-squares slope of the windows' median frame
 * time. Exit status 0 when RSS grew by at most --rss-tolerance-kb and the frame time did not
 * trend upward (slope over the run below --max-trend, default 10 %, of the median), 1 otherwise.
 * --no-rss-check for sanitizer builds (their allocator quarantines freed memory).
 */
#define _GNU_SOURCE
#include <malloc.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "mvtd.h"
#include "mvtrack_camera_frame_t.h"

#define MAX_PEOPLE 12
#define MAX_DETS 32
#define MAX_WINDOWS 4096

static mvtd_t g_d;

typedef struct person {
    int alive;
    double x, y, vx, vy, height, leave_s;
} person_t;

static uint64_t g_rng = 0x853c49e6748fea9bULL;

static double urand(void)
{
    g_rng = g_rng * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(g_rng >> 11) * (1.0 / 9007199254740992.0);
}

static double nrand(void)
{
    const double u = urand() + 1e-300, v = urand();
    return sqrt(-2.0 * log(u)) * cos(6.283185307179586 * v);
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static long rss_kb(void)
{
    FILE *f = fopen("/proc/self/statm", "r");
    long pages = 0, resident = 0;
    if (f == NULL) {
        return -1;
    }
    if (fscanf(f, "%ld %ld", &pages, &resident) != 2) {
        resident = -1;
    }
    fclose(f);
    return resident < 0 ? -1 : resident * (sysconf(_SC_PAGESIZE) / 1024);
}

static int cmp_float(const void *a, const void *b)
{
    const float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

static void usage(FILE *f)
{
    fprintf(f,
            "usage: mvtrack-soak --rig RIG.yaml [--frames N] [--window N] [--mode MODE] [--people N]\n"
            "                    [--rss-tolerance-kb K] [--max-trend X]\n"
            "                    [--no-rss-check] [--quiet] [--state FILE]\n"
            "\n"
            "Feeds mvtrackd's engine N frame sets (default 2160000 = 24 h at 25 fps) of a changing\n"
            "population seen by every rig camera, offline, and prints RSS and per-frame time per\n"
            "window (default 90000 frames = 1 h) as JSON lines, then a summary. Exit 0 when the\n"
            "RSS at the end is within K kB (default 1024) of the RSS after the first window and\n"
            "the least-squares trend of the windows' median frame time over the run is below X\n"
            "(default 0.10) of its mean; 1 otherwise; 2 on bad arguments.\n"
            "--no-rss-check: for sanitizer builds, whose allocator keeps freed memory in quarantine.\n"
            "--state FILE: checkpoints on, as mvtrackd --state FILE, one per simulated second (the\n"
            "live daemon writes one per wall-clock second), by the same writer thread.\n");
}

int main(int argc, char **argv)
{
    const char *rig = NULL, *mode = "pkf", *state = NULL;
    long frames = 2160000, window = 90000, rss_tol_kb = 1024;
    int mean_people = 5, quiet = 0, rss_check = 1;
    double max_trend = 0.10;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            usage(stdout);
            return 0;
        } else if (strcmp(a, "--quiet") == 0) {
            quiet = 1;
        } else if (strcmp(a, "--no-rss-check") == 0) {
            rss_check = 0;
        } else if (v == NULL) {
            usage(stderr);
            return 2;
        } else if (strcmp(a, "--rig") == 0) {
            rig = v, i++;
        } else if (strcmp(a, "--mode") == 0) {
            mode = v, i++;
        } else if (strcmp(a, "--state") == 0) {
            state = v, i++;
        } else if (strcmp(a, "--frames") == 0) {
            frames = strtol(v, NULL, 10), i++;
        } else if (strcmp(a, "--window") == 0) {
            window = strtol(v, NULL, 10), i++;
        } else if (strcmp(a, "--people") == 0) {
            mean_people = (int)strtol(v, NULL, 10), i++;
        } else if (strcmp(a, "--max-trend") == 0) {
            max_trend = strtod(v, NULL), i++;
        } else if (strcmp(a, "--rss-tolerance-kb") == 0) {
            rss_tol_kb = strtol(v, NULL, 10), i++;
        } else {
            fprintf(stderr, "mvtrack-soak: unknown option '%s'\n", a);
            usage(stderr);
            return 2;
        }
    }
    if (rig == NULL || frames < 1 || window < 1 || frames / window > MAX_WINDOWS || mean_people < 0 ||
        mean_people > MAX_PEOPLE) {
        fprintf(stderr, "mvtrack-soak: need --rig, frames >= 1, 1 <= window, frames/window <= %d, people 0..%d\n",
                MAX_WINDOWS, MAX_PEOPLE);
        return 2;
    }
    char *dargv[] = {"mvtrackd", "--rig", (char *)rig, "--mode", (char *)mode, "--in", "file:///dev/null", "--out",
                     "file:///dev/null", "--state", (char *)state, NULL};
    mvtd_t *d = &g_d;
    const int rc = mvtd_configure(d, state != NULL ? 11 : 9, dargv);
    if (rc != MVTD_CONTINUE) {
        return 2;
    }
    d->quiet = 1; /* the engine's bounded stderr lines would interleave with the report */
    quiet |= !isatty(2); /* the progress bar redraws with carriage returns: only on a terminal */
    const int nc = d->rig.num_cameras;
    static mvt_camera_t cams[MVT_MAX_CAMERAS];
    for (int k = 0; k < nc; k++) {
        mvt_cam_init(&cams[k], &d->rig.params[k]);
    }
    char channels[MVT_MAX_CAMERAS][MVT_RIG_NAME_MAX + 16];
    for (int k = 0; k < nc; k++) {
        snprintf(channels[k], sizeof(channels[k]), "DETECTIONS_%s", d->rig.names[k]);
    }
    const double *lo = d->rig.volume_min, *hi = d->rig.volume_max;
    const double period = 1.0 / d->rig.frame_rate;
    const int64_t period_us = (int64_t)llround(period * 1e6);

    static person_t people[MAX_PEOPLE];
    static uint8_t buf[65536];
    static float frame_ms[200000];
    if (window > 200000) {
        fprintf(stderr, "mvtrack-soak: --window at most 200000\n");
        return 2;
    }
    static double win_p50[MAX_WINDOWS];
    long rss_warm = -1, rss_end = -1, rss_max = 0;
    int64_t utime = 1700000000000000LL, frame_counter[MVT_MAX_CAMERAS] = {0};
    int down_cam = -1;
    long down_until = 0;
    int nwin = 0;
    const double t_start = now_s();
    const long clock_jump_at = frames / 2;
    int64_t garbage = 0;
    for (long f = 0; f < frames; f++) {
        const double t = (double)f * period;
        /* population: arrivals keep about mean_people inside; each stays ~60 s */
        int alive = 0;
        for (int i = 0; i < MAX_PEOPLE; i++) {
            alive += people[i].alive;
        }
        const int arrives = urand() < (double)mean_people / 60.0 * period;
        for (int i = 0; i < MAX_PEOPLE && arrives; i++) {
            if (!people[i].alive) {
                person_t *p = &people[i];
                p->alive = 1;
                p->x = lo[0] + 0.3 + urand() * (hi[0] - lo[0] - 0.6);
                p->y = lo[1] + 0.3 + urand() * (hi[1] - lo[1] - 0.6);
                p->vx = p->vy = 0.0;
                p->height = 1.5 + 0.4 * urand();
                p->leave_s = t - 60.0 * log(urand() + 1e-12);
                alive++;
                break;
            }
        }
        for (int i = 0; i < MAX_PEOPLE; i++) {
            person_t *p = &people[i];
            if (!p->alive) {
                continue;
            }
            if (t > p->leave_s) {
                p->alive = 0;
                continue;
            }
            p->vx += -0.5 * p->vx * period + 0.7 * sqrt(period) * nrand();
            p->vy += -0.5 * p->vy * period + 0.7 * sqrt(period) * nrand();
            p->x += p->vx * period;
            p->y += p->vy * period;
            if (p->x < lo[0] + 0.2 || p->x > hi[0] - 0.2) {
                p->vx = -p->vx;
                p->x = p->x < lo[0] + 0.2 ? lo[0] + 0.2 : hi[0] - 0.2;
            }
            if (p->y < lo[1] + 0.2 || p->y > hi[1] - 0.2) {
                p->vy = -p->vy;
                p->y = p->y < lo[1] + 0.2 ? lo[1] + 0.2 : hi[1] - 0.2;
            }
        }
        /* a camera stops for 2-10 s about every 5 minutes */
        if (down_cam < 0 && urand() < period / 300.0) {
            down_cam = (int)(urand() * nc);
            down_until = f + (long)((2.0 + 8.0 * urand()) / period);
        } else if (down_cam >= 0 && f >= down_until) {
            down_cam = -1;
        }
        if (f == clock_jump_at) {
            utime -= 3600LL * 1000000LL; /* the capture clock is set back an hour */
        }
        utime += period_us;
        /* camera order shuffled each frame */
        int order[MVT_MAX_CAMERAS];
        for (int k = 0; k < nc; k++) {
            order[k] = k;
        }
        for (int k = nc - 1; k > 0; k--) {
            const int j = (int)(urand() * (k + 1));
            const int tmp = order[k];
            order[k] = order[j];
            order[j] = tmp;
        }
        double frame_s = 0.0;
        for (int oi = 0; oi < nc; oi++) {
            const int k = order[oi];
            if (k == down_cam) {
                continue;
            }
            mvtrack_detection_t dets[MAX_DETS];
            int nd = 0;
            for (int i = 0; i < MAX_PEOPLE && nd < MAX_DETS; i++) {
                if (!people[i].alive || urand() < 0.1) {
                    continue;
                }
                const mvt_real xw[3] = {(mvt_real)people[i].x, (mvt_real)people[i].y, (mvt_real)people[i].height};
                mvt_real uv[2];
                if (mvt_cam_project(&cams[k], xw, uv, NULL) != MVT_OK) {
                    continue;
                }
                const double u = (double)uv[0] + 2.0 * nrand(), v = (double)uv[1] + 2.0 * nrand();
                if (u < 0 || v < 0 || u >= d->rig.params[k].width || v >= d->rig.params[k].height) {
                    continue;
                }
                mvtrack_detection_t *o = &dets[nd++];
                memset(o, 0, sizeof(*o));
                o->u = (float)u;
                o->v = (float)v;
                o->sigma_px = 2.0f;
                o->score = 0.9f;
            }
            while (nd < MAX_DETS && urand() < 0.3) { /* false alarms */
                mvtrack_detection_t *o = &dets[nd++];
                memset(o, 0, sizeof(*o));
                o->u = (float)(urand() * d->rig.params[k].width);
                o->v = (float)(urand() * d->rig.params[k].height);
                o->sigma_px = 2.0f;
                o->score = 0.3f;
            }
            if (urand() < 1e-5) {
                frame_counter[k] = 0; /* the camera's detector restarted */
            }
            mvtrack_camera_frame_t m;
            memset(&m, 0, sizeof(m));
            m.utime = utime + (int64_t)(3000.0 * (2.0 * urand() - 1.0)); /* +-3 ms capture jitter */
            m.frame = frame_counter[k]++;
            m.camera = d->rig.names[k];
            m.width = (int16_t)d->rig.params[k].width;
            m.height = (int16_t)d->rig.params[k].height;
            m.num_detections = (int16_t)nd;
            m.detections = dets;
            const int n = mvtrack_camera_frame_t_encode(buf, 0, (int)sizeof(buf), &m);
            if (n < 0) {
                fprintf(stderr, "mvtrack-soak: encode failed\n");
                return 1;
            }
            const int dup = urand() < 1e-4;
            const int junk = urand() < 1e-4;
            const double t0 = now_s();
            mvtd_handle(d, channels[k], buf, (uint32_t)n);
            if (dup) {
                mvtd_handle(d, channels[k], buf, (uint32_t)n);
            }
            if (junk) {
                buf[(size_t)(urand() * n)] ^= 0xff; /* a corrupted copy */
                mvtd_handle(d, channels[k], buf, (uint32_t)(urand() * n));
                garbage++;
            }
            frame_s += now_s() - t0;
        }
        frame_ms[f % window] = (float)(frame_s * 1e3);
        if ((f + 1) % 25 == 0) {
            const double t0 = now_s();
            mvtd_ckpt_save(d, 0); /* --state: handed to the writer thread (skipped while it writes) */
            if (t0 - d->last_status_wall_s >= 1.0) {
                mvtd_publish_status(d); /* as the live daemon does once a second */
            }
        }
        if ((f + 1) % window == 0) {
            qsort(frame_ms, (size_t)window, sizeof(float), cmp_float);
            const long rss = rss_kb();
            if (nwin == 0) {
                rss_warm = rss;
            }
            rss_max = rss > rss_max ? rss : rss_max;
            rss_end = rss;
            win_p50[nwin] = frame_ms[window / 2];
            const int i99 = (int)ceil(0.99 * (double)window) - 1;
            int confirmed = 0;
            for (int i = 0; i < d->output.num_tracks; i++) {
                confirmed += d->output.tracks[i].status == MVT_TRACK_CONFIRMED;
            }
            const struct mallinfo2 mi = mallinfo2();
            printf("{\"window\": %d, \"frames\": %ld, \"sim_hours\": %.3f, \"rss_kb\": %ld, \"heap_arena_kb\": %zu, "
                   "\"heap_in_use_kb\": %zu, \"frame_ms_p50\": %.4f, "
                   "\"frame_ms_p99\": %.4f, \"frame_ms_max\": %.4f, \"people\": %d, \"tracks\": %d, "
                   "\"confirmed\": %d, \"births\": %llu, \"wall_s\": %.1f}\n",
                   nwin, f + 1, (double)(f + 1) * period / 3600.0, rss, mi.arena / 1024, mi.uordblks / 1024, win_p50[nwin], (double)frame_ms[i99],
                   (double)frame_ms[window - 1], alive, d->output.num_tracks, confirmed,
                   (unsigned long long)d->trk->counters.births, now_s() - t_start);
            fflush(stdout);
            nwin++;
        }
        if (!quiet && (f + 1) % 10000 == 0) {
            const double el = now_s() - t_start;
            const double frac = (double)(f + 1) / (double)frames;
            fprintf(stderr, "\rmvtrack-soak: [%-40.*s] %5.1f %%  %ld/%ld frames  %.0f s left ", (int)(40 * frac),
                    "########################################", 100.0 * frac, f + 1, frames,
                    el / frac - el);
        }
    }
    if (!quiet) {
        fputc('\n', stderr);
    }
    mvtd_finish(d);
    int64_t ck_written = 0, ck_failed = 0;
    float ck_age = 0.0f;
    if (state != NULL) {
        mvtd_ckpt_stats(d, &ck_written, &ck_failed, &ck_age);
    }
    /* trend of the median frame time: least squares over the windows after warm-up */
    double slope_rel = 0.0, mean_p50 = 0.0;
    const int w0 = nwin > 2 ? 1 : 0;
    const int nw = nwin - w0;
    if (nw >= 2) {
        double sx = 0, sy = 0, sxx = 0, sxy = 0;
        for (int i = w0; i < nwin; i++) {
            const double x = (double)(i - w0);
            sx += x;
            sy += win_p50[i];
            sxx += x * x;
            sxy += x * win_p50[i];
        }
        const double slope = ((double)nw * sxy - sx * sy) / ((double)nw * sxx - sx * sx);
        mean_p50 = sy / (double)nw;
        slope_rel = mean_p50 > 0.0 ? slope * (double)(nw - 1) / mean_p50 : 0.0;
    }
    const long growth = rss_end - rss_warm;
    const int rss_ok = !rss_check || (rss_warm > 0 && growth <= rss_tol_kb);
    const int time_ok = slope_rel < max_trend;
    printf("{\"summary\": true, \"frames\": %ld, \"windows\": %d, \"rss_warm_kb\": %ld, \"rss_end_kb\": %ld, "
           "\"rss_max_kb\": %ld, \"rss_growth_kb\": %ld, \"frame_ms_p50_mean\": %.4f, "
           "\"frame_ms_p50_trend_over_run\": %.4f, \"garbage_messages\": %lld, \"rejected_undecodable\": %lld, "
           "\"rejected_duplicate\": %lld, \"clock_jumps\": %llu, \"births\": %llu, \"wall_s\": %.1f, "
           "\"checkpoints_written\": %lld, \"checkpoints_skipped\": %lld, \"rss_flat\": %s, \"time_flat\": %s}\n",
           frames, nwin, rss_warm, rss_end, rss_max, growth, mean_p50, slope_rel, (long long)garbage,
           (long long)d->rej_undecodable, (long long)d->rej_duplicate,
           (unsigned long long)d->assembler.counters.clock_jumps, (unsigned long long)d->trk->counters.births,
           now_s() - t_start, (long long)ck_written, (long long)d->ckpt_skipped, rss_ok ? "true" : "false",
           time_ok ? "true" : "false");
    return rss_ok && time_ok ? 0 : 1;
}
