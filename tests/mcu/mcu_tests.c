/*
 * mcu_tests.c - the core's tests on a Cortex-M (QEMU mps2-an386 / mps2-an500, semihosting).
 *
 * A faithful subset of the host suite, checked against references computed on the host by
 * independent code (mcu_vectors.h from gen_vectors.py: OpenCV projection, numpy Kalman filter and
 * EKF, exhaustive assignment, a ground-truth walk): camera model, constant-velocity filter,
 * projective update, assignment, the tracker end to end with a false alarm per view, an
 * occluded view and a camera that stops sending, and one particle filter's pool (the column model
 * on ray-cast masks of a standing person; random numbers against the published PCG32). The full
 * multi-target mvt_pft_t (3.3 MB with five 332 kB masks at the default capacities) does not fit
 * the boards' 4 MB: the pool is run camera by camera through one mask, image and blur workspace. Prints one line per test and the figures the
 * footprint report reads (sizeof, stack high-water of one mvt_tracker_step); exit code = number
 * of failed checks.
 */
#include <math.h>
#include <string.h>

#include "mcu_rt.h"
#include "mcu_vectors.h"
#include "mvt_assoc.h"
#include "mvt_imm.h"
#include "mvt_pf.h"
#include "mvt_tracker.h"

static int g_fail;
static int g_checks;

static void check(int ok, const char *what, float got, float want)
{
    g_checks++;
    if (!ok) {
        g_fail++;
        mcu_puts("  FAIL ");
        mcu_puts(what);
        mcu_puts(": got ");
        mcu_put_fixed(got, 6);
        mcu_puts(" want ");
        mcu_put_fixed(want, 6);
        mcu_puts("\n");
    }
}

static void report(const char *name, int fails_before, const char *figure, float value, int decimals)
{
    mcu_puts(g_fail == fails_before ? "ok   " : "FAIL ");
    mcu_puts(name);
    if (figure != NULL) {
        mcu_puts(" (");
        mcu_puts(figure);
        mcu_put_fixed(value, decimals);
        mcu_puts(")");
    }
    mcu_puts("\n");
}

static mvt_camera_t g_cams[MCU_NCAM];

static void test_camera(void)
{
    const int f0 = g_fail;
    float worst_px = 0.0f, worst_xn = 0.0f;
    for (int k = 0; k < MCU_NCAM; k++) {
        mvt_camera_params_t p;
        memset(&p, 0, sizeof(p));
        memcpy(p.camera_matrix, &cam_K[9 * k], sizeof(p.camera_matrix));
        memcpy(p.dist, &cam_dist[5 * k], 5 * sizeof(float));
        memcpy(p.rvec, &cam_rvec[3 * k], sizeof(p.rvec));
        memcpy(p.tvec, &cam_tvec[3 * k], sizeof(p.tvec));
        p.width = MCU_W;
        p.height = MCU_H;
        p.sigma_px = 2.0f;
        check(mvt_cam_init(&g_cams[k], &p) == MVT_OK, "mvt_cam_init", 0, 0);
        for (int i = 0; i < MCU_NPTS; i++) {
            mvt_real uv[2], xn[2];
            check(mvt_cam_project(&g_cams[k], &proj_X[3 * i], uv, NULL) == MVT_OK, "project", 0, 0);
            const float *want = &proj_uv[(k * MCU_NPTS + i) * 2];
            const float e = fmaxf(fabsf(uv[0] - want[0]), fabsf(uv[1] - want[1]));
            worst_px = fmaxf(worst_px, e);
            check(e < 0.01f, "projection vs OpenCV (px)", e, 0.01f);
            check(mvt_cam_undistort(&g_cams[k], want, xn) == MVT_OK, "undistort", 0, 0);
            const float *wn = &undist_xn[(k * MCU_NPTS + i) * 2];
            const float en = fmaxf(fabsf(xn[0] - wn[0]), fabsf(xn[1] - wn[1]));
            worst_xn = fmaxf(worst_xn, en);
            check(en < 2e-5f, "undistortion vs truth", en, 2e-5f);
        }
    }
    report("camera: projection vs OpenCV, worst px", f0, "", worst_px, 5);
    report("camera: undistortion vs truth, worst normalised", f0, "", worst_xn, 7);
}

static float rel(float a, float b)
{
    return fabsf(a - b) / fmaxf(fabsf(b), 1e-6f);
}

/* A state with the reference's x0 and (block-diagonal) P0. */
static void state_from(mvt_cv_state_t *s, const float x0[6], const float P0[36])
{
    memset(s, 0, sizeof(*s));
    memcpy(s->x, x0, 6 * sizeof(float));
    memcpy(s->P, P0, 36 * sizeof(float));
}

static void test_cv_filter(void)
{
    const int f0 = g_fail;
    mvt_cv_state_t s;
    state_from(&s, kf_x0, kf_P0);
    float worst = 0.0f;
    for (int n = 0; n < MCU_NKF; n++) {
        check(mvt_cv_predict(&s, kf_dt[n], kf_q) == MVT_OK, "mvt_cv_predict", 0, 0);
        check(mvt_cv_update_point(&s, &kf_z[3 * n], &kf_R[9 * n], 0.0f, NULL) == MVT_OK, "update_point", 0, 0);
        for (int i = 0; i < 6; i++) {
            const float e = fabsf(s.x[i] - kf_x[6 * n + i]);
            worst = fmaxf(worst, e);
            check(e < 1e-4f, "cv state vs numpy", e, 1e-4f);
            check(rel(s.P[i * 7], kf_P[36 * n + i * 7]) < 1e-3f, "cv covariance vs numpy (rel)", s.P[i * 7],
                  kf_P[36 * n + i * 7]);
        }
    }
    report("filter: constant velocity + point update vs numpy, worst state", f0, "", worst, 7);
}

static void test_pkf(void)
{
    const int f0 = g_fail;
    mvt_cv_state_t s;
    state_from(&s, pkf_x0, pkf_P0);
    for (int k = 0; k < MCU_NCAM; k++) {
        mvt_pkf_meas_t m;
        mvt_pkf_innov_t in;
        check(mvt_pkf_meas_make(&g_cams[k], &pkf_z[2 * k], MCU_PKF_SIGMA, &m) == MVT_OK, "meas_make", 0, 0);
        check(mvt_pkf_innovation(&s, &g_cams[k], MVT_PKF_JACOBIAN, &m, &in) == MVT_OK, "innovation", 0, 0);
        check(mvt_pkf_update(&s, &in) == MVT_OK, "pkf update", 0, 0);
    }
    float worst = 0.0f;
    for (int i = 0; i < 6; i++) {
        const float e = fabsf(s.x[i] - pkf_x[i]);
        worst = fmaxf(worst, e);
        check(e < 1e-3f, "projective update vs numpy EKF", e, 1e-3f);
        check(rel(s.P[i * 7], pkf_P[i * 7]) < 1e-2f, "projective covariance vs numpy (rel)", s.P[i * 7], pkf_P[i * 7]);
    }
    report("filter: projective update (4 views) vs numpy EKF, worst state", f0, "", worst, 7);
}

static void test_imm(void)
{
    const int f0 = g_fail;
    mvt_imm_config_t cfg;
    mvt_imm_config_default(&cfg);
    mvt_cv_state_t s;
    state_from(&s, imm_x0, imm_P0);
    static mvt_imm_t imm;
    mvt_imm_init(&imm, &cfg, &s);
    for (int n = 0; n < MCU_NIMM; n++) {
        check(mvt_imm_predict_to(&imm, &cfg, (int64_t)(n + 1) * 40000, &s) == MVT_OK, "imm predict", 0, 0);
        for (int k = 0; k < MCU_NCAM; k++) {
            mvt_pkf_meas_t m;
            mvt_pkf_innov_t in;
            check(mvt_pkf_meas_make(&g_cams[k], &imm_z[2 * (n * MCU_NCAM + k)], MCU_PKF_SIGMA, &m) == MVT_OK, "meas_make",
                  0, 0);
            check(mvt_pkf_innovation(&s, &g_cams[k], MVT_PKF_JACOBIAN, &m, &in) == MVT_OK, "innovation", 0, 0);
            const mvt_real noise[4] = {in.r, 0, 0, in.r};
            check(mvt_imm_update(&imm, &cfg, 2, in.H, in.y, noise, &s) == MVT_OK, "imm update", 0, 0);
        }
    }
    float worst = 0.0f;
    for (int i = 0; i < 3; i++) {
        const float e = fabsf(s.x[i] - imm_x[i]);
        worst = fmaxf(worst, e);
        check(e < 1e-4f, "IMM vs numpy textbook IMM (position)", e, 1e-4f);
    }
    for (int j = 0; j < cfg.n; j++) {
        check(fabsf(imm.mu[j] - imm_mu[j]) < 0.01f, "IMM model probability vs numpy", imm.mu[j], imm_mu[j]);
    }
    report("filter: IMM (4 models, robust) 60 frames x 4 views vs numpy textbook IMM, worst position", f0, "", worst, 7);
}

static mvt_assoc_ws_t g_ws;

static void test_assoc(void)
{
    const int f0 = g_fail;
    for (int i = 0; i < MCU_NASSOC; i++) {
        const int nr = assoc_dims[2 * i], nc = assoc_dims[2 * i + 1];
        const float *c = &assoc_cost[i * MCU_ASSOC_ROWS * MCU_ASSOC_STRIDE];
        int r2c[MCU_ASSOC_ROWS];
        check(mvt_assoc_solve(c, nr, nc, MCU_ASSOC_STRIDE, r2c, &g_ws) == MVT_OK, "mvt_assoc_solve", 0, 0);
        float total = 0.0f;
        int used = 0, ok = 1;
        for (int r = 0; r < nr; r++) {
            ok &= r2c[r] >= 0 && r2c[r] < nc && c[r * MCU_ASSOC_STRIDE + r2c[r]] >= 0.0f && !(used & (1 << r2c[r]));
            if (ok) {
                used |= 1 << r2c[r];
                total += c[r * MCU_ASSOC_STRIDE + r2c[r]];
            }
        }
        check(ok, "assignment feasible and one-to-one", 0, 0);
        check(fabsf(total - assoc_best[i]) < 1e-3f, "assignment cost vs enumeration", total, assoc_best[i]);
    }
    report("association: Hungarian vs exhaustive enumeration, 30 matrices", f0, NULL, 0, 0);
}

static mvt_tracker_t g_tracker;
static mvt_frame_t g_frame;
static mvt_output_t g_out;

static uint32_t sp_now(void)
{
    uint32_t sp;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    return sp;
}

extern uint32_t __stack_top;

static void test_tracker(void)
{
    const int f0 = g_fail;
    mvt_tracker_config_t cfg;
    mvt_tracker_config_default(&cfg);
    cfg.volume.min[0] = 0.0f; cfg.volume.min[1] = 0.0f; cfg.volume.min[2] = 0.0f;
    cfg.volume.max[0] = 6.0f; cfg.volume.max[1] = 5.0f; cfg.volume.max[2] = 2.5f;
    check(mvt_tracker_init(&g_tracker, &cfg, g_cams, MCU_NCAM) == MVT_OK, "tracker init", 0, 0);
    int32_t id = 0;
    float se = 0.0f, worst = 0.0f;
    int n_err = 0, stack_max = 0;
    for (int f = 0; f < MCU_NF; f++) {
        memset(&g_frame, 0, sizeof(g_frame));
        g_frame.utime_us = 1000000 + (int64_t)f * 40000;
        for (int k = 0; k < MCU_NCAM; k++) {
            mvt_view_t *v = &g_frame.views[k];
            if (k == 2 && f >= MCU_CAM2_GAP0 && f < MCU_CAM2_GAP1) {
                continue; /* camera 2 sends nothing */
            }
            v->observed = 1;
            v->utime_us = g_frame.utime_us;
            for (int d = 0; d < 2; d++) {
                const float *uv = &trk_dets[((f * MCU_NCAM + k) * 2 + d) * 2];
                if (uv[0] < 0.0f) {
                    continue;
                }
                mvt_detection_t *det = &v->det[v->num_detections++];
                det->u = uv[0];
                det->v = uv[1];
                det->sigma_px = 2.0f;
                det->score = 1.0f;
                det->hue = det->saturation = -1.0f;
            }
        }
        const uint32_t depth_at_call = (uint32_t)((uintptr_t)&__stack_top - sp_now());
        mcu_stack_paint();
        check(mvt_tracker_step(&g_tracker, &g_frame, &g_out) == MVT_OK, "tracker step", 0, 0);
        const int used = (int)mcu_stack_used() - (int)depth_at_call;
        stack_max = used > stack_max ? used : stack_max;
        int confirmed = 0;
        for (int t = 0; t < g_out.num_tracks; t++) {
            const mvt_track_out_t *o = &g_out.tracks[t];
            if (o->status == MVT_TRACK_TENTATIVE) {
                continue;
            }
            confirmed++;
            if (id == 0) {
                id = o->id;
            }
            check(o->id == id, "one identity throughout", (float)o->id, (float)id);
            const float *x = &trk_truth[3 * f];
            const float dx = o->pos_m[0] - x[0], dy = o->pos_m[1] - x[1], dz = o->pos_m[2] - x[2];
            const float e = sqrtf(dx * dx + dy * dy + dz * dz);
            se += e * e;
            n_err++;
            worst = fmaxf(worst, e);
            for (int i = 0; i < 6; i++) {
                check(isfinite(o->cov_m2[i]), "finite covariance", o->cov_m2[i], 0);
            }
            check(o->cov_m2[0] > 0.0f && o->cov_m2[3] > 0.0f && o->cov_m2[5] > 0.0f, "positive variances",
                  o->cov_m2[0], 0);
        }
        if (f >= 10) {
            check(confirmed == 1, "exactly one confirmed track", (float)confirmed, 1.0f);
        }
    }
    const float rmse = n_err > 0 ? sqrtf(se / (float)n_err) : 1e9f;
    check(rmse < 0.05f, "tracker RMSE (m)", rmse, 0.05f);
    check(worst < 0.2f, "tracker worst error (m)", worst, 0.2f);
    report("tracker: 250 frames, false alarms, occlusion, camera dropout, RMSE m", f0, "", rmse, 4);
    mcu_puts("figure stack_step_bytes ");
    mcu_put_int(stack_max);
    mcu_puts("\nfigure sizeof_tracker ");
    mcu_put_int((long long)sizeof(mvt_tracker_t));
    mcu_puts("\nfigure sizeof_frame ");
    mcu_put_int((long long)sizeof(mvt_frame_t));
    mcu_puts("\nfigure sizeof_output ");
    mcu_put_int((long long)sizeof(mvt_output_t));
    mcu_puts("\nfigure capacity ");
    mcu_put_int(MVT_MAX_CAMERAS);
    mcu_puts(" cameras, ");
    mcu_put_int(MVT_MAX_TARGETS);
    mcu_puts(" targets, ");
    mcu_put_int(MVT_MAX_DETECTIONS);
    mcu_puts(" detections\n");
}

/* ---- particle filter ----------------------------------------------------------------------- */

static mvt_mask_t g_pf_mask;
static mvt_pf_image_t g_pf_img;
static mvt_pf_blur_ws_t g_pf_blur;
static mvt_pf_pool_t g_pf_pool, g_pf_scratch;
static uint16_t g_pf_order[MVT_MAX_PARTICLES];

static void pf_mask_of(int k)
{
    int first = 0;
    for (int j = 0; j < k; j++) {
        first += pf_run_count[j];
    }
    g_pf_mask.width = MCU_PF_W;
    g_pf_mask.height = MCU_PF_H;
    g_pf_mask.scale = MCU_PF_SCALE;
    g_pf_mask.has_colour = 0;
    memset(g_pf_mask.fg, 0, MCU_PF_W * MCU_PF_H);
    for (int r = first; r < first + pf_run_count[k]; r++) {
        memset(&g_pf_mask.fg[pf_runs[2 * r]], 1, (size_t)pf_runs[2 * r + 1]);
    }
}

/* One filter of 1000 head-top hypotheses from a cloud 0.2 m off the person: 40 frames. */
static void pf_run(const mvt_pf_tables_t *tab, const mvt_pf_fov_t *fovs, uint64_t seed, mvt_pf_estimate_t *est)
{
    mvt_rng_t rng;
    mvt_rng_seed(&rng, seed, 7u);
    mvt_pf_pool_t *p = &g_pf_pool;
    p->n = MVT_MAX_PARTICLES < 1000 ? MVT_MAX_PARTICLES : 1000;
    for (int i = 0; i < p->n; i++) {
        mvt_real g[4];
        mvt_rng_normal2(&rng, g);
        mvt_rng_normal2(&rng, g + 2);
        p->x[i] = pf_head[0] + 0.15f + 0.1f * g[0];
        p->y[i] = pf_head[1] - 0.1f + 0.1f * g[1];
        p->z[i] = pf_head[2] - 0.08f + 0.1f * g[2];
        p->vx[i] = p->vy[i] = p->vz[i] = 0.0f;
        p->h[i] = p->s[i] = 0.0f;
    }
    const mvt_pf_noise_t noise = {0.02f, 0.05f, 0.0f, 0.0f, 0.0f, 2.2f, 0.02f, 0.05f};
    const mvt_pf_body_t body = {0.06f, 0.06f, 0.7f, 0.3f, 0.9f, 0.16f, 0.9f};
    for (int f = 0; f < 40; f++) {
        mvt_pf_predict(p, 0.04f, &noise, &rng);
        for (int i = 0; i < p->n; i++) {
            p->w[i] = 0.0f;
        }
        for (int k = 0; k < MCU_NCAM; k++) { /* one image at a time: weights add up */
            pf_mask_of(k);
            mvt_pf_image_build(&g_pf_img, &g_pf_mask, tab, 4.0f, &g_pf_blur);
            mvt_pf_weight(p, &g_cams[k], &fovs[k], &g_pf_img, 1, tab, 0, &body, 0.5f, NULL, NULL, NULL);
        }
        const mvt_real ess = mvt_pf_normalise(p);
        check(ess >= 1.0f, "pf effective sample size", ess, 1.0f);
        mvt_pf_estimate(p, 0.95f, 0.0f, g_pf_order, est);
        if (ess < 0.5f * (mvt_real)p->n) {
            mvt_pf_resample(p, &rng, &g_pf_scratch);
        }
    }
}

static void test_pf(void)
{
    const int f0 = g_fail;
    mvt_rng_t rng;
    mvt_rng_seed(&rng, 42u, 54u);
    for (int i = 0; i < 8; i++) {
        const uint32_t v = mvt_rng_u32(&rng);
        check(v == pcg_ref[i], "PCG32 output", (float)v, (float)pcg_ref[i]);
    }
    const mvt_pf_model_t model = {4.0f, 0.2f, 0.05f, 0.1f, 0.5f, 0.5f};
    static mvt_pf_tables_t tab;
    check(mvt_pf_tables_init(&tab, &model) == MVT_OK, "pf tables", 0, 0);
    /* camera 0's likelihood image against the direct convolution, around the body */
    pf_mask_of(0);
    mvt_pf_image_build(&g_pf_img, &g_pf_mask, &tab, 4.0f, &g_pf_blur);
    float worst_d = 0.0f;
    const int *wn = pf_d0_window;
    for (int y = wn[0]; y < wn[1]; y++) {
        for (int x = wn[2]; x < wn[3]; x++) {
            const float want = pf_d0[(y - wn[0]) * (wn[3] - wn[2]) + (x - wn[2])];
            worst_d = fmaxf(worst_d, fabsf((float)g_pf_img.d[y * MCU_PF_W + x] / 255.0f - want));
        }
    }
    check(worst_d <= 1.0f / 255.0f + 1e-3f, "pf likelihood image |D - reference|", worst_d, 1.0f / 255.0f);
    mvt_pf_fov_t fovs[MCU_NCAM];
    for (int k = 0; k < MCU_NCAM; k++) {
        mvt_pf_fov_init(&fovs[k], &g_cams[k], 0.05f);
    }
    mvt_pf_estimate_t a, b;
    pf_run(&tab, fovs, 5u, &a);
    const float exy = hypotf(a.mean[0] - pf_head[0], a.mean[1] - pf_head[1]), ez = fabsf(a.head_z - pf_head[2]);
    check(exy < 0.06f, "pf horizontal error (m)", exy, 0.06f);
    check(ez < 0.05f, "pf head height error (m)", ez, 0.05f);
    int inside = 1;
    for (int i = 0; i < 3; i++) {
        inside &= a.box_min[i] <= pf_head[i] && pf_head[i] <= a.box_max[i];
    }
    check(inside, "pf P_H volume contains the head", (float)inside, 1.0f);
    pf_run(&tab, fovs, 5u, &b);
    check(memcmp(&a, &b, sizeof(a)) == 0, "pf same seed, same estimate", 0, 0);
    report("particle filter: column model, 4 masks, 1000 particles x 40 frames, error m", f0, "", hypotf(exy, ez), 4);
    mcu_puts("figure sizeof_pf_pool ");
    mcu_put_int((long long)sizeof(mvt_pf_pool_t));
    mcu_puts("\nfigure sizeof_pf_image ");
    mcu_put_int((long long)sizeof(mvt_pf_image_t));
    mcu_puts("\n");
}

int main(void)
{
    mcu_puts("mvtrack MCU tests (" MVT_MCU_NAME ", float core)\n");
    test_camera();
    test_cv_filter();
    test_pkf();
    test_imm();
    test_assoc();
    test_tracker();
    test_pf();
    mcu_puts(g_fail == 0 ? "PASS " : "FAILED ");
    mcu_put_int(g_checks - g_fail);
    mcu_puts("/");
    mcu_put_int(g_checks);
    mcu_puts(" checks\n");
    return g_fail > 255 ? 255 : g_fail;
}
