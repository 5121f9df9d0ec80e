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
    if (a->have_closed && t > a->last_emitted_utime + MVTD_ASM_JUMP_US) {
        a->counters.time_gaps++;
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

/* A message far behind the last set: a clock that went back, or one camera's wrong clock. */
static int rebase_if_clock_jumped(mvtd_asm_t *a, int64_t u)
{
    if (!a->have_closed || u >= a->last_emitted_utime - MVTD_ASM_JUMP_US) {
        a->far_behind = 0;
        return 0;
    }
    if (++a->far_behind < a->num_cameras) {
        return 0;
    }
    emit_open(a);
    a->offset_us += a->last_emitted_utime + 2 * a->half_period_us - u;
    a->far_behind = 0;
    memset(a->cam_seen, 0, sizeof(a->cam_seen));
    a->counters.clock_jumps++;
    return 1;
}

mvtd_asm_result_t mvtd_asm_add(mvtd_asm_t *a, int cam, const mvt_view_t *view, double wall_s)
{
    if (!((a->active >> cam) & 1u)) {
        a->active |= 1u << cam; /* back: wait for it again from the next set */
        a->cam_absent_run[cam] = 0;
        a->counters.came_back[cam]++;
    }
    int64_t u = view->utime_us + a->offset_us;
    if (rebase_if_clock_jumped(a, u)) {
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
