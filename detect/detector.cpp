#include "detector.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>
#include <opencv2/video.hpp>

namespace mvdet {

namespace {

constexpr int kMaxFragments = 256;   /* largest components kept per frame */
constexpr int kMinFragmentPx = 4;    /* working pixels: smaller components are noise */
constexpr double kHeadRadiusM = 0.10;
constexpr float kHeadMinM = 1.3f;    /* a fragment reaching this high at its own place has a head */
constexpr double kShoulderDropM = 0.35; /* a standing person's shoulders below the head top */
constexpr float kTwoHighM = 2.4f;    /* a top above this height over a body's feet (at its far rim)
                                      * is a second person's: the tallest standing head (2.0 m) and
                                      * a head and neck (0.4 m) more, so that a tall person, a
                                      * raised hand or feet a shadow lowers stay under it */
constexpr float kFeetBandM = 0.2f;  /* the feet and ankles above the floor */
constexpr float kStackedRowsFilled = 0.9f; /* rows of a standing body's column that are foreground */
constexpr double kTwoWideM = 0.7;    /* wider than anyone's shoulders (about 0.45 m, the mask's
                                      * closing and blur added) */

float dot2(const float a[2], float x, float y) { return a[0] * x + a[1] * y; }

/* squared distance from (x, y) to segment a-b and the segment parameter of the nearest point */
float seg_dist2(const float a[2], const float b[2], float x, float y, float *t_out)
{
    const float dx = b[0] - a[0], dy = b[1] - a[1];
    const float l2 = dx * dx + dy * dy;
    float t = l2 > 0.f ? ((x - a[0]) * dx + (y - a[1]) * dy) / l2 : 0.f;
    t = std::min(1.f, std::max(0.f, t));
    const float ex = a[0] + t * dx - x, ey = a[1] + t * dy - y;
    *t_out = t;
    return ex * ex + ey * ey;
}

} // namespace

std::string check_config(const Config &c, int width, int height)
{
    if (c.work_scale < 1 || c.work_scale > 8) {
        return "work scale must be 1..8";
    }
    if (width % c.work_scale != 0 || height % c.work_scale != 0) {
        return "image size " + std::to_string(width) + "x" + std::to_string(height) +
               " is not a multiple of the work scale " + std::to_string(c.work_scale);
    }
    if (c.masks) {
        if (c.mask_scale < 1 || c.mask_scale > 32) {
            return "mask scale must be 1..32";
        }
        if (width % c.mask_scale != 0 || height % c.mask_scale != 0) {
            return "image size " + std::to_string(width) + "x" + std::to_string(height) +
                   " is not a multiple of the mask scale " + std::to_string(c.mask_scale);
        }
    }
    if (!(c.frame_rate > 0.0) || !(c.history_s * c.frame_rate >= 1.0) || !(c.bootstrap_s >= 0.0) ||
        c.bootstrap_s * c.frame_rate > 1000.0) {
        return "history must be at least one frame, bootstrap 0..1000 frames, frame rate > 0";
    }
    if (!(c.var_threshold > 0.0)) {
        return "variance threshold must be > 0";
    }
    if (!(c.min_outline_contrast >= 0.0 && c.min_outline_contrast <= 1.0)) {
        return "minimum outline contrast must be in [0, 1]";
    }
    if (!(c.min_person_fraction >= 0.0 && c.min_person_fraction <= 1.0)) {
        return "minimum person fraction must be in [0, 1]";
    }
    if (!(c.person_radius_m > 0.0 && c.column_height_m > 1.0 && c.body_half_width_m > 0.0 &&
          c.person_height_m > 0.5 && c.head_gap_m > 0.0)) {
        return "person geometry must be positive (column above 1 m, person above 0.5 m)";
    }
    return "";
}

Detector::Detector(const mvt_camera_t &cam, const double volume_min[3], const double volume_max[3],
                   const Config &cfg)
    : cam_(cam), cfg_(cfg)
{
    for (int i = 0; i < 3; i++) {
        vmin_[i] = volume_min[i];
        vmax_[i] = volume_max[i];
    }
    if (cfg_.model == BgModel::mog2) {
        bg_ = cv::createBackgroundSubtractorMOG2(history_frames_, cfg_.var_threshold, cfg_.shadows);
    } else {
        bg_ = cv::createBackgroundSubtractorKNN(history_frames_, cfg_.var_threshold, cfg_.shadows);
    }
    open_kernel_ = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3));
    close_kernel_ = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(5, 5));
    history_frames_ = std::max(1, (int)std::lround(cfg_.history_s * cfg_.frame_rate));
    bootstrap_frames_ = (int)std::lround(cfg_.bootstrap_s * cfg_.frame_rate);
    wsmall_ = cam_.width / cfg_.work_scale;
    hsmall_ = cam_.height / cfg_.work_scale;
}

bool Detector::ground_point(float xw, float yw, double g[3]) const
{
    const float s = (float)cfg_.work_scale;
    const mvt_real uv[2] = {(mvt_real)((xw + 0.5f) * s - 0.5f), (mvt_real)((yw + 0.5f) * s - 0.5f)};
    mvt_real o[3], d[3];
    if (mvt_cam_ray(&cam_, uv, o, d) != MVT_OK || !(d[2] < (mvt_real)-1e-4)) {
        return false;
    }
    const double t = -(double)o[2] / (double)d[2];
    if (!(t > 0.0 && t < 1e3)) {
        return false;
    }
    for (int i = 0; i < 3; i++) {
        g[i] = (double)o[i] + t * (double)d[i];
    }
    g[2] = 0.0;
    return true;
}

bool Detector::project_work(const double x[3], float p[2]) const
{
    const mvt_real xw[3] = {(mvt_real)x[0], (mvt_real)x[1], (mvt_real)x[2]};
    mvt_real uv[2];
    if (mvt_cam_project(&cam_, xw, uv, nullptr) != MVT_OK) {
        return false;
    }
    const float s = (float)cfg_.work_scale;
    p[0] = ((float)uv[0] + 0.5f) / s - 0.5f;
    p[1] = ((float)uv[1] + 0.5f) / s - 0.5f;
    return std::isfinite(p[0]) && std::isfinite(p[1]);
}

void Detector::local_up(float xw, float yw, float up[2]) const
{
    up[0] = 0.f;
    up[1] = -1.f;
    const float s = (float)cfg_.work_scale;
    const mvt_real uv[2] = {(mvt_real)((xw + 0.5f) * s - 0.5f), (mvt_real)((yw + 0.5f) * s - 0.5f)};
    mvt_real o[3], d[3];
    if (mvt_cam_ray(&cam_, uv, o, d) != MVT_OK) {
        return;
    }
    /* a point of the ray at mid-body height, or 3 m along it when the ray does not go there */
    double t = std::fabs((double)d[2]) > 1e-6 ? (1.0 - (double)o[2]) / (double)d[2] : -1.0;
    if (!(t > 0.3 && t < 30.0)) {
        t = 3.0;
    }
    double a[3], b[3];
    for (int i = 0; i < 3; i++) {
        a[i] = (double)o[i] + t * (double)d[i];
        b[i] = a[i];
    }
    b[2] += 0.1;
    float pa[2], pb[2];
    if (!project_work(a, pa) || !project_work(b, pb)) {
        return;
    }
    const float dx = pb[0] - pa[0], dy = pb[1] - pa[1], n = std::sqrt(dx * dx + dy * dy);
    if (n > 1e-6f) {
        up[0] = dx / n;
        up[1] = dy / n;
    }
}

Detector::Column Detector::column_at(const double g[3]) const
{
    Column c;
    const double fw = 0.5 * ((double)cam_.fx + (double)cam_.fy) / cfg_.work_scale;
    const int n_axis = 12;
    for (int k = 0; k < n_axis; k++) {
        const double x[3] = {g[0], g[1], cfg_.column_height_m * k / (n_axis - 1)};
        const mvt_real xr[3] = {(mvt_real)x[0], (mvt_real)x[1], (mvt_real)x[2]};
        const double depth = (double)mvt_cam_depth(&cam_, xr);
        if (!(depth > 0.1) || !project_work(x, c.axis[c.n])) {
            continue;
        }
        c.half[c.n] = (float)(cfg_.person_radius_m * fw / depth);
        c.z[c.n] = (float)x[2];
        c.n++;
    }
    if (c.n < 2) {
        return c;
    }
    const double foot[3] = {g[0], g[1], 0.0}, top[3] = {g[0], g[1], cfg_.person_height_m};
    const double mid[3] = {g[0], g[1], 0.5 * cfg_.person_height_m};
    const double head[3] = {g[0], g[1], cfg_.person_height_m - kHeadRadiusM};
    const double head_up[3] = {g[0], g[1], cfg_.person_height_m - kHeadRadiusM + 0.1};
    float pf[2], pt[2], ph[2], phu[2];
    if (!project_work(foot, pf) || !project_work(top, pt) || !project_work(head, ph) ||
        !project_work(head_up, phu)) {
        return c;
    }
    const mvt_real midr[3] = {(mvt_real)mid[0], (mvt_real)mid[1], (mvt_real)mid[2]};
    const mvt_real headr[3] = {(mvt_real)head[0], (mvt_real)head[1], (mvt_real)head[2]};
    const double d_mid = (double)mvt_cam_depth(&cam_, midr), d_head = (double)mvt_cam_depth(&cam_, headr);
    if (!(d_mid > 0.1 && d_head > 0.1)) {
        return c;
    }
    const float dx = pt[0] - pf[0], dy = pt[1] - pf[1];
    c.height_px = std::sqrt(dx * dx + dy * dy);
    const float ux = phu[0] - ph[0], uy = phu[1] - ph[1], un = std::sqrt(ux * ux + uy * uy);
    if (un > 1e-6f) {
        c.up[0] = ux / un;
        c.up[1] = uy / un;
    }
    /* the silhouette's extreme point along "up" is the head sphere's rim, not the head top: they
     * differ by r (f / D - |d(image) / d(height)|), zero for a level view, r f / D from above */
    c.head_offset_px = (float)(kHeadRadiusM * (fw / d_head - (double)un / 0.1));
    c.px_per_m = (float)(fw / d_mid);
    c.g[0] = g[0];
    c.g[1] = g[1];
    const float width_px = (float)(2.0 * cfg_.body_half_width_m * fw / d_mid);
    const float cap_px = (float)(cfg_.body_half_width_m * fw / d_head);
    c.expected_area = std::max(width_px * c.height_px, 0.5f * (float)M_PI * cap_px * cap_px);
    c.valid = true;
    return c;
}

bool Detector::in_column(const Column &c, float x, float y)
{
    for (int k = 0; k + 1 < c.n; k++) {
        float t;
        const float d2 = seg_dist2(c.axis[k], c.axis[k + 1], x, y, &t);
        const float h = c.half[k] + t * (c.half[k + 1] - c.half[k]);
        if (d2 <= h * h) {
            return true;
        }
    }
    return false;
}

float Detector::height_at(const Column &c, float x, float y)
{
    float best = 1e30f, z = 0.f;
    for (int k = 0; k + 1 < c.n; k++) {
        float t;
        const float d2 = seg_dist2(c.axis[k], c.axis[k + 1], x, y, &t);
        if (d2 < best) {
            best = d2;
            z = c.z[k] + t * (c.z[k + 1] - c.z[k]);
        }
    }
    return z;
}

void Detector::measure(const std::vector<cv::Point> &pix, const Column &col, const cv::Mat &hsv,
                       const cv::Rect &roi, Blob &b, bool *at_border) const
{
    const float *up = col.up;
    float a_max = -1e30f, a_min = 1e30f;
    int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
    for (const cv::Point &p : pix) {
        const float a = dot2(up, (float)p.x, (float)p.y);
        a_max = std::max(a_max, a);
        a_min = std::min(a_min, a);
        x0 = std::min(x0, p.x);
        y0 = std::min(y0, p.y);
        x1 = std::max(x1, p.x);
        y1 = std::max(y1, p.y);
    }
    /* the head top: the mean of the extreme pixels along up; a pixel is foreground when about half
     * covered, so the edge lies a quarter pixel beyond the extreme pixels' centres on average */
    double sx = 0, sy = 0;
    int n_top = 0;
    *at_border = false;
    for (const cv::Point &p : pix) {
        if (dot2(up, (float)p.x, (float)p.y) >= a_max - 1.0f) {
            sx += p.x;
            sy += p.y;
            n_top++;
            if (p.x == 0 || p.y == 0 || p.x == wsmall_ - 1 || p.y == hsmall_ - 1) {
                *at_border = true;
            }
        }
    }
    const float shift = 0.25f - std::max(0.f, col.head_offset_px);
    const float xt = (float)(sx / n_top) + shift * up[0];
    const float yt = (float)(sy / n_top) + shift * up[1];
    const float s = (float)cfg_.work_scale;
    b.u = (xt + 0.5f) * s - 0.5f;
    b.v = (yt + 0.5f) * s - 0.5f;
    b.bbox[0] = (float)x0 * s - 0.5f;
    b.bbox[1] = (float)y0 * s - 0.5f;
    b.bbox[2] = (float)(x1 + 1) * s - 0.5f;
    b.bbox[3] = (float)(y1 + 1) * s - 0.5f;
    b.score = col.expected_area > 0.f ? std::min(1.f, (float)pix.size() / col.expected_area) : 0.5f;
    /* torso colour: 20-45 % of the blob's length below its top */
    const float ext = a_max - a_min;
    double c_sum = 0, s_sum = 0, sat_sum = 0;
    int n_col = 0;
    for (const cv::Point &p : pix) {
        const float a = dot2(up, (float)p.x, (float)p.y);
        if (a > a_max - 0.2f * ext || a < a_max - 0.45f * ext) {
            continue;
        }
        const cv::Vec3b &h = hsv.at<cv::Vec3b>(p.y - roi.y, p.x - roi.x);
        const double ang = 2.0 * M_PI * h[0] / 256.0;
        c_sum += std::cos(ang);
        s_sum += std::sin(ang);
        sat_sum += h[1];
        n_col++;
    }
    if (n_col > 0) {
        double hue = std::atan2(s_sum, c_sum) / (2.0 * M_PI);
        if (hue < 0.0) {
            hue += 1.0;
        }
        b.hue = (float)std::min(hue, 0.999999);
        b.saturation = (float)(sat_sum / n_col / 255.0);
    }
}

float Detector::outline_contrast(const std::vector<cv::Point> &pix, const cv::Rect &roi)
{
    if (bg_img_.size() != small_.size() || bg_img_.type() != small_.type()) {
        return 1.0f;
    }
    cv::Rect r(roi.x - 1, roi.y - 1, roi.width + 2, roi.height + 2);
    r &= cv::Rect(0, 0, wsmall_, hsmall_);
    cv::cvtColor(small_(r), gray_f_, cv::COLOR_BGR2GRAY);
    cv::cvtColor(bg_img_(r), gray_b_, cv::COLOR_BGR2GRAY);
    inside_ = cv::Mat::zeros(r.size(), CV_8U);
    for (const cv::Point &p : pix) {
        inside_.at<uint8_t>(p.y - r.y, p.x - r.x) = 1;
    }
    /* 3x3 Sobel magnitudes of both images at the outline's pixels (those with a 4-neighbour
     * outside the blob); the picture's own border counts as outline too */
    const auto sobel = [](const cv::Mat &g, int x, int y) {
        const int xm = std::max(0, x - 1), xp = std::min(g.cols - 1, x + 1);
        const int ym = std::max(0, y - 1), yp = std::min(g.rows - 1, y + 1);
        const auto at = [&g](int yy, int xx) { return (int)g.at<uint8_t>(yy, xx); };
        const int gx = at(ym, xp) + 2 * at(y, xp) + at(yp, xp) - at(ym, xm) - 2 * at(y, xm) - at(yp, xm);
        const int gy = at(yp, xm) + 2 * at(yp, x) + at(yp, xp) - at(ym, xm) - 2 * at(ym, x) - at(ym, xp);
        return std::sqrt((double)(gx * gx + gy * gy));
    };
    double ef = 0.0, eb = 0.0;
    for (const cv::Point &p : pix) {
        const int x = p.x - r.x, y = p.y - r.y;
        const bool outline = x == 0 || y == 0 || x == r.width - 1 || y == r.height - 1 ||
                             !inside_.at<uint8_t>(y, x - 1) || !inside_.at<uint8_t>(y, x + 1) ||
                             !inside_.at<uint8_t>(y - 1, x) || !inside_.at<uint8_t>(y + 1, x);
        if (outline) {
            ef += sobel(gray_f_, x, y);
            eb += sobel(gray_b_, x, y);
        }
    }
    return ef + eb > 0.0 ? (float)(ef / (ef + eb)) : 1.0f;
}

void Detector::fill_masks(Result &out)
{
    if (!cfg_.masks) {
        return;
    }
    const cv::Size ms(cam_.width / cfg_.mask_scale, cam_.height / cfg_.mask_scale);
    cv::resize(fg_, mask_tmp_, ms, 0, 0, cv::INTER_AREA);
    cv::threshold(mask_tmp_, out.mask, 127, 1, cv::THRESH_BINARY);
    cv::resize(colour_, mask_bgr_, ms, 0, 0, cv::INTER_AREA);
    cv::cvtColor(mask_bgr_, mask_hsv_, cv::COLOR_BGR2HSV_FULL);
    cv::Mat ch[3];
    cv::split(mask_hsv_, ch);
    out.hue = ch[0];
    out.saturation = ch[1];
}

void Detector::process(const cv::Mat &bgr, Result &out)
{
    CV_Assert(bgr.type() == CV_8UC3 && bgr.cols == cam_.width && bgr.rows == cam_.height);
    out.blobs.clear();
    out.fragments = out.dropped_small = out.dropped_border = out.dropped_background = out.splits = 0;
    if (cfg_.work_scale == 1) {
        small_ = bgr;
    } else {
        cv::resize(bgr, resized_, cv::Size(wsmall_, hsmall_), 0, 0, cv::INTER_AREA);
        small_ = resized_;
    }
    /* colour comes from the frame as captured (hue and saturation do not depend on the gain); the
     * mask's colour is downscaled from the working image when the scales allow it */
    colour_ = (cfg_.mask_scale % cfg_.work_scale == 0) ? small_ : bgr;
    out.warming_up = false;
    out.gain = 1.0f;
    if (cfg_.gain_compensation) { /* the background's brightness now against its reference */
        const cv::Scalar m = prev_bg_.empty() ? cv::mean(small_) : cv::mean(small_, prev_bg_);
        const double now = (m[0] + m[1] + m[2]) / 3.0;
        if (ref_brightness_ < 0.0) {
            ref_brightness_ = now;
        }
        if (now > 1.0) {
            const double g = std::min(1.5, std::max(0.67, ref_brightness_ / now));
            out.gain = (float)g;
            small_.convertTo(gained_, -1, g);
            small_ = gained_;
        }
    }
    if (frames_ < bootstrap_frames_) { /* collect, then start the model from the median */
        boot_.push_back(small_.clone());
        frames_++;
        out.warming_up = true;
        if ((int)boot_.size() == bootstrap_frames_) {
            cv::Mat median(small_.size(), small_.type());
            std::vector<uint8_t> v(boot_.size());
            const size_t n_bytes = median.total() * median.elemSize();
            for (size_t i = 0; i < n_bytes; i++) {
                for (size_t f = 0; f < boot_.size(); f++) {
                    v[f] = boot_[f].data[i];
                }
                std::nth_element(v.begin(), v.begin() + (long)(v.size() / 2), v.end());
                median.data[i] = v[v.size() / 2];
            }
            boot_.clear();
            bg_->apply(median, fg_raw_, 1.0);
        }
        fg_ = cv::Mat::zeros(small_.size(), CV_8U);
        fill_masks(out);
        return;
    }
    frames_++;
    const double rate = cfg_.learning_rate >= 0.0 ? cfg_.learning_rate : 1.0 / history_frames_;
    const bool selective = cfg_.absorb_s > 0.0 && cfg_.model == BgModel::mog2;
    if (selective) {
        /* selective update: classify without learning; once the blobs are known, learn a frame in
         * which the pixels foreground for less than absorb_s show the background's own colour
         * (MOG2 only: KNN's background image is not its model's, and fed back it found no one
         * on vtest.avi) */
        bg_->apply(small_, fg_raw_, 0.0);
        if (fg_age_.size() != small_.size()) {
            fg_age_ = cv::Mat::zeros(small_.size(), CV_32S);
        }
        const int absorb_frames = std::max(1, (int)std::lround(cfg_.absorb_s * cfg_.frame_rate));
        protect_.create(small_.size(), CV_8U);
        for (int y = 0; y < small_.rows; y++) {
            const uint8_t *f = fg_raw_.ptr<uint8_t>(y);
            int32_t *a = fg_age_.ptr<int32_t>(y);
            uint8_t *p = protect_.ptr<uint8_t>(y);
            for (int x = 0; x < small_.cols; x++) {
                a[x] = f[x] == 255 ? std::min(a[x] + 1, absorb_frames) : 0; /* saturates: no overflow in months */
                p[x] = (uint8_t)(f[x] == 255 && a[x] < absorb_frames ? 255 : 0);
            }
        }
    } else {
        bg_->apply(small_, fg_raw_, rate);
    }
    /* the background's colour moves by 1/history a frame: its image, a pass over every mixture,
     * is taken once a second, not every frame */
    const int64_t refresh = std::max<int64_t>(1, std::llround(cfg_.frame_rate));
    if (bg_img_.empty() || frames_ % refresh == 0) {
        bg_->getBackgroundImage(bg_img_);
    }
    cv::threshold(fg_raw_, fg_, 200, 255, cv::THRESH_BINARY); /* shadows are 127 */
    cv::morphologyEx(fg_, tmp_, cv::MORPH_OPEN, open_kernel_);
    cv::morphologyEx(tmp_, fg_, cv::MORPH_CLOSE, close_kernel_);

    if (selective) {
        judged_ = cv::Mat::zeros(small_.size(), CV_8U);
    }
    find_blobs(out, selective);
    if (selective) {
        /* a pixel judged background (outline test) for a whole second running is learnt as it is:
         * light that changed on a still surface is absorbed at the memory's rate. A person whose
         * blob was misjudged for a frame or two keeps the protection of the selective update */
        if (bg_age_.size() != small_.size()) {
            bg_age_ = cv::Mat::zeros(small_.size(), CV_32S);
        }
        for (int y = 0; y < small_.rows; y++) {
            const uint8_t *j = judged_.ptr<uint8_t>(y);
            int32_t *a = bg_age_.ptr<int32_t>(y);
            uint8_t *p = protect_.ptr<uint8_t>(y);
            for (int x = 0; x < small_.cols; x++) {
                a[x] = j[x] ? std::min<int32_t>(a[x] + 1, (int32_t)refresh) : 0;
                if (a[x] >= refresh) {
                    p[x] = 0;
                }
            }
        }
    }

    cv::compare(fg_, 0, prev_bg_, cv::CMP_EQ); /* this frame's background, for the next gain */
    if (selective) {
        small_.copyTo(learn_);
        if (bg_img_.size() == learn_.size() && bg_img_.type() == learn_.type()) {
            bg_img_.copyTo(learn_, protect_);
        }
        bg_->apply(learn_, fg_scratch_, rate);
    }
    fill_masks(out);
}

bool Detector::stacked_head(const std::vector<cv::Point> &seg, const Column &c, Result &out)
{
    /* the top's height over the feet in this column, in pixels along up (height_at stops at the
     * column's top) */
    const float a_foot = dot2(c.up, c.axis[0][0], c.axis[0][1]);
    const float vpm = c.height_px / (float)cfg_.person_height_m;
    float a_top = -1e30f;
    for (const cv::Point &p : seg) {
        a_top = std::max(a_top, dot2(c.up, (float)p.x, (float)p.y));
    }
    /* the bar is the body's far rim at that height, not its axis: a camera looking down steeply
     * sees the far side of one body's shoulders and head well above its axis */
    const double away[2] = {c.g[0] - (double)cam_.centre[0], c.g[1] - (double)cam_.centre[1]};
    const double n_away = std::sqrt(away[0] * away[0] + away[1] * away[1]);
    const double s_rim = n_away > 1e-6 ? cfg_.body_half_width_m / n_away : 0.0;
    const double rim[3] = {c.g[0] + s_rim * away[0], c.g[1] + s_rim * away[1], (double)kTwoHighM};
    float p_rim[2];
    if (!project_work(rim, p_rim) || a_top <= std::max(dot2(c.up, p_rim[0], p_rim[1]), a_foot + kTwoHighM * vpm)) {
        return false;
    }
    /* a standing person's head top over the feet */
    const double head[3] = {c.g[0], c.g[1], cfg_.person_height_m};
    float h[2];
    if (!project_work(head, h)) {
        return false;
    }
    float hx = h[0], hy = h[1];
    /* a body stands in the column from the floor to head height: its rows (along up) are
     * foreground from the feet to the head, without the gap that a speck or a shadow on the floor
     * below a single person leaves */
    const float a_head = dot2(c.up, hx, hy);
    const int n_rows = std::max(1, (int)std::ceil(a_head - a_foot));
    rows_.assign((size_t)n_rows, 0);
    near_.clear();
    for (const cv::Point &p : seg) {
        const float a = dot2(c.up, (float)p.x, (float)p.y);
        if (a <= a_head && in_column(c, (float)p.x, (float)p.y)) {
            near_.push_back(p);
            rows_[(size_t)std::min(n_rows - 1, std::max(0, (int)(a - a_foot)))] = 1;
        }
    }
    int filled = 0;
    for (uint8_t r : rows_) {
        filled += r;
    }
    if (filled < (int)(kStackedRowsFilled * (float)n_rows)) {
        return false;
    }
    /* a walker's feet straddle the vertical under the head: centre the head between them (the
     * column stands on the lowest pixels, often the front foot alone) */
    const float perp[2] = {-c.up[1], c.up[0]};
    double s_feet = 0.0;
    int n_feet = 0;
    for (const cv::Point &p : near_) {
        if (dot2(c.up, (float)p.x, (float)p.y) - a_foot < kFeetBandM * vpm) {
            s_feet += (double)dot2(perp, (float)p.x, (float)p.y);
            n_feet++;
        }
    }
    if (n_feet > 0) {
        const float off = (float)(s_feet / n_feet) - dot2(perp, c.axis[0][0], c.axis[0][1]);
        hx += off * perp[0];
        hy += off * perp[1];
    }
    /* the nearer body's box and torso colour from its part of the blob; its head where it stands */
    const cv::Rect roi = cv::boundingRect(near_);
    cv::cvtColor(small_(roi), hsv_, cv::COLOR_BGR2HSV_FULL);
    Blob b;
    bool at_border = false;
    measure(near_, c, hsv_, roi, b, &at_border);
    const float s = (float)cfg_.work_scale;
    b.u = (hx + 0.5f) * s - 0.5f;
    b.v = (hy + 0.5f) * s - 0.5f;
    b.bbox[1] = std::min(b.bbox[1], b.v);
    out.blobs.push_back(b);
    return true;
}

void Detector::find_blobs(Result &out, bool selective)
{
    const int n = cv::connectedComponentsWithStats(fg_, labels_, stats_, centroids_, 8, CV_32S);
    /* keep the largest components */
    std::vector<int> kept;
    for (int i = 1; i < n; i++) {
        if (stats_.at<int>(i, cv::CC_STAT_AREA) >= kMinFragmentPx) {
            kept.push_back(i);
        }
    }
    if ((int)kept.size() > kMaxFragments) {
        std::nth_element(kept.begin(), kept.begin() + kMaxFragments, kept.end(), [this](int a, int b) {
            return stats_.at<int>(a, cv::CC_STAT_AREA) > stats_.at<int>(b, cv::CC_STAT_AREA);
        });
        kept.resize(kMaxFragments);
    }
    out.fragments = (int)kept.size();
    if (kept.empty()) {
        return;
    }
    std::vector<int> slot(n, -1);
    for (int k = 0; k < (int)kept.size(); k++) {
        slot[kept[k]] = k;
    }
    std::vector<std::vector<cv::Point>> pix(kept.size());
    for (int k = 0; k < (int)kept.size(); k++) {
        pix[k].reserve(stats_.at<int>(kept[k], cv::CC_STAT_AREA));
    }
    for (int y = 0; y < labels_.rows; y++) {
        const int *row = labels_.ptr<int>(y);
        for (int x = 0; x < labels_.cols; x++) {
            if (row[x] > 0 && slot[row[x]] >= 0) {
                pix[slot[row[x]]].emplace_back(x, y);
            }
        }
    }

    /* each fragment's local vertical and foot point (its extreme pixels along "down") */
    struct Frag {
        float up[2], foot[2], low, cx, cy;
    };
    std::vector<Frag> fr(kept.size());
    for (int k = 0; k < (int)kept.size(); k++) {
        Frag &f = fr[k];
        f.cx = (float)centroids_.at<double>(kept[k], 0);
        f.cy = (float)centroids_.at<double>(kept[k], 1);
        local_up(f.cx, f.cy, f.up);
        float a_min = 1e30f;
        for (const cv::Point &p : pix[k]) {
            a_min = std::min(a_min, dot2(f.up, (float)p.x, (float)p.y));
        }
        double sx = 0, sy = 0;
        int m = 0;
        for (const cv::Point &p : pix[k]) {
            if (dot2(f.up, (float)p.x, (float)p.y) <= a_min + 1.0f) {
                sx += p.x;
                sy += p.y;
                m++;
            }
        }
        f.foot[0] = (float)(sx / m);
        f.foot[1] = (float)(sy / m);
        f.low = a_min;
    }
    std::vector<int> order(kept.size());
    for (int k = 0; k < (int)order.size(); k++) {
        order[k] = k;
    }
    std::sort(order.begin(), order.end(), [&fr](int a, int b) { return fr[a].low < fr[b].low; });

    /* fragments to people: the lowest free fragment stands on the floor; its column collects the rest */
    std::vector<int> group(kept.size(), -1);
    std::vector<Column> cols;
    for (int k : order) {
        if (group[k] >= 0) {
            continue;
        }
        const int gi = (int)cols.size();
        double g[3];
        Column c;
        if (ground_point(fr[k].foot[0], fr[k].foot[1], g)) {
            c = column_at(g);
        }
        group[k] = gi;
        if (c.valid) {
            /* a seed with a head (its top above head_min_m) takes what overlaps it, up to a little
             * above its top; a seed without one (legs, a lower body) takes the column's height */
            float a_top = -1e30f, top_x = 0.f, top_y = 0.f;
            for (const cv::Point &p : pix[k]) {
                const float a = dot2(c.up, (float)p.x, (float)p.y);
                if (a > a_top) {
                    a_top = a;
                    top_x = (float)p.x;
                    top_y = (float)p.y;
                }
            }
            const float h_seed = height_at(c, top_x, top_y);
            const float h_max = h_seed >= kHeadMinM ? h_seed + 0.25f : (float)cfg_.column_height_m;
            for (int j : order) {
                if (group[j] < 0 && in_column(c, fr[j].cx, fr[j].cy) && height_at(c, fr[j].cx, fr[j].cy) <= h_max) {
                    group[j] = gi;
                }
            }
        } else {
            c.up[0] = fr[k].up[0];
            c.up[1] = fr[k].up[1];
        }
        cols.push_back(c);
    }

    /* people to blobs: split side-by-side people at the dip between two head peaks */
    std::vector<cv::Point> all, seg;
    for (int gi = 0; gi < (int)cols.size(); gi++) {
        const Column &c = cols[gi];
        all.clear();
        for (int k = 0; k < (int)kept.size(); k++) {
            if (group[k] == gi) {
                all.insert(all.end(), pix[k].begin(), pix[k].end());
            }
        }
        if (c.valid && (float)all.size() < (float)cfg_.min_person_fraction * c.expected_area) {
            out.dropped_small++;
            continue;
        }
        if (!c.valid && (int)all.size() < 50) { /* no floor under it: only a large blob is a person */
            out.dropped_small++;
            continue;
        }
        const float perp[2] = {-c.up[1], c.up[0]};
        float s_lo = 1e30f, s_hi = -1e30f;
        for (const cv::Point &p : all) {
            const float sv = dot2(perp, (float)p.x, (float)p.y);
            s_lo = std::min(s_lo, sv);
            s_hi = std::max(s_hi, sv);
        }
        const int nb = std::min(4096, (int)std::floor(s_hi - s_lo) + 1);
        std::vector<float> top(nb, -1e30f);
        for (const cv::Point &p : all) {
            const int bi = std::min(nb - 1, (int)(dot2(perp, (float)p.x, (float)p.y) - s_lo));
            top[bi] = std::max(top[bi], dot2(c.up, (float)p.x, (float)p.y));
        }
        std::vector<float> cuts; /* perp coordinates where the group is cut */
        const float ppm = c.valid ? c.px_per_m : 0.f;
        if (c.valid && (float)nb > 0.55f * ppm) { /* wider than one body: look for two heads */
            const int half_win = std::max(1, (int)std::lround(0.15 * (double)ppm));
            std::vector<int> peaks;
            for (int bi = 0; bi < nb; bi++) {
                if (top[bi] < -1e29f) {
                    continue;
                }
                bool is_max = true;
                for (int j = std::max(0, bi - half_win); j <= std::min(nb - 1, bi + half_win) && is_max; j++) {
                    is_max = top[j] < top[bi] || (!(top[j] > top[bi]) && j >= bi);
                }
                if (is_max) {
                    peaks.push_back(bi);
                }
            }
            const float gap_px = (float)cfg_.head_gap_m * (c.height_px / (float)cfg_.person_height_m);
            for (size_t q = 0; q + 1 < peaks.size();) {
                const int p0 = peaks[q], p1 = peaks[q + 1];
                int cut = p0;
                float dip = 1e30f;
                for (int j = p0 + 1; j < p1; j++) {
                    if (top[j] < dip) {
                        dip = top[j];
                        cut = j;
                    }
                }
                if (std::min(top[p0], top[p1]) - dip >= gap_px && p1 - p0 >= 2 * half_win) {
                    cuts.push_back(s_lo + (float)cut + 0.5f);
                    q++;
                } else { /* one head: keep the higher peak */
                    if (top[p0] >= top[p1]) {
                        peaks.erase(peaks.begin() + (long)q + 1);
                    } else {
                        peaks.erase(peaks.begin() + (long)q);
                    }
                }
            }
            /* no dip between heads, but wider at the shoulders (the band within shoulder_drop of
             * the top) than one person can be: two people side by side, heads touching. Cut at
             * the lowest point of the head profile away from the band's ends, or its middle */
            if (cuts.empty()) {
                const float vpm = c.height_px / (float)cfg_.person_height_m;
                float a_top = -1e30f;
                for (int bi = 0; bi < nb; bi++) {
                    a_top = std::max(a_top, top[bi]);
                }
                int first = -1, last = -1;
                for (int bi = 0; bi < nb; bi++) {
                    if (top[bi] >= a_top - (float)kShoulderDropM * vpm) {
                        first = first < 0 ? bi : first;
                        last = bi;
                    }
                }
                if (first >= 0 && (float)(last - first + 1) > (float)kTwoWideM * ppm) {
                    const int margin = (int)std::lround(0.2 * (double)ppm);
                    int cut = (first + last) / 2;
                    float dip = 1e30f;
                    for (int j = first + margin; j <= last - margin; j++) {
                        if (top[j] < dip) {
                            dip = top[j];
                            cut = j;
                        }
                    }
                    cuts.push_back(s_lo + (float)cut + 0.5f);
                }
            }
        }
        for (size_t si = 0; si <= cuts.size(); si++) {
            const float lo = si == 0 ? -1e30f : cuts[si - 1], hi = si == cuts.size() ? 1e30f : cuts[si];
            seg.clear();
            int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
            for (const cv::Point &p : all) {
                const float sv = dot2(perp, (float)p.x, (float)p.y);
                if (sv >= lo && sv < hi) {
                    seg.push_back(p);
                    x0 = std::min(x0, p.x);
                    y0 = std::min(y0, p.y);
                    x1 = std::max(x1, p.x);
                    y1 = std::max(y1, p.y);
                }
            }
            if (seg.empty() || (c.valid && (float)seg.size() < (float)cfg_.min_person_fraction * c.expected_area)) {
                out.dropped_small++;
                continue;
            }
            const cv::Rect roi(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
            if (outline_contrast(seg, roi) < (float)cfg_.min_outline_contrast) {
                /* the background's own edges under another light, or a ghost: background */
                out.dropped_background++;
                for (const cv::Point &p : seg) {
                    fg_.at<uint8_t>(p) = 0;
                    if (selective) {
                        judged_.at<uint8_t>(p) = 1;
                    }
                }
                continue;
            }
            cv::cvtColor(small_(roi), hsv_, cv::COLOR_BGR2HSV_FULL);
            Blob b;
            bool at_border = false;
            measure(seg, c, hsv_, roi, b, &at_border);
            if (at_border) {
                out.dropped_border++;
                continue;
            }
            out.blobs.push_back(b);
            if (si > 0) {
                out.splits++;
            }
            /* a top far higher above this body's feet than anyone stands is a farther person's
             * head over a nearer one: the nearer one's head lies inside the blob, at a standing
             * person's height over the feet */
            if (c.valid && stacked_head(seg, c, out)) {
                out.splits++;
            }
        }
    }
}

} // namespace mvdet
