/* Unit tests of mvt_cv, mvt_pkf and mvt_tracker: filter behaviour and the track lifecycle. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <string.h>

#include "mvt_tracker.h"
#include "test_support.h"

static mvt_tracker_t g_tracker; /* large: static */
static mvt_frame_t g_frame;
static mvt_output_t g_out;

static uint32_t g_seen; /* cameras whose image contains the point */

static void frame_of(const mvt_camera_t *cams, int n, const mvt_real x[3], int64_t utime, test_rng_t *rng, double sd)
{
    g_seen = 0;
    memset(&g_frame, 0, sizeof(g_frame));
    g_frame.utime_us = utime;
    for (int k = 0; k < n; k++) {
        mvt_view_t *v = &g_frame.views[k];
        v->observed = 1;
        v->utime_us = utime;
        mvt_real uv[2];
        if (mvt_cam_project(&cams[k], x, uv, NULL) != MVT_OK || uv[0] < 0 || uv[1] < 0 || uv[0] > 767 || uv[1] > 575) continue;
        g_seen |= 1u << k;
        v->det[0].u = uv[0] + (mvt_real)(sd * test_normal(rng));
        v->det[0].v = uv[1] + (mvt_real)(sd * test_normal(rng));
        v->det[0].sigma_px = (mvt_real)sd;
        v->num_detections = 1;
    }
}

static void init_tracker(mvt_camera_t cams[5], mvt_filter_t f, mvt_pkf_lin_t lin)
{
    assert_int_equal(test_room_cameras(cams, 1), 0);
    mvt_tracker_config_t cfg;
    mvt_tracker_config_default(&cfg);
    cfg.filter = f;
    cfg.lin = lin;
    cfg.volume.min[0] = 0; cfg.volume.min[1] = 0; cfg.volume.min[2] = 0;
    cfg.volume.max[0] = 6; cfg.volume.max[1] = 5; cfg.volume.max[2] = 2.5f;
    assert_int_equal(mvt_tracker_init(&g_tracker, &cfg, cams, 5), MVT_OK);
}

static void test_mvt_cv_predict_constant_velocity_moves_and_grows(void **state)
{
    (void)state;
    mvt_cv_state_t s;
    const mvt_real p[3] = {1, 2, 1.7f}, cov[9] = {1e-4f, 0, 0, 0, 1e-4f, 0, 0, 0, 1e-4f}, q[3] = {0.5f, 0.5f, 0.05f};
    mvt_cv_init(&s, p, cov, 0.25f, 0);
    s.x[3] = 1.0f;
    s.x[4] = -0.5f;
    assert_int_equal(mvt_cv_predict(&s, 0.04f, q), MVT_OK);
    assert_float_equal(s.x[0], 1.04, 1e-6);
    assert_float_equal(s.x[1], 1.98, 1e-6);
    /* Pxx = 1e-4 + dt^2 * 0.25 + q dt^3 / 3 */
    assert_float_equal(s.P[0], 1e-4 + 0.0016 * 0.25 + 0.5 * 0.04 * 0.04 * 0.04 / 3, 1e-8);
    assert_float_equal(s.P[3], 0.04 * 0.25 + 0.5 * 0.0016 / 2, 1e-7);
    assert_int_equal(mvt_cv_predict(&s, -1.0f, q), MVT_ERR_INVALID);
    assert_int_equal(mvt_cv_predict(&s, NAN, q), MVT_ERR_INVALID);
}

static void test_mvt_cv_update_point_outlier_gated_state_unchanged(void **state)
{
    (void)state;
    mvt_cv_state_t s;
    const mvt_real p[3] = {1, 2, 1.7f}, cov[9] = {1e-2f, 0, 0, 0, 1e-2f, 0, 0, 0, 1e-2f};
    mvt_cv_init(&s, p, cov, 0.25f, 0);
    const mvt_cv_state_t before = s;
    const mvt_real z[3] = {3, 2, 1.7f}, R[9] = {1e-2f, 0, 0, 0, 1e-2f, 0, 0, 0, 1e-2f};
    mvt_real d2;
    assert_int_equal(mvt_cv_update_point(&s, z, R, 16.0f, &d2), MVT_ERR_GATED);
    assert_float_equal(d2, 4.0 / 0.02, 1e-2);
    assert_memory_equal(&s, &before, sizeof(s));
    const mvt_real zn[3] = {NAN, 0, 0};
    assert_int_equal(mvt_cv_update_point(&s, zn, R, 0, NULL), MVT_ERR_NONFINITE);
    /* an accepted update lands halfway between equal-variance prior and measurement */
    const mvt_real z2[3] = {1.2f, 2, 1.7f};
    assert_int_equal(mvt_cv_update_point(&s, z2, R, 16.0f, NULL), MVT_OK);
    assert_float_equal(s.x[0], 1.1, 1e-5);
    assert_float_equal(s.P[0], 5e-3, 1e-6);
}

/* Mean and variance of N(mu, s2 + e) restricted to [lo, hi], by Simpson quadrature in double (an
 * independent reference for the closed form in mvt_cv_truncate). */
static void truncated_moments_quadrature(double mu, double var, double lo, double hi, double *mean, double *v)
{
    const double sd = sqrt(var);
    const double a = lo > mu - 14 * sd ? lo : mu - 14 * sd, b = hi < mu + 14 * sd ? hi : mu + 14 * sd;
    const int n = 200000; /* even */
    const double h = (b - a) / n;
    double z = 0, m1 = 0, m2 = 0;
    for (int i = 0; i <= n; i++) {
        const double x = a + i * h;
        const double w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
        const double p = w * exp(-0.5 * (x - mu) * (x - mu) / var);
        z += p;
        m1 += p * x;
        m2 += p * x * x;
    }
    *mean = m1 / z;
    *v = m2 / z - *mean * *mean;
}

static void random_state(test_rng_t *rng, mvt_cv_state_t *st)
{
    double A[36], P[36];
    for (int i = 0; i < 36; i++) A[i] = test_normal(rng) * (i % 6 < 3 ? 0.2 : 0.5);
    for (int i = 0; i < 6; i++) {
        for (int j = 0; j < 6; j++) {
            double acc = i == j ? 1e-3 : 0;
            for (int k = 0; k < 6; k++) acc += A[i * 6 + k] * A[j * 6 + k];
            P[i * 6 + j] = acc;
        }
    }
    memset(st, 0, sizeof(*st));
    for (int i = 0; i < 6; i++) st->x[i] = (mvt_real)test_normal(rng);
    for (int i = 0; i < 36; i++) st->P[i] = (mvt_real)P[i];
}

static void test_mvt_cv_truncate_matches_quadrature(void **state)
{
    (void)state;
    test_rng_t rng = {2024};
    /* bands in prior standard deviations: inside, one tail, far tail one-sided, narrow, wide open */
    const double bands[][2] = {{-0.5, 1.0}, {0.8, 2.0}, {2.5, 1e3}, {-1e3, -2.0}, {0.3, 0.32}, {-0.01, 0.01}, {-9, 9}};
    const double extras[] = {0.0, 0.5};
    for (int trial = 0; trial < 20; trial++) {
        for (size_t b = 0; b < sizeof(bands) / sizeof(bands[0]); b++) {
            for (int e = 0; e < 2; e++) {
                mvt_cv_state_t st, before;
                random_state(&rng, &st);
                before = st;
                const mvt_real H[3] = {(mvt_real)test_normal(&rng), (mvt_real)test_normal(&rng), (mvt_real)test_normal(&rng)};
                double hp[6], s2 = 0, mu = 0;
                for (int j = 0; j < 6; j++) {
                    hp[j] = 0;
                    for (int i = 0; i < 3; i++) hp[j] += (double)H[i] * (double)st.P[i * 6 + j];
                }
                for (int i = 0; i < 3; i++) {
                    s2 += hp[i] * (double)H[i];
                    mu += (double)H[i] * (double)st.x[i];
                }
                const double extra = extras[e] * s2, tot = s2 + extra, sd = sqrt(tot);
                const double lo = mu + bands[b][0] * sd, hi = mu + bands[b][1] * sd;
                double m, v;
                truncated_moments_quadrature(mu, tot, lo, hi, &m, &v);
                mvt_real mass = -1;
                assert_int_equal(mvt_cv_truncate_ex(&st, H, (mvt_real)mu, (mvt_real)extra, (mvt_real)lo, (mvt_real)hi, &mass),
                                 MVT_OK);
                assert_true(mass > 0 && mass <= 1.0001f);
                /* exact for a linear functional: x' = x + P H^T (m - mu) / tot,
                 * P' = P - P H^T H P (tot - v) / tot^2 */
                for (int i = 0; i < 6; i++) {
                    const double want = (double)before.x[i] + hp[i] * (m - mu) / tot;
                    assert_true(fabs((double)st.x[i] - want) < 2e-3 * (1 + sqrt((double)before.P[i * 7])));
                    for (int j = 0; j < 6; j++) {
                        const double wp = (double)before.P[i * 6 + j] - hp[i] * hp[j] * (tot - v) / (tot * tot);
                        assert_true(fabs((double)st.P[i * 6 + j] - wp) < 2e-3 * (1 + fabs((double)before.P[i * 6 + j])));
                    }
                }
            }
        }
    }
    /* hostile: an empty or non-finite band, a band without prior mass: refused, state untouched */
    mvt_cv_state_t st, before;
    random_state(&rng, &st);
    before = st;
    const mvt_real H[3] = {1, 0, 0};
    assert_int_equal(mvt_cv_truncate(&st, H, st.x[0], 1, 1, NULL), MVT_ERR_INVALID);
    assert_int_equal(mvt_cv_truncate(&st, H, st.x[0], 2, 1, NULL), MVT_ERR_INVALID);
    assert_int_equal(mvt_cv_truncate(&st, H, st.x[0], NAN, 1, NULL), MVT_ERR_INVALID);
    assert_int_equal(mvt_cv_truncate_ex(&st, H, st.x[0], -1, 0, 1, NULL), MVT_ERR_INVALID);
    const mvt_real far = st.x[0] + 8 * sqrtf((float)st.P[0]);
    assert_int_equal(mvt_cv_truncate(&st, H, st.x[0], far, far + 1, NULL), MVT_ERR_NUMERIC);
    assert_memory_equal(&st, &before, sizeof(st));
}

/* The ground variant: the horizontal rows follow the exact truncation (the gain rows of x, y, vx, vy
 * are the optimal ones), height and vertical speed do not move, and the covariance (Joseph form
 * with that gain) keeps their variances, stays symmetric and positive semi-definite. */
static void test_mvt_cv_truncate_ground_keeps_height(void **state)
{
    (void)state;
    test_rng_t rng = {77};
    for (int trial = 0; trial < 50; trial++) {
        mvt_cv_state_t st, ref;
        random_state(&rng, &st);
        ref = st;
        const mvt_real H[3] = {(mvt_real)test_normal(&rng), (mvt_real)test_normal(&rng), 0};
        const mvt_real mu = H[0] * st.x[0] + H[1] * st.x[1];
        double s2 = 0;
        for (int i = 0; i < 2; i++)
            for (int j = 0; j < 2; j++) s2 += (double)H[i] * (double)st.P[i * 6 + j] * (double)H[j];
        const mvt_real lo = mu + (mvt_real)(0.5 * sqrt(s2)), hi = mu + (mvt_real)(3 * sqrt(s2));
        assert_int_equal(mvt_cv_truncate_ground(&st, H, mu, 0, lo, hi, NULL), MVT_OK);
        assert_int_equal(mvt_cv_truncate_ex(&ref, H, mu, 0, lo, hi, NULL), MVT_OK);
        for (int i = 0; i < 6; i++) {
            if (i == 2 || i == 5) continue;
            assert_true(fabs((double)st.x[i] - (double)ref.x[i]) < 1e-4 * (1 + fabs((double)ref.x[i])));
        }
        /* PSD: every 2x2 principal minor and the Cholesky of the 6x6 */
        double L[36] = {0};
        for (int i = 0; i < 6; i++) {
            for (int j = 0; j < 6; j++) assert_true(st.P[i * 6 + j] == st.P[j * 6 + i]);
            for (int j = 0; j <= i; j++) {
                double a = (double)st.P[i * 6 + j];
                for (int k = 0; k < j; k++) a -= L[i * 6 + k] * L[j * 6 + k];
                if (i == j) {
                    assert_true(a > -1e-6);
                    L[i * 6 + i] = sqrt(a > 0 ? a : 0);
                } else {
                    L[i * 6 + j] = L[j * 6 + j] > 1e-9 ? a / L[j * 6 + j] : 0;
                }
            }
        }
    }
    /* the height and vertical speed themselves, and their variances, are untouched */
    for (int trial = 0; trial < 50; trial++) {
        mvt_cv_state_t st, before;
        random_state(&rng, &st);
        before = st;
        const mvt_real H[3] = {1, (mvt_real)test_normal(&rng), 0};
        const mvt_real mu = st.x[0] + H[1] * st.x[1];
        assert_int_equal(mvt_cv_truncate_ground(&st, H, mu, (mvt_real)0.3, mu + 1, mu + 4, NULL), MVT_OK);
        assert_true(st.x[2] == before.x[2] && st.x[5] == before.x[5]);
        assert_true(fabs((double)st.P[2 * 7] - (double)before.P[2 * 7]) < 1e-5 * (1 + (double)before.P[2 * 7]));
        assert_true(fabs((double)st.P[5 * 7] - (double)before.P[5 * 7]) < 1e-5 * (1 + (double)before.P[5 * 7]));
    }
}

static void test_mvt_pkf_innovation_behind_camera_refused(void **state)
{
    (void)state;
    mvt_camera_t cams[5];
    assert_int_equal(test_room_cameras(cams, 0), 0);
    mvt_cv_state_t s;
    const mvt_real p[3] = {3, 2.5f, 4.0f}, cov[9] = {1e-2f, 0, 0, 0, 1e-2f, 0, 0, 0, 1e-2f}; /* above the ceiling camera */
    mvt_cv_init(&s, p, cov, 0.25f, 0);
    mvt_pkf_meas_t m;
    const mvt_real uv[2] = {380, 290};
    assert_int_equal(mvt_pkf_meas_make(&cams[4], uv, 2, &m), MVT_OK);
    mvt_pkf_innov_t in;
    for (int lin = 0; lin < 3; lin++) {
        assert_int_equal(mvt_pkf_innovation(&s, &cams[4], (mvt_pkf_lin_t)lin, &m, &in), MVT_ERR_BEHIND);
    }
}

/* A person walking a straight line at 0.4 m/s is acquired, confirmed and tracked within 3 cm. */
static void run_straight_walk(mvt_filter_t f, mvt_pkf_lin_t lin, double tol_m)
{
    mvt_camera_t cams[5];
    init_tracker(cams, f, lin);
    test_rng_t rng = {777};
    double se = 0;
    int n = 0;
    int32_t id = -1;
    int seen_total = 0, used_total = 0;
    double vsum[2] = {0, 0};
    for (int t = 0; t < 250; t++) {
        const double ts = t * 0.04;
        const mvt_real x[3] = {(mvt_real)(1.0 + 0.35 * ts), (mvt_real)(1.0 + 0.2 * ts), 1.7f};
        frame_of(cams, 5, x, 1000000 + t * 40000, &rng, 3.0);
        assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
        assert_int_equal(g_out.num_tracks, 1);
        if (t >= 2) assert_int_equal(g_out.tracks[0].status, MVT_TRACK_CONFIRMED);
        if (id < 0) id = g_out.tracks[0].id;
        assert_int_equal(g_out.tracks[0].id, id);
        /* only cameras that see the person; the chi-square gate (13.8) may reject 0.1 % of true ones */
        assert_int_equal(g_out.tracks[0].cameras_used & ~g_seen, 0);
        for (int k = 0; k < 5; k++) {
            seen_total += (g_seen >> k) & 1u;
            used_total += (g_out.tracks[0].cameras_used >> k) & 1u;
        }
        if (t >= 50) {
            for (int i = 0; i < 3; i++) se += (double)((g_out.tracks[0].pos_m[i] - x[i]) * (g_out.tracks[0].pos_m[i] - x[i]));
            vsum[0] += (double)g_out.tracks[0].vel_ms[0];
            vsum[1] += (double)g_out.tracks[0].vel_ms[1];
            n++;
        }
    }
    assert_true(sqrt(se / n) < tol_m);
    assert_true(used_total >= seen_total - 4);
    assert_float_equal(vsum[0] / n, 0.35, 0.03);
    assert_float_equal(vsum[1] / n, 0.2, 0.03);
}

static void test_mvt_tracker_step_straight_walk_pkf_tracked(void **state)
{
    (void)state;
    run_straight_walk(MVT_FILTER_PROJECTIVE, MVT_PKF_JACOBIAN, 0.03);
}

static void test_mvt_tracker_step_straight_walk_kf_tracked(void **state)
{
    (void)state;
    run_straight_walk(MVT_FILTER_TRIANGULATE, MVT_PKF_JACOBIAN, 0.03);
}

/* The paper's gate (--gate paper) decides which detections may be a track's head: with its default
 * ellipsoid (semi-axes sqrt(6) x 4 cm) a walker is tracked from the heads of 90 % of the views or
 * more, in float too; shrunk to a tenth of a millimetre it admits none, and the heads stop updating
 * it. */
static uint64_t g_views_seen; /* paper_gate_updates: the views that showed the person */

static uint64_t paper_gate_updates(mvt_real var_m2, mvt_gate_t gate)
{
    g_views_seen = 0;
    mvt_camera_t cams[5];
    init_tracker(cams, MVT_FILTER_PROJECTIVE, MVT_PKF_JACOBIAN);
    g_tracker.cfg.gate = gate;
    for (int i = 0; i < 3; i++) g_tracker.cfg.paper.var_m2[i] = var_m2;
    test_rng_t rng = {5};
    double err = 0;
    for (int t = 0; t < 100; t++) {
        const double ts = t * 0.04;
        const mvt_real x[3] = {(mvt_real)(1.0 + 0.35 * ts), (mvt_real)(1.0 + 0.2 * ts), 1.7f};
        frame_of(cams, 5, x, 1000000 + t * 40000, &rng, 2.0);
        for (int k = 0; k < 5; k++) g_views_seen += (g_seen >> k) & 1u;
        assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
        if (t == 99 && g_out.num_tracks > 0) {
            for (int i = 0; i < 3; i++) err += (double)((g_out.tracks[0].pos_m[i] - x[i]) * (g_out.tracks[0].pos_m[i] - x[i]));
        }
    }
    if (var_m2 > 1e-4f) {
        assert_int_equal(g_out.num_tracks, 1);
        assert_true(sqrt(err) < 0.05);
    }
    return g_tracker.counters.updates;
}

static void test_mvt_tracker_paper_gate_decides_heads(void **state)
{
    (void)state;
    const uint64_t chi2 = paper_gate_updates(0.04f * 0.04f, MVT_GATE_CHI2);
    const uint64_t wide = paper_gate_updates(0.04f * 0.04f, MVT_GATE_PAPER), seen = g_views_seen;
    const uint64_t tight = paper_gate_updates(1e-8f, MVT_GATE_PAPER);
    print_message("paper gate: %llu head updates of %llu views with the default ellipsoid (chi-square gate: %llu), "
                  "%llu with a 0.1 mm one\n", (unsigned long long)wide, (unsigned long long)seen,
                  (unsigned long long)chi2, (unsigned long long)tight);
    assert_true(wide > 9 * seen / 10);
    assert_true(tight < wide / 10);
}

/* Every camera reports at t and none sees anything. */
static void blank_frame(int64_t t)
{
    memset(&g_frame, 0, sizeof(g_frame));
    g_frame.utime_us = t;
    for (int k = 0; k < 5; k++) { g_frame.views[k].observed = 1; g_frame.views[k].utime_us = t; }
}

/* A person who vanishes (every camera reports, none shows them) is no longer shown within a frame
 * or two; seen again at the same place moments later, they get their label back (the body model
 * keeps a lost label for the person found where it was lost). */
static void test_mvt_tracker_step_unseen_track_coasts_then_dies(void **state)
{
    (void)state;
    mvt_camera_t cams[5];
    init_tracker(cams, MVT_FILTER_PROJECTIVE, MVT_PKF_JACOBIAN);
    test_rng_t rng = {1};
    const mvt_real x[3] = {2, 2, 1.7f};
    int64_t t = 0;
    for (int i = 0; i < 10; i++, t += 40000) {
        frame_of(cams, 5, x, t, &rng, 1.0);
        mvt_tracker_step(&g_tracker, &g_frame, &g_out);
    }
    assert_int_equal(g_out.num_tracks, 1);
    const int32_t id = g_out.tracks[0].id;
    int coasting = 0;
    for (int i = 0; i < 25; i++, t += 40000) { /* cameras report, but see nothing */
        blank_frame(t);
        mvt_tracker_step(&g_tracker, &g_frame, &g_out);
        if (g_out.num_tracks == 1) {
            assert_int_not_equal(g_out.tracks[0].status, MVT_TRACK_CONFIRMED);
            assert_int_equal(g_out.tracks[0].cameras_used, 0);
            coasting++;
        }
    }
    /* five views that should see a person and show nobody: the odds fall by (1 - p_detect)^5 =
     * 1e-5 in one frame, so the track is no longer shown after a frame or two (its label waits) */
    assert_int_equal(g_out.num_tracks, 0);
    assert_true(coasting <= 2);
    for (int i = 0; i < 3; i++, t += 40000) {
        frame_of(cams, 5, x, t, &rng, 1.0);
        mvt_tracker_step(&g_tracker, &g_frame, &g_out);
    }
    assert_int_equal(g_out.num_tracks, 1);
    assert_int_equal(g_out.tracks[0].id, id);
    assert_int_equal(g_out.tracks[0].status, MVT_TRACK_CONFIRMED);
}

/* A saved tracker restored into a fresh one continues bit for bit; a state with one bad value is
 * refused whole. */
static mvt_tracker_t g_tracker2;
static mvt_tracker_persist_t g_saved, g_bad;

static void test_mvt_tracker_resume_continues_and_refuses_bad_state(void **state)
{
    (void)state;
    mvt_camera_t cams[5];
    init_tracker(cams, MVT_FILTER_PROJECTIVE, MVT_PKF_JACOBIAN);
    test_rng_t rng = {42}, rng_at_save;
    int64_t t = 1000000;
    for (int i = 0; i < 30; i++, t += 40000) {
        const mvt_real x[3] = {(mvt_real)(1.0 + 0.02 * i), 2.0f, 1.7f};
        frame_of(cams, 5, x, t, &rng, 2.0);
        assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
    }
    mvt_tracker_save(&g_tracker, &g_saved);
    rng_at_save = rng;
    static mvt_output_t outs[20];
    for (int i = 30; i < 50; i++) {
        const mvt_real x[3] = {(mvt_real)(1.0 + 0.02 * i), 2.0f, 1.7f};
        frame_of(cams, 5, x, t + (i - 30) * 40000, &rng, 2.0);
        assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &outs[i - 30]), MVT_OK);
    }
    assert_int_equal(outs[19].num_tracks, 1);
    mvt_tracker_config_t cfg = g_tracker.cfg;
    assert_int_equal(mvt_tracker_init(&g_tracker2, &cfg, cams, 5), MVT_OK);
    assert_int_equal(mvt_tracker_resume(&g_tracker2, &g_saved, 0), MVT_OK);
    rng = rng_at_save;
    for (int i = 30; i < 50; i++) {
        const mvt_real x[3] = {(mvt_real)(1.0 + 0.02 * i), 2.0f, 1.7f};
        frame_of(cams, 5, x, t + (i - 30) * 40000, &rng, 2.0);
        assert_int_equal(mvt_tracker_step(&g_tracker2, &g_frame, &g_out), MVT_OK);
        assert_int_equal(g_out.num_tracks, outs[i - 30].num_tracks);
        assert_memory_equal(g_out.tracks, outs[i - 30].tracks, (size_t)g_out.num_tracks * sizeof(g_out.tracks[0]));
    }
    /* one bad value anywhere: refused, the tracker unchanged */
    int live = 0;
    while (g_saved.tracks[live].id == 0) live++;
    for (int c = 0; c < 27; c++) {
        mvt_tracker_save(&g_tracker2, &g_saved);
        g_bad = g_saved;
        mvt_track_t *tr = &g_bad.tracks[live];
        switch (c) {
        case 8: tr->exist_lo = NAN; break;                       /* an existence that is no number, */
        case 9: tr->dormant = 2; break;                          /* a flag that is neither 0 nor 1, */
        case 10: tr->one_view_s = -1.0f; break;                  /* a negative time, */
        case 11: g_bad.p_detect_k[1] = 1.0f; break;              /* a camera's certain detection, */
        case 12: g_bad.clutter_n[0] = NAN; break;                /* a clutter rate that is no number, */
        case 13: tr->seen_zz = NAN; break;                       /* nor a track's last-seen height */
        case 14: g_bad.frag_n[2] = -1.0f; break;                 /* a negative fragment rate */
        case 15: g_bad.have_time = 0; break;                     /* tracks without a clock */
        case 16: tr->app.m[0] = NAN; break;                      /* a colour that is no number, */
        case 17: tr->app.m[1] = 1.5f; break;                     /* outside the chroma disc, */
        case 18: tr->app.var = 0; break;                         /* a spread of 0 */
        case 19: tr->view[2].p = 1.5f; break;                    /* a view's displacement: no probability, */
        case 20: tr->view[1].y[0] = INFINITY; break;             /* an infinite offset, */
        case 21: tr->view[0].utime_us = g_bad.last_utime_us + 1; break; /* a time after the clock; */
        case 22: tr->onset[1].p = -0.5f; break;                  /* a held displacement: no probability, */
        case 23: tr->onset[2].head[1] = NAN; break;              /* a head that is no number, */
        case 24: tr->onset[0].confirmed_us = g_bad.last_utime_us + 1; break; /* confirmed after the clock, */
        case 25: tr->onset[3].seen_s = -1.0f; break;             /* seen before it was confirmed, */
        case 26: tr->agree_s = NAN; break;                       /* an agreement's time that is no number */
        case 0: tr->s.x[1] = NAN; break;
        case 1: tr->s.P[7] = -1.0f; break;                       /* variance of y negative */
        case 2: tr->s.P[1] = 5.0f; break;                        /* not symmetric */
        case 3: tr->status = 7; break;
        case 4: tr->last_update_us = g_bad.last_utime_us + 1; break; /* after the clock */
        case 5: g_bad.tracks[(live + 1) % MVT_MAX_TARGETS] = *tr; break; /* identity twice */
        case 6: g_bad.next_id = 0; break;
        case 7: tr->id = -3; break;
        }
        assert_int_equal(mvt_tracker_resume(&g_tracker2, &g_bad, 0), MVT_ERR_INVALID);
        mvt_tracker_save(&g_tracker2, &g_bad);
        assert_memory_equal(&g_bad, &g_saved, sizeof(g_bad));
    }
    assert_int_equal(mvt_tracker_resume(&g_tracker2, &g_saved, -1), MVT_ERR_INVALID);

    /* identities reserved above those used before a restart without a state */
    assert_int_equal(mvt_tracker_init(&g_tracker2, &cfg, cams, 5), MVT_OK);
    assert_int_equal(mvt_tracker_resume(&g_tracker2, &g_saved, 0), MVT_OK);
    const int64_t restart = g_saved.last_utime_us;
    mvt_tracker_reserve_ids(&g_tracker2, 5000);
    mvt_tracker_reserve_ids(&g_tracker2, 7);
    const mvt_real newcomer[3] = {4.5f, 4.0f, 1.7f}; /* 2.5 m from the other person */
    for (int i = 1; i <= 3; i++) {
        frame_of(cams, 5, newcomer, restart + i * 40000, &rng, 1.0);
        assert_int_equal(mvt_tracker_step(&g_tracker2, &g_frame, &g_out), MVT_OK);
    }
    int found = 0;
    for (int i = 0; i < g_out.num_tracks; i++) found += g_out.tracks[i].id == 5000;
    assert_int_equal(found, 1);
}

static void test_mvt_tracker_step_hostile_detections_counted_not_fatal(void **state)
{
    (void)state;
    mvt_camera_t cams[5];
    init_tracker(cams, MVT_FILTER_PROJECTIVE, MVT_PKF_JACOBIAN);
    memset(&g_frame, 0, sizeof(g_frame));
    g_frame.utime_us = 1000;
    for (int k = 0; k < 5; k++) {
        g_frame.views[k].observed = 1;
        g_frame.views[k].utime_us = 1000;
        g_frame.views[k].num_detections = 5000; /* over capacity: clamped */
        for (int d = 0; d < MVT_MAX_DETECTIONS; d++) {
            g_frame.views[k].det[d].u = d % 3 == 0 ? NAN : (mvt_real)(d * 7 % 768);
            g_frame.views[k].det[d].v = d % 5 == 0 ? INFINITY : (mvt_real)(d * 13 % 576);
            g_frame.views[k].det[d].sigma_px = d % 7 == 0 ? -1.0f : 2.0f;
        }
    }
    g_frame.views[MVT_MAX_CAMERAS - 1].observed = 1; /* a view beyond the rig */
    assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_OK);
    assert_true(g_tracker.counters.detections_over_capacity == 5ull * (5000 - MVT_MAX_DETECTIONS));
    assert_true(g_tracker.counters.detections_nonfinite > 0);
    assert_true(g_tracker.counters.views_unknown_camera == 1);
    assert_true(g_out.num_tracks <= MVT_MAX_TARGETS);
    /* time going backwards: refused and counted */
    g_frame.utime_us = 500;
    assert_int_equal(mvt_tracker_step(&g_tracker, &g_frame, &g_out), MVT_ERR_INVALID);
    assert_true(g_tracker.counters.frames_time_backwards == 1);
}

static void test_mvt_tracker_init_bad_config_rejected(void **state)
{
    (void)state;
    mvt_camera_t cams[5];
    assert_int_equal(test_room_cameras(cams, 0), 0);
    mvt_tracker_config_t cfg;
    mvt_tracker_config_default(&cfg);
    assert_int_equal(mvt_tracker_init(&g_tracker, &cfg, cams, 0), MVT_ERR_INVALID);
    assert_int_equal(mvt_tracker_init(&g_tracker, &cfg, cams, MVT_MAX_CAMERAS + 1), MVT_ERR_INVALID);
    cfg.motion.model[0].q[1] = -1;
    assert_int_equal(mvt_tracker_init(&g_tracker, &cfg, cams, 5), MVT_ERR_INVALID);
    mvt_tracker_config_default(&cfg);
    cfg.motion.outlier_persist_s = -0.1f; /* a displacement's duration and drift: >= 0, finite */
    assert_int_equal(mvt_tracker_init(&g_tracker, &cfg, cams, 5), MVT_ERR_INVALID);
    mvt_tracker_config_default(&cfg);
    cfg.motion.outlier_drift_px2_s = NAN;
    assert_int_equal(mvt_tracker_init(&g_tracker, &cfg, cams, 5), MVT_ERR_INVALID);
    mvt_tracker_config_default(&cfg);
    cfg.motion.outlier_persist_s = INFINITY;
    assert_int_equal(mvt_tracker_init(&g_tracker, &cfg, cams, 5), MVT_ERR_INVALID);
    mvt_tracker_config_default(&cfg);
    cfg.volume.max[2] = cfg.volume.min[2];
    assert_int_equal(mvt_tracker_init(&g_tracker, &cfg, cams, 5), MVT_ERR_INVALID);
    /* the body's and the population's parameters outside their physical ranges (more in test_body) */
    mvt_tracker_config_default(&cfg);
    cfg.body.halfwidth_m = NAN;
    assert_int_equal(mvt_tracker_init(&g_tracker, &cfg, cams, 5), MVT_ERR_INVALID);
    mvt_tracker_config_default(&cfg);
    cfg.population.p_detect = 1.0f;
    assert_int_equal(mvt_tracker_init(&g_tracker, &cfg, cams, 5), MVT_ERR_INVALID);
    mvt_tracker_config_default(&cfg);
    cfg.population.stay_s = INFINITY;
    assert_int_equal(mvt_tracker_init(&g_tracker, &cfg, cams, 5), MVT_ERR_INVALID);
    mvt_tracker_config_default(&cfg);
    cfg.gate = (mvt_gate_t)7;
    assert_int_equal(mvt_tracker_init(&g_tracker, &cfg, cams, 5), MVT_ERR_INVALID);
    mvt_tracker_config_default(&cfg);
    cfg.gate = MVT_GATE_PAPER;
    assert_int_equal(mvt_tracker_init(&g_tracker, &cfg, cams, 5), MVT_OK);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mvt_cv_predict_constant_velocity_moves_and_grows),
        cmocka_unit_test(test_mvt_cv_update_point_outlier_gated_state_unchanged),
        cmocka_unit_test(test_mvt_cv_truncate_matches_quadrature),
        cmocka_unit_test(test_mvt_cv_truncate_ground_keeps_height),
        cmocka_unit_test(test_mvt_pkf_innovation_behind_camera_refused),
        cmocka_unit_test(test_mvt_tracker_step_straight_walk_pkf_tracked),
        cmocka_unit_test(test_mvt_tracker_step_straight_walk_kf_tracked),
        cmocka_unit_test(test_mvt_tracker_paper_gate_decides_heads),
        cmocka_unit_test(test_mvt_tracker_step_unseen_track_coasts_then_dies),
        cmocka_unit_test(test_mvt_tracker_resume_continues_and_refuses_bad_state),
        cmocka_unit_test(test_mvt_tracker_step_hostile_detections_counted_not_fatal),
        cmocka_unit_test(test_mvt_tracker_init_bad_config_rejected),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
