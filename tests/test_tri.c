/* Unit tests of mvt_tri: exact and noisy triangulation, outlier views, degenerate geometry. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "mvt_tri.h"
#include "test_support.h"

static void make_obs(const mvt_camera_t *cams, int n, const mvt_real x[3], mvt_tri_obs_t *obs, test_rng_t *rng, double sd)
{
    for (int k = 0; k < n; k++) {
        mvt_real uv[2];
        assert_int_equal(mvt_cam_project(&cams[k], x, uv, NULL), MVT_OK);
        if (rng != NULL) {
            uv[0] += (mvt_real)(sd * test_normal(rng));
            uv[1] += (mvt_real)(sd * test_normal(rng));
        }
        obs[k].cam = k;
        obs[k].var_px2 = (mvt_real)(sd > 0 ? sd * sd : 1.0);
        assert_int_equal(mvt_cam_undistort(&cams[k], uv, obs[k].xn), MVT_OK);
    }
}

static void test_mvt_tri_linear_exact_views_recover_point(void **state)
{
    (void)state;
    mvt_camera_t cams[5];
    assert_int_equal(test_room_cameras(cams, 1), 0);
    const mvt_real x[3] = {1.3f, 3.7f, 1.72f};
    mvt_tri_obs_t obs[5];
    make_obs(cams, 5, x, obs, NULL, 0);
    mvt_real e[3];
    for (int n = 2; n <= 5; n++) {
        assert_int_equal(mvt_tri_linear(cams, obs, n, e), MVT_OK);
        for (int i = 0; i < 3; i++) assert_float_equal(e[i], x[i], MVT_USE_DOUBLE ? 1e-9 : 2e-3);
    }
    assert_int_equal(mvt_tri_linear(cams, obs, 1, e), MVT_ERR_DEGENERATE);
}

static void test_mvt_tri_refine_noisy_views_error_matches_covariance(void **state)
{
    (void)state;
    mvt_camera_t cams[5];
    assert_int_equal(test_room_cameras(cams, 1), 0);
    const mvt_real x[3] = {3.5f, 2.0f, 1.7f};
    test_rng_t rng = {12345};
    double se2 = 0, tr = 0;
    const int N = 400;
    for (int t = 0; t < N; t++) {
        mvt_tri_obs_t obs[5];
        make_obs(cams, 5, x, obs, &rng, 3.0);
        mvt_real e[3], cov[9];
        assert_int_equal(mvt_tri_linear(cams, obs, 5, e), MVT_OK);
        assert_int_equal(mvt_tri_refine(cams, obs, 5, 5, e), MVT_OK);
        assert_int_equal(mvt_tri_covariance(cams, obs, 5, e, cov), MVT_OK);
        for (int i = 0; i < 3; i++) se2 += (double)((e[i] - x[i]) * (e[i] - x[i]));
        tr += (double)(cov[0] + cov[4] + cov[8]);
    }
    /* the ML point's mean squared error agrees with the first-order covariance within 20 % */
    const double ratio = se2 / tr;
    assert_true(ratio > 0.8 && ratio < 1.2);
}

static void test_mvt_tri_robust_outlier_view_excluded(void **state)
{
    (void)state;
    mvt_camera_t cams[5];
    assert_int_equal(test_room_cameras(cams, 1), 0);
    const mvt_real x[3] = {2.0f, 1.5f, 1.6f};
    mvt_tri_obs_t obs[5];
    make_obs(cams, 5, x, obs, NULL, 0);
    obs[2].xn[0] += MVT_R(0.3); /* ~120 px off */
    mvt_real e[3];
    uint32_t inl = 0;
    int n = 0;
    assert_int_equal(mvt_tri_robust(cams, obs, 5, 5, e, &inl, &n), MVT_OK);
    assert_int_equal(n, 4);
    assert_int_equal(inl, 0x1bu);
    for (int i = 0; i < 3; i++) assert_float_equal(e[i], x[i], 5e-3);
}

static void test_mvt_tri_linear_parallel_rays_degenerate(void **state)
{
    (void)state;
    mvt_camera_t cams[2];
    mvt_camera_params_t p;
    const double a[3] = {0, 0, 2}, b[3] = {1e-7, 0, 2}, t[3] = {3, 0, 2};
    test_look_at(&p, a, t, 400, 384, 288, NULL);
    mvt_cam_init(&cams[0], &p);
    test_look_at(&p, b, t, 400, 384, 288, NULL);
    mvt_cam_init(&cams[1], &p);
    mvt_tri_obs_t obs[2] = {{0, {0, 0}, 1}, {1, {0, 0}, 1}};
    mvt_real e[3];
    assert_int_not_equal(mvt_tri_linear(cams, obs, 2, e), MVT_OK);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mvt_tri_linear_exact_views_recover_point),
        cmocka_unit_test(test_mvt_tri_refine_noisy_views_error_matches_covariance),
        cmocka_unit_test(test_mvt_tri_robust_outlier_view_excluded),
        cmocka_unit_test(test_mvt_tri_linear_parallel_rays_degenerate),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
