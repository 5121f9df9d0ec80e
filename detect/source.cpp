#include "source.hpp"

#include <opencv2/videoio/registry.hpp>

#include <sys/stat.h>

#include <chrono>
#include <cmath>
#include <cstdlib>

namespace mvdet {

namespace {

constexpr int kMaxFailsInRow = 25;
constexpr double kMaxBackoffS = 8.0;

bool all_digits(const std::string &s)
{
    if (s.empty()) {
        return false;
    }
    for (char c : s) {
        if (c < '0' || c > '9') {
            return false;
        }
    }
    return true;
}

} // namespace

int64_t host_utime_us()
{
    return std::chrono::duration_cast<std::chrono::microseconds>(
               std::chrono::system_clock::now().time_since_epoch())
        .count();
}

bool Source::open_capture()
{
    cap_.release();
    try {
        if (all_digits(spec_)) {
            return cap_.open(std::atoi(spec_.c_str()));
        }
        if (!live_ && spec_.find('%') == std::string::npos && cv::videoio_registry::hasBackend(cv::CAP_FFMPEG)) {
            /* files: FFmpeg only. A file FFmpeg cannot open is not a video; letting GStreamer
             * probe it as well is slow, and its pipeline, disposed half-open, writes GLib
             * "CRITICAL" lines to stderr (seen as a flaky hostile-input test) */
            return cap_.open(spec_, cv::CAP_FFMPEG);
        }
        return cap_.open(spec_);
    } catch (const cv::Exception &) {
        return false;
    }
}

std::string Source::open(const std::string &spec, int width, int height, double fps)
{
    spec_ = spec;
    width_ = width;
    height_ = height;
    period_us_ = 1e6 / fps;
    struct stat st;
    const bool is_file = ::stat(spec.c_str(), &st) == 0 && S_ISREG(st.st_mode);
    const bool is_sequence = spec.find('%') != std::string::npos;
    live_ = !is_file && !is_sequence;
    if (!live_ && is_file && st.st_size == 0) {
        return spec + ": empty file";
    }
    const bool looks_like_path = spec.find('/') != std::string::npos || spec.find('.') != std::string::npos;
    if (live_ && looks_like_path && spec.find("://") == std::string::npos && spec.rfind("/dev/", 0) != 0 &&
        spec.find('!') == std::string::npos) {
        return spec + ": no such file";
    }
    if (!open_capture()) {
        return spec + ": not a video cv::VideoCapture can open";
    }
    if (!live_) {
        frame_count_ = cap_.get(cv::CAP_PROP_FRAME_COUNT);
        cv::Mat first;
        bool ok = false;
        try {
            ok = cap_.read(first);
        } catch (const cv::Exception &) {
            ok = false;
        }
        if (!ok || first.empty()) {
            return spec + ": no frame could be decoded (not a video?)";
        }
        if (first.cols != width || first.rows != height) {
            return spec + ": frames are " + std::to_string(first.cols) + "x" + std::to_string(first.rows) +
                   ", the rig says " + std::to_string(width) + "x" + std::to_string(height);
        }
        pending_ = first;
        has_pending_ = true;
    }
    return "";
}

ReadStatus Source::read(cv::Mat &img, int64_t *index, int64_t *utime_us)
{
    if (!live_) {
        if (has_pending_) {
            has_pending_ = false;
            img = pending_;
            pending_.release();
            *index = next_index_++;
            stats_.read++;
            return ReadStatus::frame;
        }
        if (!cap_.isOpened()) {
            return ReadStatus::ended;
        }
        bool ok = false;
        try {
            ok = cap_.read(img);
        } catch (const cv::Exception &) {
            ok = false;
        }
        const int64_t i = next_index_++;
        if (ok && !img.empty() && img.cols == width_ && img.rows == height_ && img.type() == CV_8UC3) {
            fails_in_row_ = 0;
            *index = i;
            stats_.read++;
            return ReadStatus::frame;
        }
        /* a decoding failure inside the stream is a corrupt frame; at (or past) its end, the end */
        fails_in_row_++;
        const bool inside = frame_count_ > 0.0 && (double)(i + 1) < frame_count_;
        if (ok && !img.empty()) { /* decoded, but of the wrong size or type */
            stats_.corrupt++;
            return ReadStatus::skipped;
        }
        if (inside && fails_in_row_ < kMaxFailsInRow) {
            stats_.corrupt++;
            return ReadStatus::skipped;
        }
        cap_.release();
        return ReadStatus::ended;
    }

    const int64_t now = host_utime_us();
    if (down_) {
        if (now < retry_at_us_) {
            return ReadStatus::waiting;
        }
        stats_.reconnects++;
        if (!open_capture()) {
            backoff_s_ = std::min(kMaxBackoffS, backoff_s_ * 2.0);
            retry_at_us_ = now + (int64_t)(backoff_s_ * 1e6);
            return ReadStatus::waiting;
        }
        down_ = false;
        backoff_s_ = 0.5;
        last_grab_us_ = -1;
    }
    bool ok = false;
    try {
        ok = cap_.grab();
    } catch (const cv::Exception &) {
        ok = false;
    }
    const int64_t t_grab = host_utime_us();
    if (!ok) {
        down_ = true;
        cap_.release();
        retry_at_us_ = t_grab + (int64_t)(backoff_s_ * 1e6);
        return ReadStatus::waiting;
    }
    try {
        ok = cap_.retrieve(img);
    } catch (const cv::Exception &) {
        ok = false;
    }
    if (!ok || img.empty() || img.cols != width_ || img.rows != height_ || img.type() != CV_8UC3) {
        stats_.corrupt++;
        return ReadStatus::skipped;
    }
    if (last_grab_us_ >= 0) {
        const double gap = (double)(t_grab - last_grab_us_) / period_us_;
        if (gap > 1.5) {
            stats_.dropped += (int64_t)std::lround(gap) - 1;
        }
    }
    last_grab_us_ = t_grab;
    *index = next_index_++;
    *utime_us = t_grab;
    stats_.read++;
    return ReadStatus::frame;
}

} // namespace mvdet
