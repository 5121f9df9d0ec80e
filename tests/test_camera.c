/* Unit tests of mvt_camera: behaviour from first principles (OpenCV comparisons: test_oracle.cpp). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "test_support.h"

static const double TOL = MVT_USE_DOUBLE ? 1e-9 : 2e-3;

static void test_mvt_cam_init_bad_params_rejected(void **state)
{
    (void)state;
    mvt_camera_params_t p;
    const double pos[3] = {0, 0, 2}, tgt[3] = {3, 3, 1};
    test_look_at(&p, pos, tgt, 400, 384, 288, NULL);
    mvt_camera_t c;
    assert_int_equal(mvt_cam_init(&c, &p), MVT_OK);
    mvt_camera_params_t q = p;
    q.camera_matrix[0] = 0;
    assert_int_equal(mvt_cam_init(&c, &q), MVT_ERR_INVALID);
    q = p;
    q.dist[1] = NAN;
    assert_int_equal(mvt_cam_init(&c, &q), MVT_ERR_NONFINITE);
    q = p;
    q.camera_matrix[8] = 2;
    assert_int_equal(mvt_cam_init(&c, &q), MVT_ERR_INVALID);
    q = p;
    q.width = 0;
    assert_int_equal(mvt_cam_init(&c, &q), MVT_ERR_INVALID);
    q = p;
    q.sigma_px = -1;
    assert_int_equal(mvt_cam_init(&c, &q), MVT_ERR_INVALID);
}

static void test_mvt_cam_project_target_lands_on_principal_point(void **state)
{
    (void)state;
    mvt_camera_params_t p;
    const double pos[3] = {1, -2, 2.5}, tgt[3] = {3, 2, 1};
    const double d[5] = {-0.3, 0.1, 0.001, 0.002, -0.01};
    test_look_at(&p, pos, tgt, 500, 350, 260, d);
    mvt_camera_t c;
    assert_int_equal(mvt_cam_init(&c, &p), MVT_OK);
    const mvt_real x[3] = {3, 2, 1};
    mvt_real uv[2];
    assert_int_equal(mvt_cam_project(&c, x, uv, NULL), MVT_OK);
    assert_float_equal(uv[0], 350, 1e-2);
    assert_float_equal(uv[1], 260, 1e-2);
    /* the camera centre is -R^T t */
    for (int i = 0; i < 3; i++) assert_float_equal(c.centre[i], pos[i], 1e-4);
    /* a point behind */
    const mvt_real b[3] = {(mvt_real)(2 * pos[0] - tgt[0]), (mvt_real)(2 * pos[1] - tgt[1]), (mvt_real)(2 * pos[2] - tgt[2])};
    assert_int_equal(mvt_cam_project(&c, b, uv, NULL), MVT_ERR_BEHIND);
}

/* k1 < 0: g(r) = r (1 + k1 r^2) peaks at r_f = 1 / sqrt(-3 k1) and maps farther points back into
 * the picture. Beyond r_f the model has no image: project refuses, undistort never lands there. */
static void test_mvt_cam_field_ends_where_the_distortion_folds(void **state)
{
    (void)state;
    mvt_camera_params_t p;
    const double pos[3] = {0, 0, 2}, tgt[3] = {3, 0, 2};
    const double d[5] = {-0.3, 0, 0, 0, 0};
    test_look_at(&p, pos, tgt, 400, 400, 300, d);
    p.width = 800;
    p.height = 600;
    mvt_camera_t c;
    assert_int_equal(mvt_cam_init(&c, &p), MVT_OK);
    const double rf = 1.0 / sqrt(0.9);
    assert_true((double)c.field_r2 <= (rf + 1.0 / 256) * (rf + 1.0 / 256));
    assert_true((double)c.field_r2 >= (rf - 2.0 / 256) * (rf - 2.0 / 256));
    /* camera looks along +x; normalised x = lateral offset / depth (3 m ahead) */
    mvt_real uv[2], jac[6];
    const mvt_real inside[3] = {3, (mvt_real)-0.9 * 3, 2}; /* r = 0.9 */
    assert_int_equal(mvt_cam_project(&c, inside, uv, jac), MVT_OK);
    const mvt_real folded[3] = {3, (mvt_real)-1.5 * 3, 2}; /* r = 1.5: the polynomial gives 0.4875 */
    assert_int_equal(mvt_cam_project(&c, folded, uv, jac), MVT_ERR_BEHIND);
    /* the pixel where the polynomial would put it undistorts to the in-field point (r = 0.5329) */
    const mvt_real px[2] = {(mvt_real)(400 + 400 * 0.4875), 300};
    mvt_real xn[2];
    assert_int_equal(mvt_cam_undistort(&c, px, xn), MVT_OK);
    assert_true(fabs(sqrt((double)(xn[0] * xn[0] + xn[1] * xn[1])) - 0.5329) < 2e-3);
    /* a pixel beyond the largest distorted radius g(r_f) = 0.7027 has no preimage */
    const mvt_real far[2] = {(mvt_real)(400 + 400 * 0.75), 300};
    assert_int_equal(mvt_cam_undistort(&c, far, xn), MVT_ERR_NUMERIC);
    /* no distortion: no fold */
    test_look_at(&p, pos, tgt, 400, 400, 300, NULL);
    assert_int_equal(mvt_cam_init(&c, &p), MVT_OK);
    assert_true(c.field_r2 > (mvt_real)1e20);
}

static void test_mvt_cam_project_jacobian_matches_finite_differences(void **state)
{
    (void)state;
    mvt_camera_t cams[5];
    assert_int_equal(test_room_cameras(cams, 1), 0);
    const mvt_real x[3] = {2.2f, 3.1f, 1.7f};
    for (int k = 0; k < 5; k++) {
        mvt_real uv[2], J[6];
        assert_int_equal(mvt_cam_project(&cams[k], x, uv, J), MVT_OK);
        for (int c = 0; c < 3; c++) {
            const mvt_real h = MVT_USE_DOUBLE ? MVT_R(1e-6) : MVT_R(1e-3);
            mvt_real xp[3] = {x[0], x[1], x[2]}, xm[3] = {x[0], x[1], x[2]}, up[2], um[2];
            xp[c] += h;
            xm[c] -= h;
            mvt_cam_project(&cams[k], xp, up, NULL);
            mvt_cam_project(&cams[k], xm, um, NULL);
            for (int r = 0; r < 2; r++) {
                const double fd = (double)(up[r] - um[r]) / (2 * (double)h);
                assert_true(fabs(fd - (double)J[r * 3 + c]) < 1e-3 * fabs(fd) + (MVT_USE_DOUBLE ? 1e-4 : 0.5));
            }
        }
    }
}

static void test_mvt_cam_undistort_round_trip_recovers_normalised_point(void **state)
{
    (void)state;
    mvt_camera_params_t p;
    const double pos[3] = {0, 0, 2.5}, tgt[3] = {3, 3, 1};
    const double d[5] = {-0.35, 0.15, 0.002, -0.001, -0.03}; /* strong barrel */
    test_look_at(&p, pos, tgt, 380, 380, 290, d);
    mvt_camera_t c;
    assert_int_equal(mvt_cam_init(&c, &p), MVT_OK);
    for (int i = 0; i <= 10; i++) {
        for (int j = 0; j <= 10; j++) {
            const mvt_real xn[2] = {MVT_R(-0.9) + MVT_R(0.18) * (mvt_real)i, MVT_R(-0.7) + MVT_R(0.14) * (mvt_real)j};
            mvt_real xd[2], uv[2], back[2];
            mvt_cam_distort(&c, xn, xd, NULL);
            uv[0] = c.fx * xd[0] + c.cx;
            uv[1] = c.fy * xd[1] + c.cy;
            assert_int_equal(mvt_cam_undistort(&c, uv, back), MVT_OK);
            assert_float_equal(back[0], xn[0], TOL);
            assert_float_equal(back[1], xn[1], TOL);
        }
    }
    const mvt_real bad[2] = {NAN, 3};
    mvt_real out[2];
    assert_int_equal(mvt_cam_undistort(&c, bad, out), MVT_ERR_NONFINITE);
}

static void test_mvt_cam_ray_passes_through_projected_point(void **state)
{
    (void)state;
    mvt_camera_t cams[5];
    assert_int_equal(test_room_cameras(cams, 1), 0);
    const mvt_real x[3] = {1.4f, 3.6f, 1.65f};
    for (int k = 0; k < 5; k++) {
        mvt_real uv[2], o[3], d[3];
        assert_int_equal(mvt_cam_project(&cams[k], x, uv, NULL), MVT_OK);
        assert_int_equal(mvt_cam_ray(&cams[k], uv, o, d), MVT_OK);
        /* distance of x from the ray */
        mvt_real v[3] = {x[0] - o[0], x[1] - o[1], x[2] - o[2]};
        const mvt_real t = v[0] * d[0] + v[1] * d[1] + v[2] * d[2];
        mvt_real e2 = 0;
        for (int i = 0; i < 3; i++) {
            const mvt_real e = v[i] - t * d[i];
            e2 += e * e;
        }
        assert_true(t > 0);
        assert_true(sqrt((double)e2) < (MVT_USE_DOUBLE ? 1e-9 : 1e-3));
    }
}

static void test_mvt_la_rodrigues_small_angle_is_orthonormal(void **state)
{
    (void)state;
    const mvt_real rv[3][3] = {{0, 0, 0}, {1e-6f, -2e-6f, 1e-6f}, {0.3f, -1.2f, 2.0f}};
    for (int c = 0; c < 3; c++) {
        mvt_real R[9];
        extern void mvt_la_rodrigues(const mvt_real rvec[3], mvt_real r[9]);
        mvt_la_rodrigues(rv[c], R);
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                double s = 0;
                for (int k = 0; k < 3; k++) s += (double)R[i * 3 + k] * (double)R[j * 3 + k];
                assert_true(fabs(s - (i == j)) < (MVT_USE_DOUBLE ? 1e-12 : 1e-5));
            }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mvt_cam_init_bad_params_rejected),
        cmocka_unit_test(test_mvt_cam_project_target_lands_on_principal_point),
        cmocka_unit_test(test_mvt_cam_field_ends_where_the_distortion_folds),
        cmocka_unit_test(test_mvt_cam_project_jacobian_matches_finite_differences),
        cmocka_unit_test(test_mvt_cam_undistort_round_trip_recovers_normalised_point),
        cmocka_unit_test(test_mvt_cam_ray_passes_through_projected_point),
        cmocka_unit_test(test_mvt_la_rodrigues_small_angle_is_orthonormal),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
