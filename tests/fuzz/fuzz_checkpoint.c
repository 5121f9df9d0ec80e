/*
 * libFuzzer target: the checkpoint loader (daemon/checkpoint.c: mvtd_ckpt_parse, then the core's
 * mvt_tracker_resume / mvt_pft_resume at the first message), in the PKF and particle-filter modes.
 *
 * Input: one flag byte, then the file's bytes. Flag bit 0: pf mode; bit 1: the header's fields
 * that identify this daemon (magic, version, byte order, sizes, capacities, cameras, mode, rig
 * hash) are set to the expected values; bit 2: both CRCs are recomputed. Without bits 1 and 2 the
 * fuzzer meets the header and checksum checks; with them it reaches the value-by-value checks of
 * the state. Each input starts from the engine as configured (a pristine copy).
 * Invariants: a refused checkpoint leaves the tracker exactly as it was (no half-loaded state);
 * after an accepted one, three frame sets run and every published number is finite.
 */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mvtd.h"
#include "mvtrack_camera_frame_t.h"

static mvtd_t g_pkf, g_pf, g_pkf0, g_pf0;
static mvt_pft_t g_pft0;
static int g_ready;
static uint8_t g_file[sizeof(mvtd_ckpt_header_t) + sizeof(mvt_pft_persist_t) + 64];

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void configure(mvtd_t *d, const char *mode)
{
    const char *rig = getenv("MVTRACK_FUZZ_RIG");
    if (rig == NULL) {
        fprintf(stderr, "fuzz_checkpoint: set MVTRACK_FUZZ_RIG to a rig file\n");
        abort();
    }
    char *argv[] = {"mvtrackd", "--rig", (char *)rig, "--mode", (char *)mode, "--particles", "64", "--in",
                    "file:///dev/null", "--out", "file:///dev/null", NULL};
    if (mvtd_configure(d, 11, argv) != MVTD_CONTINUE) {
        abort();
    }
    d->quiet = 1;
    d->rig_hash = 0x5eed5eed5eed5eedull; /* what bit 1 writes into the header */
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    configure(&g_pkf, "pkf");
    configure(&g_pf, "pf");
    g_pkf0 = g_pkf;
    g_pf0 = g_pf;
    g_pft0 = *g_pf.pft;
    g_ready = 1;
    return 0;
}

static void fix_header(const mvtd_t *d, mvtd_ckpt_header_t *h, size_t state_size)
{
    memcpy(h->magic, "MVTCKPT", 8);
    h->version = MVTD_CKPT_VERSION;
    h->endian = 0x01020304u;
    h->real_size = (uint32_t)sizeof(mvt_real);
    h->max_targets = MVT_MAX_TARGETS;
    h->max_particles = MVT_MAX_PARTICLES;
    h->max_cameras = MVT_MAX_CAMERAS;
    h->num_cameras = (uint32_t)d->rig.num_cameras;
    h->num_particles = d->pf ? (uint32_t)d->pft->cfg.num_particles : 0u;
    memset(h->mode, 0, sizeof(h->mode));
    snprintf(h->mode, sizeof(h->mode), "%s", d->mode_name);
    h->state_size = state_size;
    h->rig_hash = d->rig_hash;
}

/* One frame set: every camera reports one detection near the image centre at utime. */
static void frame_set(mvtd_t *d, int64_t utime)
{
    static uint8_t buf[4096];
    for (int k = 0; k < d->rig.num_cameras; k++) {
        mvtrack_detection_t det;
        memset(&det, 0, sizeof(det));
        det.u = 384.0f;
        det.v = 200.0f;
        det.sigma_px = 2.0f;
        det.score = 1.0f;
        det.bbox[0] = 360.0f;
        det.bbox[1] = 200.0f;
        det.bbox[2] = 410.0f;
        det.bbox[3] = 420.0f;
        det.hue = det.saturation = -1.0f;
        mvtrack_camera_frame_t m;
        memset(&m, 0, sizeof(m));
        m.utime = utime;
        m.camera = d->rig.names[k];
        m.width = (int16_t)d->rig.params[k].width;
        m.height = (int16_t)d->rig.params[k].height;
        m.num_detections = 1;
        m.detections = &det;
        const int n = mvtrack_camera_frame_t_encode(buf, 0, (int)sizeof(buf), &m);
        char channel[MVTD_NAME_MAX + 16];
        snprintf(channel, sizeof(channel), "DETECTIONS_%s", d->rig.names[k]);
        mvtd_handle(d, channel, buf, (uint32_t)n);
    }
}

static void check_output(const mvtd_t *d)
{
    const mvt_output_t *o = &d->output;
    if (o->num_tracks < 0 || o->num_tracks > MVT_MAX_TARGETS) {
        abort();
    }
    for (int i = 0; i < o->num_tracks; i++) {
        const mvt_track_out_t *t = &o->tracks[i];
        for (int a = 0; a < 3; a++) {
            if (!isfinite(t->pos_m[a]) || !isfinite(t->vel_ms[a]) || !isfinite(t->extent_min[a]) ||
                !isfinite(t->extent_max[a])) {
                abort();
            }
        }
        for (int a = 0; a < 6; a++) {
            if (!isfinite(t->cov_m2[a])) {
                abort();
            }
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!g_ready || size < 1) {
        return 0;
    }
    const int pf = data[0] & 1u;
    mvtd_t *d = pf ? &g_pf : &g_pkf;
    *d = pf ? g_pf0 : g_pkf0;
    if (pf) {
        *d->pft = g_pft0;
    }
    size_t n = size - 1;
    if (n > sizeof(g_file)) {
        n = sizeof(g_file);
    }
    memcpy(g_file, data + 1, n);
    const size_t hs = sizeof(mvtd_ckpt_header_t);
    const size_t ss = pf ? sizeof(mvt_pft_persist_t) : sizeof(mvt_tracker_persist_t);
    mvtd_ckpt_header_t h;
    if (n >= hs && (data[0] & 6u) != 0u) {
        memcpy(&h, g_file, hs);
        if (data[0] & 2u) {
            fix_header(d, &h, ss);
        }
        if (data[0] & 4u) {
            h.state_crc = mvtd_crc32(g_file + hs, n >= hs + ss ? ss : n - hs);
            h.header_crc = mvtd_crc32(&h, offsetof(mvtd_ckpt_header_t, header_crc));
        }
        memcpy(g_file, &h, hs);
    }
    char why[256];
    if (mvtd_ckpt_parse(d, g_file, n, why, sizeof(why)) != 0) {
        if (d->ckpt_pending) {
            abort(); /* refused but kept */
        }
        return 0;
    }
    memcpy(&h, g_file, hs);
    /* the first message: up to 1 s after the saved capture time, which the parser bounded */
    const int64_t first = h.capture_utime + (int64_t)(data[0] >> 3) * 40000;
    static mvt_tracker_persist_t before_trk, after_trk;
    static mvt_pft_persist_t before_pft, after_pft;
    if (pf) {
        mvt_pft_save(d->pft, &before_pft);
    } else {
        mvt_tracker_save(&d->tracker, &before_trk);
    }
    mvtd_ckpt_first_message(d, first);
    if (d->ckpt_pending) {
        abort(); /* the first message decides */
    }
    if (strstr(d->restore_note, "restored") == NULL) {
        /* refused: not one byte of the tracker changed */
        if (pf) {
            mvt_pft_save(d->pft, &after_pft);
            if (memcmp(&before_pft, &after_pft, sizeof(after_pft)) != 0) {
                abort();
            }
        } else {
            mvt_tracker_save(&d->tracker, &after_trk);
            if (memcmp(&before_trk, &after_trk, sizeof(after_trk)) != 0) {
                abort();
            }
        }
    }
    for (int f = 0; f < 3; f++) {
        frame_set(d, first + f * 40000);
        check_output(d);
    }
    return 0;
}
