/* Unit tests of the daemon's camera clocks (daemon/clock.h): one camera's offset against the
 * others' measured from arrival times, its frames re-timed or refused, a step learnt again. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdlib.h>

#include "clock.h"

#define PERIOD 40000
#define HALF 20000

/* Frame f of camera k: captured at f * PERIOD + skew_us (its clock), arriving delay_us later on
 * the true clock with +-jitter_us of transport noise (a fixed pseudo-random sequence). */
static mvtd_clock_verdict_t frame(mvtd_clock_t *c, int k, int f, int64_t skew_us, int64_t *t_out)
{
    const int64_t true_capture = 1000000000LL + (int64_t)f * PERIOD;
    const int64_t jitter = (int64_t)((f * 7919 + k * 104729) % 1001) - 500; /* +-0.5 ms */
    return mvtd_clock_observe(c, k, true_capture + skew_us, true_capture + 2000 + jitter, HALF, t_out);
}

static void one_camera_ahead_measured_and_retimed(void **state)
{
    (void)state;
    static mvtd_clock_t c;
    mvtd_clock_init(&c, 5);
    int64_t t = 0;
    int refused = 0;
    for (int f = 0; f < 40; f++) {
        for (int k = 0; k < 5; k++) {
            const mvtd_clock_verdict_t v = frame(&c, k, f, k == 2 ? 60000 : 0, &t);
            refused += v != MVTD_CLOCK_ACCEPT;
            if (f >= MVTD_CLOCK_MIN && k == 2) {
                assert_int_equal(v, MVTD_CLOCK_ACCEPT);
                /* re-timed onto the others' clock, within the transport noise */
                assert_true(llabs(t - (1000000000LL + (int64_t)f * PERIOD)) <= 1000);
            }
            if (k != 2) {
                assert_int_equal(v, MVTD_CLOCK_ACCEPT);
                assert_true(llabs(t - (1000000000LL + (int64_t)f * PERIOD)) == 0); /* within 10 ms: as stamped */
            }
        }
    }
    assert_true(c.confident[2]);
    assert_true(llabs(c.offset_us[2] - 60000) <= 500);
    for (int k = 0; k < 5; k++) {
        if (k != 2) {
            assert_true(llabs(c.offset_us[k]) <= 500);
        }
    }
    /* while learnt, 60 ms is more than half a period: held back from its third frame on */
    assert_int_equal(refused, MVTD_CLOCK_MIN - MVTD_CLOCK_PROVISIONAL);
    assert_int_equal(c.refused[2], refused);
}

static void far_clock_refused(void **state)
{
    (void)state;
    static mvtd_clock_t c;
    mvtd_clock_init(&c, 4);
    int64_t t = 0;
    mvtd_clock_verdict_t v = MVTD_CLOCK_ACCEPT;
    for (int f = 0; f < 40; f++) {
        for (int k = 0; k < 4; k++) {
            const mvtd_clock_verdict_t vk = frame(&c, k, f, k == 1 ? -700000 : 0, &t);
            if (k == 1) {
                v = vk;
            }
        }
    }
    assert_true(c.confident[1]);
    assert_true(llabs(c.offset_us[1] + 700000) <= 500);
    assert_int_equal(v, MVTD_CLOCK_FAR);
}

static void small_offsets_pass_as_stamped(void **state)
{
    (void)state;
    static mvtd_clock_t c;
    mvtd_clock_init(&c, 3);
    int64_t t = 0;
    for (int f = 0; f < 40; f++) {
        for (int k = 0; k < 3; k++) {
            assert_int_equal(frame(&c, k, f, k == 0 ? 6000 : 0, &t), MVTD_CLOCK_ACCEPT);
            assert_true(t == 1000000000LL + (int64_t)f * PERIOD + (k == 0 ? 6000 : 0)); /* delays differ this much */
        }
    }
    assert_true(llabs(c.offset_us[0] - 6000) <= 500);
}

static void a_step_is_learnt_again(void **state)
{
    (void)state;
    static mvtd_clock_t c;
    mvtd_clock_init(&c, 4);
    int64_t t = 0;
    for (int f = 0; f < 80; f++) {
        for (int k = 0; k < 4; k++) {
            /* camera 3's clock steps 200 ms ahead at frame 40 */
            (void)frame(&c, k, f, k == 3 && f >= 40 ? 200000 : 0, &t);
        }
        if (f == 40 + MVTD_CLOCK_PROVISIONAL) {
            assert_false(c.confident[3]); /* learning again */
        }
    }
    assert_true(c.confident[3]);
    assert_true(llabs(c.offset_us[3] - 200000) <= 500);
    /* one late message is not a step */
    int64_t before = c.offset_us[0];
    (void)mvtd_clock_observe(&c, 0, 1000000000LL + 80 * PERIOD, 1000000000LL + 80 * PERIOD + 2000 + 30000, HALF, &t);
    assert_true(c.confident[0]);
    assert_true(llabs(c.offset_us[0] - before) <= 1000);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(one_camera_ahead_measured_and_retimed),
        cmocka_unit_test(far_clock_refused),
        cmocka_unit_test(small_offsets_pass_as_stamped),
        cmocka_unit_test(a_step_is_learnt_again),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
