#include "mvt_rig.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

#include <opencv2/core.hpp>

namespace {

struct RigError : std::exception {
    std::string msg;
    explicit RigError(std::string m) : msg(std::move(m)) {}
    const char *what() const noexcept override { return msg.c_str(); }
};

cv::Mat read_matrix(const cv::FileNode &node, const std::string &where, const char *key, bool required)
{
    cv::FileNode n = node[key];
    if (n.empty() || n.isNone()) {
        if (required) {
            throw RigError(where + ": missing " + key);
        }
        return cv::Mat();
    }
    cv::Mat m;
    if (n.isSeq()) { /* a plain YAML list of numbers is accepted too */
        std::vector<double> v;
        n >> v;
        m = cv::Mat(v, true).reshape(1, 1);
    } else {
        n >> m;
    }
    if (m.empty()) {
        throw RigError(where + ": " + key + " is not a matrix");
    }
    cv::Mat d;
    m.convertTo(d, CV_64F);
    for (int i = 0; i < (int)d.total(); i++) {
        if (!std::isfinite(d.at<double>(i))) {
            throw RigError(where + ": " + key + " has a non-finite entry");
        }
    }
    return d;
}

void need_total(const cv::Mat &m, const std::string &where, const char *key, int total)
{
    if ((int)m.total() != total) {
        throw RigError(where + ": " + key + " must have " + std::to_string(total) + " entries, has " +
                       std::to_string(m.total()));
    }
}

void load(const char *path, double default_sigma, mvt_rig_t *rig)
{
    cv::FileStorage fs;
    try {
        if (!fs.open(path, cv::FileStorage::READ)) {
            throw RigError(std::string("cannot open rig file ") + path);
        }
    } catch (const cv::Exception &e) {
        throw RigError(std::string("cannot parse rig file ") + path + ": " + e.msg);
    }
    cv::FileNode cams = fs["cameras"];
    if (!cams.isSeq() || cams.size() == 0) {
        throw RigError("rig: 'cameras' must be a non-empty sequence");
    }
    if ((int)cams.size() > MVT_MAX_CAMERAS) {
        throw RigError("rig: " + std::to_string(cams.size()) + " cameras, capacity MVT_MAX_CAMERAS is " +
                       std::to_string(MVT_MAX_CAMERAS));
    }
    rig->num_cameras = 0;
    for (cv::FileNodeIterator it = cams.begin(); it != cams.end(); ++it) {
        const cv::FileNode c = *it;
        const int idx = rig->num_cameras;
        std::string where = "rig: camera " + std::to_string(idx);
        if (!c.isMap()) {
            throw RigError(where + " is not a map");
        }
        std::string name;
        if (!c["name"].isString()) {
            throw RigError(where + ": missing name");
        }
        c["name"] >> name;
        where += " (" + name + ")";
        if (name.empty() || name.size() >= MVT_RIG_NAME_MAX) {
            throw RigError(where + ": name must have 1.." + std::to_string(MVT_RIG_NAME_MAX - 1) + " characters");
        }
        for (int j = 0; j < idx; j++) {
            if (name == rig->names[j]) {
                throw RigError(where + ": duplicate camera name");
            }
        }
        int w = 0, h = 0;
        if (!c["image_width"].isInt() || !c["image_height"].isInt()) {
            throw RigError(where + ": image_width and image_height must be integers");
        }
        c["image_width"] >> w;
        c["image_height"] >> h;
        if (w < 1 || h < 1 || w > 32767 || h > 32767) {
            throw RigError(where + ": image size out of range");
        }
        cv::Mat K = read_matrix(c, where, "camera_matrix", true);
        need_total(K, where, "camera_matrix", 9);
        cv::Mat D = read_matrix(c, where, "distortion_coefficients", false);
        if (!D.empty() && D.total() != 4 && D.total() != 5 && D.total() != 8) {
            throw RigError(where + ": distortion_coefficients must have 4, 5 or 8 entries");
        }
        cv::Mat rv = read_matrix(c, where, "rvec", true);
        need_total(rv, where, "rvec", 3);
        cv::Mat tv = read_matrix(c, where, "tvec", true);
        need_total(tv, where, "tvec", 3);
        double sigma = default_sigma;
        if (!c["sigma_px"].empty()) {
            if (!c["sigma_px"].isReal() && !c["sigma_px"].isInt()) {
                throw RigError(where + ": sigma_px must be a number");
            }
            c["sigma_px"] >> sigma;
        }
        if (!(sigma > 0.0) || !std::isfinite(sigma)) {
            throw RigError(where + ": sigma_px must be > 0");
        }
        mvt_camera_params_t *p = &rig->params[idx];
        std::memset(p, 0, sizeof(*p));
        for (int i = 0; i < 9; i++) {
            p->camera_matrix[i] = (mvt_real)K.at<double>(i);
        }
        for (int i = 0; i < (int)D.total(); i++) {
            p->dist[i] = (mvt_real)D.at<double>(i);
        }
        for (int i = 0; i < 3; i++) {
            p->rvec[i] = (mvt_real)rv.at<double>(i);
            p->tvec[i] = (mvt_real)tv.at<double>(i);
        }
        p->width = w;
        p->height = h;
        p->sigma_px = (mvt_real)sigma;
        mvt_camera_t probe;
        const mvt_err_t err = mvt_cam_init(&probe, p);
        if (err != MVT_OK) {
            throw RigError(where + ": invalid calibration (" + mvt_err_str(err) +
                           "; need fx, fy > 0 and K's last row 0 0 1)");
        }
        std::snprintf(rig->names[idx], MVT_RIG_NAME_MAX, "%s", name.c_str());
        rig->num_cameras++;
    }
    cv::Mat vmin = read_matrix(fs.root(), "rig", "volume_min", false);
    cv::Mat vmax = read_matrix(fs.root(), "rig", "volume_max", false);
    if (vmin.empty() != vmax.empty()) {
        throw RigError("rig: give both volume_min and volume_max, or neither");
    }
    if (!vmin.empty()) {
        need_total(vmin, "rig", "volume_min", 3);
        need_total(vmax, "rig", "volume_max", 3);
        for (int i = 0; i < 3; i++) {
            rig->volume_min[i] = vmin.at<double>(i);
            rig->volume_max[i] = vmax.at<double>(i);
            if (!(rig->volume_max[i] > rig->volume_min[i])) {
                throw RigError("rig: volume_max must exceed volume_min on every axis");
            }
        }
        rig->volume_given = 1;
    } else { /* the box of the camera centres, floor to 2.5 m */
        rig->volume_given = 0;
        for (int i = 0; i < 3; i++) {
            rig->volume_min[i] = 1e30;
            rig->volume_max[i] = -1e30;
        }
        for (int k = 0; k < rig->num_cameras; k++) {
            mvt_camera_t cam;
            mvt_cam_init(&cam, &rig->params[k]);
            for (int i = 0; i < 3; i++) {
                rig->volume_min[i] = std::fmin(rig->volume_min[i], (double)cam.centre[i]);
                rig->volume_max[i] = std::fmax(rig->volume_max[i], (double)cam.centre[i]);
            }
        }
        for (int i = 0; i < 2; i++) {
            if (rig->volume_max[i] - rig->volume_min[i] < 1.0) {
                rig->volume_min[i] -= 2.0;
                rig->volume_max[i] += 2.0;
            }
        }
        rig->volume_min[2] = 0.0;
        rig->volume_max[2] = std::fmax(2.5, rig->volume_max[2]);
    }
    rig->num_occluders = 0;
    cv::FileNode occ = fs["occluders"];
    if (!occ.empty()) {
        if (!occ.isSeq()) {
            throw RigError("rig: 'occluders' must be a sequence");
        }
        if ((int)occ.size() > MVT_MAX_OCCLUDERS) {
            throw RigError("rig: " + std::to_string(occ.size()) + " occluders, capacity MVT_MAX_OCCLUDERS is " +
                           std::to_string(MVT_MAX_OCCLUDERS));
        }
        for (int o = 0; o < (int)occ.size(); o++) {
            const cv::FileNode b = occ[o];
            const std::string where = "occluders[" + std::to_string(o) + "]";
            if (!b.isMap()) {
                throw RigError(where + ": must be a map with min and max");
            }
            std::string name;
            if (!b["name"].empty()) {
                if (!b["name"].isString()) {
                    throw RigError(where + ": name must be a string");
                }
                b["name"] >> name;
            }
            cv::Mat lo = read_matrix(b, where, "min", true);
            cv::Mat hi = read_matrix(b, where, "max", true);
            need_total(lo, where, "min", 3);
            need_total(hi, where, "max", 3);
            for (int i = 0; i < 3; i++) {
                rig->occluder_min[o][i] = lo.at<double>(i);
                rig->occluder_max[o][i] = hi.at<double>(i);
                if (!(rig->occluder_max[o][i] > rig->occluder_min[o][i])) {
                    throw RigError(where + ": max must exceed min on every axis");
                }
            }
            std::snprintf(rig->occluder_names[o], MVT_RIG_NAME_MAX, "%s", name.c_str());
            rig->num_occluders++;
        }
    }
    rig->frame_rate = 25.0;
    if (!fs["frame_rate"].empty()) {
        if (!fs["frame_rate"].isReal() && !fs["frame_rate"].isInt()) {
            throw RigError("rig: frame_rate must be a number");
        }
        fs["frame_rate"] >> rig->frame_rate;
        if (!(rig->frame_rate > 0.0 && rig->frame_rate <= 1000.0)) {
            throw RigError("rig: frame_rate must be in (0, 1000]");
        }
    }
}

} // namespace

extern "C" int mvt_rig_load(const char *path, double default_sigma_px, mvt_rig_t *rig, char *err, size_t err_len)
{
    std::memset(rig, 0, sizeof(*rig));
    try {
        load(path, default_sigma_px, rig);
    } catch (const RigError &e) {
        std::snprintf(err, err_len, "%s", e.what());
        return -1;
    } catch (const cv::Exception &e) {
        std::snprintf(err, err_len, "rig %s: %s", path, e.msg.c_str());
        return -1;
    } catch (const std::exception &e) {
        std::snprintf(err, err_len, "rig %s: %s", path, e.what());
        return -1;
    }
    return 0;
}

extern "C" int mvt_rig_find(const mvt_rig_t *rig, const char *name)
{
    for (int k = 0; k < rig->num_cameras; k++) {
        if (std::strcmp(rig->names[k], name) == 0) {
            return k;
        }
    }
    return -1;
}
