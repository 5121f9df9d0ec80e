/* Unit tests of the multi-target tracker: identities through crossings, false-alarm floods,
 * capacity, identities never reused, detection selection. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>

#include "mvt_tracker.h"
#include "test_support.h"

static mvt_tracker_t g_tracker;
static mvt_frame_t g_frame;
static mvt_output_t g_out;
static mvt_camera_t g_cams[5];
static mvt_detection_t g_flood[512];

static void init(void)
{
    assert_int_equal(test_room_cameras(g_cams, 1), 0);
    mvt_tracker_config_t cfg;
    mvt_tracker_config_default(&cfg);
    cfg.volume_min[0] = 0; cfg.volume_min[1] = 0; cfg.volume_min[2] = 0;
    cfg.volume_max[0] = 6; cfg.volume_max[1] = 5; cfg.volume_max[2] = 2.5f;
    assert_int_equal(mvt_tracker_init(&g_tracker, &cfg, g_cams, 5), MVT_OK);
}

/* Detections of m heads in every camera (noise sd px), plus n_fa uniform false alarms. */
static void frame_of(const mvt_real X[][3], int m, int64_t utime, test_rng_t *rng, double sd, int n_fa)
{
    memset(&g_frame, 0, sizeof(g_frame));
    g_frame.utime_us = utime;
    for (int k = 0; k < 5; k++) {
        mvt_view_t *v = &g_frame.views[k];
        v->observed = 1;
        v->utime_us = utime;
        for (int i = 0; i < m && v->num_detections < MVT_MAX_DETECTIONS; i++) {
            mvt_real uv[2];
            if (mvt_cam_project(&g_cams[k], X[i], uv, NULL) != MVT_OK || uv[0] < 0 || uv[1] < 0 || uv[0] > 767 ||
                uv[1] > 575) {
                continue;
            }
            mvt_detection_t *d = &v->det[v->num_detections++];
            d->u = uv[0] + (mvt_real)(sd * test_normal(rng));
            d->v = uv[1] + (mvt_real)(sd * test_normal(rng));
            d->sigma_px = (mvt_real)sd;
            d->score = 1;
        }
        for (int i = 0; i < n_fa && v->num_detections < MVT_MAX_DETECTIONS; i++) {
            mvt_detection_t *d = &v->det[v->num_detections++];
            d->u = (mvt_real)(test_uniform(rng) * 767);
            d->v = (mvt_real)(test_uniform(rng) * 575);
            d->sigma_px = (mvt_real)sd;
            d->score = 1;
        }
    }
}

static const mvt_track_out_t *find_id(int32_t id)
{
    for (int i = 0; i < g_out.num_tracks; i++) {
        if (g_out.tracks[i].id == id) {
            return &g_out.tracks[i];
        }
    }
    return NULL;
}

static double dist3(const mvt_real a[3], const mvt_real b[3])
{
    return sqrt((double)((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2])));
}

/* The confirmed track nearest to x within 0.3 m, or 0. */
static int32_t id_near(const mvt_real x[3])
{
    int32_t best = 0;
    double bd = 0.3;
    for (int i = 0; i < g_out.num_tracks; i++) {
        const double d = dist3(g_out.tracks[i].pos_m, x);
        if (g_out.tracks[i].status != MVT_TRACK_TENTATIVE && d < bd) {
            bd = d;
            best = g_out.tracks[i].id;
        }
    }
    return best;
}

static void test_mvt_tracker_step_two_people_crossing_keep_identities(void **state)
{
    (void)state;
    init();
    test_rng_t rng = {7};
    /* two people walk toward each other at 1 m/s on lines 0.6 m apart, pass, and go on */
    int32_t id_a = 0, id_b = 0;
    for (int f = 0; f < 100; f++) { /* they pass each other at f = 55 */
        const double t = f * 0.04;
        const mvt_real X[2][3] = {{(mvt_real)(0.8 + t), 2.2f, 1.75f}, {(mvt_real)(5.2 - t), 2.8f, 1.65f}};
        frame_of(X, 2, 1000000 + f * 40000, &rng, 2.0, 0);
        assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
        if (f == 20) {
            id_a = id_near(X[0]);
            id_b = id_near(X[1]);
            assert_true(id_a > 0 && id_b > 0 && id_a != id_b);
        }
        if (f > 20) {
            assert_int_equal(id_near(X[0]), id_a);
            assert_int_equal(id_near(X[1]), id_b);
        }
    }
    assert_int_equal(g_tracker.counters.births, 2);
}

static void test_mvt_tracker_step_false_alarm_flood_confirmed_tracks_survive(void **state)
{
    (void)state;
    init();
    test_rng_t rng = {99};
    const mvt_real X[3][3] = {{1.5f, 1.5f, 1.7f}, {4.0f, 3.5f, 1.8f}, {3.0f, 2.0f, 1.6f}};
    int32_t ids[3];
    for (int f = 0; f < 30; f++) {
        frame_of(X, 3, 1000000 + f * 40000, &rng, 2.0, 0);
        assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
    }
    for (int i = 0; i < 3; i++) {
        ids[i] = id_near(X[i]);
        assert_true(ids[i] > 0);
    }
    /* 400 false alarms per camera and frame, the true detections among them; the core keeps
     * MVT_MAX_DETECTIONS per camera (mvt_tracker_select) */
    long dropped = 0;
    for (int f = 30; f < 90; f++) {
        frame_of(X, 3, 1000000 + f * 40000, &rng, 2.0, 0);
        for (int k = 0; k < 5; k++) {
            mvt_view_t *v = &g_frame.views[k];
            int n = 0;
            for (int i = 0; i < 400; i++) {
                g_flood[n].u = (mvt_real)(test_uniform(&rng) * 767);
                g_flood[n].v = (mvt_real)(test_uniform(&rng) * 575);
                g_flood[n].sigma_px = 2;
                g_flood[n].score = 1;
                n++;
                if (i % 100 == 50 && i / 100 < v->num_detections) {
                    g_flood[n++] = v->det[i / 100]; /* the true ones, buried in the flood */
                }
            }
            int keep[MVT_MAX_DETECTIONS];
            const int kept = mvt_tracker_select(&g_tracker, k, g_flood, n, keep);
            assert_true(kept == MVT_MAX_DETECTIONS);
            dropped += n - kept;
            for (int i = 0; i < kept; i++) {
                assert_true(keep[i] >= 0 && keep[i] < n);
                assert_true(i == 0 || keep[i] > keep[i - 1]);
                v->det[i] = g_flood[keep[i]];
            }
            v->num_detections = kept;
        }
        assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
        assert_true(g_out.num_tracks <= MVT_MAX_TARGETS);
        for (int i = 0; i < 3; i++) {
            assert_int_equal(id_near(X[i]), ids[i]);
        }
    }
    assert_true(dropped >= 60L * 5 * (400 - MVT_MAX_DETECTIONS));
    /* passing more than MVT_MAX_DETECTIONS straight to the core is counted, not overrun */
    frame_of(X, 3, 1000000 + 90 * 40000, &rng, 2.0, 0);
    g_frame.views[0].num_detections = MVT_MAX_DETECTIONS + 5;
    const uint64_t before = g_tracker.counters.detections_over_capacity;
    assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
    assert_int_equal(g_tracker.counters.detections_over_capacity - before, 5);
}

static void test_mvt_tracker_step_more_people_than_capacity_births_refused_counted(void **state)
{
    (void)state;
    init();
    test_rng_t rng = {3};
    enum { N = MVT_MAX_TARGETS + 8 };
    static mvt_real X[N][3];
    for (int i = 0; i < N; i++) { /* a grid 0.7 m apart */
        X[i][0] = (mvt_real)(0.5 + 0.7 * (i % 8));
        X[i][1] = (mvt_real)(0.5 + 0.8 * (i / 8));
        X[i][2] = 1.7f;
    }
    for (int f = 0; f < 20; f++) {
        frame_of((const mvt_real(*)[3])X, N, 1000000 + f * 40000, &rng, 1.0, 0);
        assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
        assert_true(g_out.num_tracks <= MVT_MAX_TARGETS);
    }
    assert_int_equal(g_out.num_tracks, MVT_MAX_TARGETS);
    assert_true(g_tracker.counters.births_refused_full > 0);
}

static void test_mvt_tracker_step_person_returns_new_identity(void **state)
{
    (void)state;
    init();
    test_rng_t rng = {11};
    const mvt_real X[1][3] = {{3.0f, 2.5f, 1.7f}};
    int64_t t = 1000000;
    int32_t first = 0;
    for (int f = 0; f < 20; f++, t += 40000) {
        frame_of(X, 1, t, &rng, 2.0, 0);
        mvt_tracker_step(&g_tracker, &g_frame, &g_out);
    }
    first = id_near(X[0]);
    assert_true(first > 0);
    for (int f = 0; f < 100; f++, t += 40000) { /* gone for 4 s: deleted */
        frame_of(X, 0, t, &rng, 2.0, 0);
        mvt_tracker_step(&g_tracker, &g_frame, &g_out);
    }
    assert_int_equal(g_out.num_tracks, 0);
    for (int f = 0; f < 20; f++, t += 40000) {
        frame_of(X, 1, t, &rng, 2.0, 0);
        mvt_tracker_step(&g_tracker, &g_frame, &g_out);
    }
    const int32_t second = id_near(X[0]);
    assert_true(second > first);
    assert_null(find_id(first));
}

static void test_mvt_tracker_select_under_capacity_keeps_all_in_order(void **state)
{
    (void)state;
    init();
    for (int i = 0; i < 10; i++) {
        g_flood[i].u = (mvt_real)i;
        g_flood[i].v = 1;
        g_flood[i].score = 0.5f;
    }
    int keep[MVT_MAX_DETECTIONS];
    assert_int_equal(mvt_tracker_select(&g_tracker, 0, g_flood, 10, keep), 10);
    for (int i = 0; i < 10; i++) {
        assert_int_equal(keep[i], i);
    }
    assert_int_equal(mvt_tracker_select(&g_tracker, 7, g_flood, 10, keep), 0); /* no such camera */
    /* over capacity without tracks: the highest scores win, NaN scores last */
    for (int i = 0; i < 200; i++) {
        g_flood[i].u = 10;
        g_flood[i].v = 10;
        g_flood[i].score = i % 2 ? (mvt_real)i / 200.0f : NAN;
    }
    const int n = mvt_tracker_select(&g_tracker, 0, g_flood, 200, keep);
    assert_int_equal(n, MVT_MAX_DETECTIONS);
    for (int i = 0; i < n; i++) {
        assert_true(keep[i] % 2 == 1 && keep[i] >= 200 - 2 * MVT_MAX_DETECTIONS);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mvt_tracker_step_two_people_crossing_keep_identities),
        cmocka_unit_test(test_mvt_tracker_step_false_alarm_flood_confirmed_tracks_survive),
        cmocka_unit_test(test_mvt_tracker_step_more_people_than_capacity_births_refused_counted),
        cmocka_unit_test(test_mvt_tracker_step_person_returns_new_identity),
        cmocka_unit_test(test_mvt_tracker_select_under_capacity_keeps_all_in_order),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
