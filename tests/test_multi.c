/* Scenes for the multi-target tracker (the body model): identities through crossings, false-alarm
 * floods, capacity, identities never reused, hidden people, ghosts, detection selection; the scenes
 * that ask what any tracker should do run again with the triangulate-then-KF baseline (the _kf
 * tests at the end). Not here: colour in association (the body model leaves it out) and a short
 * head measured from the mask out of a merged blob (docs/limits.md). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <string.h>

#include "mvt_mask.h"
#include "mvt_tracker.h"
#include "mvt_trk.h"
#include "test_support.h"

static mvt_tracker_t g_tracker;
static mvt_frame_t g_frame;
static mvt_output_t g_out;
static mvt_camera_t g_cams[5];
static mvt_detection_t g_flood[512];
/* The estimator the tests below run with (the triangulate-then-KF baseline runs some of them again) */
static mvt_filter_t g_filter = MVT_FILTER_PROJECTIVE;

/* The defaults, the estimator under test and the room's volume (6 x 5 m, heads up to 2.5 m). */
static void room_config(mvt_tracker_config_t *cfg)
{
    mvt_tracker_config_default(cfg);
    cfg->filter = g_filter;
    cfg->volume.min[0] = 0; cfg->volume.min[1] = 0; cfg->volume.min[2] = 0;
    cfg->volume.max[0] = 6; cfg->volume.max[1] = 5; cfg->volume.max[2] = 2.5f;
}

static void init(void)
{
    assert_int_equal(test_room_cameras(g_cams, 1), 0);
    mvt_tracker_config_t cfg;
    room_config(&cfg);
    assert_int_equal(mvt_tracker_init(&g_tracker, &cfg, g_cams, 5), MVT_OK);
}

/* A frame set at utime in which all 5 cameras reported, with no detections yet. */
static void empty_frame(int64_t utime)
{
    memset(&g_frame, 0, sizeof(g_frame));
    g_frame.utime_us = utime;
    for (int k = 0; k < 5; k++) {
        g_frame.views[k].observed = 1;
        g_frame.views[k].utime_us = utime;
    }
}

/* Detections of m heads in every camera (noise sd px), plus n_fa uniform false alarms. */
static void frame_of(const mvt_real X[][3], int m, int64_t utime, test_rng_t *rng, double sd, int n_fa)
{
    empty_frame(utime);
    for (int k = 0; k < 5; k++) {
        mvt_view_t *v = &g_frame.views[k];
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

/* A top-of-blob detector (docs/interfaces.md: the blob's top point): each person is a vertical cylinder of
 * radius 0.22 m under the head; in each camera the silhouettes' boxes that overlap merge into one
 * blob whose reported point is its highest head (smallest v) and whose box is the union. No
 * misses, no false alarms, pixel noise sd. with_boxes 0 sends all-zero boxes. */
static void frame_blobs(const mvt_real X[][3], int m, int64_t utime, test_rng_t *rng, double sd, int with_boxes)
{
    empty_frame(utime);
    for (int k = 0; k < 5; k++) {
        mvt_view_t *v = &g_frame.views[k];
        double box[8][4], top[8][2];
        int n = 0;
        for (int i = 0; i < m && i < 8; i++) {
            mvt_real uv[2], c[3], foot[3] = {X[i][0], X[i][1], 0}, fuv[2];
            mvt_cam_to_camera(&g_cams[k], X[i], c);
            if (mvt_cam_project(&g_cams[k], X[i], uv, NULL) != MVT_OK ||
                mvt_cam_project(&g_cams[k], foot, fuv, NULL) != MVT_OK || uv[0] < 0 || uv[1] < 0 || uv[0] > 767 ||
                uv[1] > 575) {
                continue;
            }
            const double half = 0.22 * (double)g_cams[k].fx / (double)c[2];
            box[n][0] = (uv[0] < fuv[0] ? uv[0] : fuv[0]) - half;
            box[n][2] = (uv[0] > fuv[0] ? uv[0] : fuv[0]) + half;
            box[n][1] = uv[1] - 0.3 * half;
            box[n][3] = fuv[1];
            top[n][0] = uv[0];
            top[n][1] = uv[1];
            n++;
        }
        for (int merged = 1; merged;) { /* merge overlapping boxes until none overlap */
            merged = 0;
            for (int a = 0; a < n && !merged; a++) {
                for (int b = a + 1; b < n && !merged; b++) {
                    if (box[a][0] > box[b][2] || box[b][0] > box[a][2] || box[a][1] > box[b][3] || box[b][1] > box[a][3]) {
                        continue;
                    }
                    for (int j = 0; j < 2; j++) {
                        box[a][j] = box[a][j] < box[b][j] ? box[a][j] : box[b][j];
                        box[a][j + 2] = box[a][j + 2] > box[b][j + 2] ? box[a][j + 2] : box[b][j + 2];
                    }
                    if (top[b][1] < top[a][1]) {
                        top[a][0] = top[b][0];
                        top[a][1] = top[b][1];
                    }
                    for (int j = 0; j < 4; j++) box[b][j] = box[n - 1][j];
                    top[b][0] = top[n - 1][0];
                    top[b][1] = top[n - 1][1];
                    n--;
                    merged = 1;
                }
            }
        }
        for (int i = 0; i < n; i++) {
            mvt_detection_t *d = &v->det[v->num_detections++];
            d->u = (mvt_real)(top[i][0] + sd * test_normal(rng));
            d->v = (mvt_real)(top[i][1] + sd * test_normal(rng));
            d->sigma_px = (mvt_real)sd;
            d->score = 1;
            d->hue = d->saturation = -1;
            for (int j = 0; j < 4; j++) {
                d->box[j] = with_boxes ? (mvt_real)box[i][j] : 0;
            }
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

/* The confirmed tracks of the two people at X, which must be two. */
static void two_ids(const mvt_real X[2][3], int32_t *id_a, int32_t *id_b)
{
    *id_a = id_near(X[0]);
    *id_b = id_near(X[1]);
    assert_true(*id_a > 0 && *id_b > 0 && *id_a != *id_b);
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
            two_ids(X, &id_a, &id_b);
        }
        if (f > 20) {
            assert_int_equal(id_near(X[0]), id_a);
            assert_int_equal(id_near(X[1]), id_b);
        }
    }
    assert_int_equal(g_tracker.counters.births, 2);
}

/* A walks at 1 m/s and vanishes at frame 40 (nothing reports them again); their track coasts on,
 * its prediction widening. B, seen all along, crosses the coasting prediction's path about 10 frames
 * later. Returns the frames in which A's track took a detection (of B's: nobody else is there)
 * after A vanished, and whether B kept one identity. */
static int coaster_takes(uint32_t seed, int *b_kept)
{
    init();
    test_rng_t rng = {seed};
    int32_t id_a = 0, id_b = 0;
    int taken = 0;
    *b_kept = 1;
    for (int f = 0; f < 90; f++) {
        const double t = f * 0.04;
        const mvt_real X[2][3] = {{(mvt_real)(1.0 + t), 2.0f, 1.75f}, {3.0f, (mvt_real)(0.4 + 0.8 * t), 1.65f}};
        frame_of(f < 40 ? X : X + 1, f < 40 ? 2 : 1, 1000000 + f * 40000, &rng, 2.0, 0);
        assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
        if (f == 20) {
            two_ids(X, &id_a, &id_b);
        }
        if (f > 20) {
            *b_kept &= id_near(X[1]) == id_b;
        }
        const mvt_track_out_t *a = find_id(id_a);
        taken += f >= 40 && a != NULL && a->cameras_used != 0u;
    }
    return taken;
}

/* Association by likelihood (mvt_body_explain.c): a coasting track's wide prediction spreads its
 * likelihood thin, so the track that predicted B's detections keeps them; over 8 seeds the coaster
 * may take at most one frame's. */
static void test_mvt_tracker_step_coasting_track_does_not_take_passer_by(void **state)
{
    (void)state;
    int taken = 0, kept = 1;
    for (uint32_t seed = 1; seed <= 8; seed++) {
        int b_kept;
        const int n = coaster_takes(seed, &b_kept);
        print_message("seed %u: the coasting track took %d frames of detections, B kept its identity: %d\n",
                      (unsigned)seed, n, b_kept);
        taken += n;
        kept &= b_kept;
    }
    assert_true(taken <= 1);
    assert_true(kept);
}

/* Two people walk toward each other (a short one and a tall one), stop, and nobody sees them for
 * 1 s (cameras report nothing): each track's constant-velocity prediction lands on the other
 * person. When they are seen again, the ceiling camera, which cannot tell heights, reports first.
 * After the gap the persons found again are paired with the labels all at once, by position and
 * height (mvt_body_birth.c), so each track gets its own person. */
static void test_mvt_tracker_step_lost_tracks_reacquired_by_height(void **state)
{
    (void)state;
    init();
    test_rng_t rng = {11};
    int64_t t = 1000000;
    mvt_real X[2][3];
    for (int f = 0; f < 40; f++, t += 40000) {
        const mvt_real s = (mvt_real)(f * 0.04);
        const mvt_real A[3] = {2.2f + 0.5f * s, 2.4f, 1.55f}, B[3] = {4.2f - 0.5f * s, 2.6f, 1.85f};
        memcpy(X[0], A, sizeof(A));
        memcpy(X[1], B, sizeof(B));
        frame_of((const mvt_real(*)[3])X, 2, t, &rng, 1.0, 0);
        assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
    }
    const int32_t id_a = id_near(X[0]), id_b = id_near(X[1]);
    assert_true(id_a > 0 && id_b > 0 && id_a != id_b);
    for (int f = 0; f < 25; f++, t += 40000) { /* they stop; the cameras see nobody */
        empty_frame(t);
        assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
    }
    const uint64_t before = g_tracker.counters.reacquired;
    for (int f = 0; f < 10; f++, t += 40000) {
        frame_of((const mvt_real(*)[3])X, 2, t, &rng, 1.0, 0);
        g_frame.views[4].utime_us = t - 5000; /* the ceiling camera, blind to heights, reports first */
        assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
    }
    if (id_near(X[0]) != id_a || id_near(X[1]) != id_b) {
        fail_msg("after the gap: short person has %d (was %d), tall person %d (was %d)", (int)id_near(X[0]), (int)id_a,
                 (int)id_near(X[1]), (int)id_b);
    }
    assert_true(g_tracker.counters.reacquired > before);
}

/* Two people walk up to each other and stand talking, heads 0.29 m apart, for 6 s, seen by a
 * detector that reports both heads (merged_blobs 0), or by a top-of-blob detector that merges them
 * into one blob in every view, its top the taller head (merged_blobs 1): both tracks live on under
 * their identities, neither deleted as the other's duplicate, each within 0.2 m
 * of its person. With merged blobs the shorter person is hidden in every view: the track lives on
 * the blobs' boxes (occlusion) and the height two views last measured (hold_height); its height
 * used to sink to the floor in 3 s. Five noise seeds (29 of 30 pass in a longer scratch loop). */
static void close_pair(int merged_blobs, unsigned long long seed)
{
    init();
    test_rng_t rng = {seed};
    int64_t t = 1000000;
    int32_t id_a = 0, id_b = 0;
    for (int f = 0; f < 200; f++, t += 40000) {
        const mvt_real s = (mvt_real)(f < 46 ? f : 46) * 0.04f; /* they stop 0.29 m apart */
        const mvt_real X[2][3] = {{1.6f + 0.6f * s, 2.5f, 1.72f}, {4.1f - 0.6f * s, 2.5f, 1.64f}};
        if (merged_blobs) {
            frame_blobs(X, 2, t, &rng, 1.5, 1);
        } else {
            frame_of(X, 2, t, &rng, 1.5, 0);
        }
        assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
        if (f == 20) {
            two_ids(X, &id_a, &id_b);
        }
        if (f >= 20 && (find_id(id_a) == NULL || find_id(id_b) == NULL)) {
            const mvt_counters_t *c = &g_tracker.counters;
            fail_msg("%s: frame %d: track %d or %d gone (heads %.2f m apart; deleted unlikely %d duplicate %d "
                     "uncertain %d exit %d)",
                     merged_blobs ? "merged blobs" : "split", f, (int)id_a, (int)id_b, (double)(X[1][0] - X[0][0]),
                     (int)c->deleted_unlikely, (int)c->duplicates_deleted, (int)c->deleted_uncertain,
                     (int)c->deleted_exit);
        }
        if (f == 199) {
            const mvt_track_out_t *a = find_id(id_a), *b = find_id(id_b);
            if (!(dist3(a->pos_m, X[0]) < 0.2 && dist3(b->pos_m, X[1]) < 0.2)) {
                fail_msg("%s: tracks %.2f and %.2f m from their people", merged_blobs ? "merged blobs" : "split",
                         dist3(a->pos_m, X[0]), dist3(b->pos_m, X[1]));
            }
        }
    }
    assert_int_equal(g_tracker.counters.duplicates_deleted, 0);
}

static void test_mvt_tracker_step_close_pair_both_kept(void **state)
{
    (void)state;
    close_pair(0, 23);
}

static void test_mvt_tracker_step_close_pair_merged_blobs_both_kept(void **state)
{
    (void)state;
    for (unsigned long long k = 1; k <= 5; k++) { /* without the held height 4 of these 5 fail */
        close_pair(1, 7919 * k);
    }
}

/* The appearance model (mvt_trk_app.c) against a double-precision computation of its formulas:
 * it learns a person's colour and spread from detections of which a fifth carry other colours
 * (merged blobs, fragments), and an odd colour costs at most -2 ln MVT_TRK_APP_OUTLIER. */
static void test_mvt_trk_app_learns_colour_bounds_outliers(void **state)
{
    (void)state;
    mvt_detection_t det = {0};
    mvt_real a[2];
    det.hue = 0.25f;
    det.saturation = 0.5f;
    assert_true(mvt_trk_chroma(&det, a));
    assert_true(fabs(a[0]) < 1e-6 && fabs(a[1] - 0.5) < 1e-6);
    const mvt_real bad[5][2] = {{-1, 0.5f}, {0.3f, -1}, {NAN, 0.5f}, {0.3f, 1.5f}, {0.3f, INFINITY}};
    for (int i = 0; i < 5; i++) {
        det.hue = bad[i][0];
        det.saturation = bad[i][1];
        assert_false(mvt_trk_chroma(&det, a));
    }
    mvt_app_t app;
    mvt_trk_app_reset(&app);
    const mvt_real probe[2] = {0.1f, 0.1f};
    assert_true(mvt_trk_app_cost(&app, probe) == 0 && mvt_trk_app_cost_min(&app) == 0); /* unknown: no evidence */
    test_rng_t rng = {5};
    const double mx = 0.4, my = -0.3, sd = 0.1;
    for (int i = 0; i < 2000; i++) {
        if (i % 5 == 4) { /* someone else's colour, anywhere in the disc */
            const double r = sqrt(test_uniform(&rng)), th = 6.283185307179586 * test_uniform(&rng);
            a[0] = (mvt_real)(r * cos(th));
            a[1] = (mvt_real)(r * sin(th));
        } else {
            a[0] = (mvt_real)(mx + sd * test_normal(&rng));
            a[1] = (mvt_real)(my + sd * test_normal(&rng));
        }
        mvt_trk_app_update(&app, a);
    }
    assert_true(mvt_trk_app_ok(&app));
    assert_true(fabs(app.m[0] - mx) < 0.03 && fabs(app.m[1] - my) < 0.03);
    assert_true(sqrt(app.var) > 0.07 && sqrt(app.var) < 0.13); /* the person's spread, not the outliers' */
    assert_true(app.n <= MVT_TRK_APP_NMAX);
    /* the cost against the formula in double */
    const double V = (double)app.var * (1.0 + 1.0 / (double)app.n), eps = (double)MVT_TRK_APP_OUTLIER;
    const mvt_real pts[3][2] = {{0.4f, -0.3f}, {0.5f, -0.2f}, {-0.6f, 0.6f}};
    for (int i = 0; i < 3; i++) {
        const double dx = pts[i][0] - app.m[0], dy = pts[i][1] - app.m[1];
        const double lr = (1 - eps) * exp(-0.5 * (dx * dx + dy * dy) / V) / (2 * V) + eps;
        assert_true(fabs(mvt_trk_app_cost(&app, pts[i]) - (-2 * log(lr))) < 1e-3);
    }
    assert_true(fabs(mvt_trk_app_cost_min(&app) - (-2 * log((1 - eps) / (2 * V) + eps))) < 1e-3);
    assert_true(mvt_trk_app_cost(&app, pts[2]) <= -2 * log(eps) + 1e-4); /* bounded */
    assert_true(mvt_trk_app_cost(&app, pts[2]) > mvt_trk_app_cost(&app, pts[1]));
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
            v->num_offered = n;
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
    for (int f = 0; f < 175; f++, t += 40000) { /* gone for 7 s: its label waits 3 s for them,
                                                    then is let go */
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
    assert_int_equal(g_tracker.counters.reacquired, 0);
}

/* A lost label. A person whose track is no longer shown while they are still in the room (here:
 * the detector loses them for gap_s) and who is found again soon after, within walking reach of
 * where they were lost, keeps their identity; someone out of walking reach, or anyone after
 * MVT_BODY_DORMANT_S (3 s), does not. Returns the identity of the person found at `back` after the
 * person at X was lost; *was receives the lost identity. */
static int32_t g_new; /* lost_and_born's result (C leaves the order of `f(&x) > x` open) */
static int32_t lost_and_born(const mvt_real back[3], double gap_s, int32_t *was)
{
    init();
    test_rng_t rng = {23};
    const mvt_real X[1][3] = {{3.0f, 2.5f, 1.75f}};
    int64_t t = 1000000;
    for (int f = 0; f < 25; f++, t += 40000) {
        frame_of(X, 1, t, &rng, 2.0, 0);
        mvt_tracker_step(&g_tracker, &g_frame, &g_out);
    }
    *was = id_near(X[0]);
    assert_true(*was > 0);
    const int gap = (int)(gap_s * 25.0 + 0.5);
    for (int f = 0; f < gap; f++, t += 40000) {
        frame_of(X, 0, t, &rng, 2.0, 0);
        mvt_tracker_step(&g_tracker, &g_frame, &g_out);
    }
    assert_null(find_id(*was)); /* no longer shown: five views show nobody there */
    const mvt_real B[1][3] = {{back[0], back[1], back[2]}};
    for (int f = 0; f < 10; f++, t += 40000) {
        frame_of(B, 1, t, &rng, 2.0, 0);
        mvt_tracker_step(&g_tracker, &g_frame, &g_out);
    }
    const int32_t id = id_near(B[0]);
    assert_true(id > 0);
    g_new = id;
    for (int i = 0; i < g_out.num_tracks; i++) { /* one confirmed track, the one at B */
        assert_true(g_out.tracks[i].id == id || g_out.tracks[i].status == MVT_TRACK_TENTATIVE);
    }
    return id;
}

static void test_mvt_tracker_step_person_lost_and_back_keeps_identity(void **state)
{
    (void)state;
    int32_t was = 0;
    /* back 0.3 m away at the same height, 2.4 s after the last detection */
    const mvt_real near_same[3] = {3.2f, 2.7f, 1.76f};
    int32_t back = lost_and_born(near_same, 2.4, &was);
    assert_int_equal(back, was);
    /* 2.8 m away 0.4 s after the person was last seen: out of walking reach (the same place is
     * within it) */
    const mvt_real far[3] = {5.0f, 0.6f, 1.75f};
    assert_true(lost_and_born(far, 0.4, &was) > 0 && g_new > was);
    back = lost_and_born(near_same, 0.4, &was);
    assert_int_equal(back, was);
    /* after MVT_BODY_DORMANT_S: let go */
    assert_true(lost_and_born(near_same, 5.6, &was) > 0 && g_new > was);
}

/* A lost label's height. A person 1.62 m tall is tracked by five cameras for 1 s; then, for half a
 * second, every camera's point comes from lower on their body (a piece of it: the point slides down
 * to 1.42 m, as a track can slide down onto a fragment), then nobody sees them for 1 s, and they are
 * found again 0.6 m away (beyond a body's width, inside walking reach) at their own height. The
 * height that track last had (1.42 m) had wandered 0.2 m in half a second: it is not known to be the
 * person's, and the person keeps their identity. A track whose height held, lost the same way, is
 * not given to someone 0.2 m shorter found at the same place. */
static int32_t slid_and_back(int slide, double back_z, int32_t *was)
{
    init();
    test_rng_t rng = {41};
    mvt_real X[1][3] = {{3.0f, 2.5f, 1.62f}};
    int64_t t = 1000000;
    for (int f = 0; f < 25; f++, t += 40000) {
        frame_of(X, 1, t, &rng, 2.0, 0);
        mvt_tracker_step(&g_tracker, &g_frame, &g_out);
    }
    *was = id_near(X[0]);
    assert_true(*was > 0);
    for (int f = 0; f < 12; f++, t += 40000) {
        X[0][2] = slide ? 1.62f - 0.2f * (mvt_real)(f + 1) / 12.0f : 1.62f;
        frame_of(X, 1, t, &rng, 2.0, 0);
        mvt_tracker_step(&g_tracker, &g_frame, &g_out);
    }
    for (int f = 0; f < 25; f++, t += 40000) {
        frame_of(X, 0, t, &rng, 2.0, 0);
        mvt_tracker_step(&g_tracker, &g_frame, &g_out);
    }
    assert_null(find_id(*was));
    const mvt_real B[1][3] = {{3.6f, 2.5f, (mvt_real)back_z}};
    for (int f = 0; f < 10; f++, t += 40000) {
        frame_of(B, 1, t, &rng, 2.0, 0);
        mvt_tracker_step(&g_tracker, &g_frame, &g_out);
    }
    const int32_t id = id_near(B[0]);
    assert_true(id > 0);
    return id;
}

static void test_mvt_tracker_step_label_height_as_sure_as_it_held(void **state)
{
    (void)state;
    int32_t was = 0;
    const int32_t slid = slid_and_back(1, 1.62, &was);
    assert_int_equal(slid, was);
    const int32_t held = slid_and_back(0, 1.42, &was);
    assert_true(held > was);
}

/* Two tracks on one person. Two people stand 1 m apart; for 0.6 s every camera's point of the second
 * slides onto the first one's head (as a track can follow merged blobs' tops onto a neighbour), so
 * that both tracks stand on the first person and become one; then the second person's points are
 * where they stand again. Which of the two tracks followed the wrong person no model can tell, but
 * neither label is evidence that its person left: the person found again takes the label that
 * slept, and the two people carry the two labels they had, no third. */
static void test_mvt_tracker_step_merged_label_waits_for_its_person(void **state)
{
    (void)state;
    for (unsigned long long seed = 1; seed <= 3; seed++) {
        init();
        test_rng_t rng = {seed};
        const mvt_real A[3] = {2.0f, 2.5f, 1.75f}, B[3] = {3.0f, 2.5f, 1.70f};
        mvt_real X[2][3] = {{A[0], A[1], A[2]}, {B[0], B[1], B[2]}};
        int64_t t = 1000000;
        int32_t id_a = 0, id_b = 0;
        for (int f = 0; f < 30; f++, t += 40000) {
            frame_of((const mvt_real(*)[3])X, 2, t, &rng, 2.0, 0);
            assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
        }
        two_ids((const mvt_real(*)[3])X, &id_a, &id_b);
        for (int f = 1; f <= 25; f++, t += 40000) {
            const mvt_real w = f < 15 ? (mvt_real)f / 15.0f : 1.0f;
            for (int i = 0; i < 3; i++) {
                X[1][i] = B[i] + w * (A[i] - B[i]);
            }
            frame_of((const mvt_real(*)[3])X, 2, t, &rng, 2.0, 0);
            assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
        }
        int on_a = 0;
        for (int i = 0; i < g_out.num_tracks; i++) {
            on_a += g_out.tracks[i].status != MVT_TRACK_TENTATIVE && dist3(g_out.tracks[i].pos_m, A) < 0.3;
        }
        assert_int_equal(on_a, 1); /* one person, one track */
        for (int i = 0; i < 3; i++) {
            X[1][i] = B[i];
        }
        for (int f = 0; f < 40; f++, t += 40000) {
            frame_of((const mvt_real(*)[3])X, 2, t, &rng, 2.0, 0);
            assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
        }
        const int32_t now_a = id_near(A), now_b = id_near(B);
        if (!(now_a > 0 && now_b > 0 && ((now_a == id_a && now_b == id_b) || (now_a == id_b && now_b == id_a)))) {
            fail_msg("seed %llu: labels %d and %d before, %d and %d after", seed, (int)id_a, (int)id_b, (int)now_a,
                     (int)now_b);
        }
    }
}

/* Bursts in three views at once (an occluder's blob in front of the person, the paper's Experiment
 * 1 occlusions): one person walks across the room, seen by all five cameras; for 0.4 s three views
 * report the person's blob displaced as a whole, each by its own steady offset (angle a + 120 k
 * degrees, 45 px), one view stays clean and the zenith camera sends nothing. Each displacement began
 * while the other views placed the person, so it is no error of the track's: the largest error of
 * the track nearest the person from 0.2 s before the bursts to 0.8 s after them. */
static double g_burst_err;
static double burst_error(unsigned long long seed, double angle_deg)
{
    init();
    test_rng_t rng = {seed};
    mvt_real X[1][3] = {{1.5f, 2.0f, 1.72f}};
    int64_t t = 1000000;
    g_burst_err = 0.0;
    for (int f = 0; f < 70; f++, t += 40000) {
        X[0][0] = (mvt_real)(1.5 + 0.024 * f);
        X[0][1] = (mvt_real)(2.0 + 0.012 * f);
        frame_blobs((const mvt_real(*)[3])X, 1, t, &rng, 8.0, 1);
        if (f >= 30 && f < 40) {
            static const int shown[3] = {0, 2, 3};
            for (int i = 0; i < 3; i++) {
                const double a = (angle_deg + 120.0 * i) * 3.14159265358979 / 180.0;
                const mvt_real du = (mvt_real)(45.0 * cos(a)), dv = (mvt_real)(45.0 * sin(a));
                mvt_view_t *v = &g_frame.views[shown[i]];
                for (int d = 0; d < v->num_detections; d++) {
                    v->det[d].u += du;
                    v->det[d].v += dv;
                    v->det[d].box[0] += du;
                    v->det[d].box[2] += du;
                    v->det[d].box[1] += dv;
                    v->det[d].box[3] += dv;
                }
            }
            g_frame.views[4].observed = 0;
        }
        assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
        if (f >= 25) {
            double best = 1e9;
            for (int i = 0; i < g_out.num_tracks; i++) {
                const double e = dist3(g_out.tracks[i].pos_m, X[0]);
                best = e < best ? e : best;
            }
            g_burst_err = best > g_burst_err ? best : g_burst_err;
        }
    }
    return g_burst_err;
}

static void test_mvt_tracker_step_bursts_in_three_views_do_not_carry_track(void **state)
{
    (void)state;
    int lost = 0, off = 0;
    double worst = 0.0;
    for (int a = 0; a < 360; a += 30) {
        for (unsigned long long seed = 1; seed <= 5; seed++) {
            const double e = burst_error(seed, a);
            lost += e > 0.5;
            off += e > 0.3;
            worst = e > worst ? e : worst;
        }
    }
    /* 12 directions x 5 seeds: never a lost frame (0.5 m), at most 12 of 60 scenes beyond 0.3 m */
    if (lost > 0 || off > 12) {
        fail_msg("%d of 60 scenes beyond 0.5 m, %d beyond 0.3 m, worst %.2f m", lost, off, worst);
    }
}

/* A track that left its person. For 1 s only cameras 0 and 1 report, and both show one wrong point W,
 * 0.6 m beside the person's head (a piece of a body cut alike in two views, a top that is not the
 * head): the track is born there. Then every camera reports, 0 and 1 still W, 2 to 4 the person's
 * head, within the displaced radius of the track's. Three views that agree to their pixel noise
 * are not three displacements: for each of 5 seeds, from 0.5 s on the person's track (within
 * 0.3 m) is the one born at W. */
static void test_mvt_tracker_step_track_rejoins_person_three_views_agree_on(void **state)
{
    (void)state;
    for (unsigned long long seed = 1; seed <= 5; seed++) {
        init();
        test_rng_t rng = {seed};
        int64_t t = 1000000;
        int32_t born = 0;
        for (int f = 0; f < 75; f++, t += 40000) {
            const mvt_real P[1][3] = {{(mvt_real)(2.3 + 0.012 * f), 2.4f, 1.72f}};
            const mvt_real W[1][3] = {{P[0][0] + 0.45f, P[0][1] + 0.4f, 1.72f}};
            frame_of(W, 1, t, &rng, 2.0, 0);
            mvt_frame_t w = g_frame;
            frame_of(P, 1, t, &rng, 2.0, 0);
            for (int k = 0; k < 2; k++) {
                g_frame.views[k] = w.views[k];
            }
            for (int k = 2; k < 5 && f < 25; k++) {
                g_frame.views[k].observed = 0;
            }
            assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
            if (f == 24) {
                born = id_near(W[0]);
                assert_true(born > 0);
            }
            if (f >= 25 + 12 && id_near(P[0]) != born) {
                fail_msg("seed %llu: %.2f s after every camera reported, the person's track is %d, not %d (born at W)",
                         seed, (f - 25) * 0.04, id_near(P[0]), born);
            }
        }
    }
}

/* Found again by one far view first. A tall person (1.90 m) far from camera 0 (about 6 m, the
 * camera 2.75 m up: its ray to the head falls 0.85 m over 6 m) is tracked by all five cameras, lost
 * by all of them for 1 s, then seen by camera 0 alone for 0.4 s (the others' frames do not come;
 * no boxes: no feet) and by all five again. One view's ray there places the head only to about
 * 0.8 m along it, more than this room's bound on a track's spread (max_pos_std_m 0.6 m; newcomers
 * every 2 s, birth_per_s 0.5, so that one view's blob is likely enough to start someone): whatever
 * is born from it must not take the person's label and lose it. For each of 5 seeds the person
 * ends with the identity they had. */
static void test_mvt_tracker_step_person_found_by_one_far_view_keeps_identity(void **state)
{
    (void)state;
    for (unsigned long long seed = 1; seed <= 5; seed++) {
        assert_int_equal(test_room_cameras(g_cams, 1), 0);
        mvt_tracker_config_t cfg;
        room_config(&cfg);
        cfg.numerics.max_pos_std_m = 0.6f;
        cfg.population.birth_per_s = 0.5f;
        assert_int_equal(mvt_tracker_init(&g_tracker, &cfg, g_cams, 5), MVT_OK);
        test_rng_t rng = {seed};
        const mvt_real X[1][3] = {{5.0f, 4.2f, 1.90f}};
        int64_t t = 1000000;
        for (int f = 0; f < 25; f++, t += 40000) {
            frame_of(X, 1, t, &rng, 2.0, 0);
            mvt_tracker_step(&g_tracker, &g_frame, &g_out);
        }
        const int32_t was = id_near(X[0]);
        assert_true(was > 0);
        for (int f = 0; f < 25; f++, t += 40000) {
            frame_of(X, 0, t, &rng, 2.0, 0);
            mvt_tracker_step(&g_tracker, &g_frame, &g_out);
        }
        assert_null(find_id(was));
        for (int f = 0; f < 10; f++, t += 40000) {
            frame_of(X, 1, t, &rng, 2.0, 0);
            for (int k = 1; k < 5; k++) {
                g_frame.views[k].observed = 0;
            }
            assert_int_equal(g_frame.views[0].num_detections, 1);
            mvt_tracker_step(&g_tracker, &g_frame, &g_out);
        }
        for (int f = 0; f < 25; f++, t += 40000) {
            frame_of(X, 1, t, &rng, 2.0, 0);
            mvt_tracker_step(&g_tracker, &g_frame, &g_out);
        }
        assert_int_equal(id_near(X[0]), was);
    }
}

/* A person walks along a side wall, 0.3 m from it, and the detector loses them for 0.6 s: near a
 * wall they may have walked out, but found again where they walked on they keep their identity. */
static void test_mvt_tracker_step_walker_along_wall_keeps_identity(void **state)
{
    (void)state;
    init();
    test_rng_t rng = {31};
    int64_t t = 1000000;
    int32_t first = 0;
    for (int f = 0; f < 150; f++, t += 40000) {
        const double x = 1.0 + 0.6 * f * 0.04;
        const mvt_real X[1][3] = {{(mvt_real)x, 4.7f, 1.72f}};
        const int lost = f >= 60 && f < 75;
        frame_of(X, lost ? 0 : 1, t, &rng, 2.0, 0);
        assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
        if (f == 55) {
            first = id_near(X[0]);
            assert_true(first > 0);
        }
    }
    const mvt_real end[3] = {(mvt_real)(1.0 + 0.6 * 149 * 0.04), 4.7f, 1.72f};
    assert_int_equal(id_near(end), first);
}

/* A short person walks into the middle of a group of three tall ones, stands there 3 s (hidden in
 * their blobs in most views: never two views' top point), and walks out. Returns the number of
 * distinct identities the short person had while confirmed; fills the closest horizontal distance
 * of the short person's track to a tall person's track while hidden, and g_sank_m. */
static double g_sank_m; /* hidden_in_group: the short person's track's largest height error while confirmed */

static int hidden_in_group(double *closest_m, int *covered)
{
    *covered = 0;
    g_sank_m = 0.0;
    init();
    /* visibility alone, with the single constant-velocity model this scene was built for: with the
     * IMM default the hidden head's height drifts under the one camera that still sees it while
     * the standing model holds it stiff (docs/filters.md, "Motion that adapts": known limits) */
    const mvt_real q[3] = {0.5f, 0.5f, 0.05f};
    mvt_imm_config_single(&g_tracker.cfg.motion, q);
    test_rng_t rng = {5};
    const mvt_real tall[3][2] = {{2.45f, 2.5f}, {3.45f, 1.95f}, {3.45f, 3.05f}}; /* 0.65 m from the middle */
    int32_t ids[8] = {0};
    int nid = 0;
    *closest_m = 1e9;
    for (int f = 0; f < 350; f++) {
        const double t = f * 0.04;
        /* 0-2 s outside at (5.1, 2.5), 2-6 s walking in between two of them at 0.5 m/s, 6-9 s in
         * the middle (3.1, 2.5), then out the same way */
        double x = 5.1;
        if (t > 2 && t <= 6) {
            x = 5.1 - 0.5 * (t - 2);
        } else if (t > 6 && t <= 9) {
            x = 3.1;
        } else if (t > 9) {
            x = 3.1 + 0.5 * (t - 9);
        }
        const mvt_real X[4][3] = {{(mvt_real)x, 2.5f, 1.5f},
                                  {tall[0][0], tall[0][1], 1.92f},
                                  {tall[1][0], tall[1][1], 1.90f},
                                  {tall[2][0], tall[2][1], 1.94f}};
        frame_blobs(X, 4, 1000000 + f * 40000, &rng, 2.0, 1);
        assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
        /* the short person's confirmed track: the one nearest within 0.5 m */
        int32_t id = 0;
        double bd = 0.5;
        const mvt_track_out_t *me = NULL;
        for (int i = 0; i < g_out.num_tracks; i++) {
            const mvt_track_out_t *o = &g_out.tracks[i];
            const double d = hypot((double)(o->pos_m[0] - X[0][0]), (double)(o->pos_m[1] - X[0][1]));
            if (o->status != MVT_TRACK_TENTATIVE && d < bd) {
                bd = d;
                id = o->id;
                me = o;
            }
        }
        *covered += id != 0;
        if (me != NULL) {
            const double dz = fabs((double)me->pos_m[2] - (double)X[0][2]);
            g_sank_m = dz > g_sank_m ? dz : g_sank_m;
        }
        if (id != 0 && (nid == 0 || ids[nid - 1] != id) && nid < 8) {
            ids[nid++] = id;
        }
        if (me != NULL && t > 6.5 && t < 9) {
            for (int i = 0; i < g_out.num_tracks; i++) {
                const mvt_track_out_t *o = &g_out.tracks[i];
                if (o != me && o->status != MVT_TRACK_TENTATIVE) {
                    const double d = hypot((double)(o->pos_m[0] - me->pos_m[0]), (double)(o->pos_m[1] - me->pos_m[1]));
                    *closest_m = d < *closest_m ? d : *closest_m;
                }
            }
        }
        if (f == 40) { /* everyone tracked before the short person walks in */
            assert_int_equal(g_out.num_tracks, 4);
        }
    }
    return nid;
}

/* The short person hidden in the group: one identity all along, never on a tall person's place,
 * the height held. */
static void test_mvt_tracker_step_hidden_in_group_keeps_identity(void **state)
{
    (void)state;
    double closest;
    int covered;
    const int nid = hidden_in_group(&closest, &covered);
    print_message("hidden in group: %d identities, %d of 350 frames covered, closest %.2f m, sank %.2f m\n", nid,
                  covered, closest, g_sank_m);
    assert_int_equal(nid, 1);
    assert_true(covered >= 340);
    assert_true(closest > 0.3);
    assert_true(g_sank_m < 0.2);
}

/* A queue: a short person stands between two tall ones, 0.42 m from each along camera 0's and
 * camera 2's line of sight and 0.15 m aside of it, for 20 s, then (phase 2) vanishes or (phase 3)
 * walks out. Every view merges the three into one blob whose top is a tall head, so no camera ever
 * detects the short person; the blob's box, though, reaches out where only their body puts it.
 * Returns the number of identities the short person's confirmed track had while present, and in
 * *gone_after the frames from the vanishing until that track was deleted (-1: never). */
static int queue_hidden(int vanish, int *covered, int *gone_after)
{
    init();
    test_rng_t rng = {23};
    const double dir[2] = {0.7713, 0.6364}, perp[2] = {-0.6364, 0.7713};
    const double c[2] = {2.2, 1.85}, aside = 0.15;
    mvt_real X[3][3] = {{(mvt_real)(c[0] - 0.42 * dir[0]), (mvt_real)(c[1] - 0.42 * dir[1]), 1.88f},
                        {(mvt_real)(c[0] + aside * perp[0]), (mvt_real)(c[1] + aside * perp[1]), 1.55f},
                        {(mvt_real)(c[0] + 0.42 * dir[0]), (mvt_real)(c[1] + 0.42 * dir[1]), 1.92f}};
    int32_t ids[8] = {0};
    int nid = 0;
    *covered = 0;
    *gone_after = -1;
    int32_t last = 0;
    for (int f = 0; f < 900; f++) {
        const double t = f * 0.04;
        int m = 3;
        const mvt_real *order[3] = {X[0], X[2], X[1]};
        mvt_real P[3][3];
        if (t < 2.0) { /* the short person walks into the gap from 1 m aside */
            const double a = 1.0 - t / 2.0;
            X[1][0] = (mvt_real)(c[0] + (aside + a) * perp[0]);
            X[1][1] = (mvt_real)(c[1] + (aside + a) * perp[1]);
        } else if (t >= 24.0 && !vanish) { /* walks out the same way */
            const double a = (t - 24.0) < 3.0 ? (t - 24.0) : 3.0;
            X[1][0] = (mvt_real)(c[0] + (aside + 0.5 * a) * perp[0]);
            X[1][1] = (mvt_real)(c[1] + (aside + 0.5 * a) * perp[1]);
        }
        if (t >= 24.0 && vanish) {
            m = 2;
        }
        for (int i = 0; i < m; i++) {
            memcpy(P[i], order[i], sizeof(P[i]));
        }
        frame_blobs((const mvt_real(*)[3])P, m, 1000000 + f * 40000, &rng, 2.0, 1);
        assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
        if (m == 3) {
            const int32_t id = id_near(X[1]);
            *covered += id != 0;
            if (id != 0 && (nid == 0 || ids[nid - 1] != id) && nid < 8) {
                ids[nid++] = id;
            }
            last = id != 0 ? id : last;
        } else if (*gone_after < 0 && find_id(last) == NULL) {
            *gone_after = f - 600;
        }
    }
    return nid;
}

static void test_mvt_tracker_step_queue_hidden_kept_while_box_needs_them(void **state)
{
    (void)state;
    int covered, gone_after;
    /* hidden for 22 s: one identity all along, never deleted */
    assert_int_equal(queue_hidden(0, &covered, &gone_after), 1);
    assert_true(covered >= 890);
    assert_int_equal(g_tracker.counters.deletions, 0);
    assert_true(g_tracker.counters.occluded_updates > 1000);
    /* the person vanishes from the middle of the queue: the boxes shrink to the tall two and the
     * track goes within a second */
    assert_int_equal(queue_hidden(1, &covered, &gone_after), 1);
    assert_true(gone_after >= 0 && gone_after <= 25);
}

/* A person vanishes in the middle of the room while two others stay in view: five views that each
 * miss the head end the track within a few frames, with boxes or without. */
static void test_mvt_tracker_step_vanished_person_contradicted_deleted(void **state)
{
    (void)state;
    for (int with_boxes = 1; with_boxes >= 0; with_boxes--) {
        init();
        test_rng_t rng = {17};
        const mvt_real X[3][3] = {{3.0f, 2.5f, 1.7f}, {1.0f, 1.0f, 1.8f}, {5.0f, 4.0f, 1.75f}};
        int f = 0;
        for (; f < 30; f++) {
            frame_blobs(X, 3, 1000000 + f * 40000, &rng, 2.0, with_boxes);
            mvt_tracker_step(&g_tracker, &g_frame, &g_out);
        }
        const int32_t id = id_near(X[0]);
        assert_true(id > 0);
        int gone_after = -1;
        for (int g = 0; g < 100; g++, f++) {
            frame_blobs(&X[1], 2, 1000000 + f * 40000, &rng, 2.0, with_boxes);
            mvt_tracker_step(&g_tracker, &g_frame, &g_out);
            if (gone_after < 0 && find_id(id) == NULL) {
                gone_after = g;
            }
        }
        /* five views that each miss the head: the existence falls within a few frames */
        assert_true(gone_after >= 0 && gone_after <= 5);
        assert_true(id_near(X[1]) > 0 && id_near(X[2]) > 0);
    }
}

/* The ghost tests' scene: two real people, and the place G where two views' blobs meet. */
static const mvt_real GHOST_PEOPLE[2][3] = {{1.2f, 1.0f, 1.75f}, {4.8f, 3.9f, 1.7f}};
static const mvt_real GHOST_AT[3] = {3.0f, 2.6f, 1.7f};

/* A ghost's blob in camera k: its top uv (G's projection) and a body's box under it. Returns the
 * body's half width in pixels at G's depth. */
static mvt_real ghost_box(int k, const mvt_real G[3], mvt_real uv[2], mvt_real box[4])
{
    mvt_real c[3];
    assert_int_equal(mvt_cam_project(&g_cams[k], G, uv, NULL), MVT_OK);
    mvt_cam_to_camera(&g_cams[k], G, c);
    const mvt_real half = (mvt_real)0.22 * g_cams[k].fx / c[2];
    box[0] = uv[0] - half;
    box[1] = uv[1] - half;
    box[2] = uv[0] + half;
    box[3] = uv[1] + 8 * half;
    return half;
}

/* Appends the ghost's blob to camera k's view: its top with 2 px of noise, its box if with_box. */
static void add_ghost_blob(int k, const mvt_real G[3], test_rng_t *rng, int with_box)
{
    mvt_real uv[2], box[4];
    (void)ghost_box(k, G, uv, box);
    mvt_view_t *v = &g_frame.views[k];
    mvt_detection_t *d = &v->det[v->num_detections++];
    memset(d, 0, sizeof(*d));
    d->u = uv[0] + (mvt_real)(2.0 * test_normal(rng));
    d->v = uv[1] + (mvt_real)(2.0 * test_normal(rng));
    d->sigma_px = 2;
    d->score = 1;
    d->hue = d->saturation = -1;
    if (with_box) {
        memcpy(d->box, box, sizeof(box));
    }
}

/* A ghost: cameras 0 and 1 each report a blob whose rays meet at G (as two other people's blobs
 * may), while cameras 2-4, which send boxes and have G in their pictures, show nobody there. Two
 * real people are seen by all five. With boxes the ghost is never confirmed (births refuted, a
 * tentative track refuted in the frames it lives); without boxes nothing speaks against it and
 * it is confirmed (so the test can fail). */
static void test_mvt_tracker_step_ghost_two_views_refuted_by_three(void **state)
{
    (void)state;
    const mvt_real(*X)[3] = GHOST_PEOPLE;
    const mvt_real *G = GHOST_AT;
    for (int with_boxes = 1; with_boxes >= 0; with_boxes--) {
        init();
        test_rng_t rng = {23};
        int ghost_confirmed = 0;
        for (int f = 0; f < 75; f++) {
            frame_blobs(X, 2, 1000000 + f * 40000, &rng, 2.0, with_boxes);
            for (int k = 0; k < 2; k++) {
                add_ghost_blob(k, G, &rng, with_boxes);
            }
            mvt_tracker_step(&g_tracker, &g_frame, &g_out);
            ghost_confirmed += id_near(G) > 0;
        }
        assert_true(id_near(X[0]) > 0 && id_near(X[1]) > 0);
        if (with_boxes) {
            /* three views' misses outweigh the two views' blobs within a few frames (docs/limits.md) */
            print_message("ghost of two views: confirmed in %d of 75 frames\n", ghost_confirmed);
            assert_true(ghost_confirmed <= 3);
        } else {
            assert_true(ghost_confirmed > 50);
        }
    }
}

/* Camera k's foreground mask at quarter resolution: the rectangles box[0..n-1] (raw pixels). */
static mvt_mask_t g_masks[5];

/* Camera k's mask, empty (192 x 144, scale 4) and attached to its view. */
static mvt_mask_t *blank_mask(int k)
{
    mvt_mask_t *m = &g_masks[k];
    memset(m, 0, sizeof(*m));
    m->width = 192;
    m->height = 144;
    m->scale = 4;
    g_frame.views[k].mask = m;
    return m;
}

static void set_fg(mvt_mask_t *m, int u, int v)
{
    m->num_fg += !m->fg[v * m->width + u];
    m->fg[v * m->width + u] = 1;
}

static void mask_of_boxes(int k, const mvt_real (*box)[4], int n)
{
    mvt_mask_t *m = blank_mask(k);
    for (int i = 0; i < n; i++) {
        for (int v = 0; v < m->height; v++) {
            for (int u = 0; u < m->width; u++) {
                const mvt_real cu = (mvt_real)(4 * u + 2), cv = (mvt_real)(4 * v + 2); /* pixel centre */
                if (cu >= box[i][0] && cu <= box[i][2] && cv >= box[i][1] && cv <= box[i][3]) {
                    set_fg(m, u, v);
                }
            }
        }
    }
}

/* Every box of camera k's view widened to hold gbox and half its width more on each side (a
 * shadow, or people's merged blob spanning that place, as a box does). */
static void widen_boxes_over(int k, const mvt_real gbox[4], mvt_real half)
{
    mvt_view_t *v = &g_frame.views[k];
    for (int d = 0; d < v->num_detections; d++) {
        for (int j = 0; j < 2; j++) {
            v->det[d].box[j] = v->det[d].box[j] < gbox[j] - half ? v->det[d].box[j] : gbox[j] - half;
            v->det[d].box[j + 2] = v->det[d].box[j + 2] > gbox[j + 2] + half ? v->det[d].box[j + 2] : gbox[j + 2] + half;
        }
    }
}

/* The ghost of the test above, where cameras 2-4's blobs' boxes also hold its place (a shadow, or
 * people's merged blob spanning it, as a box does): the boxes no longer refute it, and it is
 * confirmed. Where those cameras also send their foreground masks, which hold the two people's
 * silhouettes only, the ghost's place is empty in three views and it is never confirmed. */
static void test_mvt_tracker_step_ghost_in_boxes_refuted_by_masks(void **state)
{
    (void)state;
    const mvt_real(*X)[3] = GHOST_PEOPLE;
    const mvt_real *G = GHOST_AT;
    for (int with_masks = 1; with_masks >= 0; with_masks--) {
        init();
        test_rng_t rng = {23};
        int ghost_confirmed = 0;
        for (int f = 0; f < 75; f++) {
            frame_blobs(X, 2, 1000000 + f * 40000, &rng, 2.0, 1);
            for (int k = 0; k < 5; k++) {
                mvt_view_t *v = &g_frame.views[k];
                mvt_real uv[2], gbox[4], boxes[MVT_MAX_DETECTIONS + 1][4];
                const mvt_real half = ghost_box(k, G, uv, gbox);
                int nb = 0;
                for (int d = 0; d < v->num_detections; d++, nb++) {
                    memcpy(boxes[nb], v->det[d].box, sizeof(boxes[nb]));
                }
                if (k < 2) { /* the two views whose fragments meet at G */
                    add_ghost_blob(k, G, &rng, 1);
                    memcpy(boxes[nb++], gbox, sizeof(gbox));
                } else { /* every box of the view widened over G's place: background in the mask */
                    widen_boxes_over(k, gbox, half);
                }
                if (with_masks) {
                    mask_of_boxes(k, (const mvt_real(*)[4])boxes, nb);
                }
            }
            mvt_tracker_step(&g_tracker, &g_frame, &g_out);
            ghost_confirmed += id_near(G) > 0;
        }
        assert_true(id_near(X[0]) > 0 && id_near(X[1]) > 0);
        if (with_masks) {
            assert_int_equal(ghost_confirmed, 0);
        } else {
            assert_true(ghost_confirmed > 50);
        }
    }
}

/* A person vanishes in the middle of the room, and from then on every camera's boxes (the two
 * remaining people's) are widened over the place where they stood: the track is hidden in those
 * boxes, and the boxes' extent even needs it, so it lives on. Where the cameras send their masks,
 * which hold the two people's silhouettes only, the place is background in every view: the track
 * is hidden nowhere and ends within 15 frames. */
static void test_mvt_tracker_step_vanished_in_widened_boxes_deleted_by_masks(void **state)
{
    (void)state;
    const mvt_real X[3][3] = {{3.0f, 2.5f, 1.7f}, {1.0f, 1.0f, 1.8f}, {5.0f, 4.0f, 1.75f}};
    for (int with_masks = 1; with_masks >= 0; with_masks--) {
        init();
        test_rng_t rng = {17};
        int f = 0;
        for (; f < 30; f++) {
            frame_blobs(X, 3, 1000000 + f * 40000, &rng, 2.0, 1);
            mvt_tracker_step(&g_tracker, &g_frame, &g_out);
        }
        const int32_t id = id_near(X[0]);
        assert_true(id > 0);
        int gone_after = -1;
        for (int g = 0; g < 100; g++, f++) {
            frame_blobs(&X[1], 2, 1000000 + f * 40000, &rng, 2.0, 1);
            for (int k = 0; k < 5; k++) {
                mvt_view_t *v = &g_frame.views[k];
                mvt_real uv[2], gbox[4], boxes[MVT_MAX_DETECTIONS][4];
                const mvt_real half = ghost_box(k, X[0], uv, gbox);
                for (int d = 0; d < v->num_detections; d++) {
                    memcpy(boxes[d], v->det[d].box, sizeof(boxes[d]));
                }
                if (with_masks) {
                    mask_of_boxes(k, (const mvt_real(*)[4])boxes, v->num_detections);
                }
                widen_boxes_over(k, gbox, half);
            }
            mvt_tracker_step(&g_tracker, &g_frame, &g_out);
            if (gone_after < 0 && find_id(id) == NULL) {
                gone_after = g;
            }
        }
        print_message("vanished in widened boxes, masks %d: gone after %d frames\n", with_masks, gone_after);
        if (with_masks) {
            assert_true(gone_after >= 0 && gone_after <= 15);
        } else {
            assert_true(gone_after < 0 || gone_after > 45);
        }
        assert_true(id_near(X[1]) > 0 && id_near(X[2]) > 0);
    }
}

/* A person stands right under camera 0 (outside its picture, next to its focal plane), seen by the
 * other four; camera 0 sends a blob of someone else each frame. The prediction in camera 0 lies far
 * outside its picture with an image spread wider than the picture: camera 0 must not update the
 * track (a gate that wide admits any blob and the linearised update drags the track). */
static void test_mvt_tracker_step_camera_that_cannot_see_does_not_update(void **state)
{
    (void)state;
    init();
    test_rng_t rng = {5};
    const mvt_real P[1][3] = {{0.45f, 0.40f, 1.75f}};
    mvt_real uv[2];
    assert_int_not_equal(mvt_cam_project(&g_cams[0], P[0], uv, NULL) == MVT_OK && uv[0] >= 0 && uv[0] < 768 &&
                             uv[1] >= 0 && uv[1] < 576, 1);
    double worst = 0;
    for (int f = 0; f < 100; f++) {
        frame_of(P, 1, 1000000 + f * 40000, &rng, 2.0, 0);
        mvt_view_t *v = &g_frame.views[0];
        mvt_detection_t *d = &v->det[v->num_detections++];
        memset(d, 0, sizeof(*d));
        d->u = (mvt_real)(60 + 5 * test_normal(&rng));
        d->v = (mvt_real)(540 + 5 * test_normal(&rng));
        d->sigma_px = 2;
        d->score = 1;
        d->hue = d->saturation = -1;
        mvt_tracker_step(&g_tracker, &g_frame, &g_out);
        /* the person's track (the body model may also track the someone else camera 0 alone sees) */
        int near = 0;
        for (int i = 0; i < g_out.num_tracks; i++) {
            const double e = dist3(g_out.tracks[i].pos_m, P[0]);
            if (e > 0.5) {
                continue;
            }
            near++;
            assert_true((g_out.tracks[i].cameras_used & 1u) == 0u);
            worst = f > 10 && e > worst ? e : worst;
        }
        if (f > 10) {
            assert_int_equal(near, 1);
        }
    }
    assert_true(worst < 0.1);
}

/* The room's corner camera 0 and its zenith camera as a two-camera rig; a person at y (x 3.0 m,
 * head 1.72 m) reported by every camera whose picture holds the head (sd 2 px, no boxes), except
 * the zenith camera when silent. Returns whether the zenith camera sees x. */
static mvt_camera_t g_two[2];

static int two_camera_frame(double y, int64_t utime, test_rng_t *rng, int zenith_silent)
{
    const mvt_real X[3] = {3.0f, (mvt_real)y, 1.72f};
    empty_frame(utime);
    for (int k = 2; k < 5; k++) {
        g_frame.views[k].observed = 0;
    }
    int zenith_sees = 0;
    for (int k = 0; k < 2; k++) {
        mvt_real uv[2];
        if (mvt_cam_project(&g_two[k], X, uv, NULL) != MVT_OK || uv[0] < 0 || uv[1] < 0 || uv[0] > 767 ||
            uv[1] > 575) {
            continue;
        }
        zenith_sees |= k == 1;
        if (k == 1 && zenith_silent) {
            continue;
        }
        mvt_detection_t *d = &g_frame.views[k].det[g_frame.views[k].num_detections++];
        d->u = uv[0] + (mvt_real)(2.0 * test_normal(rng));
        d->v = uv[1] + (mvt_real)(2.0 * test_normal(rng));
        d->sigma_px = 2;
        d->score = 1;
        d->hue = d->saturation = -1;
    }
    return zenith_sees;
}

/* Where one camera reaches. A person born where both cameras see them (the room's middle) walks at
 * 0.76 m/s to y = 4.4 m, where the zenith camera's field has ended (at 4.0 m), stands there 4 s and
 * walks back. Every camera whose picture holds the head reports it, so one view
 * there sees the track all the same: one identity throughout, within 0.25 m (the height held to
 * what two views measured fixes the point on the corner camera's ray). The guard: where the
 * zenith camera's picture holds the head and it reports nothing for 3 s, the track is kept: each
 * frame's blob at the predicted head outweighs one view's miss (a detector that loses a person the
 * other view sees). */
static void test_mvt_tracker_step_person_where_one_camera_reaches_kept(void **state)
{
    (void)state;
    assert_int_equal(test_room_cameras(g_cams, 1), 0);
    g_two[0] = g_cams[0];
    g_two[1] = g_cams[4];
    mvt_tracker_config_t cfg;
    room_config(&cfg);
    assert_int_equal(mvt_tracker_init(&g_tracker, &cfg, g_two, 2), MVT_OK);
    test_rng_t rng = {23};
    int64_t t = 1000000;
    int32_t id = 0;
    int one_view_frames = 0;
    double worst = 0.0;
    for (int f = 0; f < 325; f++, t += 40000) {
        const double s = f * 0.04; /* 1 s still, 2.5 s out, 4 s still, 2.5 s back, 3 s still */
        double y = 2.5;
        if (s > 1.0 && s <= 3.5) {
            y = 2.5 + 0.76 * (s - 1.0);
        } else if (s > 3.5 && s <= 7.5) {
            y = 4.4;
        } else if (s > 7.5 && s <= 10.0) {
            y = 4.4 - 0.76 * (s - 7.5);
        }
        const int zenith_sees = two_camera_frame(y, t, &rng, 0);
        assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
        const mvt_real X[3] = {3.0f, (mvt_real)y, 1.72f};
        if (f == 20) {
            id = id_near(X);
            assert_true(id > 0);
        }
        if (f > 20) {
            const mvt_track_out_t *o = find_id(id);
            assert_non_null(o);
            assert_int_equal(g_out.num_tracks, 1);
            const double e = dist3(o->pos_m, X);
            worst = e > worst ? e : worst;
            one_view_frames += !zenith_sees;
        }
    }
    assert_true(one_view_frames > 100); /* the 4 s at y = 4.4 m at least */
    assert_true(worst < 0.25);
    assert_int_equal(g_tracker.counters.deletions, 0);
    /* the guard: at y = 3.0 m the zenith camera sees the head; it goes silent */
    int gone_after = -1;
    for (int g = 0; g < 100; g++, t += 40000) {
        assert_int_equal(two_camera_frame(2.5 + 0.02 * (g < 25 ? g : 25), t, &rng, g >= 25), 1);
        assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
        if (gone_after < 0 && g >= 25 && find_id(id) == NULL) {
            gone_after = g - 25;
        }
    }
    assert_true(gone_after < 0);
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


/* ... and with the triangulate-then-KF baseline (--mode kf), which runs the body model with a
 * triangulated point for the projective filter's per-view heads. Not the merged pair or the hidden
 * queue: a head that no view shows as a blob's top is kept by the edges of the blob that hosts it,
 * a per-view pixel measurement, the projective filter's (mvt_body_update.c). */
#define WITH_KF(test)                         \
    static void test##_kf(void **state)       \
    {                                         \
        g_filter = MVT_FILTER_TRIANGULATE;    \
        test(state);                          \
        g_filter = MVT_FILTER_PROJECTIVE;     \
    }
WITH_KF(test_mvt_tracker_step_two_people_crossing_keep_identities)
WITH_KF(test_mvt_tracker_step_coasting_track_does_not_take_passer_by)
WITH_KF(test_mvt_tracker_step_lost_tracks_reacquired_by_height)
WITH_KF(test_mvt_tracker_step_close_pair_both_kept)
WITH_KF(test_mvt_tracker_step_false_alarm_flood_confirmed_tracks_survive)
WITH_KF(test_mvt_tracker_step_more_people_than_capacity_births_refused_counted)
WITH_KF(test_mvt_tracker_step_person_returns_new_identity)

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mvt_tracker_step_two_people_crossing_keep_identities),
        cmocka_unit_test(test_mvt_tracker_step_coasting_track_does_not_take_passer_by),
        cmocka_unit_test(test_mvt_tracker_step_lost_tracks_reacquired_by_height),
        cmocka_unit_test(test_mvt_tracker_step_close_pair_both_kept),
        cmocka_unit_test(test_mvt_tracker_step_close_pair_merged_blobs_both_kept),
        cmocka_unit_test(test_mvt_tracker_step_false_alarm_flood_confirmed_tracks_survive),
        cmocka_unit_test(test_mvt_tracker_step_more_people_than_capacity_births_refused_counted),
        cmocka_unit_test(test_mvt_tracker_step_person_returns_new_identity),
        cmocka_unit_test(test_mvt_tracker_step_person_lost_and_back_keeps_identity),
        cmocka_unit_test(test_mvt_tracker_step_label_height_as_sure_as_it_held),
        cmocka_unit_test(test_mvt_tracker_step_merged_label_waits_for_its_person),
        cmocka_unit_test(test_mvt_tracker_step_bursts_in_three_views_do_not_carry_track),
        cmocka_unit_test(test_mvt_tracker_step_track_rejoins_person_three_views_agree_on),
        cmocka_unit_test(test_mvt_tracker_step_person_found_by_one_far_view_keeps_identity),
        cmocka_unit_test(test_mvt_tracker_step_walker_along_wall_keeps_identity),
        cmocka_unit_test(test_mvt_tracker_select_under_capacity_keeps_all_in_order),
        cmocka_unit_test(test_mvt_tracker_step_hidden_in_group_keeps_identity),
        cmocka_unit_test(test_mvt_tracker_step_queue_hidden_kept_while_box_needs_them),
        cmocka_unit_test(test_mvt_trk_app_learns_colour_bounds_outliers),
        cmocka_unit_test(test_mvt_tracker_step_vanished_person_contradicted_deleted),
        cmocka_unit_test(test_mvt_tracker_step_ghost_two_views_refuted_by_three),
        cmocka_unit_test(test_mvt_tracker_step_ghost_in_boxes_refuted_by_masks),
        cmocka_unit_test(test_mvt_tracker_step_vanished_in_widened_boxes_deleted_by_masks),
        cmocka_unit_test(test_mvt_tracker_step_camera_that_cannot_see_does_not_update),
        cmocka_unit_test(test_mvt_tracker_step_person_where_one_camera_reaches_kept),
        cmocka_unit_test(test_mvt_tracker_step_two_people_crossing_keep_identities_kf),
        cmocka_unit_test(test_mvt_tracker_step_coasting_track_does_not_take_passer_by_kf),
        cmocka_unit_test(test_mvt_tracker_step_lost_tracks_reacquired_by_height_kf),
        cmocka_unit_test(test_mvt_tracker_step_close_pair_both_kept_kf),
        cmocka_unit_test(test_mvt_tracker_step_false_alarm_flood_confirmed_tracks_survive_kf),
        cmocka_unit_test(test_mvt_tracker_step_more_people_than_capacity_births_refused_counted_kf),
        cmocka_unit_test(test_mvt_tracker_step_person_returns_new_identity_kf),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
