/*
 * assembler.h - groups per-camera messages into frame sets for the tracker.
 *
 * A frame set collects messages whose capture times lie within half a frame period of the first
 * message of the set. It is emitted (in this order of precedence) when every rig camera has
 * reported, when a message of a later frame proves it complete, when a wall-clock deadline passes
 * (live mode only: mvtd_asm_poll), or at the end of input (mvtd_asm_flush). Only message times
 * decide, except the live deadline. Late, duplicate and time-reversed messages are counted and
 * dropped. No allocation; one frame set is open at a time.
 */
#ifndef MVTD_ASSEMBLER_H
#define MVTD_ASSEMBLER_H

#include "mvt_tracker.h"

typedef void (*mvtd_emit_fn)(void *ctx, mvt_frame_t *frame, int complete);

typedef enum mvtd_asm_result {
    MVTD_ASM_ACCEPTED = 0,
    MVTD_ASM_LATE = 1,       /* its frame set was already emitted */
    MVTD_ASM_DUPLICATE = 2,  /* the camera already reported in the open set */
    MVTD_ASM_BACKWARDS = 3   /* older than the camera's previous message */
} mvtd_asm_result_t;

typedef struct mvtd_asm_counters {
    uint64_t sets_complete, sets_partial;
    uint64_t late, duplicate, backwards;
    uint64_t missing[MVT_MAX_CAMERAS];  /* sets emitted without camera k */
} mvtd_asm_counters_t;

typedef struct mvtd_asm {
    int num_cameras;
    int64_t half_period_us;
    mvtd_emit_fn emit;
    void *ctx;
    int open;
    int64_t ref_utime;          /* first message of the open set */
    uint32_t present;
    double open_wall_s;         /* wall time the open set received its first message */
    int have_closed;
    int64_t last_closed_ref;
    int64_t last_emitted_utime;
    int64_t cam_last_utime[MVT_MAX_CAMERAS];
    uint8_t cam_seen[MVT_MAX_CAMERAS];
    mvtd_asm_counters_t counters;
    mvt_frame_t frame;
} mvtd_asm_t;

void mvtd_asm_init(mvtd_asm_t *a, int num_cameras, double frame_rate_hz, mvtd_emit_fn emit, void *ctx);

/* Adds camera cam's view (copied) captured at utime. May emit the previous set and/or this one. */
mvtd_asm_result_t mvtd_asm_add(mvtd_asm_t *a, int cam, const mvt_view_t *view, double wall_s);

/* Live mode: emits the open set if it has waited more than deadline_s since its first message. */
void mvtd_asm_poll(mvtd_asm_t *a, double wall_s, double deadline_s);

/* Seconds until the open set's deadline (<= 0: due), or a negative huge value when none is open. */
double mvtd_asm_time_to_deadline(const mvtd_asm_t *a, double wall_s, double deadline_s);

/* Emits the open set, if any (end of input, shutdown). */
void mvtd_asm_flush(mvtd_asm_t *a);

#endif /* MVTD_ASSEMBLER_H */
