#include "assembler.h"

#include <string.h>

void mvtd_asm_init(mvtd_asm_t *a, int num_cameras, double frame_rate_hz, mvtd_emit_fn emit, void *ctx)
{
    memset(a, 0, sizeof(*a));
    a->num_cameras = num_cameras;
    a->half_period_us = (int64_t)(0.5e6 / frame_rate_hz);
    a->emit = emit;
    a->ctx = ctx;
}

static void emit_open(mvtd_asm_t *a)
{
    if (!a->open) {
        return;
    }
    const uint32_t all = (a->num_cameras >= 32) ? 0xffffffffu : ((1u << a->num_cameras) - 1u);
    const int complete = (a->present & all) == all;
    int64_t t = a->ref_utime;
    for (int k = 0; k < a->num_cameras; k++) {
        a->frame.views[k].observed = (a->present >> k) & 1u;
        if (a->frame.views[k].observed) {
            t = a->frame.views[k].utime_us > t ? a->frame.views[k].utime_us : t;
        } else {
            a->counters.missing[k]++;
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

mvtd_asm_result_t mvtd_asm_add(mvtd_asm_t *a, int cam, const mvt_view_t *view, double wall_s)
{
    const int64_t u = view->utime_us;
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
    const uint32_t all = (a->num_cameras >= 32) ? 0xffffffffu : ((1u << a->num_cameras) - 1u);
    if ((a->present & all) == all) {
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
