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

#include "fuzz_engine.h"
#include "mvtd.h"
#include "mvtrack_camera_frame_t.h"

static mvtd_t g_pkf, g_pf, g_pkf0, g_pf0;
static mvt_pft_t g_pft0;
static int g_ready;
static uint8_t g_file[sizeof(mvtd_ckpt_header_t) + sizeof(mvt_pft_persist_t) + 64];

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    fuzz_configure(&g_pkf, "pkf");
    fuzz_configure(&g_pf, "pf");
    g_pkf.rig_hash = g_pf.rig_hash = 0x5eed5eed5eed5eedull; /* what bit 1 writes into the header */
    g_pkf0 = g_pkf;
    g_pf0 = g_pf;
    g_pft0 = *g_pf.pft;
    g_ready = 1;
    return 0;
}

/* The fields that identify this daemon, as it would write them; times, lease and CRCs kept. */
static void fix_header(const mvtd_t *d, mvtd_ckpt_header_t *h)
{
    mvtd_ckpt_header_t want;
    mvtd_ckpt_expected_header(d, &want);
    want.capture_utime = h->capture_utime;
    want.asm_offset_us = h->asm_offset_us;
    want.asm_last_emitted_utime = h->asm_last_emitted_utime;
    want.id_lease = h->id_lease;
    want.state_crc = h->state_crc;
    want.header_crc = h->header_crc;
    *h = want;
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
        char channel[MVT_RIG_NAME_MAX + 16];
        snprintf(channel, sizeof(channel), "DETECTIONS_%s", d->rig.names[k]);
        mvtd_handle(d, channel, buf, (uint32_t)n);
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
            fix_header(d, &h);
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
        fuzz_check_output(d);
    }
    return 0;
}
