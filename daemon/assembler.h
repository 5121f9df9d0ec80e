/*
 * assembler.h - groups per-camera messages into frame sets for the tracker.
 *
 * A frame set collects messages whose capture times lie within half a frame period of the first
 * message of the set. It is emitted (in this order of precedence) when every active camera has
 * reported, when a message of a later frame proves it complete, when a wall-clock deadline passes
 * (live mode only: mvtd_asm_poll), or at the end of input (mvtd_asm_flush). Only message times
 * and their order decide, except the live deadline. No allocation; one frame set is open at a time.
 *
 * Cameras that stop: a camera absent from MVTD_ASM_DOWN_SETS consecutive sets is "down" and no
 * longer waited for, so a dead camera costs the deadline once, not every frame; its next message
 * makes it active again.
 *
 * Time: late, duplicate and time-reversed messages are counted and dropped. A message
 * MVTD_ASM_JUMP_US or more behind or ahead of the last emitted set is refused (counted) unless as
 * many consecutive messages as there are cameras agree, so one camera with a wrong clock can
 * neither stall the others nor drag the time base. When they agree, the capture clock jumped: the
 * assembler re-bases, adding offset_us to every message time from then on. After a jump back the
 * tracker sees time continue one frame later and keeps its tracks; after a jump ahead it sees the
 * gap, capped at MVTD_ASM_MAX_GAP_US (longer than any track coasts: the room was unwatched).
 * Publish capture times as frame time - offset_us.
 *
 * Bounds: the caller keeps message times in 0..2^60 us. Tracker time then starts below 2^60 and
 * grows by less than MVTD_ASM_MAX_GAP_US per frame set, whatever the input: no int64 overflow
 * for over a century of frame sets at 25 Hz.
 */
#ifndef MVTD_ASSEMBLER_H
#define MVTD_ASSEMBLER_H

#include "mvt_tracker.h"

#define MVTD_ASM_DOWN_SETS 2
#define MVTD_ASM_JUMP_US 2000000
#define MVTD_ASM_MAX_GAP_US 60000000

typedef void (*mvtd_emit_fn)(void *ctx, mvt_frame_t *frame, int complete);

typedef enum mvtd_asm_result {
    MVTD_ASM_ACCEPTED = 0,
    MVTD_ASM_LATE = 1,       /* its frame set was already emitted */
    MVTD_ASM_DUPLICATE = 2,  /* the camera already reported in the open set */
    MVTD_ASM_BACKWARDS = 3,  /* older than the camera's previous message, or far behind the last set */
    MVTD_ASM_AHEAD = 4       /* far ahead of the last set, other cameras not (yet) agreeing */
} mvtd_asm_result_t;

typedef struct mvtd_asm_counters {
    uint64_t sets_complete, sets_partial;
    uint64_t late, duplicate, backwards;
    uint64_t clock_jumps;               /* re-basings after the capture clock went back */
    uint64_t time_gaps;                 /* re-basings after it jumped ahead */
    uint64_t far[2];                    /* messages refused far behind [0] / ahead [1] */
    uint64_t missing[MVT_MAX_CAMERAS];  /* sets emitted without camera k */
    uint64_t went_down[MVT_MAX_CAMERAS];
    uint64_t came_back[MVT_MAX_CAMERAS];
} mvtd_asm_counters_t;

typedef struct mvtd_asm {
    int num_cameras;
    int64_t half_period_us;
    mvtd_emit_fn emit;
    void *ctx;
    int open;
    int64_t ref_utime;          /* first message of the open set */
    uint32_t present;
    uint32_t active;            /* cameras a set waits for */
    double open_wall_s;         /* wall time the open set received its first message */
    int have_closed;
    int64_t last_closed_ref;
    int64_t last_emitted_utime;
    int64_t offset_us;          /* added to message times since the last backward clock jump */
    int far_dir, far_run;       /* consecutive messages MVTD_ASM_JUMP_US behind (-1) / ahead (+1) */
    int64_t cam_last_utime[MVT_MAX_CAMERAS];
    uint8_t cam_seen[MVT_MAX_CAMERAS];
    uint8_t cam_absent_run[MVT_MAX_CAMERAS];
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
