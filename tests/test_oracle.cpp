/*
 * Oracle tests: the core against independent double-precision references.
 *  - camera model against OpenCV (cv::projectPoints, its Jacobian, cv::undistortPoints, cv::Rodrigues);
 *  - the projective filters against an Eigen implementation of the paper's 8x8 homogeneous form
 *    (state [X Y Z 1 Vx Vy Vz 0], F of Eq. 16 with the real dt, H of Eq. 18 or the Jacobian,
 *    dense Kalman equations 7-11 with the Joseph covariance update);
 *  - the paper's gate (Eq. 22-26) against an Eigen dual-quadric projection and the geometric fact
 *    that every projected point of the ellipsoid lies inside its outline.
 */
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include <Eigen/Dense>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

extern "C" {
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
}

#include "mvt_pkf.h"
#include "mvt_tracker.h"
#include "test_support.h"

using Mat8 = Eigen::Matrix<double, 8, 8>;
using Vec6d = Eigen::Matrix<double, 6, 1>;
using Mat6d = Eigen::Matrix<double, 6, 6>;
using Vec8 = Eigen::Matrix<double, 8, 1>;

static const double POS_TOL = MVT_USE_DOUBLE ? 1e-9 : 2e-4;   /* metres */
static const double PX_TOL = MVT_USE_DOUBLE ? 1e-8 : 2e-3;    /* pixels */

struct OracleCam {
    cv::Mat K, D, rvec, tvec;
    Eigen::Matrix<double, 3, 4> P;
    Eigen::Matrix3d R;
};

static OracleCam oracle_of(const mvt_camera_params_t &p)
{
    OracleCam o;
    o.K = cv::Mat(3, 3, CV_64F);
    for (int i = 0; i < 9; i++) o.K.at<double>(i) = p.camera_matrix[i];
    o.D = cv::Mat(1, 8, CV_64F);
    for (int i = 0; i < 8; i++) o.D.at<double>(i) = p.dist[i];
    o.rvec = (cv::Mat_<double>(3, 1) << p.rvec[0], p.rvec[1], p.rvec[2]);
    o.tvec = (cv::Mat_<double>(3, 1) << p.tvec[0], p.tvec[1], p.tvec[2]);
    cv::Mat R;
    cv::Rodrigues(o.rvec, R);
    Eigen::Matrix<double, 3, 4> Rt;
    Eigen::Matrix3d Ke;
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++) {
            Rt(r, c) = R.at<double>(r, c);
            o.R(r, c) = R.at<double>(r, c);
            Ke(r, c) = o.K.at<double>(r, c);
        }
        Rt(r, 3) = o.tvec.at<double>(r);
    }
    o.P = Ke * Rt;
    return o;
}

static void cv_project(const OracleCam &o, const Eigen::Vector3d &X, Eigen::Vector2d &uv, Eigen::Matrix<double, 2, 3> *J)
{
    std::vector<cv::Point3d> pts{cv::Point3d(X(0), X(1), X(2))};
    std::vector<cv::Point2d> out;
    cv::Mat jac;
    cv::projectPoints(pts, o.rvec, o.tvec, o.K, o.D, out, jac);
    uv << out[0].x, out[0].y;
    if (J != nullptr) { /* d uv / d X = d uv / d tvec * R */
        Eigen::Matrix<double, 2, 3> dt;
        for (int r = 0; r < 2; r++)
            for (int c = 0; c < 3; c++) dt(r, c) = jac.at<double>(r, 3 + c);
        *J = dt * o.R;
    }
}

/* The radius (normalised) where OpenCV's radial map r (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2
 * + k5 r^4 + k6 r^6) has its first maximum: beyond it projectPoints folds points back into the
 * picture. Found here by the derivative's sign change and bisection, in double. */
static double fold_radius(const OracleCam &o)
{
    const double *d = o.D.ptr<double>();
    auto g = [d](double r) {
        const double r2 = r * r;
        return r * (1 + r2 * (d[0] + r2 * (d[1] + r2 * d[4]))) / (1 + r2 * (d[5] + r2 * (d[6] + r2 * d[7])));
    };
    auto dg = [&g](double r) { return (g(r + 1e-7) - g(r - 1e-7)) / 2e-7; };
    double lo = 1e-3;
    for (double r = 1e-3; r < 20; r += 1e-3) {
        if (!(dg(r) > 0)) {
            double hi = r;
            for (int i = 0; i < 60; i++) {
                const double m = 0.5 * (lo + hi);
                (dg(m) > 0 ? lo : hi) = m;
            }
            return lo;
        }
        lo = r;
    }
    return 1e15;
}

static Eigen::Vector2d cv_undistort_ideal(const OracleCam &o, const Eigen::Vector2d &uv)
{
    std::vector<cv::Point2d> in{cv::Point2d(uv(0), uv(1))}, out;
    cv::undistortPoints(in, out, o.K, o.D, cv::noArray(), o.K,
                        cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 200, 1e-15));
    return Eigen::Vector2d(out[0].x, out[0].y);
}

static std::vector<mvt_camera_params_t> random_params(std::mt19937 &g, int n, bool eight)
{
    std::uniform_real_distribution<double> U(0, 1);
    std::vector<mvt_camera_params_t> ps;
    for (int k = 0; k < n; k++) {
        const double a = 2 * M_PI * (k + 0.3 * U(g)) / n;
        const double pos[3] = {3 + 3.2 * std::cos(a), 2.5 + 2.7 * std::sin(a), 2.3 + 0.6 * U(g)};
        const double tgt[3] = {3 + U(g) - 0.5, 2.5 + U(g) - 0.5, 0.8 + 0.4 * U(g)};
        const double d[5] = {-0.35 + 0.4 * U(g), 0.1 * U(g), 2e-3 * (U(g) - 0.5), 2e-3 * (U(g) - 0.5), -0.02 * U(g)};
        mvt_camera_params_t p;
        test_look_at(&p, pos, tgt, 350 + 400 * U(g), 300 + 150 * U(g), 220 + 120 * U(g), d);
        p.camera_matrix[4] = (mvt_real)((double)p.camera_matrix[0] * (0.97 + 0.06 * U(g)));
        if (eight) {
            p.dist[5] = (mvt_real)(0.05 * U(g));
            p.dist[6] = (mvt_real)(0.01 * U(g));
            p.dist[7] = (mvt_real)(0.002 * U(g));
        }
        ps.push_back(p);
    }
    return ps;
}

static int g_folded;

static void test_mvt_cam_project_matches_opencv(void **state)
{
    (void)state;
    std::mt19937 g(7);
    std::uniform_real_distribution<double> U(0, 1);
    for (int eight = 0; eight < 2; eight++) {
        for (const auto &p : random_params(g, 8, eight != 0)) {
            mvt_camera_t cam;
            assert_int_equal(mvt_cam_init(&cam, &p), MVT_OK);
            const OracleCam o = oracle_of(p);
            for (int i = 0; i < 9; i++) { /* Rodrigues */
                assert_true(std::fabs((double)cam.R[i] - o.R(i / 3, i % 3)) < (MVT_USE_DOUBLE ? 1e-12 : 1e-6));
            }
            const double rf = fold_radius(o);
            for (int t = 0; t < 50; t++) {
                const Eigen::Vector3d X(0.5 + 5 * U(g), 0.5 + 4 * U(g), 0.2 + 1.8 * U(g));
                Eigen::Vector2d uv;
                Eigen::Matrix<double, 2, 3> J;
                cv_project(o, X, uv, &J);
                if (uv(0) < 0 || uv(0) > 767 || uv(1) < 0 || uv(1) > 575) continue;
                const mvt_real x[3] = {(mvt_real)X(0), (mvt_real)X(1), (mvt_real)X(2)};
                mvt_real m[2], mj[6];
                const Eigen::Vector3d Xc = o.R * X + Eigen::Vector3d(o.tvec.ptr<double>());
                const double r = std::hypot(Xc(0) / Xc(2), Xc(1) / Xc(2));
                if (r > rf + 0.01) { /* OpenCV folded it into the picture; the core has no image of it */
                    assert_int_equal(mvt_cam_project(&cam, x, m, mj), MVT_ERR_BEHIND);
                    g_folded++;
                    continue;
                }
                if (r > rf - 0.01) continue; /* the scan's step */
                assert_int_equal(mvt_cam_project(&cam, x, m, mj), MVT_OK);
                assert_true(std::fabs(m[0] - uv(0)) < PX_TOL * 10 && std::fabs(m[1] - uv(1)) < PX_TOL * 10);
                for (int i = 0; i < 6; i++) {
                    const double ref = J(i / 3, i % 3);
                    assert_true(std::fabs(mj[i] - ref) < 1e-4 * std::fabs(ref) + (MVT_USE_DOUBLE ? 1e-8 : 1e-2));
                }
                /* undistortion (iterative inverse) against OpenCV's, run to convergence */
                const Eigen::Vector2d ideal = cv_undistort_ideal(o, uv);
                mvt_real xn[2], mi[2];
                const mvt_real raw[2] = {(mvt_real)uv(0), (mvt_real)uv(1)};
                assert_int_equal(mvt_cam_undistort(&cam, raw, xn), MVT_OK);
                mvt_cam_normalised_to_ideal(&cam, xn, mi);
                assert_true(std::fabs(mi[0] - ideal(0)) < PX_TOL * 20 && std::fabs(mi[1] - ideal(1)) < PX_TOL * 20);
            }
        }
    }
    print_message("# %d in-picture OpenCV projections lay beyond the fold and were refused\n", g_folded);
}

/* n random cameras (no extreme lenses) for the core and for the oracle. */
static void random_rig(std::mt19937 &g, int n, std::vector<mvt_camera_t> &cams, std::vector<OracleCam> &oc)
{
    const auto ps = random_params(g, n, false);
    cams.resize((size_t)n);
    for (int k = 0; k < n; k++) {
        assert_int_equal(mvt_cam_init(&cams[(size_t)k], &ps[(size_t)k]), MVT_OK);
        oc.push_back(oracle_of(ps[(size_t)k]));
    }
}

/* The oracle filter: the paper's 8x8 form in Eigen double. */
struct OracleFilter {
    Vec8 s;
    Mat8 S;
    void init(const mvt_cv_state_t &c)
    {
        s.setZero();
        S.setZero();
        for (int i = 0; i < 3; i++) {
            s(i) = c.x[i];
            s(4 + i) = c.x[3 + i];
        }
        s(3) = 1.0;
        const int map[6] = {0, 1, 2, 4, 5, 6};
        for (int i = 0; i < 6; i++)
            for (int j = 0; j < 6; j++) S(map[i], map[j]) = c.P[i * 6 + j];
    }
    void predict(double dt, const double q[3])
    {
        Mat8 F = Mat8::Identity();
        Mat8 Q = Mat8::Zero();
        for (int i = 0; i < 3; i++) {
            F(i, 4 + i) = dt; /* Eq. 16 with the frame interval */
            Q(i, i) = q[i] * dt * dt * dt / 3;
            Q(i, 4 + i) = Q(4 + i, i) = q[i] * dt * dt / 2;
            Q(4 + i, 4 + i) = q[i] * dt;
        }
        s = F * s;
        S = F * S * F.transpose() + Q;
    }
    /* one camera's pixel rows; lin 0 Jacobian, 1 paper, 2 paper centred */
    void update(const OracleCam &o, int lin, const Eigen::Vector2d &raw, double r)
    {
        Eigen::Matrix<double, 2, 8> H = Eigen::Matrix<double, 2, 8>::Zero();
        Eigen::Vector2d y;
        if (lin == 0) {
            Eigen::Vector2d uv;
            Eigen::Matrix<double, 2, 3> J;
            cv_project(o, s.head<3>(), uv, &J);
            H.block<2, 3>(0, 0) = J;
            y = raw - uv;
        } else {
            const double alpha = 1.0 / (o.P.row(2).dot(s.head<4>())); /* Eq. 18 */
            Eigen::Matrix<double, 3, 4> Pc = o.P;
            if (lin == 2) {
                Pc.row(0) -= o.K.at<double>(0, 2) * o.P.row(2);
                Pc.row(1) -= o.K.at<double>(1, 2) * o.P.row(2);
            }
            H.block<2, 4>(0, 0) = alpha * Pc.topRows<2>();
            Eigen::Vector2d z = cv_undistort_ideal(o, raw);
            if (lin == 2) z -= Eigen::Vector2d(o.K.at<double>(0, 2), o.K.at<double>(1, 2));
            y = z - H * s;
        }
        const Eigen::Matrix2d R = r * Eigen::Matrix2d::Identity();
        const Eigen::Matrix2d Sy = H * S * H.transpose() + R;
        const Eigen::Matrix<double, 8, 2> K = S * H.transpose() * Sy.inverse();
        s += K * y;
        const Mat8 A = Mat8::Identity() - K * H;
        S = A * S * A.transpose() + K * R * K.transpose();
    }
};

static void test_mvt_pkf_update_sequence_matches_eigen_oracle(void **state)
{
    (void)state;
    std::mt19937 g(11);
    std::normal_distribution<double> N(0, 1);
    std::vector<mvt_camera_t> cams;
    std::vector<OracleCam> oc;
    random_rig(g, 5, cams, oc);
    const double q[3] = {0.6, 0.4, 0.03};
    const mvt_real qr[3] = {(mvt_real)q[0], (mvt_real)q[1], (mvt_real)q[2]};
    for (int lin = 0; lin < 3; lin++) {
        mvt_cv_state_t c;
        const mvt_real p0[3] = {2.5f, 2.0f, 1.6f}, cov[9] = {0.01f, 0.002f, 0, 0.002f, 0.01f, 0, 0, 0, 0.004f};
        mvt_cv_init(&c, p0, cov, 0.5f, 0);
        OracleFilter of;
        of.init(c);
        double worst = 0;
        for (int step = 0; step < 100; step++) {
            const double dt = 0.04 + 0.002 * std::sin(step); /* cameras are not perfectly periodic */
            const double t = step * 0.04;
            const Eigen::Vector3d truth(2.5 + 0.8 * std::sin(0.5 * t), 2.0 + 0.6 * std::cos(0.4 * t), 1.7);
            assert_int_equal(mvt_cv_predict(&c, (mvt_real)dt, qr), MVT_OK);
            of.predict(dt, q);
            for (int k = 0; k < 5; k++) {
                if (step % 7 == k) continue; /* occluded view: rows left out */
                Eigen::Vector2d uv;
                cv_project(oc[k], truth, uv, nullptr);
                uv += 3.0 * Eigen::Vector2d(N(g), N(g));
                const mvt_real raw[2] = {(mvt_real)uv(0), (mvt_real)uv(1)};
                mvt_pkf_meas_t m;
                mvt_pkf_innov_t in;
                assert_int_equal(mvt_pkf_meas_make(&cams[k], raw, 3.0f, &m), MVT_OK);
                assert_int_equal(mvt_pkf_innovation(&c, &cams[k], (mvt_pkf_lin_t)lin, &m, &in), MVT_OK);
                assert_int_equal(mvt_pkf_update(&c, &in), MVT_OK);
                /* the oracle sees the same (float-rounded) measurement */
                of.update(oc[k], lin, Eigen::Vector2d(raw[0], raw[1]), 9.0);
            }
            const int map[6] = {0, 1, 2, 4, 5, 6};
            for (int i = 0; i < 6; i++) {
                const double d = std::fabs((double)c.x[i] - of.s(map[i]));
                worst = std::fmax(worst, d);
                assert_true(d < POS_TOL * (i < 3 ? 1 : 10));
                for (int j = 0; j < 6; j++) {
                    const double ref = of.S(map[i], map[j]);
                    const double scale = std::sqrt(of.S(map[i], map[i]) * of.S(map[j], map[j]));
                    assert_true(std::fabs((double)c.P[i * 6 + j] - ref) < (MVT_USE_DOUBLE ? 1e-9 : 2e-3) * scale);
                }
            }
            /* the homogeneous entries stay constants in the oracle */
            assert_true(std::fabs(of.s(3) - 1.0) < 1e-12 && std::fabs(of.s(7)) < 1e-12);
        }
        std::printf("# linearisation %d: worst |x - oracle| over 100 steps = %.3g\n", lin, worst);
    }
}

/* The textbook IMM (Blom and Bar-Shalom; Bar-Shalom, Li and Kirubarajan, Sec. 11.6.6) in Eigen
 * double: full 6x6 transition and noise matrices per model, each model's EKF linearised at its own
 * estimate, Gaussian likelihoods with their normalisation; with p_outlier > 0 the measurement is
 * the person's with probability 1 - p_outlier (the PDA filter's one-measurement update,
 * Bar-Shalom and Li, Sec. 6.4: x += w K y, P = P - w K S K^T + w (1 - w) K y y^T K^T). */
struct OracleImm {
    int n;
    Vec6d x[MVT_IMM_MODELS];
    Mat6d P[MVT_IMM_MODELS];
    double mu[MVT_IMM_MODELS];
    mvt_imm_config_t cfg;
    void transition(int j, double dt, Mat6d &F, Mat6d &Q) const
    {
        F.setIdentity();
        Q.setZero();
        for (int i = 0; i < 3; i++) {
            const double q = cfg.model[j].q[i];
            if (cfg.model[j].kind[i] == MVT_MOTION_STILL) {
                F(3 + i, 3 + i) = 0.0;
                Q(i, i) = q * dt;
                Q(3 + i, 3 + i) = q;
            } else {
                F(i, 3 + i) = dt;
                Q(i, i) = q * dt * dt * dt / 3;
                Q(i, 3 + i) = Q(3 + i, i) = q * dt * dt / 2;
                Q(3 + i, 3 + i) = q * dt;
            }
        }
    }
    void predict(double dt)
    {
        Eigen::MatrixXd p(n, n);
        for (int i = 0; i < n; i++) {
            const double stay = std::exp(-(double)cfg.model[i].leave_hz * dt);
            for (int j = 0; j < n; j++) p(i, j) = i == j ? stay : (1 - stay) / (n - 1);
        }
        Vec6d x0[MVT_IMM_MODELS];
        Mat6d P0[MVT_IMM_MODELS];
        double c[MVT_IMM_MODELS];
        for (int j = 0; j < n; j++) {
            c[j] = 0;
            for (int i = 0; i < n; i++) c[j] += p(i, j) * mu[i];
            x0[j].setZero();
            for (int i = 0; i < n; i++) x0[j] += p(i, j) * mu[i] / c[j] * x[i];
            P0[j].setZero();
            for (int i = 0; i < n; i++) {
                const Vec6d d = x[i] - x0[j];
                P0[j] += p(i, j) * mu[i] / c[j] * (P[i] + d * d.transpose());
            }
        }
        for (int j = 0; j < n; j++) {
            Mat6d F, Q;
            transition(j, dt, F, Q);
            x[j] = F * x0[j];
            P[j] = F * P0[j] * F.transpose() + Q;
            mu[j] = c[j];
        }
    }
    /* With a view's memory (mvt_imm_view_t): the last displacement continues with probability
     * p exp(-dt / persist), the detection then at the remembered offset from the combined
     * prediction, spread by J P J^T + 2 R + drift dt (all taken at the combination). */
    struct View {
        double p = 0, t = 0;
        Eigen::Vector2d y = Eigen::Vector2d::Zero();
    };
    void update(const OracleCam &o, const Eigen::Vector2d &raw, double r, View *vm = nullptr, double t = 0)
    {
        const double eps = cfg.p_outlier, rad = cfg.outlier_radius_px;
        double pc = 0, gc = 0;
        Eigen::Vector2d yc = Eigen::Vector2d::Zero();
        if (vm != nullptr) {
            const Vec6d xm = combined();
            Mat6d Pm = Mat6d::Zero();
            for (int j = 0; j < n; j++) Pm += mu[j] * (P[j] + (x[j] - xm) * (x[j] - xm).transpose());
            Eigen::Vector2d uv;
            Eigen::Matrix<double, 2, 3> J;
            cv_project(o, xm.head<3>(), uv, &J);
            yc = raw - uv;
            if (vm->p > 0 && cfg.outlier_persist_s > 0) {
                const double dt = t - vm->t;
                pc = vm->p * std::exp(-dt / cfg.outlier_persist_s);
                const Eigen::Matrix2d Sc = J * Pm.topLeftCorner<3, 3>() * J.transpose() +
                                           (2 * r + cfg.outlier_drift_px2_s * dt) * Eigen::Matrix2d::Identity();
                const Eigen::Vector2d e = yc - vm->y;
                gc = std::exp(-0.5 * e.dot(Sc.inverse() * e)) / (2 * M_PI * std::sqrt(Sc.determinant()));
            }
        }
        const double displaced = eps * (1 - pc) / (M_PI * rad * rad) + pc * gc;
        double like[MVT_IMM_MODELS], sum = 0;
        for (int j = 0; j < n; j++) {
            Eigen::Vector2d uv;
            Eigen::Matrix<double, 2, 3> J;
            cv_project(o, x[j].head<3>(), uv, &J);
            Eigen::Matrix<double, 2, 6> H = Eigen::Matrix<double, 2, 6>::Zero();
            H.leftCols<3>() = J;
            const Eigen::Vector2d y = raw - uv;
            const Eigen::Matrix2d S = H * P[j] * H.transpose() + r * Eigen::Matrix2d::Identity();
            const Eigen::Matrix<double, 6, 2> K = P[j] * H.transpose() * S.inverse();
            const double gauss = std::exp(-0.5 * y.dot(S.inverse() * y)) / (2 * M_PI * std::sqrt(S.determinant()));
            like[j] = (1 - eps) * (1 - pc) * gauss + displaced;
            const double w = (1 - eps) * (1 - pc) * gauss / like[j]; /* P(the detection is the person's) */
            x[j] += w * K * y;
            P[j] = P[j] - w * K * S * K.transpose() + w * (1 - w) * (K * y) * (K * y).transpose();
            sum += mu[j] * like[j];
        }
        for (int j = 0; j < n; j++) mu[j] = mu[j] * like[j] / sum;
        if (vm != nullptr) {
            vm->p = displaced / sum;
            vm->y = yc;
            vm->t = t;
        }
    }
    Vec6d combined() const
    {
        Vec6d m = Vec6d::Zero();
        for (int j = 0; j < n; j++) m += mu[j] * x[j];
        return m;
    }
};

/* The IMM tests' start: a head at (2.5, 2.0, 1.7) m, 0.1 m std per axis, 0.25 m/s velocity std. */
static void imm_start(const mvt_imm_config_t &cfg, mvt_cv_state_t &s, mvt_imm_t &imm)
{
    const mvt_real p0[3] = {2.5f, 2.0f, 1.7f}, cov[9] = {0.01f, 0, 0, 0, 0.01f, 0, 0, 0, 0.01f};
    mvt_cv_init(&s, p0, cov, 0.25f, 0);
    mvt_imm_init(&imm, &cfg, &s);
}

/* The textbook IMM started where the core's bank is. */
static OracleImm oracle_imm_of(const mvt_imm_config_t &cfg, const mvt_imm_t &imm, const mvt_cv_state_t &s)
{
    OracleImm o;
    o.n = cfg.n;
    o.cfg = cfg;
    for (int j = 0; j < cfg.n; j++) {
        o.mu[j] = imm.mu[j];
        for (int a = 0; a < 6; a++) {
            o.x[j](a) = s.x[a];
            for (int b = 0; b < 6; b++) o.P[j](a, b) = s.P[a * 6 + b];
        }
    }
    return o;
}

static void test_mvt_imm_matches_eigen_textbook_imm(void **state)
{
    (void)state;
    std::mt19937 g(5);
    std::normal_distribution<double> N(0, 1);
    std::vector<mvt_camera_t> cams;
    std::vector<OracleCam> oc;
    random_rig(g, 5, cams, oc);
  for (int robust = 0; robust < 2; robust++) {
    mvt_imm_config_t cfg;
    mvt_imm_config_default(&cfg);
    if (!robust) cfg.p_outlier = 0; /* Gaussian measurements: the textbook IMM */
    mvt_cv_state_t s;
    mvt_imm_t imm;
    imm_start(cfg, s, imm);
    /* the tracker's path: between cameras only the position part of the combination, whole once
     * per frame; it must give the same estimate */
    mvt_imm_t imm2 = imm;
    mvt_cv_state_t s2 = s;
    double worst_lean = 0;
    auto close = [&](mvt_real a, mvt_real b) {
        const double d = std::fabs((double)a - (double)b) / (1e-6 + std::fabs((double)b));
        worst_lean = std::fmax(worst_lean, d);
        return d < 1e-5;
    };
    auto same_position = [&]() {
        for (int a = 0; a < 3; a++) {
            assert_true(close(s2.x[a], s.x[a]));
            for (int b = 0; b < 3; b++) assert_true(close(s2.P[a * 6 + b], s.P[a * 6 + b]));
        }
    };
    OracleImm o = oracle_imm_of(cfg, imm, s);
    /* stands 2 s, walks east at 1 m/s, turns north sharply at 4 s, stops at 6 s, sits down at 8 s
     * (the head drops 0.48 m in 0.8 s) and stays seated */
    Eigen::Vector3d truth(2.5, 2.0, 1.7);
    double worst = 0, worst_mu = 0;
    double mu_at[5][MVT_IMM_MODELS];
    for (int step = 1; step <= 260; step++) {
        const double t = step * 0.04;
        const Eigen::Vector3d v = t < 2 ? Eigen::Vector3d(0, 0, 0) : t < 4 ? Eigen::Vector3d(1, 0, 0)
                                  : t < 6 ? Eigen::Vector3d(0, 1, 0) : t > 8 && t <= 8.8 ? Eigen::Vector3d(0, 0, -0.6)
                                                                                       : Eigen::Vector3d(0, 0, 0);
        truth += 0.04 * v;
        const int64_t us = (int64_t)step * 40000;
        assert_int_equal(mvt_imm_predict_to(&imm, &cfg, us, &s), MVT_OK);
        assert_int_equal(mvt_imm_predict_to_pos(&imm2, &cfg, us, &s2), MVT_OK);
        same_position();
        o.predict(0.04);
        for (int k = 0; k < 5; k++) {
            Eigen::Vector2d uv;
            cv_project(oc[k], truth, uv, nullptr);
            uv += 2.0 * Eigen::Vector2d(N(g), N(g));
            if (robust && step % 9 == k) uv += Eigen::Vector2d(12.0, -9.0); /* a displaced blob */
            const mvt_real raw[2] = {(mvt_real)uv(0), (mvt_real)uv(1)};
            mvt_pkf_meas_t m;
            mvt_pkf_innov_t in;
            assert_int_equal(mvt_pkf_meas_make(&cams[k], raw, 2.0f, &m), MVT_OK);
            assert_int_equal(mvt_pkf_innovation(&s, &cams[k], MVT_PKF_JACOBIAN, &m, &in), MVT_OK);
            const mvt_real noise[4] = {in.r, 0, 0, in.r};
            assert_int_equal(mvt_imm_update(&imm, &cfg, 2, in.H, in.y, noise, &s), MVT_OK);
            mvt_pkf_innov_t in2;
            assert_int_equal(mvt_pkf_innovation(&s2, &cams[k], MVT_PKF_JACOBIAN, &m, &in2), MVT_OK);
            const mvt_real noise2[4] = {in2.r, 0, 0, in2.r};
            assert_int_equal(mvt_imm_update_pos(&imm2, &cfg, 2, in2.H, in2.y, noise2, &s2), MVT_OK);
            same_position();
            o.update(oc[k], Eigen::Vector2d(raw[0], raw[1]), 4.0);
        }
        mvt_imm_combine(&imm2, &cfg, &s2);
        for (int a = 0; a < 6; a++) {
            assert_true(close(s2.x[a], s.x[a]));
            for (int b = 0; b < 6; b++) assert_true(close(s2.P[a * 6 + b], s.P[a * 6 + b]));
        }
        for (int j = 0; j < cfg.n; j++) assert_true(close(imm2.mu[j], imm.mu[j]));
        const Vec6d xo = o.combined();
        for (int i = 0; i < 3; i++) {
            const double d = std::fabs((double)s.x[i] - xo(i));
            worst = std::fmax(worst, d);
            assert_true(d < (robust ? 5e-4 : 2e-4)); /* linearised at the combination, float */
        }
        double sum = 0;
        for (int j = 0; j < cfg.n; j++) {
            worst_mu = std::fmax(worst_mu, std::fabs((double)imm.mu[j] - o.mu[j]));
            assert_true(std::fabs((double)imm.mu[j] - o.mu[j]) < (robust ? 0.02 : 5e-3));
            sum += imm.mu[j];
        }
        assert_true(std::fabs(sum - 1.0) < 1e-5);
        const int mark = step == 45 ? 0 : step == 105 ? 1 : step == 199 ? 2 : step == 214 ? 3 : step == 260 ? 4 : -1;
        if (mark >= 0)
            for (int j = 0; j < cfg.n; j++) mu_at[mark][j] = imm.mu[j];
    }
    /* the bank says what the person does: standing, then walking/turning, then standing, sitting
     * down (model 3, the height's own manoeuvre), seated */
    assert_true(mu_at[0][0] > 0.8);
    assert_true(mu_at[1][0] < 0.05);
    assert_true(mu_at[2][0] > 0.8);
    assert_true(cfg.n < 4 || mu_at[3][3] > 0.5);
    assert_true(mu_at[4][0] > 0.8);
    std::printf("# IMM (p_outlier %.2f) vs the textbook IMM over 260 steps: worst |x| %.3g m, worst |mu| %.3g; "
                "P(still) %.2f / %.2f / %.2f / %.2f at 1.8 s / 4.2 s / 8 s / 10.4 s, P(sitting) %.2f at 8.56 s; the "
                "per-frame combination's path differs by %.2g (relative)\n", (double)cfg.p_outlier, worst, worst_mu,
                (double)mu_at[0][0], (double)mu_at[1][0], (double)mu_at[2][0], (double)mu_at[4][0],
                cfg.n < 4 ? -1.0 : (double)mu_at[3][3], worst_lean);
  }
}

/* A person walks and stands before 5 cameras; camera (step / 12) % 5 is displaced by a fixed offset
 * in 8 of every 12 frames (a lasting displacement, as an occluding or merged blob gives). The
 * tracker's path (mvt_imm_predict_to_pos, mvt_imm_update_view with a memory per camera) against
 * OracleImm with the same memories, relinearised per model. */
static void test_mvt_imm_view_memory_matches_eigen(void **state)
{
    (void)state;
    std::mt19937 g(11);
    std::normal_distribution<double> N(0, 1);
    std::vector<mvt_camera_t> cams;
    std::vector<OracleCam> oc;
    random_rig(g, 5, cams, oc);
    mvt_imm_config_t cfg;
    mvt_imm_config_default(&cfg);
    assert_true(cfg.outlier_persist_s > 0);
    mvt_cv_state_t s;
    mvt_imm_t imm;
    imm_start(cfg, s, imm);
    mvt_imm_view_t view[5];
    memset(view, 0, sizeof(view));
    OracleImm o = oracle_imm_of(cfg, imm, s);
    OracleImm::View ov[5];
    Eigen::Vector3d truth(2.5, 2.0, 1.7);
    double worst = 0, worst_p = 0, p_burst = 0, p_clean = 0;
    int n_burst = 0, n_clean = 0;
    for (int step = 1; step <= 240; step++) {
        const double t = step * 0.04;
        const Eigen::Vector3d v = t < 2 ? Eigen::Vector3d(0, 0, 0) : t < 5 ? Eigen::Vector3d(0.8, 0.3, 0) : Eigen::Vector3d(0, 0, 0);
        truth += 0.04 * v;
        const int64_t us = (int64_t)step * 40000;
        assert_int_equal(mvt_imm_predict_to_pos(&imm, &cfg, us, &s), MVT_OK);
        o.predict(0.04);
        for (int k = 0; k < 5; k++) {
            Eigen::Vector2d uv;
            cv_project(oc[k], truth, uv, nullptr);
            uv += 2.0 * Eigen::Vector2d(N(g), N(g));
            const bool displaced = (step / 12) % 5 == k && step % 12 < 8;
            if (displaced) uv += Eigen::Vector2d(6.0, -4.0);
            const mvt_real raw[2] = {(mvt_real)uv(0), (mvt_real)uv(1)};
            mvt_pkf_meas_t m;
            mvt_pkf_innov_t in;
            assert_int_equal(mvt_pkf_meas_make(&cams[k], raw, 2.0f, &m), MVT_OK);
            assert_int_equal(mvt_pkf_innovation(&s, &cams[k], MVT_PKF_JACOBIAN, &m, &in), MVT_OK);
            const mvt_real noise[4] = {in.r, 0, 0, in.r};
            assert_int_equal(mvt_imm_update_view(&imm, &cfg, in.H, in.y, noise, in.S, &view[k], &s), MVT_OK);
            o.update(oc[k], Eigen::Vector2d(raw[0], raw[1]), 4.0, &ov[k], t);
            worst_p = std::fmax(worst_p, std::fabs((double)view[k].p - ov[k].p));
            assert_true(std::fabs((double)view[k].p - ov[k].p) < 0.03);
            assert_true(view[k].utime_us == us);
            if (displaced && step % 12 >= 3) {
                p_burst += view[k].p;
                n_burst++;
            } else if (!displaced) {
                p_clean += view[k].p;
                n_clean++;
            }
        }
        mvt_imm_combine(&imm, &cfg, &s);
        const Vec6d xo = o.combined();
        for (int i = 0; i < 3; i++) {
            worst = std::fmax(worst, std::fabs((double)s.x[i] - xo(i)));
            assert_true(std::fabs((double)s.x[i] - xo(i)) < 5e-4);
        }
        for (int j = 0; j < cfg.n; j++) assert_true(std::fabs((double)imm.mu[j] - o.mu[j]) < 0.02);
    }
    p_burst /= n_burst;
    p_clean /= n_clean;
    /* the memory does its job: a lasting displacement is recognised from its third frame on, a
     * clean view is not taken for displaced */
    assert_true(p_burst > 0.8);
    assert_true(p_clean < 0.05);
    std::printf("# view memory vs Eigen over 240 steps: worst |x| %.3g m, worst |p| %.3g; mean P(displaced) %.3f in "
                "a burst's frames 3-8, %.4f in clean frames\n", worst, worst_p, p_burst, p_clean);
}

/* The same walk at 6 px noise, each camera in turn displaced by 18 px (3 sigma, inside any gate) for 10
 * frames: the view memory against the same filter without it (outlier_persist_s 0). Returns the mean
 * position error over the frames with a displaced view, m. */
static double burst_error(mvt_real persist_s, unsigned seed)
{
    std::mt19937 g(seed);
    std::normal_distribution<double> N(0, 1);
    std::uniform_real_distribution<double> U(0, 2 * M_PI);
    std::vector<mvt_camera_t> cams;
    std::vector<OracleCam> oc;
    std::mt19937 grig(11);
    random_rig(grig, 5, cams, oc);
    mvt_imm_config_t cfg;
    mvt_imm_config_default(&cfg);
    cfg.outlier_persist_s = persist_s;
    mvt_cv_state_t s;
    mvt_imm_t imm;
    imm_start(cfg, s, imm);
    mvt_imm_view_t view[5];
    memset(view, 0, sizeof(view));
    Eigen::Vector3d truth(2.5, 2.0, 1.7);
    Eigen::Vector2d off(0, 0);
    double err = 0;
    int n = 0;
    for (int step = 1; step <= 600; step++) {
        const double t = step * 0.04;
        const Eigen::Vector3d v = std::fmod(t, 8.0) < 4 ? Eigen::Vector3d(0.7 * std::cos(t / 3), 0.7 * std::sin(t / 3), 0)
                                                        : Eigen::Vector3d(0, 0, 0);
        truth += 0.04 * v;
        if (step % 20 == 0) {
            const double a = U(g);
            off = 18.0 * Eigen::Vector2d(std::cos(a), std::sin(a));
        }
        assert_int_equal(mvt_imm_predict_to_pos(&imm, &cfg, (int64_t)step * 40000, &s), MVT_OK);
        bool any = false;
        for (int k = 0; k < 5; k++) {
            Eigen::Vector2d uv;
            cv_project(oc[k], truth, uv, nullptr);
            uv += 6.0 * Eigen::Vector2d(N(g), N(g));
            const bool displaced = step > 100 && (step / 20) % 5 == k && step % 20 < 10;
            if (displaced) uv += off;
            any |= displaced;
            const mvt_real raw[2] = {(mvt_real)uv(0), (mvt_real)uv(1)};
            mvt_pkf_meas_t m;
            mvt_pkf_innov_t in;
            assert_int_equal(mvt_pkf_meas_make(&cams[k], raw, 6.0f, &m), MVT_OK);
            assert_int_equal(mvt_pkf_innovation(&s, &cams[k], MVT_PKF_JACOBIAN, &m, &in), MVT_OK);
            const mvt_real noise[4] = {in.r, 0, 0, in.r};
            assert_int_equal(mvt_imm_update_view(&imm, &cfg, in.H, in.y, noise, in.S, &view[k], &s), MVT_OK);
        }
        mvt_imm_combine(&imm, &cfg, &s);
        if (any) {
            err += (Eigen::Vector3d(s.x[0], s.x[1], s.x[2]) - truth).norm();
            n++;
        }
    }
    return err / n;
}

static void test_mvt_imm_view_memory_lowers_burst_error(void **state)
{
    (void)state;
    double with = 0, without = 0;
    for (unsigned seed = 1; seed <= 4; seed++) {
        with += burst_error(MVT_R(0.5), seed);
        without += burst_error(MVT_R(0.0), seed);
    }
    std::printf("# lasting 18 px displacements at 6 px noise, 4 seeds: mean error %.1f mm with the view memory, "
                "%.1f mm without (%.2f)\n", 250 * with, 250 * without, with / without);
    assert_true(with < 0.8 * without);
}

static void test_mvt_cv_update_point_matches_eigen_kalman(void **state)
{
    (void)state;
    mvt_cv_state_t c;
    const mvt_real p0[3] = {1, 2, 1.7f}, cov[9] = {0.02f, 0.001f, 0, 0.001f, 0.03f, 0.002f, 0, 0.002f, 0.01f};
    mvt_cv_init(&c, p0, cov, 0.3f, 0);
    const mvt_real q[3] = {0.5f, 0.5f, 0.05f};
    mvt_cv_predict(&c, 0.04f, q);
    Eigen::Matrix<double, 6, 6> P;
    Eigen::Matrix<double, 6, 1> x;
    for (int i = 0; i < 6; i++) {
        x(i) = c.x[i];
        for (int j = 0; j < 6; j++) P(i, j) = c.P[i * 6 + j];
    }
    const mvt_real z[3] = {1.05f, 1.97f, 1.72f}, R[9] = {4e-3f, 1e-3f, 0, 1e-3f, 5e-3f, 0, 0, 0, 2e-3f};
    Eigen::Matrix<double, 3, 6> H = Eigen::Matrix<double, 3, 6>::Zero();
    H.leftCols<3>().setIdentity();
    Eigen::Matrix3d Re;
    Eigen::Vector3d ze;
    for (int i = 0; i < 3; i++) {
        ze(i) = z[i];
        for (int j = 0; j < 3; j++) Re(i, j) = R[i * 3 + j];
    }
    const Eigen::Matrix3d S = H * P * H.transpose() + Re;
    const Eigen::Matrix<double, 6, 3> K = P * H.transpose() * S.inverse();
    x += K * (ze - H * x);
    P = (Eigen::Matrix<double, 6, 6>::Identity() - K * H) * P;
    assert_int_equal(mvt_cv_update_point(&c, z, R, 0, NULL), MVT_OK);
    for (int i = 0; i < 6; i++) {
        assert_true(std::fabs(c.x[i] - x(i)) < POS_TOL);
        for (int j = 0; j < 6; j++) assert_true(std::fabs(c.P[i * 6 + j] - P(i, j)) < (MVT_USE_DOUBLE ? 1e-12 : 1e-6));
    }
}

static void test_mvt_pkf_paper_distance_matches_projected_ellipsoid(void **state)
{
    (void)state;
    std::mt19937 g(3);
    std::uniform_real_distribution<double> U(-1, 1);
    const auto ps = random_params(g, 4, false);
    /* a wide ellipsoid, and the default's head-sized one (gamma (4 cm)^2: semi-axes 10 cm) */
    static const mvt_real vars[2][3] = {{0.01f, 0.02f, 0.005f}, {0.0016f, 0.0016f, 0.0016f}};
    for (int vi = 0; vi < 2; vi++)
    for (const auto &p : ps) {
        mvt_camera_t cam;
        assert_int_equal(mvt_cam_init(&cam, &p), MVT_OK);
        const OracleCam o = oracle_of(p);
        mvt_cv_state_t c;
        const mvt_real p0[3] = {2.8f, 2.4f, 1.5f}, cov[9] = {1e-2f, 0, 0, 0, 1e-2f, 0, 0, 0, 1e-2f};
        mvt_cv_init(&c, p0, cov, 0.3f, 0);
        const mvt_real *var = vars[vi];
        const double gamma = 6.0;
        /* Eigen: outline conic of the ellipsoid's dual quadric */
        Eigen::Matrix4d Qd = Eigen::Matrix4d::Zero();
        Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
        for (int i = 0; i < 3; i++) {
            Qd(i, i) = gamma * var[i];
            T(i, 3) = p0[i];
        }
        Qd(3, 3) = -1;
        const Eigen::Matrix3d C = (o.P * T * Qd * T.transpose() * o.P.transpose()).inverse();
        const Eigen::Matrix2d A = C.topLeftCorner<2, 2>();
        const Eigen::Vector2d b = C.topRightCorner<2, 1>();
        const Eigen::Vector2d x0 = -A.inverse() * b;
        const double k = x0.dot(A * x0) - C(2, 2);
        double maxd = 0;
        for (int t = 0; t < 400; t++) {
            /* a point on the ellipsoid surface, projected (pinhole) */
            Eigen::Vector3d u(U(g), U(g), U(g));
            u.normalize();
            Eigen::Vector4d X(p0[0] + std::sqrt(gamma * var[0]) * u(0), p0[1] + std::sqrt(gamma * var[1]) * u(1),
                              p0[2] + std::sqrt(gamma * var[2]) * u(2), 1);
            const Eigen::Vector3d xh = o.P * X;
            const Eigen::Vector2d z(xh(0) / xh(2), xh(1) / xh(2));
            mvt_pkf_meas_t m;
            m.ideal[0] = (mvt_real)z(0);
            m.ideal[1] = (mvt_real)z(1);
            mvt_real dist;
            assert_int_equal(mvt_pkf_paper_distance(&c, &cam, var, (mvt_real)gamma, &m, &dist), MVT_OK);
            const Eigen::Vector2d d = z - x0;
            const double ref = std::sqrt(d.dot(A * d) / k);
            assert_true(std::fabs(dist - ref) < (MVT_USE_DOUBLE ? 1e-9 : 2e-3));
            maxd = std::fmax(maxd, ref);
        }
        /* the outline contains every projected surface point and touches some */
        assert_true(maxd <= 1.0 + 1e-3 && maxd > 0.9);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mvt_cam_project_matches_opencv),
        cmocka_unit_test(test_mvt_pkf_update_sequence_matches_eigen_oracle),
        cmocka_unit_test(test_mvt_cv_update_point_matches_eigen_kalman),
        cmocka_unit_test(test_mvt_imm_matches_eigen_textbook_imm),
        cmocka_unit_test(test_mvt_imm_view_memory_matches_eigen),
        cmocka_unit_test(test_mvt_imm_view_memory_lowers_burst_error),
        cmocka_unit_test(test_mvt_pkf_paper_distance_matches_projected_ellipsoid),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
