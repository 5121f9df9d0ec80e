/*
 * mvtrack-bench [NAME...] - benchmarks; one JSON object per line:
 *   {"bench": NAME, "median_ns": ..., "runs": ..., "iters": ...}
 * Peers measured in the same run print their own lines (NAME.eigen).
 *
 *   filter_update_5cam         one predict + update of one target from 5 cameras, default filter
 *                              (PKF, Jacobian linearisation, distortion in h, Joseph form), float
 *   filter_update_5cam.eigen   the same step as a good C++ engineer writes it with fixed-size Eigen
 *                              (float, batch 10-row update, LLT solve, Joseph form)
 *   filter_update_5cam.eigen_tuned  the tuned peer: fixed-size Eigen, sequential per-camera 2x2
 *                              innovations with the closed-form inverse, velocity columns of H
 *                              skipped, block prediction, expanded Joseph form (the same algorithm
 *                              as mvtrack's, so the ratio is the implementation's)
 *   filter_update_5cam_imm     the IMM step (mvt_imm, default 3-model bank): mixing, prediction,
 *                              5 cameras projected at the combination and applied to every model
 *   filter_update_5cam_imm.eigen_tuned  the same IMM step in the tuned peer's style
 *   NAME.vs_single, NAME.vs_eigen_tuned  mvtrack's step over the single-model step or over the
 *                              tuned peer's, timed in alternating blocks (robust to the machine's
 *                              speed, which can swing 30 % between two separate runs)
 *   tracker_frame_5cam_1target a whole mvt_tracker_step: 5 cameras, one person, one detection each
 *   tracker_frame_8cam_16people  a whole mvt_tracker_step: 8 cameras around an 8 x 7 m room, 16
 *                              people walking circles at 0.6-1.2 m/s, 2 px noise, 10 % misses,
 *                              0.3 false alarms per camera per frame; 3000 frames (2 min), each
 *                              step timed alone, the first 100 (births) excluded; also prints the
 *                              p99 and max and how many tracks were confirmed
 *                              (the body model)
 *   tracker_frame_8cam_16people_masks  the same with each camera's 192 x 144 foreground mask (a
 *                              head over a body per person, painted outside the timed step):
 *                              empty places, hidden tracks and heads standing out of merged blobs
 *                              read from the masks; also prints how many tops were measured
 *   pf_frame_5cam_4targets     a whole mvt_pft_step (--mode pf): 5 cameras with 192 x 144 masks
 *                              and hue/saturation (the likelihood images are built inside the
 *                              step), 4 people walking, 1000 particles each, MS+C; 600 frames,
 *                              each timed alone, the first 50 (births) excluded
 *   detect_frame_768x576       mvtrack-detect's work per frame on real 768 x 576 footage (vtest.avi)
 *                              on one core, each frame timed alone (bench/detect_bench.cpp); the
 *                              peer line NAME.with_decode includes decoding the frame
 */
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "detect_bench.hpp"
#include "mvt_pft.h"
#include "mvt_tracker.h"

namespace {

volatile double g_sink;

template <class F>
void measure(const char *name, int iters, int runs, F &&step)
{
    std::vector<double> ns;
    for (int w = 0; w < iters / 10; w++) step(w); /* warm-up */
    for (int r = 0; r < runs; r++) {
        const auto t0 = std::chrono::steady_clock::now();
        for (int i = 0; i < iters; i++) step(i);
        const auto t1 = std::chrono::steady_clock::now();
        ns.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count() / iters);
    }
    std::sort(ns.begin(), ns.end());
    std::printf("{\"bench\": \"%s\", \"median_ns\": %.1f, \"min_ns\": %.1f, \"max_ns\": %.1f, \"runs\": %d, \"iters\": %d}\n",
                name, ns[ns.size() / 2], ns.front(), ns.back(), runs, iters);
    std::fflush(stdout);
}

/* Two steps timed in alternating blocks (a, b, a, b, ...), so that both see the same machine: on
 * a shared or frequency-scaling machine the medians of two separate runs can differ by 30 % for
 * the same code. Prints the median and range of the per-pair ratios b / a. */
template <class A, class B>
void measure_ratio(const char *name, int iters, int runs, A &&a, B &&b)
{
    std::vector<double> r;
    for (int w = 0; w < iters / 10; w++) {
        a(w);
        b(w);
    }
    for (int k = 0; k < runs; k++) {
        const auto t0 = std::chrono::steady_clock::now();
        for (int i = 0; i < iters; i++) a(i);
        const auto t1 = std::chrono::steady_clock::now();
        for (int i = 0; i < iters; i++) b(i);
        const auto t2 = std::chrono::steady_clock::now();
        r.push_back(std::chrono::duration<double>(t2 - t1).count() / std::chrono::duration<double>(t1 - t0).count());
    }
    std::sort(r.begin(), r.end());
    std::printf("{\"bench\": \"%s\", \"median_ratio\": %.3f, \"min_ratio\": %.3f, \"max_ratio\": %.3f, \"runs\": %d, "
                "\"iters\": %d}\n",
                name, r[r.size() / 2], r.front(), r.back(), runs, iters);
    std::fflush(stdout);
}

void look_at(mvt_camera_params_t *p, const double pos[3], const double tgt[3], double f, double k1)
{
    std::memset(p, 0, sizeof(*p));
    Eigen::Vector3d c(pos[0], pos[1], pos[2]), t(tgt[0], tgt[1], tgt[2]);
    Eigen::Vector3d fw = (t - c).normalized();
    Eigen::Vector3d up = std::fabs(fw.z()) > 0.99 ? Eigen::Vector3d(0, 1, 0) : Eigen::Vector3d(0, 0, 1);
    Eigen::Vector3d x = fw.cross(up).normalized(), y = fw.cross(x);
    Eigen::Matrix3d R;
    R.row(0) = x;
    R.row(1) = y;
    R.row(2) = fw;
    Eigen::AngleAxisd aa(R);
    Eigen::Vector3d rv = aa.axis() * aa.angle(), tv = -R * c;
    for (int i = 0; i < 3; i++) {
        p->rvec[i] = (mvt_real)rv(i);
        p->tvec[i] = (mvt_real)tv(i);
    }
    const double K[9] = {f, 0, 383.5, 0, f, 287.5, 0, 0, 1};
    for (int i = 0; i < 9; i++) p->camera_matrix[i] = (mvt_real)K[i];
    p->dist[0] = (mvt_real)k1;
    p->dist[1] = (mvt_real)0.06;
    p->width = 768;
    p->height = 576;
    p->sigma_px = 3;
}

struct Rig5 {
    mvt_camera_t cams[5];
    Rig5()
    {
        const double tgt[3] = {3, 2.5, 0.9}, down[3] = {3, 2.5, 0};
        const double pos[5][3] = {{0.15, 0.15, 2.75}, {5.85, 0.15, 2.75}, {5.85, 4.85, 2.75}, {0.15, 4.85, 2.75}, {3, 2.5, 2.95}};
        for (int k = 0; k < 5; k++) {
            mvt_camera_params_t p;
            look_at(&p, pos[k], k == 4 ? down : tgt, k == 4 ? 300 : 420, -0.22);
            mvt_cam_init(&cams[k], &p);
        }
    }
};

/* ---- the Eigen peer ------------------------------------------------------------------------- */
using Vec6 = Eigen::Matrix<float, 6, 1>;
using Mat6 = Eigen::Matrix<float, 6, 6>;
using Mat10x6 = Eigen::Matrix<float, 10, 6>;
using Mat10 = Eigen::Matrix<float, 10, 10>;
using Vec10 = Eigen::Matrix<float, 10, 1>;

struct EigenCam {
    Eigen::Matrix3f R;
    Eigen::Vector3f t;
    float fx, fy, cx, cy, k1, k2, p1, p2, k3;
    explicit EigenCam(const mvt_camera_t &c)
    {
        for (int i = 0; i < 9; i++) R(i / 3, i % 3) = c.R[i];
        t << c.t[0], c.t[1], c.t[2];
        fx = c.fx; fy = c.fy; cx = c.cx; cy = c.cy;
        k1 = c.dist[0]; k2 = c.dist[1]; p1 = c.dist[2]; p2 = c.dist[3]; k3 = c.dist[4];
    }
    /* projection with distortion and its Jacobian wrt the world point */
    Eigen::Vector2f project(const Eigen::Vector3f &X, Eigen::Matrix<float, 2, 3> &J) const
    {
        const Eigen::Vector3f Xc = R * X + t;
        const float iz = 1.0f / Xc.z(), x = Xc.x() * iz, y = Xc.y() * iz;
        const float r2 = x * x + y * y, rad = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
        const float drad = k1 + r2 * (2 * k2 + 3 * r2 * k3);
        Eigen::Matrix2f Jd;
        Jd << rad + 2 * x * x * drad + 2 * p1 * y + 6 * p2 * x, 2 * x * y * drad + 2 * p1 * x + 2 * p2 * y,
            2 * x * y * drad + 2 * p1 * x + 2 * p2 * y, rad + 2 * y * y * drad + 6 * p1 * y + 2 * p2 * x;
        Eigen::Matrix<float, 2, 3> Jn;
        Jn << iz, 0, -x * iz, 0, iz, -y * iz;
        J = Eigen::DiagonalMatrix<float, 2>(fx, fy) * Jd * Jn * R;
        const float xd = x * rad + 2 * p1 * x * y + p2 * (r2 + 2 * x * x);
        const float yd = y * rad + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y;
        return Eigen::Vector2f(fx * xd + cx, fy * yd + cy);
    }
};

struct EigenFilter {
    Vec6 x;
    Mat6 P;
    void step(float dt, const Eigen::Vector3f &q, const EigenCam *cams, const Eigen::Vector2f *z, float r)
    {
        Mat6 F = Mat6::Identity();
        F.topRightCorner<3, 3>().diagonal().setConstant(dt);
        Mat6 Q = Mat6::Zero();
        for (int i = 0; i < 3; i++) {
            Q(i, i) = q(i) * dt * dt * dt / 3;
            Q(i, i + 3) = Q(i + 3, i) = q(i) * dt * dt / 2;
            Q(i + 3, i + 3) = q(i) * dt;
        }
        x = F * x;
        P = F * P * F.transpose() + Q;
        Mat10x6 H = Mat10x6::Zero();
        Vec10 y;
        for (int k = 0; k < 5; k++) {
            Eigen::Matrix<float, 2, 3> J;
            const Eigen::Vector2f h = cams[k].project(x.head<3>(), J);
            H.block<2, 3>(2 * k, 0) = J;
            y.segment<2>(2 * k) = z[k] - h;
        }
        const Mat10 S = H * P * H.transpose() + Mat10::Identity() * r;
        const Eigen::LLT<Mat10> llt(S);
        const Eigen::Matrix<float, 6, 10> K = llt.solve(H * P).transpose();
        x += K * y;
        const Mat6 A = Mat6::Identity() - K * H;
        P = A * P * A.transpose() + r * K * K.transpose();
    }
};

/* The tuned peer: what a careful engineer writes with fixed-size Eigen for the same step as
 * mvtrack's (sequential per-camera updates, a 2x2 innovation with its closed-form inverse, H's
 * zero velocity columns skipped, the Joseph form expanded as P - K HP - (HP)^T K^T + K S K^T). */
struct EigenSeqFilter {
    Vec6 x;
    Mat6 P;
    void predict_cv(float dt, const Eigen::Vector3f &q)
    {
        x.head<3>() += dt * x.tail<3>();
        const Eigen::Matrix3f A = P.topLeftCorner<3, 3>(), B = P.topRightCorner<3, 3>(), C = P.bottomRightCorner<3, 3>();
        P.topLeftCorner<3, 3>() = A + dt * (B + B.transpose()) + (dt * dt) * C;
        P.topRightCorner<3, 3>() = B + dt * C;
        P.bottomLeftCorner<3, 3>() = P.topRightCorner<3, 3>().transpose();
        const float dt2 = dt * dt;
        for (int i = 0; i < 3; i++) {
            P(i, i) += q(i) * dt2 * dt / 3;
            P(i, i + 3) += q(i) * dt2 / 2;
            P(i + 3, i) = P(i, i + 3);
            P(i + 3, i + 3) += q(i) * dt;
        }
    }
    /* returns -0.5 y^T S^-1 y - 0.5 log det S (the IMM's likelihood) */
    float update(const Eigen::Matrix<float, 2, 3> &J, const Eigen::Vector2f &y, float r)
    {
        const Eigen::Matrix<float, 2, 6> HP = J * P.topRows<3>();
        Eigen::Matrix2f S = HP.leftCols<3>() * J.transpose();
        S(0, 0) += r;
        S(1, 1) += r;
        const float det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
        Eigen::Matrix2f Si;
        Si << S(1, 1) / det, -S(0, 1) / det, -S(1, 0) / det, S(0, 0) / det;
        const Eigen::Matrix<float, 6, 2> K = HP.transpose() * Si;
        x.noalias() += K * y;
        const Eigen::Matrix<float, 6, 2> M = K * S - HP.transpose();
        P.noalias() += M * K.transpose();
        P.noalias() -= K * HP;
        P.triangularView<Eigen::StrictlyLower>() = P.transpose(); /* exactly symmetric, as mvtrack's */
        return -0.5f * y.dot(Si * y) - 0.5f * std::log(det);
    }
    /* The IMM's update, as mvt_imm's pixel update: S = L D L^T, whitened rows v = L^-1 H P, the
     * robust covariance change in terms of them; NX = 3 for a standing model (its P_pv is 0).
     * Returns the measurement's likelihood (1 - eps) N(y; 0, S) + clutter. */
    template <int NX>
    float update_ldl(const Eigen::Matrix<float, 2, 3> &J, const Eigen::Vector2f &y, float r, float eps, float clutter)
    {
        Eigen::Matrix<float, 2, NX> V = J * P.topLeftCorner<3, NX>();
        const float s00 = V.row(0).template head<3>().dot(J.row(0)) + r;
        const float s01 = V.row(0).template head<3>().dot(J.row(1));
        const float s11 = V.row(1).template head<3>().dot(J.row(1)) + r;
        const float i0 = 1 / s00, l = s01 * i0, d1 = s11 - l * s01, i1 = 1 / d1;
        V.row(1) -= l * V.row(0);
        const float z1 = y(1) - l * y(0);
        /* robust, as mvt_imm: the detection is right with probability w */
        const float g = std::exp(-0.5f * (y(0) * y(0) * i0 + z1 * z1 * i1)) * std::sqrt(i0 * i1) * 0.15915494f;
        const float like = (1 - eps) * g + clutter, w = (1 - eps) * g / like;
        const Eigen::Matrix<float, NX, 1> d = V.row(0).transpose() * (y(0) * i0) + V.row(1).transpose() * (z1 * i1);
        x.head<NX>() += w * d;
        P.topLeftCorner<NX, NX>().noalias() -= (w * i0 * V.row(0).transpose()) * V.row(0) +
                                               (w * i1 * V.row(1).transpose()) * V.row(1) - (w * (1 - w) * d) * d.transpose();
        return like;
    }
    void step(float dt, const Eigen::Vector3f &q, const EigenCam *cams, const Eigen::Vector2f *z, float r)
    {
        predict_cv(dt, q);
        for (int k = 0; k < 5; k++) {
            Eigen::Matrix<float, 2, 3> J;
            const Eigen::Vector2f h = cams[k].project(x.head<3>(), J);
            update(J, z[k] - h, r);
        }
    }
};

/* The same bank as mvt_imm_config_default in the tuned peer's style: mixing, per-model prediction,
 * each camera projected once at the combined position, every model updated (the same L D L^T form
 * as mvt_imm, the standing model on its position rows, robust with the same p_outlier), one
 * combination at the end. */
struct EigenImm {
    enum { N = 4 };
    int n = N;
    EigenSeqFilter m[N];
    float mu[N];
    float leave[N];
    Eigen::Vector3f q[N];
    bool still[N][3];  /* per model and axis: the axis holds (STILL), else constant velocity */
    bool all_still[N]; /* the standing model: updated on its position rows only */
    float eps = 0.1f, radius = 150.0f; /* p_outlier, outlier_radius_px */
    Vec6 xc;
    Mat6 Pc;
    void combine()
    {
        xc.setZero();
        for (int j = 0; j < n; j++) xc += mu[j] * m[j].x;
        Pc.setZero();
        for (int j = 0; j < n; j++) {
            const Vec6 d = m[j].x - xc;
            Pc.noalias() += mu[j] * (m[j].P + d * d.transpose());
        }
    }
    void predict(int j, float dt)
    {
        Eigen::Vector3f qcv = q[j];
        bool any_cv = false;
        for (int i = 0; i < 3; i++) {
            if (!still[j][i]) {
                any_cv = true;
                continue;
            }
            qcv(i) = 0;
            m[j].x(3 + i) = 0;
            m[j].P.row(3 + i).setZero();
            m[j].P.col(3 + i).setZero();
        }
        if (any_cv) m[j].predict_cv(dt, qcv);
        for (int i = 0; i < 3; i++) {
            if (still[j][i]) {
                m[j].P(i, i) += dt * q[j](i);
                m[j].P(3 + i, 3 + i) = q[j](i);
            }
        }
    }
    void step(float dt, const EigenCam *cams, const Eigen::Vector2f *z, float r)
    {
        float p[N][N], c[N];
        for (int i = 0; i < n; i++) {
            const float stay = std::exp(-leave[i] * dt);
            for (int j = 0; j < n; j++) p[i][j] = i == j ? stay : (1 - stay) / (n - 1);
        }
        Vec6 x0[N];
        Mat6 P0[N];
        for (int j = 0; j < n; j++) {
            c[j] = 0;
            for (int i = 0; i < n; i++) c[j] += p[i][j] * mu[i];
            x0[j].setZero();
            for (int i = 0; i < n; i++) x0[j] += (p[i][j] * mu[i] / c[j]) * m[i].x;
            P0[j].setZero();
            for (int i = 0; i < n; i++) {
                const Vec6 d = m[i].x - x0[j];
                P0[j].noalias() += (p[i][j] * mu[i] / c[j]) * (m[i].P + d * d.transpose());
            }
        }
        for (int j = 0; j < n; j++) {
            m[j].x = x0[j];
            m[j].P = P0[j];
            mu[j] = c[j];
            predict(j, dt);
        }
        /* between cameras only the combined position is read (the next projection), as in mvt_imm */
        for (int k = 0; k < 5; k++) {
            Eigen::Vector3f pc = Eigen::Vector3f::Zero();
            for (int j = 0; j < n; j++) pc += mu[j] * m[j].x.head<3>();
            Eigen::Matrix<float, 2, 3> J;
            const Eigen::Vector2f h = cams[k].project(pc, J);
            const float clutter = eps / (3.14159265f * radius * radius);
            float sum = 0;
            for (int j = 0; j < n; j++) {
                const Eigen::Vector2f y = z[k] - h - J * (m[j].x.head<3>() - pc);
                sum += (mu[j] *= all_still[j] ? m[j].update_ldl<3>(J, y, r, eps, clutter)
                                              : m[j].update_ldl<6>(J, y, r, eps, clutter));
            }
            for (int j = 0; j < n; j++) mu[j] /= sum;
        }
        combine();
    }
};

/* Sets the mask pixels whose centres lie in the raw-pixel rectangle [u0, u1] x [v0, v1]. */
void paint_rect(mvt_mask_t &m, double u0, double v0, double u1, double v1)
{
    const int a = std::max(0, (int)std::ceil((u0 - 1.5) / m.scale));
    const int b = std::min(m.width - 1, (int)std::floor((u1 - 1.5) / m.scale));
    const int c = std::max(0, (int)std::ceil((v0 - 1.5) / m.scale));
    const int d = std::min(m.height - 1, (int)std::floor((v1 - 1.5) / m.scale));
    for (int v = c; v <= d; v++) {
        for (int u = a; u <= b; u++) {
            m.num_fg += !m.fg[v * m.width + u];
            m.fg[v * m.width + u] = 1;
        }
    }
}

/* Adds a detection at (u, v), sigma 2 px, with a box half_w wide either side and height_px below. */
void add_blob(mvt_view_t *v, mvt_real u, mvt_real vv, mvt_real half_w, mvt_real height_px)
{
    mvt_detection_t *d = &v->det[v->num_detections++];
    d->u = u;
    d->v = vv;
    d->sigma_px = 2;
    d->score = 1;
    d->box[0] = u - half_w;
    d->box[1] = vv;
    d->box[2] = u + half_w;
    d->box[3] = vv + height_px;
}

/* tracker_frame_8cam_16people (masks: the _masks variant, each camera also sending a 192 x 144
 * foreground mask of the people, a head over a body, painted outside the timed step). */
void bench_tracker_8cam(bool masks)
{
    static mvt_tracker_t tr;
    static mvt_frame_t fr;
    static mvt_output_t out;
    const int nc = 8, np = 16, frames = 3000, skip = 100;
    static mvt_camera_t cams[8];
    static mvt_mask_t mk[8];
    for (int k = 0; k < nc; k++) {
        const double a = 2 * M_PI * k / nc;
        const double pos[3] = {4 + 4.1 * std::cos(a), 3.5 + 3.6 * std::sin(a), 2.8};
        const double tgt[3] = {4, 3.5, 0.9};
        mvt_camera_params_t p;
        look_at(&p, pos, tgt, 380 + 10 * k, -0.2);
        mvt_cam_init(&cams[k], &p);
    }
    mvt_tracker_config_t cfg;
    mvt_tracker_config_default(&cfg);
    cfg.volume.min[0] = 0; cfg.volume.min[1] = 0; cfg.volume.min[2] = 0;
    cfg.volume.max[0] = 8; cfg.volume.max[1] = 7; cfg.volume.max[2] = 2.5f;
    mvt_tracker_init(&tr, &cfg, cams, nc);
    unsigned long long lcg = 88172645463325252ull;
    auto rnd = [&]() { lcg = lcg * 6364136223846793005ull + 1442695040888963407ull; return (double)(lcg >> 11) / 9007199254740992.0; };
    double r[16], th[16], w[16], h[16];
    for (int i = 0; i < np; i++) {
        r[i] = 0.5 + 0.18 * i;
        th[i] = rnd() * 2 * M_PI;
        w[i] = (0.6 + 0.6 * rnd()) / r[i] * (i % 2 ? 1 : -1);
        h[i] = 1.6 + 0.25 * rnd();
    }
    std::vector<double> ns;
    int max_conf = 0, conf_sum = 0;
    for (int f = 0; f < frames; f++) {
        const double t = f * 0.04;
        fr.utime_us = 1000000 + (int64_t)f * 40000;
        for (int k = 0; k < nc; k++) {
            mvt_view_t *v = &fr.views[k];
            v->observed = 1;
            v->utime_us = fr.utime_us;
            v->num_detections = 0;
            v->mask = masks ? &mk[k] : nullptr;
            if (masks) {
                mk[k].width = 192;
                mk[k].height = 144;
                mk[k].scale = 4;
                mk[k].num_fg = 0;
                std::memset(mk[k].fg, 0, 192 * 144);
            }
            for (int i = 0; i < np; i++) {
                const mvt_real X[3] = {(mvt_real)(4 + r[i] * std::cos(th[i] + w[i] * t)),
                                       (mvt_real)(3.5 + r[i] * std::sin(th[i] + w[i] * t)), (mvt_real)h[i]};
                mvt_real uv[2];
                const bool missed = rnd() < 0.1; /* drawn first: the same draws as without masks */
                if (mvt_cam_project(&cams[k], X, uv, nullptr) != MVT_OK) continue;
                if (masks) { /* a head 8 px wide and 16 px high over a body 50 px wide */
                    paint_rect(mk[k], uv[0] - 4, uv[1], uv[0] + 4, uv[1] + 16);
                    paint_rect(mk[k], uv[0] - 25, uv[1] + 16, uv[0] + 25, uv[1] + 160);
                }
                if (missed) continue;
                const mvt_real u = uv[0] + (mvt_real)(2 * (rnd() + rnd() + rnd() - 1.5) * 1.414);
                const mvt_real vv = uv[1] + (mvt_real)(2 * (rnd() + rnd() + rnd() - 1.5) * 1.414);
                add_blob(v, u, vv, 25, 160); /* a body-sized box, so the occlusion step has blobs to test */
            }
            if (rnd() < 0.3) {
                const mvt_real u = (mvt_real)(rnd() * 767);
                add_blob(v, u, (mvt_real)(rnd() * 575), 15, 90);
            }
        }
        const auto t0 = std::chrono::steady_clock::now();
        mvt_tracker_step(&tr, &fr, &out);
        const auto t1 = std::chrono::steady_clock::now();
        if (f >= skip) {
            ns.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count());
            int conf = 0;
            for (int i = 0; i < out.num_tracks; i++) conf += out.tracks[i].status != MVT_TRACK_TENTATIVE;
            max_conf = std::max(max_conf, conf);
            conf_sum += conf;
        }
    }
    std::sort(ns.begin(), ns.end());
    std::printf("{\"bench\": \"%s\", \"median_ns\": %.1f, \"p99_ns\": %.1f, "
                "\"max_ns\": %.1f, \"runs\": %zu, \"mean_confirmed_tracks\": %.2f, \"births\": %llu}\n",
                masks ? "tracker_frame_8cam_16people_masks" : "tracker_frame_8cam_16people", ns[ns.size() / 2], ns[ns.size() * 99 / 100], ns.back(), ns.size(),
                (double)conf_sum / (double)ns.size(), (unsigned long long)tr.counters.births);
    if (masks) {
        std::printf("{\"bench\": \"tracker_frame_8cam_16people_masks.tops\", \"mask_top_updates\": %llu, "
                    "\"occluded_updates\": %llu}\n", (unsigned long long)tr.counters.mask_top_updates,
                    (unsigned long long)tr.counters.occluded_updates);
    }
    std::fflush(stdout);
    }

/* Paints person p's body (a vertical cylinder of radius 0.2 m under the head point) into a mask. */
void paint_body(const mvt_camera_t &cam, mvt_mask_t &m, const mvt_real head[3], uint8_t hue, uint8_t sat)
{
    for (int iz = 0; iz <= 34; iz++) {
        for (int ia = 0; ia < 16; ia++) {
            for (int ir = 0; ir <= 2; ir++) {
                const double a = 2 * M_PI * ia / 16, r = 0.1 * ir;
                const mvt_real x[3] = {(mvt_real)(head[0] + r * std::cos(a)), (mvt_real)(head[1] + r * std::sin(a)),
                                       (mvt_real)(head[2] * iz / 34.0)};
                mvt_real uv[2];
                if (mvt_cam_project(&cam, x, uv, nullptr) != MVT_OK) continue;
                const int mu = (int)((uv[0] + 0.5f) / m.scale), mv = (int)((uv[1] + 0.5f) / m.scale);
                for (int dv = -1; dv <= 1; dv++) {
                    for (int du = -1; du <= 1; du++) {
                        const int u = mu + du, v = mv + dv;
                        if (u < 0 || v < 0 || u >= m.width || v >= m.height) continue;
                        m.fg[v * m.width + u] = 1;
                        m.hue[v * m.width + u] = hue;
                        m.sat[v * m.width + u] = sat;
                    }
                }
            }
        }
    }
}

void bench_pf(const mvt_camera_t *cams)
{
    static mvt_pft_t pft;
    static mvt_frame_t frame;
    static mvt_mask_t masks[5];
    mvt_pft_config_t cfg;
    mvt_pft_config_default(&cfg);
    cfg.det.volume.min[0] = cfg.det.volume.min[1] = cfg.det.volume.min[2] = 0;
    cfg.det.volume.max[0] = 6;
    cfg.det.volume.max[1] = 5;
    cfg.det.volume.max[2] = 2.5;
    if (mvt_pft_init(&pft, &cfg, cams, 5) != MVT_OK) {
        std::fprintf(stderr, "mvtrack-bench: pft init failed\n");
        return;
    }
    const int frames = 600, skip = 50;
    std::vector<double> ns;
    for (int f = 0; f < frames; f++) {
        const double t = f / 25.0;
        mvt_real heads[4][3];
        for (int p = 0; p < 4; p++) {  /* circles of 1 m radius around four centres */
            const double a = 0.8 * t + p * 1.57;
            heads[p][0] = (mvt_real)(1.8 + 2.4 * (p & 1) + 0.7 * std::cos(a));
            heads[p][1] = (mvt_real)(1.5 + 2.0 * (p >> 1) + 0.7 * std::sin(a));
            heads[p][2] = (mvt_real)(1.65 + 0.05 * p);
        }
        frame.utime_us = 1000000 + (int64_t)f * 40000;
        for (int k = 0; k < 5; k++) {
            mvt_mask_t &m = masks[k];
            m.width = 192;
            m.height = 144;
            m.scale = 4;
            m.has_colour = 1;
            std::memset(m.fg, 0, 192 * 144);
            std::memset(m.hue, 20, 192 * 144);
            std::memset(m.sat, 30, 192 * 144);
            mvt_view_t &v = frame.views[k];
            v.observed = 1;
            v.utime_us = frame.utime_us;
            v.num_detections = 0;
            for (int p = 0; p < 4; p++) {
                paint_body(cams[k], m, heads[p], (uint8_t)(64 * p), (uint8_t)(160 + 20 * p));
                mvt_real uv[2];
                if (mvt_cam_project(&cams[k], heads[p], uv, nullptr) == MVT_OK) {
                    mvt_detection_t &d = v.det[v.num_detections++];
                    std::memset(&d, 0, sizeof(d));
                    d.u = uv[0];
                    d.v = uv[1];
                    d.sigma_px = 3;
                    d.score = 1;
                    d.hue = d.saturation = -1;
                }
            }
            v.mask = &m;
        }
        static mvt_output_t out;
        const auto t0 = std::chrono::steady_clock::now();
        mvt_pft_step(&pft, &frame, &out);
        const auto t1 = std::chrono::steady_clock::now();
        if (f >= skip) ns.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count());
    }
    int targets = 0;
    for (const auto &a : pft.targets) targets += a.id != 0;
    std::sort(ns.begin(), ns.end());
    std::printf("{\"bench\": \"pf_frame_5cam_4targets\", \"median_ns\": %.1f, \"p99_ns\": %.1f, \"max_ns\": %.1f, "
                "\"runs\": %zu, \"iters\": 1, \"targets\": %d, \"particles\": %d}\n",
                ns[ns.size() / 2], ns[ns.size() * 99 / 100], ns.back(), ns.size(), targets, cfg.num_particles);
    std::fflush(stdout);
}

}  // namespace

int main(int argc, char **argv)
{
    std::vector<std::string> want(argv + 1, argv + argc);
    auto enabled = [&](const char *n) { return want.empty() || std::find(want.begin(), want.end(), n) != want.end(); };
    for (const auto &w : want) {
        if (w == "--help" || w == "-h") {
            std::printf("usage: mvtrack-bench [filter_update_5cam] [tracker_frame_5cam_1target] "
                        "[tracker_frame_8cam_16people] [tracker_frame_8cam_16people_masks] [pf_frame_5cam_4targets] [detect_frame_768x576]\n"
                        "Prints one JSON object per benchmark (peers: NAME.eigen).\n");
            return 0;
        }
        if (w != "filter_update_5cam" && w != "tracker_frame_5cam_1target" && w != "tracker_frame_8cam_16people" &&
            w != "tracker_frame_8cam_16people_masks" &&
            w != "pf_frame_5cam_4targets" && w != "detect_frame_768x576") {
            std::fprintf(stderr, "mvtrack-bench: unknown benchmark '%s'\n", w.c_str());
            return 2;
        }
    }
    static Rig5 rig;
    const mvt_real truth[3] = {2.7f, 2.1f, 1.7f};
    mvt_real uv[5][2];
    for (int k = 0; k < 5; k++) mvt_cam_project(&rig.cams[k], truth, uv[k], nullptr);
    const mvt_real q[3] = {0.5f, 0.5f, 0.05f};
    const int runs = 21;

    if (enabled("filter_update_5cam")) {
        mvt_cv_state_t s;
        const mvt_real cov[9] = {1e-3f, 0, 0, 0, 1e-3f, 0, 0, 0, 1e-3f};
        mvt_cv_init(&s, truth, cov, 0.25f, 0);
        mvt_pkf_meas_t m[5];
        for (int k = 0; k < 5; k++) mvt_pkf_meas_make(&rig.cams[k], uv[k], 3.0f, &m[k]);
        auto single_step = [&](int i) {
            mvt_cv_predict(&s, 0.04f, q);
            for (int k = 0; k < 5; k++) {
                mvt_pkf_innov_t in;
                if (mvt_pkf_innovation(&s, &rig.cams[k], MVT_PKF_JACOBIAN, &m[k], &in) == MVT_OK) mvt_pkf_update(&s, &in);
            }
            if ((i & 1023) == 0) g_sink += s.x[0];
        };
        measure("filter_update_5cam", 200000, runs, single_step);
        std::vector<EigenCam> ec;
        for (int k = 0; k < 5; k++) ec.emplace_back(rig.cams[k]);
        EigenFilter ef;
        ef.x << truth[0], truth[1], truth[2], 0, 0, 0;
        ef.P = Mat6::Identity() * 1e-3f;
        ef.P.bottomRightCorner<3, 3>() = Eigen::Matrix3f::Identity() * 0.25f;
        Eigen::Vector2f z[5];
        for (int k = 0; k < 5; k++) z[k] << uv[k][0], uv[k][1];
        const Eigen::Vector3f qe(q[0], q[1], q[2]);
        measure("filter_update_5cam.eigen", 200000, runs, [&](int i) {
            ef.step(0.04f, qe, ec.data(), z, 9.0f);
            if ((i & 1023) == 0) g_sink += ef.x(0);
        });
        std::fprintf(stderr, "# agreement after the run: |x_mvtrack - x_eigen| = %.3g m\n",
                     (double)(Eigen::Vector3f(s.x[0], s.x[1], s.x[2]) - ef.x.head<3>()).norm());
        EigenSeqFilter es;
        es.x = ef.x;
        es.x << truth[0], truth[1], truth[2], 0, 0, 0;
        es.P = Mat6::Identity() * 1e-3f;
        es.P.bottomRightCorner<3, 3>() = Eigen::Matrix3f::Identity() * 0.25f;
        auto peer_step = [&](int i) {
            es.step(0.04f, qe, ec.data(), z, 9.0f);
            if ((i & 1023) == 0) g_sink += es.x(0);
        };
        measure("filter_update_5cam.eigen_tuned", 200000, runs, peer_step);
        measure_ratio("filter_update_5cam.vs_eigen_tuned", 2000, 401, peer_step, single_step);
        std::fprintf(stderr, "# agreement after the run: |x_mvtrack - x_eigen_tuned| = %.3g m\n",
                     (double)(Eigen::Vector3f(s.x[0], s.x[1], s.x[2]) - es.x.head<3>()).norm());
        /* the IMM step: the tracker's path (mvt_trk_motion.c) for one track */
        mvt_imm_config_t icfg;
        mvt_imm_config_default(&icfg);
        mvt_cv_state_t si;
        mvt_cv_init(&si, truth, cov, 0.25f, 0);
        mvt_imm_t imm;
        mvt_imm_init(&imm, &icfg, &si);
        int64_t t_us = 0;
        auto imm_step = [&](int i) {
            t_us += 40000;
            mvt_imm_predict_to_pos(&imm, &icfg, t_us, &si);
            for (int k = 0; k < 5; k++) {
                mvt_pkf_pred_t pred;
                mvt_pkf_innov_t in;
                if (mvt_pkf_predict_obs(&si, &rig.cams[k], MVT_PKF_JACOBIAN, &pred) != MVT_OK ||
                    mvt_pkf_innovation_from(&pred, &m[k], nullptr, &in) != MVT_OK)
                    continue;
                const mvt_real noise[4] = {in.r, 0, 0, in.r};
                mvt_imm_update_pos(&imm, &icfg, 2, in.H, in.y, noise, &si);
            }
            mvt_imm_combine(&imm, &icfg, &si);
            if ((i & 1023) == 0) g_sink += si.x[0];
        };
        measure("filter_update_5cam_imm", 100000, runs, imm_step);
        measure_ratio("filter_update_5cam_imm.vs_single", 2000, 401, single_step, imm_step);
        EigenImm ei;
        ei.n = icfg.n < EigenImm::N ? icfg.n : (int)EigenImm::N;
        for (int j = 0; j < ei.n; j++) {
            ei.m[j] = es;
            ei.m[j].x << truth[0], truth[1], truth[2], 0, 0, 0;
            ei.m[j].P = Mat6::Identity() * 1e-3f;
            ei.m[j].P.bottomRightCorner<3, 3>() = Eigen::Matrix3f::Identity() * 0.25f;
            ei.leave[j] = icfg.model[j].leave_hz;
            ei.q[j] << icfg.model[j].q[0], icfg.model[j].q[1], icfg.model[j].q[2];
            for (int a = 0; a < 3; a++) ei.still[j][a] = icfg.model[j].kind[a] == MVT_MOTION_STILL;
            ei.all_still[j] = mvt_imm_model_is(&icfg.model[j], MVT_MOTION_STILL);
            ei.eps = (float)icfg.p_outlier;
            ei.radius = (float)icfg.outlier_radius_px;
        }
        mvt_real mu0[MVT_IMM_MODELS];
        mvt_imm_stationary(&icfg, mu0);
        for (int j = 0; j < ei.n; j++) ei.mu[j] = (float)mu0[j];
        auto peer_imm_step = [&](int i) {
            ei.step(0.04f, ec.data(), z, 9.0f);
            if ((i & 1023) == 0) g_sink += ei.xc(0);
        };
        measure("filter_update_5cam_imm.eigen_tuned", 100000, runs, peer_imm_step);
        measure_ratio("filter_update_5cam_imm.vs_eigen_tuned", 2000, 401, peer_imm_step, imm_step);
        std::fprintf(stderr, "# agreement after the run: |x_imm - x_eigen_imm| = %.3g m\n",
                     (double)(Eigen::Vector3f(si.x[0], si.x[1], si.x[2]) - ei.xc.head<3>()).norm());
    }
    if (enabled("tracker_frame_5cam_1target")) {
        static mvt_tracker_t tr;
        static mvt_frame_t fr;
        static mvt_output_t out;
        mvt_tracker_config_t cfg;
        mvt_tracker_config_default(&cfg);
        mvt_tracker_init(&tr, &cfg, rig.cams, 5);
        std::memset(&fr, 0, sizeof(fr));
        int64_t t = 0;
        measure("tracker_frame_5cam_1target", 20000, runs, [&](int i) {
            t += 40000;
            fr.utime_us = t;
            for (int k = 0; k < 5; k++) {
                fr.views[k].observed = 1;
                fr.views[k].utime_us = t;
                fr.views[k].num_detections = 1;
                fr.views[k].det[0].u = uv[k][0] + (mvt_real)((i * 7 + k) % 5 - 2);
                fr.views[k].det[0].v = uv[k][1] + (mvt_real)((i * 3 + k) % 5 - 2);
                fr.views[k].det[0].sigma_px = 3;
            }
            mvt_tracker_step(&tr, &fr, &out);
            if ((i & 1023) == 0) g_sink += out.num_tracks;
        });
    }
    if (enabled("tracker_frame_8cam_16people")) {
        bench_tracker_8cam(false);
    }
    if (enabled("tracker_frame_8cam_16people_masks")) {
        bench_tracker_8cam(true);
    }
    if (enabled("pf_frame_5cam_4targets")) {
        bench_pf(rig.cams);
    }
    if (enabled("detect_frame_768x576") &&
        bench_detect(MVT_VTEST_VIDEO, MVT_SOURCE_DIR "/tests/data/vtest_rig.yaml") != 0) {
        return 1;
    }
    return 0;
}
