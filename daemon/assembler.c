#include "assembler.h"

#include <string.h>

static uint32_t all_cameras(const mvtd_asm_t *a)
{
    return a->num_cameras >= 32 ? 0xffffffffu : ((1u << a->num_cameras) - 1u);
}

void mvtd_asm_init(mvtd_asm_t *a, int num_cameras, double frame_rate_hz, mvtd_emit_fn emit, void *ctx)
{
    memset(a, 0, sizeof(*a));
    a->num_cameras = num_cameras;
    a->half_period_us = (int64_t)(0.5e6 / frame_rate_hz);
    a->emit = emit;
    a->ctx = ctx;
    a->active = all_cameras(a);
}

static void emit_open(mvtd_asm_t *a)
{
    if (!a->open) {
        return;
    }
    const int complete = (a->present & all_cameras(a)) == all_cameras(a);
    int64_t t = a->ref_utime;
    for (int k = 0; k < a->num_cameras; k++) {
        a->frame.views[k].observed = (a->present >> k) & 1u;
        if (a->frame.views[k].observed) {
            t = a->frame.views[k].utime_us > t ? a->frame.views[k].utime_us : t;
            a->cam_absent_run[k] = 0;
            continue;
        }
        a->counters.missing[k]++;
        if (a->cam_absent_run[k] < 255) {
            a->cam_absent_run[k]++;
        }
        if (a->cam_absent_run[k] >= MVTD_ASM_DOWN_SETS && ((a->active >> k) & 1u)) {
            a->active &= ~(1u << k);
            a->counters.went_down[k]++;
        }
    }
    if (a->have_closed && t < a->last_emitted_utime) {
        t = a->last_emitted_utime; /* never hand the tracker a time earlier than the last frame */
    }
    a->frame.utime_us = t;
    if (complete) {
        a->counters.sets_complete++;
    } else {
        a->counters.sets_partial++;
    }
    a->open = 0;
    a->have_closed = 1;
    a->last_closed_ref = a->ref_utime;
    a->last_emitted_utime = t;
    a->emit(a->ctx, &a->frame, complete);
}

/* A message MVTD_ASM_JUMP_US or more behind or ahead of the last set: the capture clock jumped,
 * or one camera's clock is wrong. Returns 0 (normal), -1/+1 (refused: not yet agreed) or 2
 * (re-based: the caller recomputes the message time). */
static int rebase_if_clock_jumped(mvtd_asm_t *a, int64_t u)
{
    const int64_t ref = a->open ? a->ref_utime : a->last_emitted_utime;
    const int dir = !a->open && !a->have_closed    ? 0
                    : u < ref - MVTD_ASM_JUMP_US ? -1
                    : u > ref + MVTD_ASM_JUMP_US ? 1
                                                 : 0;
    if (dir == 0) {
        a->far_run = 0;
        return 0;
    }
    if (dir != a->far_dir) {
        a->far_dir = dir;
        a->far_run = 0;
    }
    if (++a->far_run < a->num_cameras) {
        return dir;
    }
    emit_open(a);
    const int64_t target = dir < 0 ? a->last_emitted_utime + 2 * a->half_period_us
                                   : a->last_emitted_utime + (u - a->last_emitted_utime < MVTD_ASM_MAX_GAP_US
                                                                  ? u - a->last_emitted_utime
                                                                  : MVTD_ASM_MAX_GAP_US);
    a->offset_us += target - u;
    a->far_run = 0;
    memset(a->cam_seen, 0, sizeof(a->cam_seen));
    if (dir < 0) {
        a->counters.clock_jumps++;
    } else {
        a->counters.time_gaps++;
    }
    return 2;
}

mvtd_asm_result_t mvtd_asm_add(mvtd_asm_t *a, int cam, const mvt_view_t *view, double wall_s)
{
    int64_t u = view->utime_us + a->offset_us;
    const int jump = rebase_if_clock_jumped(a, u);
    if (jump == -1 || jump == 1) {
        a->counters.far[jump > 0]++;
        return jump < 0 ? MVTD_ASM_BACKWARDS : MVTD_ASM_AHEAD;
    }
    if (jump == 2) {
        u = view->utime_us + a->offset_us;
    }
    if (a->cam_seen[cam] && u <= a->cam_last_utime[cam]) {
        if (u == a->cam_last_utime[cam]) {
            a->counters.duplicate++;
            return MVTD_ASM_DUPLICATE;
        }
        a->counters.backwards++;
        return MVTD_ASM_BACKWARDS;
    }
    if (a->open && u > a->ref_utime + a->half_period_us) {
        emit_open(a); /* a later frame proves the open set complete */
    }
    if (!((a->active >> cam) & 1u)) { /* a plausible time from a camera that was down */
        a->active |= 1u << cam;           /* back: waited for again (from the next set if late) */
        a->cam_absent_run[cam] = 0;
        a->counters.came_back[cam]++;
    }
    if (!a->open) {
        if (a->have_closed && u <= a->last_closed_ref + a->half_period_us) {
            a->counters.late++;
            return MVTD_ASM_LATE;
        }
        a->open = 1;
        a->ref_utime = u;
        a->present = 0;
        a->open_wall_s = wall_s;
    } else if (u < a->ref_utime - a->half_period_us) {
        a->counters.late++;
        return MVTD_ASM_LATE;
    }
    if ((a->present >> cam) & 1u) {
        a->counters.duplicate++;
        return MVTD_ASM_DUPLICATE;
    }
    a->cam_seen[cam] = 1;
    a->cam_last_utime[cam] = u;
    a->present |= 1u << cam;
    a->frame.views[cam] = *view;
    a->frame.views[cam].utime_us = u;
    if ((a->present & a->active) == a->active) {
        emit_open(a);
    }
    return MVTD_ASM_ACCEPTED;
}

void mvtd_asm_poll(mvtd_asm_t *a, double wall_s, double deadline_s)
{
    if (a->open && wall_s - a->open_wall_s >= deadline_s) {
        emit_open(a);
    }
}

double mvtd_asm_time_to_deadline(const mvtd_asm_t *a, double wall_s, double deadline_s)
{
    if (!a->open) {
        return -1e30;
    }
    return a->open_wall_s + deadline_s - wall_s;
}

void mvtd_asm_flush(mvtd_asm_t *a)
{
    emit_open(a);
}
