/* Unit tests of the daemon's frame assembler: completeness, proof by a later frame, late,
 * duplicate and backwards messages, deadline. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "assembler.h"

static mvtd_asm_t g_asm;
static int g_emitted;
static int g_complete;
static int64_t g_utime;
static uint32_t g_observed;

static void on_emit(void *ctx, mvt_frame_t *f, int complete)
{
    (void)ctx;
    g_emitted++;
    g_complete = complete;
    g_utime = f->utime_us;
    g_observed = 0;
    for (int k = 0; k < MVT_MAX_CAMERAS; k++) g_observed |= (uint32_t)(f->views[k].observed != 0) << k;
}

static mvtd_asm_result_t add(int cam, int64_t utime, double wall)
{
    mvt_view_t v;
    memset(&v, 0, sizeof(v));
    v.observed = 1;
    v.utime_us = utime;
    return mvtd_asm_add(&g_asm, cam, &v, wall);
}

static void setup_asm(int ncam)
{
    g_emitted = 0;
    mvtd_asm_init(&g_asm, ncam, 25.0, on_emit, NULL);
}

static void test_mvtd_asm_add_all_cameras_emits_complete_set(void **state)
{
    (void)state;
    setup_asm(3);
    assert_int_equal(add(1, 1000000, 0), MVTD_ASM_ACCEPTED);
    assert_int_equal(add(0, 1002000, 0), MVTD_ASM_ACCEPTED); /* +2 ms capture jitter */
    assert_int_equal(g_emitted, 0);
    assert_int_equal(add(2, 999000, 0), MVTD_ASM_ACCEPTED);
    assert_int_equal(g_emitted, 1);
    assert_int_equal(g_complete, 1);
    assert_int_equal(g_utime, 1002000); /* the latest capture time of the set */
    assert_int_equal(g_observed, 7);
}

static void test_mvtd_asm_add_later_frame_proves_partial_set(void **state)
{
    (void)state;
    setup_asm(3);
    add(0, 1000000, 0);
    add(2, 1000000, 0);
    assert_int_equal(g_emitted, 0);
    add(0, 1040000, 0); /* next frame: camera 1 never came */
    assert_int_equal(g_emitted, 1);
    assert_int_equal(g_complete, 0);
    assert_int_equal(g_observed, 5);
    assert_int_equal(g_asm.counters.missing[1], 1);
    /* camera 1's late message for the emitted frame is refused */
    assert_int_equal(add(1, 1000000, 0), MVTD_ASM_LATE);
    assert_int_equal(g_asm.counters.late, 1);
}

static void test_mvtd_asm_add_duplicate_and_backwards_refused(void **state)
{
    (void)state;
    setup_asm(2);
    add(0, 1000000, 0);
    assert_int_equal(add(0, 1000000, 0), MVTD_ASM_DUPLICATE);
    assert_int_equal(add(0, 990000, 0), MVTD_ASM_BACKWARDS);
    assert_int_equal(add(0, 1001000, 0), MVTD_ASM_DUPLICATE); /* same camera twice in one set */
    assert_int_equal(g_emitted, 0);
    assert_int_equal(g_asm.counters.duplicate, 2);
    assert_int_equal(g_asm.counters.backwards, 1);
}

static void test_mvtd_asm_poll_deadline_emits_open_set(void **state)
{
    (void)state;
    setup_asm(4);
    add(3, 1000000, 10.0);
    mvtd_asm_poll(&g_asm, 10.010, 0.020);
    assert_int_equal(g_emitted, 0);
    assert_true(mvtd_asm_time_to_deadline(&g_asm, 10.010, 0.020) > 0.0);
    mvtd_asm_poll(&g_asm, 10.021, 0.020);
    assert_int_equal(g_emitted, 1);
    assert_int_equal(g_complete, 0);
    assert_true(mvtd_asm_time_to_deadline(&g_asm, 11, 0.020) < -1e29);
    mvtd_asm_flush(&g_asm); /* nothing open: nothing emitted */
    assert_int_equal(g_emitted, 1);
}

static void test_mvtd_asm_add_dead_camera_not_waited_for_then_back(void **state)
{
    (void)state;
    setup_asm(3);
    for (int f = 0; f < 2; f++) { /* camera 2 silent for two sets: each closed by the next frame */
        add(0, 1000000 + f * 40000, 0);
        add(1, 1000000 + f * 40000, 0);
    }
    add(0, 1080000, 0);
    assert_int_equal(g_emitted, 2);
    assert_int_equal(g_asm.counters.went_down[2], 1);
    assert_int_equal(g_asm.active, 3u);
    /* camera 2 down: cameras 0 and 1 alone complete a set at once, no waiting */
    add(1, 1080000, 0);
    assert_int_equal(g_emitted, 3);
    assert_int_equal(g_observed, 3);
    /* camera 2 returns (late for the emitted set): counted, and waited for from the next set */
    assert_int_equal(add(2, 1080000, 0), MVTD_ASM_LATE);
    assert_int_equal(g_asm.counters.came_back[2], 1);
    add(0, 1120000, 0);
    add(1, 1120000, 0);
    assert_int_equal(g_emitted, 3);
    assert_int_equal(add(2, 1120000, 0), MVTD_ASM_ACCEPTED);
    assert_int_equal(g_emitted, 4);
    assert_int_equal(g_complete, 1);
}

static void test_mvtd_asm_add_clock_jump_back_rebases_time(void **state)
{
    (void)state;
    setup_asm(2);
    for (int f = 0; f < 3; f++) {
        add(0, 500000000 + f * 40000, 0);
        add(1, 500000000 + f * 40000, 0);
    }
    assert_int_equal(g_emitted, 3);
    assert_int_equal(g_utime, 500080000);
    /* the shared capture clock restarts near zero: the first message alone is only counted */
    assert_int_equal(add(0, 1000, 0), MVTD_ASM_BACKWARDS);
    assert_int_equal(add(1, 1000, 0), MVTD_ASM_ACCEPTED); /* second camera agrees: re-base */
    assert_int_equal(g_asm.counters.clock_jumps, 1);
    assert_int_equal(add(0, 41000, 0), MVTD_ASM_ACCEPTED);
    assert_int_equal(add(1, 41000, 0), MVTD_ASM_ACCEPTED);
    /* the tracker sees time go on frame by frame; capture time = frame time - offset */
    assert_int_equal(g_utime, 500080000 + 40000 + 40000);
    assert_int_equal(g_utime - g_asm.offset_us, 41000);
    assert_int_equal(g_asm.counters.time_gaps, 0);
}

static void test_mvtd_asm_add_one_wrong_clock_never_rebases(void **state)
{
    (void)state;
    setup_asm(3);
    for (int f = 0; f < 20; f++) {
        const int64_t t = 500000000 + f * 40000;
        add(0, t, 0);
        add(1, t, 0);
        const mvtd_asm_result_t r = add(2, f < 2 ? t : 1000 + f * 40000, 0); /* camera 2's clock resets */
        assert_true(f < 2 ? r == MVTD_ASM_ACCEPTED : r == MVTD_ASM_BACKWARDS);
    }
    assert_int_equal(g_asm.counters.clock_jumps, 0);
    assert_int_equal(g_asm.offset_us, 0);
    assert_int_equal(g_asm.counters.far[0], 18);
    /* one camera far ahead: refused, the others go on */
    assert_int_equal(add(0, 900000000, 0), MVTD_ASM_AHEAD);
    assert_int_equal(add(1, 500800000, 0), MVTD_ASM_ACCEPTED);
    assert_int_equal(g_asm.counters.time_gaps, 0);
    /* forward jump of everyone: re-based once all agree, the gap capped at MVTD_ASM_MAX_GAP_US */
    assert_int_equal(add(0, 600000000, 0), MVTD_ASM_AHEAD);
    assert_int_equal(add(1, 600000000, 0), MVTD_ASM_AHEAD);
    assert_int_equal(add(2, 600000000, 0), MVTD_ASM_ACCEPTED);
    assert_int_equal(g_asm.counters.time_gaps, 1);
    assert_int_equal(g_asm.counters.far[1], 3);
    add(0, 600040000, 0);
    add(1, 600040000, 0);
    assert_int_equal(g_utime - g_asm.offset_us, 600000000);
    assert_true(g_utime <= 500800000 + MVTD_ASM_MAX_GAP_US);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mvtd_asm_add_all_cameras_emits_complete_set),
        cmocka_unit_test(test_mvtd_asm_add_later_frame_proves_partial_set),
        cmocka_unit_test(test_mvtd_asm_add_duplicate_and_backwards_refused),
        cmocka_unit_test(test_mvtd_asm_poll_deadline_emits_open_set),
        cmocka_unit_test(test_mvtd_asm_add_dead_camera_not_waited_for_then_back),
        cmocka_unit_test(test_mvtd_asm_add_clock_jump_back_rebases_time),
        cmocka_unit_test(test_mvtd_asm_add_one_wrong_clock_never_rebases),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
