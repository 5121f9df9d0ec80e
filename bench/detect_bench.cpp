/*
 * detect_frame_768x576: mvtrack-detect's per-camera work on real footage (vtest.avi, 768 x 576,
 * Debian's opencv-doc) on one core (cv::setNumThreads(1)), with the rig fitted to that view
 * (tests/data/vtest_rig.yaml). Every frame is timed alone: decoding (cv::VideoCapture::read) and
 * detection (mvdet::Detector::process: downscale, gain compensation, MOG2, morphology, components,
 * grouping, splitting, measurement, masks at 1/4 with hue/saturation). Frames of the 2 s bootstrap
 * are excluded. Prints the median and p99 with decode excluded (the bench's name) and included
 * (NAME.with_decode).
 */
#include "detect_bench.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <vector>

#include <opencv2/core/utility.hpp>
#include <opencv2/videoio.hpp>

#include "detector.hpp"
#include "mvt_rig.h"

namespace {

void print(const char *name, std::vector<double> ns)
{
    std::sort(ns.begin(), ns.end());
    const double p50 = ns[ns.size() / 2], p99 = ns[std::min(ns.size() - 1, ns.size() * 99 / 100)];
    std::printf("{\"bench\": \"%s\", \"median_ns\": %.0f, \"p99_ns\": %.0f, \"max_ns\": %.0f, \"runs\": %zu, "
                "\"threads\": 1}\n", name, p50, p99, ns.back(), ns.size());
}

} // namespace

int bench_detect(const char *video, const char *rig_path)
{
    static mvt_rig_t rig;
    char err[256];
    if (mvt_rig_load(rig_path, 2.0, &rig, err, sizeof err) != 0) {
        std::fprintf(stderr, "mvtrack-bench: %s\n", err);
        return -1;
    }
    cv::VideoCapture cap(video);
    if (!cap.isOpened()) {
        std::fprintf(stderr, "mvtrack-bench: cannot open %s (tools/mvtrack setup installs opencv-doc)\n", video);
        return -1;
    }
    cv::setNumThreads(1);
    mvt_camera_t cam;
    mvt_cam_init(&cam, &rig.params[0]);
    mvdet::Config cfg;
    cfg.frame_rate = rig.frame_rate;
    cfg.masks = true;
    mvdet::Detector det(cam, rig.volume_min, rig.volume_max, cfg);
    mvdet::Result res;
    cv::Mat img;
    std::vector<double> proc, total;
    const int skip = (int)(cfg.bootstrap_s * cfg.frame_rate) + 1;
    for (int i = 0;; i++) {
        const auto t0 = std::chrono::steady_clock::now();
        if (!cap.read(img)) {
            break;
        }
        const auto t1 = std::chrono::steady_clock::now();
        det.process(img, res);
        const auto t2 = std::chrono::steady_clock::now();
        if (i >= skip) {
            proc.push_back(std::chrono::duration<double, std::nano>(t2 - t1).count());
            total.push_back(std::chrono::duration<double, std::nano>(t2 - t0).count());
        }
    }
    if (proc.empty()) {
        std::fprintf(stderr, "mvtrack-bench: %s has too few frames\n", video);
        return -1;
    }
    print("detect_frame_768x576", proc);
    print("detect_frame_768x576.with_decode", total);
    std::fflush(stdout);
    return 0;
}
