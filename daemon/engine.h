/*
 * engine.h - what the engine's files share (mvtd.h is the engine's interface to its callers).
 *
 * A message's path, one file per step, in one direction:
 *   loop.c       LCM socket, signals, timers: lcm_handle() calls mvtd_handle() per message
 *   ingest.c     admission (rate bound per camera), wire check, decoding, validation -> mvt_view_t
 *   assembler.c  views of one capture time -> a frame set (mvt_frame_t), emitted to mvtd_on_frame
 *   track.c      the tracker's step -> TRACKS (and MVTRACK_PARTICLES)
 *   status.c     counters -> MVTRACK_STATUS about once a second
 * Beside it: options.c (command line, configuration), checkpoint.c (--state: save and restore the
 * tracker across restarts), log.c (clocks, rate-limited stderr).
 */
#ifndef MVTD_ENGINE_H
#define MVTD_ENGINE_H

#include <stdint.h>

#include "mvtd.h"

/* Without LCM output (fuzzing, soak) messages are still encoded, into this buffer. */
extern uint8_t g_mvtd_encode_buf[1 << 22];

#define PUBLISH(d, T, channel, msg)                                                                \
    do {                                                                                           \
        if ((d)->lcm_out != NULL) {                                                                \
            T##_publish((d)->lcm_out, channel, msg);                                               \
        } else {                                                                                   \
            const int n_ = T##_encode(g_mvtd_encode_buf, 0, (int)sizeof(g_mvtd_encode_buf), msg);  \
            (d)->bytes_encoded += n_ > 0 ? n_ : 0;                                                 \
        }                                                                                          \
    } while (0)

/* CLOCK_MONOTONIC seconds (deadlines, periods) and CLOCK_REALTIME microseconds (publish_utime). */
double mvtd_wall_s(void);
int64_t mvtd_wall_utime(void);

/* stderr at a bounded rate: one line per class per second, with the count of suppressed lines.
 * Returns 1 when the line was written, 0 when it was suppressed (a once-only line can try again). */
int mvtd_log(mvtd_t *d, enum mvtd_log_class cls, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/* The assembler's emit callback: tracks the frame set and publishes TRACKS. */
void mvtd_on_frame(void *ctx, mvt_frame_t *frame, int complete);

/* Cameras that went down or came back, clock re-basings, since the last call: one line each; a
 * camera's clock off the others' once per verdict (re-timed, refused). */
void mvtd_log_camera_events(mvtd_t *d);

#endif /* MVTD_ENGINE_H */
