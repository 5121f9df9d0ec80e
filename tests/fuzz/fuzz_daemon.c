/*
 * libFuzzer target: message decoding + frame assembly + tracking, through the daemon's own engine
 * (mvtd_handle), in the PKF, the triangulating baseline and the particle-filter modes.
 *
 * Input: records [h][n_hi][n_lo][n bytes]. The first byte of the input picks the mode: bit 0 set,
 * pf; otherwise bit 1 set, kf; otherwise pkf. For each record: unless h & 0x80, the camera_frame_t fingerprint is put in
 * front of the n bytes (so the fuzzer spends its time past the hash check; with h & 0x80 the raw
 * bytes are the whole message); (h & 0x07) picks the channel (rig camera k, or a stranger's).
 * Invariants checked after every record: tracks within capacity, every published number finite,
 * a message that passed the wire check decodes.
 *
 * The rig: $MVTRACK_FUZZ_RIG (tools/mvtrack fuzz writes one).
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz_engine.h"
#include "mvtd.h"
#include "mvtrack_camera_frame_t.h"

static mvtd_t g_pkf, g_pf, g_kf;
static int g_ready;

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    fuzz_configure(&g_pkf, "pkf");
    fuzz_configure(&g_pf, "pf");
    fuzz_configure(&g_kf, "kf");
    g_ready = 1;
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static uint8_t msg[70000];
    if (!g_ready || size < 1) {
        return 0;
    }
    mvtd_t *d = (data[0] & 1u) ? &g_pf : (data[0] & 2u) ? &g_kf : &g_pkf;
    /* a fresh engine state per input would cost a rig load; instead the engine runs on across
     * inputs, as the daemon does across messages: capacity and time handling get exercised too */
    const int64_t hash = __mvtrack_camera_frame_t_get_hash();
    size_t pos = 1;
    while (pos + 3 <= size) {
        const uint8_t h = data[pos];
        size_t n = ((size_t)data[pos + 1] << 8) | data[pos + 2];
        pos += 3;
        if (n > size - pos) {
            n = size - pos;
        }
        size_t len = 0;
        if (!(h & 0x80u)) {
            for (int i = 0; i < 8; i++) {
                msg[len++] = (uint8_t)((uint64_t)hash >> (56 - 8 * i));
            }
        }
        memcpy(msg + len, data + pos, n);
        len += n;
        pos += n;
        const int k = h & 0x07;
        char channel[MVT_RIG_NAME_MAX + 16];
        snprintf(channel, sizeof(channel), "DETECTIONS_%s", k < d->rig.num_cameras ? d->rig.names[k] : "stranger");
        if (mvtd_frame_wire_check(msg, (uint32_t)len) == 0) {
            mvtrack_camera_frame_t m;
            if (mvtrack_camera_frame_t_decode(msg, 0, (int)len, &m) < 0) {
                fprintf(stderr, "fuzz_daemon: %zu bytes passed the wire check but did not decode:", len);
                for (size_t i = 0; i < len && i < 100000; i++) {
                    fprintf(stderr, " %02x", msg[i]);
                }
                fputc('\n', stderr);
                abort();
            }
            mvtrack_camera_frame_t_decode_cleanup(&m);
        }
        const int64_t before = d->frames_processed;
        mvtd_handle(d, channel, msg, (uint32_t)len);
        if (d->frames_processed != before) {
            fuzz_check_output(d);
        }
    }
    return 0;
}
