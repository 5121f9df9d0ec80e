/*
 * source.hpp - one camera's frames from anything cv::VideoCapture opens (docs/interfaces.md section 3b).
 *
 * A *file* source (a regular file or an image sequence pattern with '%') is read frame by frame;
 * frame i is stamped by the caller from its index. A frame that fails to decode is skipped and
 * counted as corrupt (its index is used up, so time stays right); 25 failures in a row, or a failure
 * at the end of the stream, end the source: a truncated file ends cleanly with what it had.
 *
 * A *live* source (a device index, /dev/video*, a URL or a GStreamer pipeline) is stamped with the
 * host clock at grab. When it stops delivering it is released and reopened with exponential
 * back-off (0.5 s doubling to 8 s), counted; the program never exits because a camera went away.
 */
#pragma once

#include <cstdint>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

namespace mvdet {

struct SourceStats {
    int64_t read = 0;        /* frames delivered */
    int64_t corrupt = 0;     /* frames that failed to decode or had the wrong size */
    int64_t dropped = 0;     /* live: frames missing between two grabs (capture-time gaps) */
    int64_t reconnects = 0;  /* live: reopen attempts after the source stopped */
};

enum class ReadStatus { frame, skipped, waiting, ended };

class Source {
  public:
    /* Opens spec; returns "" or a one-line reason. A file source's first frame is decoded here
     * so that a non-video file and a wrong image size are refused at start. */
    std::string open(const std::string &spec, int width, int height, double fps);

    /* Next frame. frame: the image was read into img (index is its frame index for file sources,
     * utime_us the host capture time for live ones). skipped: a corrupt frame used up an index.
     * waiting: a live source is reconnecting. ended: a file source has no more frames. */
    ReadStatus read(cv::Mat &img, int64_t *index, int64_t *utime_us);

    bool live() const { return live_; }
    double frame_count() const { return frame_count_; }
    const SourceStats &stats() const { return stats_; }
    const std::string &spec() const { return spec_; }

  private:
    bool open_capture();

    std::string spec_;
    cv::VideoCapture cap_;
    bool live_ = false;
    int width_ = 0, height_ = 0;
    double period_us_ = 40000.0;
    double frame_count_ = 0.0;
    int64_t next_index_ = 0;
    int fails_in_row_ = 0;
    cv::Mat pending_;              /* the first frame, decoded by open() */
    bool has_pending_ = false;
    int64_t last_grab_us_ = -1;
    int64_t retry_at_us_ = 0;
    double backoff_s_ = 0.5;
    bool down_ = false;
    SourceStats stats_;
};

/* Host clock in microseconds since the epoch (the capture clock of live sources). */
int64_t host_utime_us();

} // namespace mvdet
