/*
 * mvtrack-detect - camera pixels to mvtrack.camera_frame_t (docs/interfaces.md section 3b).
 *
 *   mvtrack-detect --rig RIG.yaml --video NAME=SOURCE [--video NAME=SOURCE ...] [--out URL]
 *                  [--start-utime US] [--mask-scale N] [--masks] [options]
 *
 * One --video per process is the live deployment; several read their sources in lockstep, frame
 * by frame (recorded multi-camera video, offline and deterministic). Exit 0 at the end of file
 * sources or on SIGINT/SIGTERM, 2 on bad arguments, a bad rig, an unknown camera or a source that
 * cannot be opened or has the wrong size.
 */
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <getopt.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm.h>
#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/core/utils/logger.hpp>

#include "detector.hpp"
#include "mvtrack_camera_frame_t.h"
#include "mvt_rig.h"
#include "source.hpp"

namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

const char *kDefaultUrl = "udpm://239.255.76.67:7667?ttl=0";
const int64_t kDefaultStartUtime = 1700000000000000LL;

void usage(FILE *f)
{
    std::fprintf(f,
        "usage: mvtrack-detect --rig RIG.yaml --video NAME=SOURCE [--video NAME=SOURCE ...] [options]\n"
        "\n"
        "Camera pixels to person blobs: background subtraction (Gaussian mixture, shadows removed),\n"
        "morphology, connected components, fragments grouped into people with the rig's geometry,\n"
        "side-by-side people split at the dip between their heads. Publishes mvtrack.camera_frame_t\n"
        "on DETECTIONS_<NAME> (docs/interfaces.md section 3b).\n"
        "\n"
        "  --rig FILE              rig file (docs/interfaces.md section 2); required\n"
        "  --video NAME=SOURCE     camera NAME of the rig reads SOURCE: a video file, an image sequence\n"
        "                          (frames/%%06d.png), a device index or /dev/videoN, a URL or pipeline.\n"
        "                          Repeatable: several sources are read in lockstep, frame by frame\n"
        "  --out URL               LCM URL to publish on (default %s;\n"
        "                          'file://OUT.lcm?mode=w' writes a log)\n"
        "  --start-utime US        utime of frame 0 of file sources (default %lld); frame i is\n"
        "                          start + round(i * 1e6 / frame_rate). Live sources: host clock at grab\n"
        "  --masks                 also send the foreground mask and per-pixel hue/saturation\n"
        "  --mask-scale N          image pixels per mask pixel (default 4: 192x144 for 768x576)\n"
        "  --bg mog2|knn           background model (default mog2)\n"
        "  --work-scale N          image pixels per working pixel (default 2)\n"
        "  --history-s S           the background model's memory in seconds (default 120)\n"
        "  --absorb-s S            a pixel foreground for less than S seconds is learnt as the\n"
        "                          background's own colour there, so a person standing still stays\n"
        "                          foreground that long, and a moved object joins the background\n"
        "                          after it (default 120; mog2 only; 0: off, anything still fades\n"
        "                          after about --history-s/10)\n"
        "  --bootstrap-s S         seconds of video whose per-pixel median starts the background model\n"
        "                          (default 2; no blobs meanwhile)\n"
        "  --no-gain-compensation  do not scale frames to the background's reference brightness\n"
        "  --var-threshold X       mog2: squared Mahalanobis distance (default 16); knn: squared\n"
        "                          distance (default 400)\n"
        "  --no-shadows            do not detect shadows (they become foreground)\n"
        "  --min-outline-contrast X  drop blobs whose outline is less than X the frame's edges and\n"
        "                          the rest the background image's (the background under another\n"
        "                          light, a ghost of what it learnt; default 0.55; 0: off)\n"
        "  --min-person-fraction X drop blobs with less foreground than X of a person's expected\n"
        "                          silhouette at their place (default 0.15)\n"
        "  --sigma-px X            1-sigma pixel noise written in each detection (default 0: the rig's)\n"
        "  --max-frames N          stop after N frames per source\n"
        "  --realtime              pace file sources at the rig's frame rate (recorded video replayed as\n"
        "                          if live; the utimes stay those of the frames)\n"
        "  --status-s S            status line on stderr every S seconds (default 5; 0: only at the end)\n"
        "  --threads N             OpenCV threads (default 1: one detector per core)\n"
        "  --progress              'progress I TOTAL' lines on stderr (for tools/mvtrack detect)\n"
        "  --quiet                 no status lines\n"
        "  -h, --help              this text\n",
        kDefaultUrl, (long long)kDefaultStartUtime);
}

[[noreturn]] void fail(const std::string &msg)
{
    std::fprintf(stderr, "mvtrack-detect: %s\n", msg.c_str());
    std::exit(2);
}

bool parse_double(const char *s, double *out)
{
    char *end = nullptr;
    const double v = std::strtod(s, &end);
    if (end == s || *end != '\0' || !std::isfinite(v)) {
        return false;
    }
    *out = v;
    return true;
}

bool parse_int64(const char *s, long long *out)
{
    char *end = nullptr;
    errno = 0;
    const long long v = std::strtoll(s, &end, 10);
    if (end == s || *end != '\0' || errno != 0) {
        return false;
    }
    *out = v;
    return true;
}

struct Camera {
    std::string name;
    int index = -1;
    mvdet::Source source;
    std::unique_ptr<mvdet::Detector> detector;
    std::vector<double> times_ms;  /* detection time per frame since the last status line */
    std::vector<double> all_ms;    /* ... over the whole run (bounded: last 100,000) */
    int64_t blobs = 0, messages = 0, publish_errors = 0;
    bool ended = false;
};

void encode_runs(const cv::Mat &mask, std::vector<int32_t> &runs)
{
    runs.clear();
    int32_t run = 0;
    uint8_t cur = 0;
    for (int y = 0; y < mask.rows; y++) {
        const uint8_t *row = mask.ptr<uint8_t>(y);
        for (int x = 0; x < mask.cols; x++) {
            const uint8_t v = row[x] ? 1 : 0;
            if (v != cur) {
                runs.push_back(run);
                run = 0;
                cur = v;
            }
            run++;
        }
    }
    runs.push_back(run);
}

double percentile(std::vector<double> v, double q)
{
    if (v.empty()) {
        return 0.0;
    }
    std::sort(v.begin(), v.end());
    const size_t i = std::min(v.size() - 1, (size_t)(q * (double)(v.size() - 1) + 0.5));
    return v[i];
}

/* counters since start; detection time over `when` */
void status_line(const Camera &c, const char *when, const std::vector<double> &ms)
{
    const mvdet::SourceStats &s = c.source.stats();
    std::fprintf(stderr,
                 "mvtrack-detect: %s: frames read %lld, dropped %lld, corrupt %lld, reconnects %lld, "
                 "messages %lld, blobs %.2f per frame; detect p50 %.2f ms p99 %.2f ms (%s)\n",
                 c.name.c_str(), (long long)s.read, (long long)s.dropped, (long long)s.corrupt,
                 (long long)s.reconnects, (long long)c.messages,
                 c.messages ? (double)c.blobs / (double)c.messages : 0.0, percentile(ms, 0.5), percentile(ms, 0.99),
                 when);
}

} // namespace

int main(int argc, char **argv)
{
    std::string rig_path, out_url = kDefaultUrl, bg = "mog2";
    std::vector<std::pair<std::string, std::string>> videos;
    long long start_utime = kDefaultStartUtime, max_frames = -1;
    double var_threshold = -1.0, status_s = 5.0, sigma_px = 0.0;
    int threads = 1;
    bool progress = false, quiet = false, realtime = false;
    mvdet::Config cfg;

    enum { O_RIG = 1000, O_VIDEO, O_OUT, O_START, O_MASKS, O_MASK_SCALE, O_BG, O_WORK, O_HISTORY, O_ABSORB, O_BOOT, O_NO_GAIN, O_VAR,
           O_NO_SHADOWS, O_MINFRAC, O_OUTLINE, O_SIGMA, O_MAXF, O_STATUS, O_THREADS, O_PROGRESS, O_QUIET, O_REALTIME };
    static const struct option opts[] = {
        {"rig", required_argument, nullptr, O_RIG}, {"video", required_argument, nullptr, O_VIDEO},
        {"out", required_argument, nullptr, O_OUT}, {"start-utime", required_argument, nullptr, O_START},
        {"masks", no_argument, nullptr, O_MASKS}, {"mask-scale", required_argument, nullptr, O_MASK_SCALE},
        {"bg", required_argument, nullptr, O_BG}, {"work-scale", required_argument, nullptr, O_WORK},
        {"history-s", required_argument, nullptr, O_HISTORY},
        {"absorb-s", required_argument, nullptr, O_ABSORB},
        {"bootstrap-s", required_argument, nullptr, O_BOOT}, {"no-gain-compensation", no_argument, nullptr, O_NO_GAIN}, {"var-threshold", required_argument, nullptr, O_VAR},
        {"no-shadows", no_argument, nullptr, O_NO_SHADOWS},
        {"min-person-fraction", required_argument, nullptr, O_MINFRAC},
        {"min-outline-contrast", required_argument, nullptr, O_OUTLINE},
        {"sigma-px", required_argument, nullptr, O_SIGMA}, {"max-frames", required_argument, nullptr, O_MAXF},
        {"status-s", required_argument, nullptr, O_STATUS}, {"threads", required_argument, nullptr, O_THREADS},
        {"progress", no_argument, nullptr, O_PROGRESS}, {"quiet", no_argument, nullptr, O_QUIET},
        {"realtime", no_argument, nullptr, O_REALTIME},
        {"help", no_argument, nullptr, 'h'}, {nullptr, 0, nullptr, 0}};
    int c;
    long long iv;
    double dv;
    while ((c = getopt_long(argc, argv, "h", opts, nullptr)) != -1) {
        switch (c) {
        case O_RIG: rig_path = optarg; break;
        case O_VIDEO: {
            const char *eq = std::strchr(optarg, '=');
            if (!eq || eq == optarg || eq[1] == '\0') {
                fail(std::string("--video takes NAME=SOURCE, got '") + optarg + "'");
            }
            videos.emplace_back(std::string(optarg, (size_t)(eq - optarg)), std::string(eq + 1));
            break;
        }
        case O_OUT: out_url = optarg; break;
        case O_START:
            if (!parse_int64(optarg, &start_utime) || start_utime < 0 || start_utime > (1LL << 60)) {
                fail("--start-utime must be an integer in 0..2^60");
            }
            break;
        case O_MASKS: cfg.masks = true; break;
        case O_MASK_SCALE:
            if (!parse_int64(optarg, &iv) || iv < 1 || iv > 32) fail("--mask-scale must be 1..32");
            cfg.mask_scale = (int)iv;
            break;
        case O_BG:
            bg = optarg;
            if (bg != "mog2" && bg != "knn") fail("--bg must be mog2 or knn");
            break;
        case O_WORK:
            if (!parse_int64(optarg, &iv) || iv < 1 || iv > 8) fail("--work-scale must be 1..8");
            cfg.work_scale = (int)iv;
            break;
        case O_HISTORY:
            if (!parse_double(optarg, &dv) || dv <= 0 || dv > 36000) fail("--history-s must be in (0, 36000]");
            cfg.history_s = dv;
            break;
        case O_ABSORB:
            if (!parse_double(optarg, &dv) || dv < 0 || dv > 36000) fail("--absorb-s must be in [0, 36000]");
            cfg.absorb_s = dv;
            break;
        case O_BOOT:
            if (!parse_double(optarg, &dv) || dv < 0 || dv > 40) fail("--bootstrap-s must be in [0, 40]");
            cfg.bootstrap_s = dv;
            break;
        case O_NO_GAIN: cfg.gain_compensation = false; break;
        case O_VAR:
            if (!parse_double(optarg, &var_threshold) || !(var_threshold > 0)) fail("--var-threshold must be > 0");
            break;
        case O_NO_SHADOWS: cfg.shadows = false; break;
        case O_MINFRAC:
            if (!parse_double(optarg, &dv) || dv < 0 || dv > 1) fail("--min-person-fraction must be in [0, 1]");
            cfg.min_person_fraction = dv;
            break;
        case O_OUTLINE:
            if (!parse_double(optarg, &dv) || dv < 0 || dv > 1) fail("--min-outline-contrast must be in [0, 1]");
            cfg.min_outline_contrast = dv;
            break;
        case O_SIGMA:
            if (!parse_double(optarg, &sigma_px) || sigma_px < 0 || sigma_px > 1000) fail("--sigma-px must be in [0, 1000]");
            break;
        case O_MAXF:
            if (!parse_int64(optarg, &max_frames) || max_frames < 1) fail("--max-frames must be >= 1");
            break;
        case O_STATUS:
            if (!parse_double(optarg, &status_s) || status_s < 0) fail("--status-s must be >= 0");
            break;
        case O_THREADS:
            if (!parse_int64(optarg, &iv) || iv < 0 || iv > 64) fail("--threads must be 0..64");
            threads = (int)iv;
            break;
        case O_PROGRESS: progress = true; break;
        case O_QUIET: quiet = true; break;
        case O_REALTIME: realtime = true; break;
        case 'h': usage(stdout); return 0;
        default: usage(stderr); return 2;
        }
    }
    if (optind < argc) {
        fail(std::string("unexpected argument '") + argv[optind] + "' (see --help)");
    }
    if (rig_path.empty()) {
        fail("--rig is required (see --help)");
    }
    if (videos.empty()) {
        fail("at least one --video NAME=SOURCE is required (see --help)");
    }
    cfg.model = bg == "knn" ? mvdet::BgModel::knn : mvdet::BgModel::mog2;
    cfg.var_threshold = var_threshold > 0 ? var_threshold : (cfg.model == mvdet::BgModel::knn ? 400.0 : 16.0);
    cv::setNumThreads(threads);
    /* OpenCV's backends log every probe that fails; this program says what failed in one line */
    cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);

    static mvt_rig_t rig;
    char err[512];
    if (mvt_rig_load(rig_path.c_str(), 2.0, &rig, err, sizeof err) != 0) {
        fail(err);
    }
    cfg.frame_rate = rig.frame_rate;
    std::vector<std::unique_ptr<Camera>> cams;
    for (const auto &v : videos) {
        const int k = mvt_rig_find(&rig, v.first.c_str());
        if (k < 0) {
            std::string names;
            for (int j = 0; j < rig.num_cameras; j++) {
                names += std::string(j ? ", " : "") + rig.names[j];
            }
            fail("camera '" + v.first + "' is not in the rig " + rig_path + " (it has " + names + ")");
        }
        for (const auto &other : cams) {
            if (other->index == k) {
                fail("camera '" + v.first + "' is given twice");
            }
        }
        auto cam = std::make_unique<Camera>();
        cam->name = v.first;
        cam->index = k;
        mvt_camera_t model;
        if (mvt_cam_init(&model, &rig.params[k]) != MVT_OK) {
            fail("camera '" + v.first + "': invalid calibration");
        }
        const std::string why = mvdet::check_config(cfg, model.width, model.height);
        if (!why.empty()) {
            fail("camera '" + v.first + "': " + why);
        }
        const std::string open_err = cam->source.open(v.second, model.width, model.height, rig.frame_rate);
        if (!open_err.empty()) {
            fail("camera '" + v.first + "': " + open_err);
        }
        const long mask_px = (long)(model.width / cfg.mask_scale) * (long)(model.height / cfg.mask_scale);
        if (cfg.masks && mask_px > (long)MVT_MAX_MASK_PIXELS) {
            std::fprintf(stderr,
                         "mvtrack-detect: warning: camera '%s': a %dx%d mask has %ld pixels, more than mvtrackd's "
                         "MVT_MAX_MASK_PIXELS (%ld), so the daemon will reject it; raise --mask-scale\n",
                         v.first.c_str(), model.width / cfg.mask_scale, model.height / cfg.mask_scale, mask_px,
                         (long)MVT_MAX_MASK_PIXELS);
        }
        cam->detector = std::make_unique<mvdet::Detector>(model, rig.volume_min, rig.volume_max, cfg);
        cams.push_back(std::move(cam));
    }
    lcm_t *lcm = lcm_create(out_url.c_str());
    if (!lcm) {
        fail("cannot open LCM output '" + out_url + "'");
    }
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);

    double total = 0.0;
    for (const auto &cam : cams) {
        total = std::max(total, cam->source.live() ? 0.0 : cam->source.frame_count());
    }
    if (max_frames > 0 && (total <= 0.0 || total > (double)max_frames)) {
        total = (double)max_frames;
    }
    const double period_us = 1e6 / rig.frame_rate;
    auto last_status = std::chrono::steady_clock::now();
    mvdet::Result res;
    cv::Mat img;
    std::vector<mvtrack_detection_t> dets;
    std::vector<int32_t> runs;
    std::vector<uint8_t> hue_bytes, sat_bytes;
    int64_t step = 0;
    const auto run_start = std::chrono::steady_clock::now();
    while (!g_stop) {
        if (realtime) { /* step i starts i frame periods after the first */
            std::this_thread::sleep_until(run_start + std::chrono::microseconds((int64_t)std::llround((double)step * period_us)));
        }
        bool any = false, waiting = false;
        for (auto &cam : cams) {
            if (cam->ended) {
                continue;
            }
            if (max_frames > 0 && cam->source.stats().read >= max_frames) {
                cam->ended = true;
                continue;
            }
            int64_t index = 0, utime = 0;
            const mvdet::ReadStatus st = cam->source.read(img, &index, &utime);
            if (st == mvdet::ReadStatus::ended) {
                cam->ended = true;
                continue;
            }
            any = true;
            if (st == mvdet::ReadStatus::waiting) {
                waiting = true;
                continue;
            }
            if (st == mvdet::ReadStatus::skipped) {
                continue;
            }
            if (!cam->source.live()) {
                utime = start_utime + (int64_t)std::llround((double)index * period_us);
            }
            const auto t0 = std::chrono::steady_clock::now();
            cam->detector->process(img, res);
            const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
            cam->times_ms.push_back(ms);
            if (cam->all_ms.size() < 100000) {
                cam->all_ms.push_back(ms);
            }

            const float sigma = sigma_px > 0 ? (float)sigma_px : 0.0f;
            dets.resize(std::min<size_t>(res.blobs.size(), 32767));
            for (size_t i = 0; i < dets.size(); i++) {
                const mvdet::Blob &b = res.blobs[i];
                mvtrack_detection_t &d = dets[i];
                d.u = b.u;
                d.v = b.v;
                d.sigma_px = sigma;
                std::memcpy(d.bbox, b.bbox, sizeof d.bbox);
                d.score = b.score;
                d.hue = b.hue;
                d.saturation = b.saturation;
            }
            mvtrack_camera_frame_t msg;
            std::memset(&msg, 0, sizeof msg);
            msg.utime = utime;
            msg.frame = index;
            msg.camera = const_cast<char *>(cam->name.c_str());
            msg.width = (int16_t)rig.params[cam->index].width;
            msg.height = (int16_t)rig.params[cam->index].height;
            msg.num_detections = (int16_t)dets.size();
            msg.detections = dets.data();
            if (cfg.masks) {
                encode_runs(res.mask, runs);
                msg.mask_width = (int16_t)res.mask.cols;
                msg.mask_height = (int16_t)res.mask.rows;
                msg.num_runs = (int32_t)runs.size();
                msg.runs = runs.data();
                hue_bytes.assign(res.hue.datastart, res.hue.dataend);
                sat_bytes.assign(res.saturation.datastart, res.saturation.dataend);
                msg.num_hs = (int32_t)hue_bytes.size();
                msg.hue = hue_bytes.data();
                msg.saturation = sat_bytes.data();
            }
            const std::string channel = "DETECTIONS_" + cam->name;
            if (mvtrack_camera_frame_t_publish(lcm, channel.c_str(), &msg) != 0) {
                cam->publish_errors++;
            }
            cam->messages++;
            cam->blobs += (int64_t)dets.size();
        }
        if (!any) {
            break;
        }
        step++;
        if (progress && (step % 25 == 0)) {
            std::fprintf(stderr, "progress %lld %.0f\n", (long long)step, total);
        }
        const auto now = std::chrono::steady_clock::now();
        if (!quiet && status_s > 0 && std::chrono::duration<double>(now - last_status).count() >= status_s) {
            for (auto &cam : cams) {
                status_line(*cam, "last period", cam->times_ms);
                cam->times_ms.clear();
            }
            last_status = now;
        }
        if (waiting) {
            bool all_waiting = true;
            for (auto &cam : cams) {
                all_waiting = all_waiting && (cam->ended || cam->source.live());
            }
            if (all_waiting) {
                std::this_thread::sleep_for(std::chrono::milliseconds(20));
            }
        }
    }
    if (progress) {
        std::fprintf(stderr, "progress %lld %.0f\n", (long long)step, total);
    }
    int64_t publish_errors = 0;
    for (auto &cam : cams) {
        if (!quiet) {
            status_line(*cam, "whole run", cam->all_ms);
        }
        publish_errors += cam->publish_errors;
    }
    lcm_destroy(lcm);
    if (publish_errors > 0) {
        std::fprintf(stderr, "mvtrack-detect: %lld messages could not be published\n", (long long)publish_errors);
        return 1;
    }
    return 0;
}
