/* Particle filter: mask decoding (valid and hostile runs), likelihood images against a direct
 * double-precision 2D convolution, weights, resampling, estimates, and the tracker end to end on
 * painted masks (two people, reproducible with a seed). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "mvt_pft.h"
#include "test_support.h"

static mvt_mask_t g_mask;

static void test_mask_from_runs_valid_decodes(void **state)
{
    (void)state;
    /* 8 x 2 mask for a 32 x 8 image (factor 4): rows 00111000 / 11000001 */
    const int32_t runs[] = {2, 3, 3, 2, 5, 1};
    uint8_t hue[16], sat[16];
    for (int i = 0; i < 16; i++) hue[i] = (uint8_t)i, sat[i] = (uint8_t)(255 - i);
    assert_int_equal(mvt_mask_from_runs(&g_mask, 32, 8, 8, 2, runs, 6, hue, sat, 16), MVT_OK);
    const uint8_t want[16] = {0, 0, 1, 1, 1, 0, 0, 0, 1, 1, 0, 0, 0, 0, 0, 1};
    assert_memory_equal(g_mask.fg, want, 16);
    assert_int_equal(g_mask.scale, 4);
    assert_int_equal(g_mask.num_fg, 6);
    assert_true(g_mask.has_colour);
    assert_int_equal(g_mask.hue[7], 7);
    /* a first run of 0: starts with foreground */
    const int32_t runs0[] = {0, 1, 15};
    assert_int_equal(mvt_mask_from_runs(&g_mask, 8, 2, 8, 2, runs0, 3, NULL, NULL, 0), MVT_OK);
    assert_int_equal(g_mask.fg[0], 1);
    assert_int_equal(g_mask.num_fg, 1);
    assert_false(g_mask.has_colour);
}

/* mvt_mask_fg_near against a brute-force reference over every foreground mask pixel (a mask pixel
 * (i, j) covers raw [i s, (i + 1) s) x [j s, (j + 1) s); the square [u - r, u + r] x [v - r, v + r]
 * touches it when the intervals meet), on sparse random masks at three scales and random squares,
 * some reaching outside the picture; then the edges: empty mask, NaN, negative and huge r. */
static void test_mask_fg_near_matches_brute_force(void **state)
{
    (void)state;
    test_rng_t rng = {77};
    static const int scales[3] = {1, 2, 4};
    for (int si = 0; si < 3; si++) {
        const int sc = scales[si], w = 96 / sc, h = 64 / sc;
        int32_t runs[4096];
        int n = 0, total = 0, val = 0;
        while (total < w * h && n < 4095) { /* sparse: long background runs, short foreground ones */
            int len = val ? 1 + (int)(test_uniform(&rng) * 3) : (int)(test_uniform(&rng) * 200);
            len = total + len > w * h ? w * h - total : len;
            runs[n++] = len;
            total += len;
            val ^= 1;
        }
        if (total < w * h) runs[n++] = w * h - total;
        assert_int_equal(mvt_mask_from_runs(&g_mask, w * sc, h * sc, w, h, runs, n, NULL, NULL, 0), MVT_OK);
        int hits = 0, misses = 0;
        for (int q = 0; q < 3000; q++) {
            const mvt_real uv[2] = {(mvt_real)(test_uniform(&rng) * 120.0 - 12.0),
                                    (mvt_real)(test_uniform(&rng) * 88.0 - 12.0)};
            const mvt_real r = (mvt_real)(test_uniform(&rng) * 10.0);
            int want = 0;
            for (int j = 0; j < h && !want; j++) {
                for (int i = 0; i < w && !want; i++) {
                    want = g_mask.fg[j * w + i] && (double)(i * sc) <= (double)uv[0] + (double)r &&
                           (double)((i + 1) * sc) > (double)uv[0] - (double)r &&
                           (double)(j * sc) <= (double)uv[1] + (double)r &&
                           (double)((j + 1) * sc) > (double)uv[1] - (double)r;
                }
            }
            assert_int_equal(mvt_mask_fg_near(&g_mask, uv, r), want);
            hits += want;
            misses += !want;
        }
        assert_true(hits > 300 && misses > 300); /* both answers exercised */
        const mvt_real mid[2] = {48.0f, 32.0f}, nan_uv[2] = {NAN, 32.0f};
        assert_int_equal(mvt_mask_fg_near(&g_mask, mid, 1e30f), g_mask.num_fg > 0);
        assert_int_equal(mvt_mask_fg_near(&g_mask, mid, INFINITY), 0);
        assert_int_equal(mvt_mask_fg_near(&g_mask, mid, -1.0f), 0);
        assert_int_equal(mvt_mask_fg_near(&g_mask, nan_uv, 5.0f), 0);
    }
    const mvt_real mid[2] = {48.0f, 32.0f};
    static mvt_mask_t empty;
    memset(&empty, 0, sizeof(empty));
    assert_int_equal(mvt_mask_fg_near(&empty, mid, 1e30f), 0);
}

/* Paints a person at mask pixel column cx: a head disc of radius 3 whose top is row top, a body
 * 11 pixels wide from row top + 6 down to row bottom; a gap of `hole` background rows under the
 * head (a fragmenting hole). */
static void paint_person(int cx, int top, int bottom, int hole)
{
    const int w = g_mask.width;
    for (int y = top; y <= top + 6 && y < g_mask.height; y++) {
        for (int x = cx - 3; x <= cx + 3; x++) {
            if ((x - cx) * (x - cx) + (y - top - 3) * (y - top - 3) <= 10 && x >= 0 && x < w && y >= 0) {
                g_mask.fg[y * w + x] = 1;
            }
        }
    }
    for (int y = top + 6 + hole; y <= bottom && y < g_mask.height; y++) {
        for (int x = cx - 5; x <= cx + 5; x++) {
            if (x >= 0 && x < w) {
                g_mask.fg[y * w + x] = 1;
            }
        }
    }
}

/* The expected point of a top at mask row r: the mean column of the top two rows' foreground over
 * columns [lo, hi] (the top run and one beside each end), the row's upper quarter; scale s. */
static void top_point(int r, int lo, int hi, int s, double out[2])
{
    double sum = 0;
    int n = 0;
    for (int x = lo; x <= hi; x++) {
        if (g_mask.fg[r * g_mask.width + x] || g_mask.fg[(r + 1) * g_mask.width + x]) {
            sum += x;
            n++;
        }
    }
    out[0] = (sum / n + 0.5) * s - 0.5;
    out[1] = r * s - 0.5 + 0.25 * s;
}

/* mvt_mask_top_in_band on painted people (scale 4, 96 x 72 mask): a head's top in its own band;
 * the lower of two merged heads in its band; nothing where the band holds only the slope of a
 * head's side, a torso fragment under a hole, a shoulder line, a head cut by the picture's top, or
 * the inside of a silhouette; and the hostile arguments. */
static void test_mask_top_in_band_finds_heads_only(void **state)
{
    (void)state;
    const int s = 4, w = 96, h = 72;
    memset(&g_mask, 0, sizeof(g_mask));
    g_mask.width = w;
    g_mask.height = h;
    g_mask.scale = s;
    paint_person(30, 20, 70, 0); /* tall person, head top row 20 */
    paint_person(38, 26, 70, 0); /* shorter neighbour, merged into one silhouette, head top row 26 */
    paint_person(70, 30, 70, 2); /* a person with a hole under the head */
    const mvt_real max_w = 9.0f * s, clear = 6.0f * s; /* 9 mask pixels wide (the body: 11), 6 rows clear */
    mvt_real uv[2];
    double want[2];
    /* the tall head in a band around it */
    assert_int_equal(mvt_mask_top_in_band(&g_mask, 30 * s + 2, 2 * s, 15 * s, 30 * s, max_w, clear, uv), 1);
    top_point(20, 28, 32, s, want);
    assert_true(fabs((double)uv[0] - want[0]) < 1e-3 && fabs((double)uv[1] - want[1]) < 1e-3);
    assert_true(fabs((double)uv[0] - (30 * s + 1.5)) < 1e-3); /* the disc's middle column */
    /* the lower head of the merged pair, in its own band (its top rows are its own) */
    assert_int_equal(mvt_mask_top_in_band(&g_mask, 38 * s + 2, 1.5f * s, 22 * s, 34 * s, max_w, clear, uv), 1);
    top_point(26, 36, 40, s, want);
    assert_true(fabs((double)uv[0] - want[0]) < 1e-3 && fabs((double)uv[1] - want[1]) < 1e-3);
    /* a band on the tall head's side: its first row is the slope, which rises out of the band */
    assert_int_equal(mvt_mask_top_in_band(&g_mask, 33 * s + 2, 0.5f * s, 15 * s, 30 * s, max_w, clear, uv), 0);
    /* the torso fragment under the hole: the head is above it */
    assert_int_equal(mvt_mask_top_in_band(&g_mask, 70 * s + 2, 2 * s, 37 * s, 45 * s, max_w, clear, uv), 0);
    /* ... the head itself is found, and with no clearance or width asked the fragment is a top */
    assert_int_equal(mvt_mask_top_in_band(&g_mask, 70 * s + 2, 2 * s, 25 * s, 45 * s, max_w, clear, uv), 1);
    assert_true(fabs((double)uv[1] - (30 * s - 0.5 + 0.25 * s)) < 1e-3);
    assert_int_equal(mvt_mask_top_in_band(&g_mask, 70 * s + 2, 2 * s, 37 * s, 45 * s, 1e3f, 0, uv), 1);
    assert_true(fabs((double)uv[1] - (38 * s - 0.5 + 0.25 * s)) < 1e-3);
    /* a window inside a silhouette (the body below both heads): no top */
    assert_int_equal(mvt_mask_top_in_band(&g_mask, 34 * s + 2, 2 * s, 40 * s, 60 * s, max_w, clear, uv), 0);
    /* a top wider than max_width: a shoulder line (the fragment's 11 px top, asked for 6) */
    assert_int_equal(mvt_mask_top_in_band(&g_mask, 70 * s + 2, 2 * s, 37 * s, 45 * s, 6.0f * s, 0, uv), 0);
    /* a head cut by the picture's top edge */
    memset(g_mask.fg, 0, sizeof(g_mask.fg));
    paint_person(50, 0, 70, 0);
    assert_int_equal(mvt_mask_top_in_band(&g_mask, 50 * s + 2, 2 * s, 0, 10 * s, max_w, clear, uv), 0);
    /* ... one row lower it is a top (its clearance reaches the picture's edge) */
    memset(g_mask.fg, 0, sizeof(g_mask.fg));
    paint_person(50, 1, 70, 0);
    assert_int_equal(mvt_mask_top_in_band(&g_mask, 50 * s + 2, 2 * s, 0, 10 * s, max_w, clear, uv), 1);
    /* ... and a head cut by the picture's side: its outline may rise beyond the edge */
    memset(g_mask.fg, 0, sizeof(g_mask.fg));
    paint_person(1, 20, 70, 0);
    assert_int_equal(mvt_mask_top_in_band(&g_mask, 1 * s + 2, 2 * s, 15 * s, 30 * s, max_w, clear, uv), 0);
    paint_person(w - 2, 20, 70, 0);
    assert_int_equal(mvt_mask_top_in_band(&g_mask, (w - 2) * s + 2, 2 * s, 15 * s, 30 * s, max_w, clear, uv), 0);
    memset(g_mask.fg, 0, sizeof(g_mask.fg));
    paint_person(4, 20, 70, 0); /* its head clear of the edge */
    assert_int_equal(mvt_mask_top_in_band(&g_mask, 4 * s + 2, 2 * s, 15 * s, 30 * s, max_w, clear, uv), 1);
    /* hostile arguments */
    assert_int_equal(mvt_mask_top_in_band(&g_mask, NAN, 2 * s, 0, 10 * s, max_w, clear, uv), 0);
    assert_int_equal(mvt_mask_top_in_band(&g_mask, 50 * s, -1, 0, 10 * s, max_w, clear, uv), 0);
    assert_int_equal(mvt_mask_top_in_band(&g_mask, 50 * s, 2 * s, 10 * s, 0, max_w, clear, uv), 0);
    assert_int_equal(mvt_mask_top_in_band(&g_mask, 50 * s, 2 * s, 0, INFINITY, max_w, clear, uv), 0);
    assert_int_equal(mvt_mask_top_in_band(&g_mask, 50 * s, 2 * s, 0, 10 * s, max_w, -1, uv), 0);
    assert_int_equal(mvt_mask_top_in_band(&g_mask, 1e30f, 2 * s, 0, 10 * s, max_w, clear, uv), 0);
    assert_int_equal(mvt_mask_top_in_band(&g_mask, 50 * s, 1e30f, -1e30f, 1e30f, 1e30f, 1e30f, uv), 1);
    static mvt_mask_t empty;
    memset(&empty, 0, sizeof(empty));
    assert_int_equal(mvt_mask_top_in_band(&empty, 50 * s, 2 * s, 0, 10 * s, max_w, clear, uv), 0);
}

static void test_mask_from_runs_hostile_rejected(void **state)
{
    (void)state;
    uint8_t hs[16] = {0};
    const int32_t ok[] = {16};
    const int32_t neg[] = {20, -4};
    const int32_t short_[] = {10, 5};
    const int32_t over[] = {10, 7};
    const int32_t huge[] = {INT32_MAX, INT32_MAX, 16};
    struct { int iw, ih, w, h; const int32_t *r; int n; const uint8_t *hue; int nhs; } cases[] = {
        {32, 8, 8, 2, neg, 2, NULL, 0},      /* negative run */
        {32, 8, 8, 2, short_, 2, NULL, 0},   /* runs sum below w * h */
        {32, 8, 8, 2, over, 2, NULL, 0},     /* ... above */
        {32, 8, 8, 2, huge, 3, NULL, 0},     /* overflow of a naive int sum */
        {30, 8, 8, 2, ok, 1, NULL, 0},       /* image not a multiple of the mask */
        {32, 4, 8, 2, ok, 1, NULL, 0},       /* unequal factors */
        {32, 8, 8, 2, ok, 1, hs, 15},        /* hue/sat count neither 0 nor w * h */
        {32, 8, 8, 2, ok, 1, NULL, 16},      /* count without arrays */
        {32, 8, 8, 2, NULL, 1, NULL, 0},     /* runs NULL with a count */
        {32, 8, 0, 2, ok, 1, NULL, 0},       /* zero size */
        {32, 8, 8, 2, ok, -1, NULL, 0},      /* negative count */
        {32767, 32767, 32767, 32767, ok, 1, NULL, 0}, /* over MVT_MAX_MASK_PIXELS */
    };
    for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
        g_mask.width = 99;
        const mvt_err_t e = mvt_mask_from_runs(&g_mask, cases[i].iw, cases[i].ih, cases[i].w, cases[i].h, cases[i].r,
                                               cases[i].n, cases[i].hue, cases[i].hue, cases[i].nhs);
        if (e != MVT_ERR_INVALID) fail_msg("case %zu accepted", i);
        assert_int_equal(g_mask.width, 0);
    }
}

static mvt_pf_image_t g_img;
static mvt_pf_blur_ws_t g_ws;

/* D against max(direct 2D discrete Gaussian convolution in double, p_B), zero outside. */
static void check_image(int w, int h, int scale, double sigma_px, unsigned seed)
{
    srand(seed);
    int32_t runs[4096];
    int n = 0, total = 0, val = 0;
    while (total < w * h && n < 4095) {
        int len = val ? 1 + rand() % 12 : rand() % 40;
        if (total + len > w * h) len = w * h - total;
        runs[n++] = len;
        total += len;
        val ^= 1;
    }
    if (total < w * h) runs[n++] = w * h - total;
    assert_int_equal(mvt_mask_from_runs(&g_mask, w * scale, h * scale, w, h, runs, n, NULL, NULL, 0), MVT_OK);
    mvt_pf_model_t model = {(mvt_real)sigma_px, 0.2f, 0.05f, 0.1f, 0.1f, 0.1f};
    mvt_pf_tables_t tab;
    assert_int_equal(mvt_pf_tables_init(&tab, &model), MVT_OK);
    mvt_pf_image_build(&g_img, &g_mask, &tab, (mvt_real)sigma_px, &g_ws);
    const double s = sigma_px / scale;
    const int r = (int)ceil(3 * s);
    double norm = 0;
    for (int dy = -r; dy <= r; dy++)
        for (int dx = -r; dx <= r; dx++) norm += exp(-(dx * dx + dy * dy) / (2 * s * s));
    double worst = 0;
    for (int y = 0; y < h; y++) {
        for (int x = 0; x < w; x++) {
            double acc = 0;
            for (int dy = -r; dy <= r; dy++)
                for (int dx = -r; dx <= r; dx++) {
                    const int u = x + dx, v = y + dy;
                    if (u >= 0 && v >= 0 && u < w && v < h && g_mask.fg[v * w + u])
                        acc += exp(-(dx * dx + dy * dy) / (2 * s * s));
                }
            const double want = fmax(acc / norm, 0.2);
            const double got = g_img.d[y * w + x] / 255.0;
            worst = fmax(worst, fabs(got - want));
        }
    }
    if (worst > 1.0 / 255 + 1e-3) fail_msg("%dx%d scale %d: worst |D - reference| %.5f", w, h, scale, worst);
}

static void test_image_build_matches_direct_convolution(void **state)
{
    (void)state;
    check_image(192, 144, 4, 4.0, 1);  /* the default: sigma 1 mask pixel */
    check_image(96, 72, 8, 4.0, 2);    /* coarser mask: sigma 0.5 */
    check_image(160, 120, 2, 4.0, 3);  /* finer mask: sigma 2 */
    check_image(40, 30, 1, 6.0, 4);    /* full resolution, wider blur */
}

static mvt_pf_pool_t g_pool, g_scratch;

static void test_normalise_matches_double_and_ess(void **state)
{
    (void)state;
    g_pool.n = 500;
    double ref[500], sum = 0;
    for (int i = 0; i < 500; i++) {
        g_pool.w[i] = (mvt_real)(-300.0 - 40.0 * sin(i * 0.37)); /* exp() of these underflows float */
        ref[i] = exp(-40.0 * sin(i * 0.37) + 40.0);
    }
    for (int i = 0; i < 500; i++) sum += ref[i];
    double sq = 0;
    for (int i = 0; i < 500; i++) ref[i] /= sum, sq += ref[i] * ref[i];
    const mvt_real ess = mvt_pf_normalise(&g_pool);
    for (int i = 0; i < 500; i++) assert_true(fabs(g_pool.w[i] - ref[i]) < 1e-5 + 1e-4 * ref[i]);
    assert_true(fabs(ess - 1.0 / sq) < 1e-3 / sq);
    g_pool.w[3] = NAN;
    assert_true(mvt_pf_normalise(&g_pool) == 0);
    assert_true(fabs(g_pool.w[7] - 1.0 / 500) < 1e-9);
}

static void test_resample_systematic_copies_floor_or_ceil(void **state)
{
    (void)state;
    mvt_rng_t rng;
    mvt_rng_seed(&rng, 5, 1);
    g_pool.n = 200;
    double sum = 0;
    for (int i = 0; i < 200; i++) {
        g_pool.w[i] = (mvt_real)(1.0 + (i % 7) * (i % 3));
        sum += g_pool.w[i];
        g_pool.x[i] = (mvt_real)i;
    }
    double w[200];
    for (int i = 0; i < 200; i++) g_pool.w[i] = (mvt_real)(g_pool.w[i] / sum), w[i] = g_pool.w[i];
    mvt_pf_resample(&g_pool, &rng, &g_scratch);
    int count[200] = {0};
    for (int i = 0; i < 200; i++) count[(int)g_pool.x[i]]++;
    for (int i = 0; i < 200; i++) {
        const double e = 200 * w[i];
        if (count[i] < floor(e) - 1e-6 - 1 || count[i] > ceil(e) + 1e-6) fail_msg("particle %d: %d copies for %.2f", i, count[i], e);
        assert_true(fabs(g_pool.w[i] - 1.0 / 200) < 1e-9);
    }
}

static void test_estimate_box_is_heaviest_set(void **state)
{
    (void)state;
    g_pool.n = 100;
    for (int i = 0; i < 100; i++) {
        g_pool.x[i] = (mvt_real)i;
        g_pool.y[i] = (mvt_real)(-i);
        g_pool.z[i] = (mvt_real)(i % 10);
        g_pool.vx[i] = g_pool.vy[i] = g_pool.vz[i] = 0;
        g_pool.h[i] = 0.95f;
        g_pool.s[i] = 0.5f;
        g_pool.w[i] = i < 10 ? 0.096f : 0.04f / 90; /* the first 10 carry 0.96 */
    }
    uint16_t order[MVT_MAX_PARTICLES];
    mvt_pf_estimate_t e;
    mvt_pf_estimate(&g_pool, 0.95f, 0.97f, order, &e);
    assert_int_equal(e.box_count, 10);
    assert_true(e.box_min[0] == 0 && e.box_max[0] == 9 && e.box_min[1] == -9 && e.box_max[1] == 0);
    assert_true(fabs(e.hue - 0.95) < 1e-4); /* circular mean near the wrap */
    double mx = 0;
    for (int i = 0; i < 100; i++) mx += g_pool.w[i] * i;
    assert_true(fabs(e.mean[0] - mx) < 1e-3);
}

/* ---- weights: both particle models against the general projection -------------------------- */

static mvt_camera_t g_wcams[5];
static mvt_pf_image_t g_wimg[5];
static mvt_mask_t g_wmask[5];

/* D at a world point through mvt_cam_project (the Jacobian-capable path, checked against OpenCV in
 * test_camera), or `unseen` outside the image / behind the camera (the level whose log term is 0:
 * 255 for a point expected on the body, 0 for one expected on background). */
static mvt_pf_fov_t g_wfov[5];
static int ref_level(int k, const double xw[3], int unseen, int *idx_out)
{
    const mvt_real x[3] = {(mvt_real)xw[0], (mvt_real)xw[1], (mvt_real)xw[2]};
    mvt_real uv[2], xc[3];
    *idx_out = -1;
    mvt_cam_to_camera(&g_wcams[k], x, xc);
    const mvt_pf_fov_t *f = &g_wfov[k]; /* outside the lens model's window: not projected */
    if (xc[2] > 1e-3 && !(xc[0] / xc[2] >= f->x_min && xc[0] / xc[2] <= f->x_max && xc[1] / xc[2] >= f->y_min &&
                          xc[1] / xc[2] <= f->y_max))
        return unseen;
    if (mvt_cam_project(&g_wcams[k], x, uv, NULL) != MVT_OK) return unseen;
    const int idx = mvt_pf_image_index(&g_wimg[k], uv[0], uv[1]);
    *idx_out = idx;
    return idx >= 0 ? g_wimg[k].d[idx] : unseen;
}

static double ref_colour(const mvt_pf_tables_t *tab, int k, int idx, double h, double s)
{
    if (idx < 0 || !g_wmask[k].fg[idx]) return tab->log_colour_background;
    const int hq = (int)(h * 256) & 255, sq = (int)(s * 255 + 0.5);
    int dh = abs(g_wmask[k].hue[idx] - hq);
    dh = dh > 128 ? 256 - dh : dh;
    return tab->log_h[dh] + tab->log_s[abs(g_wmask[k].sat[idx] - sq)];
}

/* g_pool: 300 particles spread over the room and beyond it (some outside a view's image), random
 * colours, zero weights. */
static void scatter_pool(test_rng_t *r)
{
    g_pool.n = 300;
    for (int i = 0; i < g_pool.n; i++) {
        g_pool.x[i] = (mvt_real)(-0.5 + 7 * test_uniform(r));
        g_pool.y[i] = (mvt_real)(-0.5 + 6 * test_uniform(r));
        g_pool.z[i] = (mvt_real)(0.9 + 1.2 * test_uniform(r));
        g_pool.h[i] = (mvt_real)test_uniform(r);
        g_pool.s[i] = (mvt_real)test_uniform(r);
        g_pool.w[i] = 0;
    }
}

static void test_weight_point_and_column_match_projection(void **state)
{
    (void)state;
    assert_int_equal(test_room_cameras(g_wcams, 1), 0);
    mvt_pf_model_t model = {4.0f, 0.2f, 0.05f, 0.1f, 0.5f, 0.5f};
    static mvt_pf_tables_t tab;
    assert_int_equal(mvt_pf_tables_init(&tab, &model), MVT_OK);
    mvt_pf_fov_t *fovs = g_wfov;
    test_rng_t r = {0x5eedULL};
    for (int k = 0; k < 5; k++) {
        /* random likelihood levels (not a blur: every level is exercised) and colours */
        g_wmask[k].width = 192; g_wmask[k].height = 144; g_wmask[k].scale = 4; g_wmask[k].has_colour = k != 2;
        g_wimg[k].width = 192; g_wimg[k].height = 144; g_wimg[k].scale = 4; g_wimg[k].mask = &g_wmask[k];
        for (int i = 0; i < 192 * 144; i++) {
            g_wimg[k].d[i] = (uint8_t)(test_uniform(&r) * 256);
            g_wmask[k].fg[i] = g_wimg[k].d[i] > 150;
            g_wmask[k].hue[i] = (uint8_t)(test_uniform(&r) * 256);
            g_wmask[k].sat[i] = (uint8_t)(test_uniform(&r) * 256);
        }
        mvt_pf_fov_init(&fovs[k], &g_wcams[k], 0.05f);
    }
    g_wimg[3].width = 0; /* a camera without a mask this frame: skipped */
    const mvt_pf_body_t body = {0.06f, 0.06f, 0.7f, 0.3f, 0.9f, 0.0f, 0.0f}; /* no face, no clear column: see the claims test */
    for (int column = 0; column <= 1; column++) {
        scatter_pool(&r);
        mvt_real on_fg[5];
        mvt_pf_weight(&g_pool, g_wcams, fovs, g_wimg, 5, &tab, 1, column ? &body : NULL, 0.5f, NULL, on_fg, NULL);
        int off = 0, n_fg[5] = {0};
        const int fg_level = (tab.d_floor + 255) / 2;
        for (int i = 0; i < g_pool.n; i++) {
            double want = 0;
            for (int k = 0; k < 5; k++) {
                if (k == 3) continue;
                const double x = g_pool.x[i], y = g_pool.y[i], z = g_pool.z[i];
                int idx;
                double lw;
                if (!column) {
                    const double p[3] = {x, y, z};
                    const int l = ref_level(k, p, 255, &idx);
                    lw = tab.log_d[l];
                    n_fg[k] += idx >= 0 && l > fg_level;
                } else {
                    const double above[3] = {x, y, z + 0.06}, head[3] = {x, y, z - 0.06};
                    const double legs[3] = {x, y, 0.3 * z}, torso[3] = {x, y, 0.7 * z};
                    int ia, ih, il;
                    lw = tab.log_bg[ref_level(k, above, 0, &ia)] + tab.log_d[ref_level(k, legs, 255, &il)];
                    const int lh = ref_level(k, head, 255, &ih);
                    lw += tab.log_d[lh] + tab.log_d[ref_level(k, torso, 255, &idx)];
                    n_fg[k] += ih >= 0 && lh > fg_level;
                }
                if (g_wmask[k].has_colour) lw += ref_colour(&tab, k, idx, g_pool.h[i], g_pool.s[i]);
                want += 0.5 * lw;
            }
            off += fabs(g_pool.w[i] - want) > 1e-4;
        }
        /* the column's points are offsets in the camera frame, the reference's are world points:
         * float rounding may put one a pixel over, rarely (the random levels make that visible) */
        if (off > 3) fail_msg("%s model: %d of 300 log weights differ from the reference", column ? "column" : "point", off);
        for (int k = 0; k < 5; k++) {
            if (fabs(on_fg[k] - (k == 3 ? 0.0 : n_fg[k] / 300.0)) > 0.011)
                fail_msg("camera %d: on_fg %.4f, reference %.4f", k, on_fg[k], n_fg[k] / 300.0);
        }
    }
}

/* Claims (and the column's face point and clear column above): a point on a claimed pixel reads D = 1/2; its colour counts only when the claim is
 * farther than the point; a view's support counts unclaimed foreground only, and its hidden share
 * the head points on claimed pixels. Against the same projection reference. */
static mvt_pf_claims_t g_claims[5];
static void test_weight_claimed_pixels_are_no_evidence(void **state)
{
    (void)state;
    test_weight_point_and_column_match_projection(state); /* g_wimg, g_wmask, g_wfov as there */
    mvt_pf_model_t model = {4.0f, 0.2f, 0.05f, 0.1f, 0.5f, 0.5f};
    static mvt_pf_tables_t tab;
    assert_int_equal(mvt_pf_tables_init(&tab, &model), MVT_OK);
    test_rng_t r = {0xc1a1ULL};
    for (int k = 0; k < 5; k++) { /* claimed blocks of 8 x 8 mask pixels, random depths 1..9 m */
        g_claims[k].width = 192;
        g_claims[k].height = 144;
        for (int by = 0; by < 18; by++)
            for (int bx = 0; bx < 24; bx++) {
                const uint8_t dq = test_uniform(&r) < 0.4 ? mvt_pf_claim_depth((mvt_real)(1 + 8 * test_uniform(&r))) : 0;
                for (int y = 0; y < 8; y++) memset(&g_claims[k].depth[(by * 8 + y) * 192 + bx * 8], dq, 8);
            }
    }
    g_claims[1].width = 96; /* a size that is not the image's: ignored */
    const mvt_pf_body_t body = {0.06f, 0.06f, 0.7f, 0.3f, 0.9f, 0.16f, 0.9f};
    const int fg_level = (tab.d_floor + 255) / 2;
    int claimed_points = 0, farther_colour = 0;
    scatter_pool(&r);
    mvt_real on_fg[5], hidden[5];
    mvt_pf_weight(&g_pool, g_wcams, g_wfov, g_wimg, 5, &tab, 1, &body, 0.5f, g_claims, on_fg, hidden);
    int off = 0, n_fg[5] = {0}, n_hid[5] = {0}, n_out[5] = {0};
    for (int i = 0; i < g_pool.n; i++) {
        double want = 0;
        for (int k = 0; k < 5; k++) {
            if (k == 3) continue;
            const double x = g_pool.x[i], y = g_pool.y[i], z = g_pool.z[i];
            const double pts[8][3] = {{x, y, z + 0.06}, {x, y, z - 0.06}, {x, y, 0.7 * z}, {x, y, 0.3 * z},
                                      {x, y, z - 0.16}, {x, y, z + 0.3}, {x, y, z + 0.6}, {x, y, z + 0.9}};
            int lv[8], idx[8], behind[8];
            for (int j = 0; j < 8; j++) {
                lv[j] = ref_level(k, pts[j], j == 0 || j >= 5 ? 0 : 255, &idx[j]);
                behind[j] = 0;
                if (k != 1 && idx[j] >= 0 && g_claims[k].depth[idx[j]] != 0) {
                    const mvt_real xw[3] = {(mvt_real)pts[j][0], (mvt_real)pts[j][1], (mvt_real)pts[j][2]};
                    mvt_real xc[3];
                    mvt_cam_to_camera(&g_wcams[k], xw, xc);
                    behind[j] = g_claims[k].depth[idx[j]] < mvt_pf_claim_depth(xc[2]) ? 2 : 1;
                    lv[j] = 128;
                    claimed_points++;
                }
            }
            const int clear = lv[5] > lv[6] ? (lv[5] > lv[7] ? lv[5] : lv[7]) : (lv[6] > lv[7] ? lv[6] : lv[7]);
            double lw = tab.log_bg[lv[0]] + tab.log_d[lv[1]] + tab.log_d[lv[2]] + tab.log_d[lv[3]] + tab.log_d[lv[4]] +
                        tab.log_bg[clear];
            n_fg[k] += !behind[1] && idx[1] >= 0 && lv[1] > fg_level;
            n_hid[k] += behind[1] != 0 || idx[1] < 0;
            n_out[k] += idx[1] < 0;
            if (g_wmask[k].has_colour) {
                lw += behind[2] == 2 ? tab.log_colour_background : ref_colour(&tab, k, idx[2], g_pool.h[i], g_pool.s[i]);
                farther_colour += behind[2] == 1 && idx[2] >= 0 && g_wmask[k].fg[idx[2]];
            }
            want += 0.5 * lw;
        }
        off += fabs(g_pool.w[i] - want) > 1e-4;
    }
    assert_true(claimed_points > 500 && farther_colour > 20); /* both kinds of claim were exercised */
    if (off > 3) fail_msg("%d of 300 log weights differ from the reference with claims", off);
    for (int k = 0; k < 5; k++) {
        const double f = k == 3 ? 0.0 : n_fg[k] / 300.0, h = k == 3 ? 0.0 : n_hid[k] / 300.0;
        if (fabs(on_fg[k] - f) > 0.011 || fabs(hidden[k] - h) > 0.011)
            fail_msg("camera %d: on_fg %.4f hidden %.4f, reference %.4f %.4f", k, on_fg[k], hidden[k], f, h);
    }
    /* the mis-sized claims were ignored: camera 1 hides only heads outside its image */
    assert_true(fabs(hidden[1] - n_out[1] / 300.0) < 1e-6 && hidden[0] > n_out[0] / 300.0 + 0.1);
}

/* ---- the tracker on painted masks ---------------------------------------------------------- */

static mvt_camera_t g_cams[5];
static mvt_frame_t g_frame;
static mvt_mask_t g_masks[5];
static mvt_pft_t g_pft;
static mvt_output_t g_out;

static void paint(int k, const double head[3], uint8_t hue)
{
    mvt_mask_t *m = &g_masks[k];
    for (int iz = 0; iz <= 40; iz++)
        for (int ia = 0; ia < 24; ia++)
            for (int ir = 0; ir <= 4; ir++) {
                const double a = 6.283185307179586 * ia / 24, r = 0.05 * ir;
                const mvt_real x[3] = {(mvt_real)(head[0] + r * cos(a)), (mvt_real)(head[1] + r * sin(a)),
                                       (mvt_real)(head[2] * iz / 40.0)};
                mvt_real uv[2];
                if (mvt_cam_project(&g_cams[k], x, uv, NULL) != MVT_OK) continue;
                const int u = (int)((uv[0] + 0.5f) / 4), v = (int)((uv[1] + 0.5f) / 4);
                if (u < 0 || v < 0 || u >= 192 || v >= 144) continue;
                m->fg[v * 192 + u] = 1;
                m->hue[v * 192 + u] = hue;
                m->sat[v * 192 + u] = 200;
            }
}

/* Camera k's view of g_frame: an empty 192 x 144 mask with background colour, no detections. */
static mvt_view_t *empty_view(int k)
{
    mvt_mask_t *m = &g_masks[k];
    m->width = 192; m->height = 144; m->scale = 4; m->has_colour = 1;
    memset(m->fg, 0, 192 * 144);
    memset(m->hue, 30, 192 * 144);
    memset(m->sat, 20, 192 * 144);
    mvt_view_t *v = &g_frame.views[k];
    v->observed = 1;
    v->utime_us = g_frame.utime_us;
    v->num_detections = 0;
    v->mask = m;
    return v;
}

/* g_frame at frame f of two people walking parallel 0.9 m apart: masks painted, head detections. */
static void two_people_frame(int f, double heads[2][3])
{
    const double h[2][3] = {{2.0 + 0.02 * f, 2.1, 1.70}, {2.0 + 0.02 * f, 3.0, 1.80}};
    memcpy(heads, h, sizeof(h));
    g_frame.utime_us = 1000000 + (int64_t)f * 40000;
    for (int k = 0; k < 5; k++) {
        mvt_view_t *v = empty_view(k);
        for (int p = 0; p < 2; p++) {
            paint(k, heads[p], (uint8_t)(90 * p + 10));
            const mvt_real hp[3] = {(mvt_real)heads[p][0], (mvt_real)heads[p][1], (mvt_real)heads[p][2]};
            mvt_real uv[2];
            if (mvt_cam_project(&g_cams[k], hp, uv, NULL) == MVT_OK) {
                mvt_detection_t *d = &v->det[v->num_detections++];
                memset(d, 0, sizeof(*d));
                d->u = uv[0]; d->v = uv[1]; d->sigma_px = 3; d->score = 1; d->hue = d->saturation = -1;
            }
        }
    }
}

/* Two people walking parallel 0.9 m apart; returns the worst horizontal error over the last 50
 * frames; *head_out counts frames x people whose true head lies inside the reported volume. */
static double run_two(uint64_t seed, int frames, int column, mvt_output_t *last, int *head_in)
{
    mvt_pft_config_t cfg;
    mvt_pft_config_default(&cfg);
    cfg.seed = seed;
    cfg.column = column;
    *head_in = 0;
    cfg.num_particles = 400;
    for (int i = 0; i < 3; i++) cfg.det.volume.min[i] = 0;
    cfg.det.volume.max[0] = 6; cfg.det.volume.max[1] = 5; cfg.det.volume.max[2] = 2.5;
    assert_int_equal(mvt_pft_init(&g_pft, &cfg, g_cams, 5), MVT_OK);
    double worst = 0;
    for (int f = 0; f < frames; f++) {
        double heads[2][3];
        two_people_frame(f, heads);
        assert_int_equal(mvt_pft_step(&g_pft, &g_frame, last), MVT_OK);
        if (f >= frames - 50) {
            assert_int_equal(last->num_tracks, 2);
            for (int t = 0; t < 2; t++) {
                const mvt_track_out_t *o = &last->tracks[t];
                int near = 0;
                for (int p = 0; p < 2; p++)
                    near = hypot(o->pos_m[0] - heads[p][0], o->pos_m[1] - heads[p][1]) <
                                   hypot(o->pos_m[0] - heads[near][0], o->pos_m[1] - heads[near][1]) ? p : near;
                worst = fmax(worst, hypot(o->pos_m[0] - heads[near][0], o->pos_m[1] - heads[near][1]));
                int in = 1;
                for (int a = 0; a < 3; a++) in &= o->extent_min[a] <= heads[near][a] && heads[near][a] <= o->extent_max[a];
                *head_in += in;
            }
        }
    }
    return worst;
}

static void test_pft_two_people_tracked_and_reproducible(void **state)
{
    (void)state;
    assert_int_equal(test_room_cameras(g_cams, 1), 0);
    static mvt_output_t a, b;
    int head_in;
    /* the paper's point model: the volume is a body, about 0.4 m wide, floor to head */
    double worst = run_two(7, 90, 0, &a, &head_in);
    if (worst > 0.15) fail_msg("point model: worst horizontal error %.3f m", worst);
    assert_true(g_pft.counters.births == 2); /* no identity lost over 90 frames */
    for (int t = 0; t < 2; t++) {
        assert_true(a.tracks[t].extent_max[0] - a.tracks[t].extent_min[0] < 0.8);
        assert_true(a.tracks[t].extent_max[2] > 1.2 && a.tracks[t].extent_min[2] < 0.6);
        assert_true(fabs(a.tracks[t].pos_m[2] - (a.tracks[t].pos_m[1] < 2.5 ? 1.70 : 1.80)) < 0.1);
    }
    /* the column model (default): the volume is where the head top is, and contains it. Over 8
     * seeds, since one seed's share moves by a few frames with anything that moves a birth (the
     * blob tracker's displacement memory, 2026-11-25: 93-99 of 100 per seed, mean 96.3; before it
     * 96-99, mean 97.6, and seed 7, the only one tested then, went from 98 to 93). */
    int head_in_sum = 0;
    for (uint64_t seed = 1; seed <= 8; seed++) {
        worst = run_two(seed, 90, 1, &a, &head_in);
        if (worst > 0.08) fail_msg("column model, seed %d: worst horizontal error %.3f m", (int)seed, worst);
        assert_true(g_pft.counters.births == 2);
        if (head_in < 90) fail_msg("column model, seed %d: true head inside the volume in %d of 100", (int)seed, head_in);
        head_in_sum += head_in;
    }
    if (head_in_sum < 95 * 8) fail_msg("column model: true head inside the volume in %.1f of 100 (mean)", head_in_sum / 8.0);
    worst = run_two(7, 90, 1, &a, &head_in);
    for (int t = 0; t < 2; t++) {
        assert_int_equal(a.tracks[t].status, MVT_TRACK_CONFIRMED);
        /* the painted body is a flat-topped cylinder 0.4 m across: every point of its top is a head top */
        if (!(a.tracks[t].extent_max[0] - a.tracks[t].extent_min[0] < 0.6))
            fail_msg("column volume %.3f m long", a.tracks[t].extent_max[0] - a.tracks[t].extent_min[0]);
        /* painting marks every mask pixel (about 5 cm here) a body point falls in: the painted top
         * stands up to one pixel above the true one */
        if (!(fabs(a.tracks[t].pos_m[2] - (a.tracks[t].pos_m[1] < 2.5 ? 1.70 : 1.80)) < 0.08))
            fail_msg("column model: head height %.3f m at y %.2f", a.tracks[t].pos_m[2], a.tracks[t].pos_m[1]);
    }
    run_two(7, 90, 1, &b, &head_in);
    assert_memory_equal(&a, &b, sizeof(a)); /* same seed, same output, bit for bit */
}

/* A head-top detection of the head at h in camera k's view (no colour, no box), if it projects. */
static void add_head(mvt_view_t *v, int k, const double h[3])
{
    const mvt_real hp[3] = {(mvt_real)h[0], (mvt_real)h[1], (mvt_real)h[2]};
    mvt_real uv[2];
    if (mvt_cam_project(&g_cams[k], hp, uv, NULL) == MVT_OK) {
        mvt_detection_t *d = &v->det[v->num_detections++];
        memset(d, 0, sizeof(*d));
        d->u = uv[0]; d->v = uv[1]; d->sigma_px = 3; d->score = 1; d->hue = d->saturation = -1;
    }
}

/* g_pft in the 6 x 5 x 2.5 m test room: particles per target, pixels shared or not, identity
 * recovery time. */
static uint64_t g_seed = 1; /* the particle filters' random seed in init_room_pft */

static void init_room_pft(int particles, int share, mvt_real recover_s)
{
    mvt_pft_config_t cfg;
    mvt_pft_config_default(&cfg);
    cfg.seed = g_seed;
    cfg.num_particles = particles;
    cfg.share_pixels = share;
    cfg.recover_s = recover_s;
    for (int i = 0; i < 3; i++) cfg.det.volume.min[i] = 0;
    cfg.det.volume.max[0] = 6; cfg.det.volume.max[1] = 5; cfg.det.volume.max[2] = 2.5;
    assert_int_equal(mvt_pft_init(&g_pft, &cfg, g_cams, 5), MVT_OK);
}

/* One person walking; their masks go blank for frames 60..99 (the filter loses them) while the
 * detector's blobs continue (the blob tracker keeps them). Returns the identity reported at frame
 * 59 and at the last frame. */
static void run_lost_person(mvt_real recover_s, int32_t *before, int32_t *after)
{
    init_room_pft(300, 1, recover_s);
    *before = *after = 0;
    for (int f = 0; f < 150; f++) {
        const double head[3] = {2.0 + 0.015 * f, 2.4, 1.75};
        g_frame.utime_us = 1000000 + (int64_t)f * 40000;
        for (int k = 0; k < 5; k++) {
            mvt_view_t *v = empty_view(k);
            if (f < 60 || f >= 100) paint(k, head, 40);
            add_head(v, k, head);
        }
        assert_int_equal(mvt_pft_step(&g_pft, &g_frame, &g_out), MVT_OK);
        if (f == 59 || f == 149) {
            assert_int_equal(g_out.num_tracks, 1);
            *(f == 59 ? before : after) = g_out.tracks[0].id;
        }
    }
}

static void test_pft_lost_person_recovers_identity_from_blob_track(void **state)
{
    (void)state;
    int32_t before, after;
    run_lost_person(MVT_R(3.0), &before, &after);
    assert_true(g_pft.counters.deleted_lost >= 1); /* the filter did lose them ... */
    assert_int_equal(g_pft.counters.identities_recovered, 1);
    assert_int_equal(after, before);                /* ... and the same person keeps one identity */
    run_lost_person(MVT_R(0.0), &before, &after);  /* without recovery: a new identity */
    assert_true(g_pft.counters.deleted_lost >= 1);
    assert_int_equal(g_pft.counters.identities_recovered, 0);
    assert_true(after != before && after > 0);
}


/* B stands still; A walks up to 0.64 m beside B and vanishes (masks and detections gone: they
 * left through a door there). Returns B's identity at frame 60 and at the end, the number of
 * targets at the end, and the frames after A left in which a confirmed target other than B's
 * (the one nearest to B, within 0.3 m) was reported. */
static void run_leave_beside(int share, int32_t *b_before, int32_t *b_after, int *num_end, int *linger)
{
    init_room_pft(400, share, MVT_R(3.0));
    const double b[3] = {3.0, 2.5, 1.80};
    *b_before = *b_after = 0;
    *linger = 0;
    for (int f = 0; f < 200; f++) {
        const double a[3] = {f < 100 ? 1.0 + 0.0155 * f : 2.55, 2.5, 1.70};
        const int a_here = f < 100;
        g_frame.utime_us = 1000000 + (int64_t)f * 40000;
        for (int k = 0; k < 5; k++) {
            mvt_view_t *v = empty_view(k);
            paint(k, b, 200);
            if (a_here) paint(k, a, 200); /* the same colour: only geometry tells them apart */
            for (int p = 0; p < 1 + a_here; p++) {
                add_head(v, k, p == 0 ? b : a);
            }
        }
        assert_int_equal(mvt_pft_step(&g_pft, &g_frame, &g_out), MVT_OK);
        int32_t b_id = 0;
        double best = 0.3;
        int confirmed = 0;
        for (int t = 0; t < g_out.num_tracks; t++) {
            const mvt_track_out_t *o = &g_out.tracks[t];
            if (o->status == MVT_TRACK_TENTATIVE) continue;
            confirmed++;
            const double d = hypot(o->pos_m[0] - b[0], o->pos_m[1] - b[1]);
            if (d < best) best = d, b_id = o->id;
        }
        if (f == 60) *b_before = b_id;
        *b_after = b_id;
        *linger += f >= 100 && confirmed - (b_id != 0) > 0; /* a target that is not B's */
    }
    *num_end = g_out.num_tracks;
}

static void test_pft_person_leaving_beside_another_does_not_take_them(void **state)
{
    (void)state;
    assert_int_equal(test_room_cameras(g_cams, 1), 0);
    int32_t before, after;
    int num_end, linger;
    /* several random streams: which of A's and B's targets is weighted first when A vanishes must
     * not be a coin toss (it was when only their histories ranked them: 4 of 12 seeds failed) */
    for (g_seed = 1; g_seed <= 8; g_seed++) {
        run_leave_beside(1, &before, &after, &num_end, &linger);
        if (!(before > 0 && after == before && num_end == 1 && linger <= 15))
            fail_msg("seed %d, shared pixels: B %d -> %d, %d targets at the end, a false target in %d frames after A left",
                     (int)g_seed, before, after, num_end, linger);
        print_message("seed %d, shared pixels: B keeps identity %d; a false target in %d of 100 frames after A left\n",
                      (int)g_seed, after, linger);
    }
    g_seed = 1;
    run_leave_beside(0, &before, &after, &num_end, &linger); /* for the record: independent filters */
    print_message("independent: B %d -> %d, %d targets at the end, a false target in %d of 100 frames\n", before,
                  after, num_end, linger);
}

/* A ghost column: B and C stand 2 m apart; the place G between them lies, from camera 0, in front
 * of B and, from camera 1, in front of C, so both cameras see foreground on G's column (the
 * others' bodies), and cameras 2, 3 and 4 see its place empty. A false agreement of cameras 0 and 1
 * (a detection at G's head in both for 1.6 s) is a candidate the blob tracker (the body model) weighs
 * against the three empty masks. Returns the frames (of 200) in which a
 * confirmed target more than 0.3 m from B and C was reported. */
static int run_ghost_column(int share)
{
    init_room_pft(400, share, MVT_R(3.0));
    const double gh[3] = {3.0, 1.8, 1.70};
    /* behind G on the rays from cameras 0 (0.15, 0.15) and 1 (5.85, 0.15), 1.15 m farther */
    const double b[3] = {0.15 + 1.35 * (3.0 - 0.15), 0.15 + 1.35 * (1.8 - 0.15), 1.80};
    const double c[3] = {5.85 + 1.35 * (3.0 - 5.85), 0.15 + 1.35 * (1.8 - 0.15), 1.75};
    int ghost_frames = 0;
    for (int f = 0; f < 200; f++) {
        g_frame.utime_us = 1000000 + (int64_t)f * 40000;
        for (int k = 0; k < 5; k++) {
            mvt_view_t *v = empty_view(k);
            paint(k, b, 60);
            paint(k, c, 160);
            for (int p = 0; p < 3; p++) {
                if (p == 2 && (k > 1 || f >= 40)) continue; /* the false agreement */
                add_head(v, k, p == 0 ? b : (p == 1 ? c : gh));
            }
        }
        assert_int_equal(mvt_pft_step(&g_pft, &g_frame, &g_out), MVT_OK);
        int ghost = 0;
        for (int t = 0; t < g_out.num_tracks; t++) {
            const mvt_track_out_t *o = &g_out.tracks[t];
            ghost |= o->status != MVT_TRACK_TENTATIVE && hypot(o->pos_m[0] - b[0], o->pos_m[1] - b[1]) > 0.3 &&
                     hypot(o->pos_m[0] - c[0], o->pos_m[1] - c[1]) > 0.3;
        }
        ghost_frames += ghost;
    }
    return ghost_frames;
}

static void test_pft_ghost_column_of_others_bodies_not_kept(void **state)
{
    (void)state;
    assert_int_equal(test_room_cameras(g_cams, 1), 0);
    /* the blob tracker does not propose it, with independent filters or shared pixels */
    const int body_independent = run_ghost_column(0);
    const int body_shared = run_ghost_column(1);
    print_message("ghost column: a confirmed ghost in %d and %d of 200 frames\n", body_independent, body_shared);
    assert_true(body_independent <= 5 && body_shared <= 5);
}

/* A saved state restored into a fresh filter continues bit for bit (particles, random stream,
 * identities); a state with one bad value is refused whole. */
static mvt_pft_t g_pft2;
static mvt_pft_persist_t g_saved, g_bad;
static mvt_output_t g_outs[20];

static void test_pft_resume_continues_bit_for_bit_and_refuses_bad_state(void **state)
{
    (void)state;
    assert_int_equal(test_room_cameras(g_cams, 1), 0);
    mvt_pft_config_t cfg;
    mvt_pft_config_default(&cfg);
    cfg.num_particles = 200;
    for (int i = 0; i < 3; i++) cfg.det.volume.min[i] = 0;
    cfg.det.volume.max[0] = 6; cfg.det.volume.max[1] = 5; cfg.det.volume.max[2] = 2.5;
    assert_int_equal(mvt_pft_init(&g_pft, &cfg, g_cams, 5), MVT_OK);
    double heads[2][3];
    for (int f = 0; f < 30; f++) {
        two_people_frame(f, heads);
        assert_int_equal(mvt_pft_step(&g_pft, &g_frame, &g_out), MVT_OK);
    }
    assert_int_equal(g_out.num_tracks, 2);
    mvt_pft_save(&g_pft, &g_saved);
    for (int f = 30; f < 50; f++) {
        two_people_frame(f, heads);
        assert_int_equal(mvt_pft_step(&g_pft, &g_frame, &g_outs[f - 30]), MVT_OK);
    }
    assert_int_equal(mvt_pft_init(&g_pft2, &cfg, g_cams, 5), MVT_OK);
    assert_int_equal(mvt_pft_resume(&g_pft2, &g_saved, 0), MVT_OK);
    for (int f = 30; f < 50; f++) {
        two_people_frame(f, heads);
        assert_int_equal(mvt_pft_step(&g_pft2, &g_frame, &g_out), MVT_OK);
        assert_int_equal(g_out.num_tracks, g_outs[f - 30].num_tracks);
        assert_memory_equal(g_out.tracks, g_outs[f - 30].tracks, (size_t)g_out.num_tracks * sizeof(g_out.tracks[0]));
    }
    /* bad states: refused, the filter unchanged */
    for (int c = 0; c < 6; c++) {
        mvt_pft_save(&g_pft2, &g_saved); /* the state before the refused resume */
        int t = 0;
        while (g_saved.targets[t].id == 0) t++;
        g_bad = g_saved;
        switch (c) {
        case 0: g_bad.targets[t].pool.n = 199; break;              /* not the configured count */
        case 1: g_bad.targets[t].pool.w[3] = NAN; break;
        case 2: g_bad.targets[t].pool.x[0] = INFINITY; break;
        case 3: g_bad.rng.inc = 2; break;                          /* not a PCG stream */
        case 4: g_bad.targets[(t + 1) % MVT_MAX_TARGETS] = g_bad.targets[t]; break; /* identity twice */
        case 5: g_bad.det.tracks[0].id = 5; g_bad.det.tracks[0].status = 9; break;
        }
        assert_int_equal(mvt_pft_resume(&g_pft2, &g_bad, 0), MVT_ERR_INVALID);
        mvt_pft_save(&g_pft2, &g_bad);
        assert_memory_equal(&g_bad, &g_saved, sizeof(g_bad));
    }
    /* identities reserved above the ones used before a restart */
    mvt_pft_reserve_ids(&g_pft2, 1000);
    assert_true(g_pft2.next_id == 1000 && g_pft2.det.next_id == 1000);
    mvt_pft_reserve_ids(&g_pft2, 10);
    assert_true(g_pft2.next_id == 1000);
}

static void test_pft_time_backwards_refused(void **state)
{
    (void)state;
    const int64_t t = g_pft.last_utime_us;
    g_frame.utime_us = t - 1;
    assert_int_equal(mvt_pft_step(&g_pft, &g_frame, &g_out), MVT_ERR_INVALID);
    assert_int_equal(g_pft.counters.frames_time_backwards, 1);
}

static void test_pft_config_invalid_rejected(void **state)
{
    (void)state;
    mvt_pft_config_t cfg;
    mvt_pft_config_default(&cfg);
    cfg.num_particles = MVT_MAX_PARTICLES + 1;
    assert_int_equal(mvt_pft_init(&g_pft, &cfg, g_cams, 5), MVT_ERR_INVALID);
    mvt_pft_config_default(&cfg);
    cfg.model.p_b = 1.5f;
    assert_int_equal(mvt_pft_init(&g_pft, &cfg, g_cams, 5), MVT_ERR_INVALID);
    mvt_pft_config_default(&cfg);
    cfg.noise.z_renew = NAN;
    assert_int_equal(mvt_pft_init(&g_pft, &cfg, g_cams, 5), MVT_ERR_INVALID);
    mvt_pft_config_default(&cfg);
    cfg.recover_s = -1.0f;
    assert_int_equal(mvt_pft_init(&g_pft, &cfg, g_cams, 5), MVT_ERR_INVALID);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mask_from_runs_valid_decodes),
        cmocka_unit_test(test_mask_from_runs_hostile_rejected),
        cmocka_unit_test(test_mask_fg_near_matches_brute_force),
        cmocka_unit_test(test_mask_top_in_band_finds_heads_only),
        cmocka_unit_test(test_image_build_matches_direct_convolution),
        cmocka_unit_test(test_normalise_matches_double_and_ess),
        cmocka_unit_test(test_resample_systematic_copies_floor_or_ceil),
        cmocka_unit_test(test_estimate_box_is_heaviest_set),
        cmocka_unit_test(test_weight_point_and_column_match_projection),
        cmocka_unit_test(test_weight_claimed_pixels_are_no_evidence),
        cmocka_unit_test(test_pft_two_people_tracked_and_reproducible),
        cmocka_unit_test(test_pft_lost_person_recovers_identity_from_blob_track),
        cmocka_unit_test(test_pft_person_leaving_beside_another_does_not_take_them),
        cmocka_unit_test(test_pft_ghost_column_of_others_bodies_not_kept),
        cmocka_unit_test(test_pft_resume_continues_bit_for_bit_and_refuses_bad_state),
        cmocka_unit_test(test_pft_time_backwards_refused),
        cmocka_unit_test(test_pft_config_invalid_rejected),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
