/* Unit tests of mvt_assoc: the Hungarian solver against exhaustive enumeration. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>

#include "mvt_assoc.h"
#include "test_support.h"

static mvt_assoc_ws_t g_ws;

/* Minimum over all injective row -> column maps (forbidden entries < 0 may be skipped: the row
 * stays unassigned at cost `forbid_penalty`), by recursion over rows. */
static double brute(const mvt_real *c, int nr, int nc, int r, unsigned used, double penalty)
{
    if (r == nr) {
        return 0.0;
    }
    double best = penalty + brute(c, nr, nc, r + 1, used, penalty); /* row r unassigned */
    for (int j = 0; j < nc; j++) {
        const mvt_real x = c[r * nc + j];
        if ((used & (1u << j)) || x < 0) {
            continue;
        }
        const double v = x + brute(c, nr, nc, r + 1, used | (1u << j), penalty);
        if (v < best) {
            best = v;
        }
    }
    return best;
}

/* Random nr x nc matrices with a share `forbid` of forbidden entries, nr <= max_rows: the solver's
 * choice is distinct feasible columns whose cost equals the exhaustive optimum among assignments
 * that leave the fewest rows unassigned. */
static void check_random(uint32_t seed, int trials, int max_rows, int max_extra_cols, double forbid)
{
    test_rng_t rng = {seed};
    for (int trial = 0; trial < trials; trial++) {
        const int nr = 1 + (int)(test_uniform(&rng) * max_rows);
        const int nc = nr + (int)(test_uniform(&rng) * (max_extra_cols + 1));
        mvt_real c[8 * 12];
        for (int i = 0; i < nr * nc; i++) {
            c[i] = test_uniform(&rng) < forbid ? -1.0f : (mvt_real)(test_uniform(&rng) * 20.0);
        }
        int a[8];
        assert_int_equal(mvt_assoc_solve(c, nr, nc, nc, a, &g_ws), MVT_OK);
        double cost = 0.0;
        int unassigned = 0;
        unsigned used = 0;
        for (int r = 0; r < nr; r++) {
            if (a[r] < 0) {
                unassigned++;
                continue;
            }
            assert_true(a[r] < nc);
            assert_false(used & (1u << a[r]));
            used |= 1u << a[r];
            assert_true(c[r * nc + a[r]] >= 0.0f);
            cost += c[r * nc + a[r]];
        }
        const double penalty = 1e6; /* makes the brute force maximise the matched rows first */
        const double ref = brute(c, nr, nc, 0, 0, penalty);
        assert_float_equal(cost + penalty * unassigned, ref, 1e-3);
    }
}

static void test_mvt_assoc_solve_random_matrices_match_brute_force(void **state)
{
    (void)state;
    check_random(12345, 400, 5, 3, 0.3);
}

/* Mostly forbidden entries: rows fall into groups linked through shared columns, some groups with
 * more rows than feasible columns. */
static void test_mvt_assoc_solve_sparse_groups_match_brute_force(void **state)
{
    (void)state;
    check_random(777, 300, 8, 4, 0.8);
}

static void test_mvt_assoc_solve_greedy_trap_global_optimum(void **state)
{
    (void)state;
    /* greedy takes (0,0)=1 and then must give row 1 column 1 = 10: total 11; optimum is 2 + 3 */
    const mvt_real c[4] = {1, 2, 3, 10};
    int a[2];
    assert_int_equal(mvt_assoc_solve(c, 2, 2, 2, a, &g_ws), MVT_OK);
    assert_int_equal(a[0], 1);
    assert_int_equal(a[1], 0);
}

static void test_mvt_assoc_solve_bad_sizes_invalid(void **state)
{
    (void)state;
    const mvt_real c[4] = {1, 2, 3, 4};
    int a[2];
    assert_int_equal(mvt_assoc_solve(c, 2, 1, 1, a, &g_ws), MVT_ERR_INVALID);
    assert_int_equal(mvt_assoc_solve(c, 0, 2, 2, a, &g_ws), MVT_ERR_INVALID);
    assert_int_equal(mvt_assoc_solve(c, 1, 2, 1, a, &g_ws), MVT_ERR_INVALID);
    assert_int_equal(mvt_assoc_solve(c, MVT_ASSOC_MAX_ROWS + 1, MVT_ASSOC_MAX_COLS, MVT_ASSOC_MAX_COLS, a, &g_ws),
                     MVT_ERR_INVALID);
    const mvt_real nan_row[2] = {NAN, INFINITY};
    assert_int_equal(mvt_assoc_solve(nan_row, 1, 2, 2, a, &g_ws), MVT_OK);
    assert_int_equal(a[0], -1);
}

static void test_mvt_assoc_solve_full_capacity_identity(void **state)
{
    (void)state;
    static mvt_real c[MVT_ASSOC_MAX_ROWS * MVT_ASSOC_MAX_COLS];
    const int nr = MVT_ASSOC_MAX_ROWS, nc = MVT_ASSOC_MAX_COLS;
    for (int r = 0; r < nr; r++) {
        for (int j = 0; j < nc; j++) {
            c[r * nc + j] = (mvt_real)(1 + ((r * 7 + j * 13) % 17)); /* >= 1 everywhere ... */
        }
        c[r * nc + (nc - 1 - r)] = 0.0f; /* ... except one zero per row, distinct columns */
    }
    static int a[MVT_ASSOC_MAX_ROWS];
    assert_int_equal(mvt_assoc_solve(c, nr, nc, nc, a, &g_ws), MVT_OK);
    for (int r = 0; r < nr; r++) {
        assert_int_equal(a[r], nc - 1 - r);
    }
}

/* Matrices shaped as the tracker's per-camera assignment: n detections, then one column per row
 * that only that row may take (its "missed", at a cost above its other choices, or own_anywhere:
 * any), feasible entries with share `dense`, costs drawn from `levels` values (few levels: many
 * exact ties). The solver for that shape must give the general solver's assignment, row for row,
 * ties included. */
static void check_own_columns(uint32_t seed, int trials, int max_rows, int max_dets, double dense, int levels,
                              int own_anywhere)
{
    test_rng_t rng = {seed};
    static mvt_real c[MVT_ASSOC_MAX_ROWS * MVT_ASSOC_MAX_COLS];
    for (int trial = 0; trial < trials; trial++) {
        const int nr = 1 + (int)(test_uniform(&rng) * max_rows);
        const int nd = (int)(test_uniform(&rng) * (max_dets + 1));
        const int nc = nd + nr;
        for (int r = 0; r < nr; r++) {
            for (int j = 0; j < nd; j++) {
                c[r * nc + j] = test_uniform(&rng) < dense ? (mvt_real)(int)(test_uniform(&rng) * levels) : -1.0f;
            }
            for (int j = 0; j < nr; j++) {
                c[r * nc + nd + j] = j != r        ? -1.0f
                                     : own_anywhere ? (mvt_real)(int)(test_uniform(&rng) * levels)
                                                    : (mvt_real)levels;
            }
        }
        int a[MVT_ASSOC_MAX_ROWS], b[MVT_ASSOC_MAX_ROWS];
        assert_int_equal(mvt_assoc_solve(c, nr, nc, nc, a, &g_ws), MVT_OK);
        assert_int_equal(mvt_assoc_solve_own(c, nr, nc, nc, b, &g_ws), MVT_OK);
        for (int r = 0; r < nr; r++) {
            assert_int_equal(a[r], b[r]);
        }
    }
}

static void test_mvt_assoc_solve_own_same_as_general_solver(void **state)
{
    (void)state;
    check_own_columns(31, 2000, 12, 14, 0.5, 1000, 0); /* distinct costs, mostly */
    check_own_columns(32, 2000, 12, 14, 0.8, 4, 0);    /* many exact ties */
    check_own_columns(33, 2000, 12, 14, 0.6, 4, 1);    /* a row's own column any cost */
    check_own_columns(34, 300, MVT_ASSOC_MAX_ROWS, MVT_ASSOC_MAX_COLS - MVT_ASSOC_MAX_ROWS, 0.3, 50, 1);
}

/* Without the own-column shape it is the general solver. */
static void test_mvt_assoc_solve_own_other_shapes_fall_back(void **state)
{
    (void)state;
    const mvt_real c[6] = {1, 2, 5, 3, 10, 5}; /* the last two columns feasible for both rows */
    int a[2], b[2];
    assert_int_equal(mvt_assoc_solve(c, 2, 3, 3, a, &g_ws), MVT_OK);
    assert_int_equal(mvt_assoc_solve_own(c, 2, 3, 3, b, &g_ws), MVT_OK);
    assert_int_equal(a[0], b[0]);
    assert_int_equal(a[1], b[1]);
    assert_int_equal(mvt_assoc_solve_own(c, 2, 1, 1, b, &g_ws), MVT_ERR_INVALID);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mvt_assoc_solve_random_matrices_match_brute_force),
        cmocka_unit_test(test_mvt_assoc_solve_sparse_groups_match_brute_force),
        cmocka_unit_test(test_mvt_assoc_solve_greedy_trap_global_optimum),
        cmocka_unit_test(test_mvt_assoc_solve_bad_sizes_invalid),
        cmocka_unit_test(test_mvt_assoc_solve_full_capacity_identity),
        cmocka_unit_test(test_mvt_assoc_solve_own_same_as_general_solver),
        cmocka_unit_test(test_mvt_assoc_solve_own_other_shapes_fall_back),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
