/* Unit tests of the daemon's camera clocks (daemon/clock.h): one camera's offset against the
 * others' measured from arrival times, its frames re-timed or refused, a step learnt again; a
 * camera whose detector is slower, re-timed by its arrivals and seen late by the tracks. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
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

/* A fixed pseudo-random sequence: uniform in [0, 1), and normal. */
static uint64_t g_rng = 88172645463325252ULL;
static double uniform(void)
{
    g_rng ^= g_rng << 13;
    g_rng ^= g_rng >> 7;
    g_rng ^= g_rng << 17;
    return (double)(g_rng >> 11) * (1.0 / 9007199254740992.0);
}
static double normal(void)
{
    const double u = uniform() + 1e-12, v = uniform();
    return sqrt(-2.0 * log(u)) * cos(6.283185307179586 * v);
}

/* 5 cameras, 25 fps, for seconds: camera 1's messages leave delay_us later than the others' (a
 * slower detector), stamped with the true capture time. Each frame, 4 walking people in every
 * camera give residuals as tracks fused from all 5 would see them: a camera whose frame is put
 * lag_k after its true capture shows each person that late, the tracks lag by the cameras' mean,
 * so the residual is a - (lag_k - mean lag) u' + noise (a: a constant 3 px offset of blob tops
 * from heads; noise 2 px; image speeds 40-200 px/s every way). */
static void slow_detector(mvtd_clock_t *c, int64_t delay_us, int seconds)
{
    mvtd_clock_init(c, 5);
    for (int f = 0; f < seconds * 25; f++) {
        const int64_t capture = 1000000000LL + (int64_t)f * PERIOD;
        double lag_s[5], mean = 0.0;
        for (int k = 0; k < 5; k++) {
            const int64_t jitter = (int64_t)((f * 7919 + k * 104729) % 1001) - 500;
            int64_t t = capture;
            (void)mvtd_clock_observe(c, k, capture, capture + 2000 + jitter + (k == 1 ? delay_us : 0), HALF, &t);
            lag_s[k] = (double)(t - capture) * 1e-6;
            mean += lag_s[k] / 5.0;
        }
        for (int k = 0; k < 5; k++) {
            for (int p = 0; p < 4; p++) {
                const double speed = 40.0 + 160.0 * uniform(), dir = 6.283185307179586 * uniform();
                const double ud[2] = {speed * cos(dir), speed * sin(dir)};
                const double r[2] = {1.0 - (lag_s[k] - mean) * ud[0] + 2.0 * normal(),
                                     -3.0 - (lag_s[k] - mean) * ud[1] + 2.0 * normal()};
                mvtd_clock_motion_sample(c, k, r, ud);
            }
        }
        mvtd_clock_motion_frame(c, capture);
    }
}

static void a_slower_detector_is_seen_by_the_tracks(void **state)
{
    (void)state;
    static mvtd_clock_t c;
    slow_detector(&c, 60000, 20);
    /* its arrivals say 60 ms behind, and its frames are put 60 ms later; the tracks see them late */
    assert_true(llabs(c.offset_us[1] + 60000) <= 500);
    assert_true(c.lag_known[1]);
    assert_true(fabs(c.lag_us[1] - 60000.0) <= 3.0 * c.lag_se_us[1] + 500.0);
    for (int k = 0; k < 5; k++) {
        if (k != 1) {
            assert_true(c.lag_known[k]);
            assert_true(fabs(c.lag_us[k]) <= 3.0 * c.lag_se_us[k] + 500.0);
        }
    }
}

static void on_time_cameras_show_no_lag(void **state)
{
    (void)state;
    static mvtd_clock_t c;
    slow_detector(&c, 0, 120);
    for (int k = 0; k < 5; k++) {
        assert_true(c.lag_known[k]);
        assert_true(fabs(c.lag_us[k]) < 2000.0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(one_camera_ahead_measured_and_retimed),
        cmocka_unit_test(far_clock_refused),
        cmocka_unit_test(small_offsets_pass_as_stamped),
        cmocka_unit_test(a_step_is_learnt_again),
        cmocka_unit_test(a_slower_detector_is_seen_by_the_tracks),
        cmocka_unit_test(on_time_cameras_show_no_lag),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
