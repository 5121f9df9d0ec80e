/*
 * detector.hpp - one camera's pixels to person blobs (the producer side of docs/interfaces.md section 3b).
 *
 * Per frame: downscale by `work_scale`, per-pixel Gaussian-mixture background subtraction
 * (OpenCV's MOG2, Zivkovic's refinement of Stauffer-Grimson, or KNN) with shadow suppression,
 * an opening against speckle, a closing against cracks, connected components. Then the rig:
 *
 *  - fragments to people: a real mask splits a body (clothes the colour of the background, holes,
 *    legs behind furniture). The lowest unassigned fragment (along the image's local "down",
 *    the direction in which the world's vertical projects) is taken as standing on the floor:
 *    its foot point back-projects to a ground point G, and the camera projects the column of a
 *    person at G (radius `person_radius_m`, floor to `column_height_m`). Every fragment whose
 *    centroid lies in that column joins the person. Repeat until every fragment has a person.
 *  - people to blobs: a group wider than one person is split where its head profile (the highest
 *    pixel per slice across the local vertical) has two peaks a body apart with a dip between them
 *    (two heads side by side; the dip is the shoulders), or, with no such dip, where it is wider
 *    within a shoulder's drop of its top than anyone's shoulders (two heads touching): at the
 *    profile's lowest point away from that band's ends. A blob whose top stands higher over its
 *    feet than anyone stands (`kTwoHighM`) while a body fills its column from the feet to head
 *    height holds a nearer person in front of a farther one: a second blob is sent for the nearer
 *    one, its head at a standing person's height over the feet.
 *  - background, not a blob: where the outline of a blob is no more an edge of the frame than of
 *    the background image (`min_outline_contrast`), what changed is the light on a still surface
 *    (a wall, a windscreen, a car roof) or a ghost of what the background learnt (a person present
 *    while it started): its pixels leave the mask, and after a second judged so they are learnt
 *    like the background's.
 *  - a blob too small for a person at its place (area under `min_person_fraction` of the
 *    expected silhouette) is clutter and dropped; a blob whose top touches the image border has no
 *    visible head top and is dropped too (its mask still goes out).
 *
 * Each blob: the head-top point (the extreme foreground pixels along the local vertical) in raw
 * full-resolution pixels, the box, a score (foreground area over the expected silhouette, <= 1)
 * and the circular-mean hue and mean saturation of the torso band (20-45 % of the blob's height
 * below its top). Optionally the cleaned mask and per-pixel hue/saturation at `mask_scale`.
 *
 * Memory: the background model and a handful of images at working resolution, allocated on the
 * first frame and reused (OpenCV allocates once per size). Cost per frame: O(pixels / work_scale^2)
 * for subtraction, morphology and labelling, plus O(blob pixels) for grouping.
 */
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/video/background_segm.hpp>

#include "mvt_camera.h"

namespace mvdet {

enum class BgModel { mog2, knn };

struct Config {
    BgModel model = BgModel::mog2;
    int work_scale = 2;              /* image pixels per working pixel, 1..8 */
    double history_s = 120.0;        /* the background model's memory, seconds (without absorb_s a
                                      * person standing still fades into it after about a tenth of
                                      * that) */
    double frame_rate = 25.0;        /* frames per second (the rig's), to turn seconds into frames */
    double var_threshold = 16.0;     /* MOG2: squared Mahalanobis distance; KNN: squared distance (400) */
    bool shadows = true;             /* detect shadows (darker, same chromaticity) and drop them */
    double learning_rate = -1.0;     /* < 0: 1/history */
    double absorb_s = 120.0;         /* a pixel that has been foreground for less than this is
                                      * learnt as the background's own colour there, not as its
                                      * colour now, so a person standing still stays foreground that
                                      * long, and a moved chair joins the background after it
                                      * (selective update, MOG2 only); 0: every pixel is learnt,
                                      * and anything still fades after about a tenth of history_s */
    double bootstrap_s = 2.0;        /* the model starts from the per-pixel median of the first
                                      * frames (people walking through are not in it); no blobs
                                      * meanwhile. OpenCV's own start (rate 1/frames until `history`)
                                      * would learn anyone standing still within seconds */
    bool gain_compensation = true;   /* scale each frame so that its background pixels keep the
                                      * brightness they had (illumination drift, flicker, auto gain) */
    double person_radius_m = 0.35;   /* half-width of the column that collects one body's fragments */
    double column_height_m = 2.2;    /* the column's top above the floor */
    double body_half_width_m = 0.22; /* a standing person's half-width, for the expected silhouette */
    double person_height_m = 1.7;    /* a standing person's height, for the expected silhouette */
    double min_person_fraction = 0.15; /* minimum foreground area / expected silhouette area */
    double min_outline_contrast = 0.55; /* minimum share of the edges along a blob's outline that are
                                      * the frame's rather than the background image's: something new
                                      * in front of the background ends in an edge of its own (share
                                      * near 1 over a plain background, above 0.5 over texture); the
                                      * background's own edges under another light, or a ghost of
                                      * what the background learnt, give 0.5 or less. 0: off */
    double head_gap_m = 0.12;        /* dip below two head peaks that splits a group */
    int mask_scale = 4;              /* image pixels per mask pixel (output mask) */
    bool masks = false;              /* produce the mask and per-pixel hue/saturation */
};

struct Blob {
    float u = 0, v = 0;              /* head top, raw full-resolution pixels */
    float bbox[4] = {0, 0, 0, 0};    /* x_min, y_min, x_max, y_max, full-resolution pixels */
    float score = 0;                 /* [0, 1] */
    float hue = -1, saturation = -1; /* torso colour; < 0 unknown */
};

struct Result {
    std::vector<Blob> blobs;
    cv::Mat mask;                    /* CV_8U 0/1 at mask resolution (masks only) */
    cv::Mat hue, saturation;         /* CV_8U at mask resolution, 0..255 (masks only) */
    int fragments = 0;               /* connected components kept before grouping */
    int dropped_small = 0;           /* groups too small for a person */
    int dropped_border = 0;          /* groups whose head top is cut by the image border */
    int dropped_background = 0;      /* blobs whose outline is the background's edges (light, ghosts) */
    bool warming_up = false;         /* the background model is still being initialised: no blobs */
    float gain = 1.0f;               /* illumination gain applied to this frame */
    int splits = 0;                  /* extra blobs made by splitting groups */
};

/* Checks a configuration; returns "" or the reason. */
std::string check_config(const Config &cfg, int width, int height);

class Detector {
  public:
    /* cam: the rig camera (core model, raw pixels at full resolution). volume: the tracked volume,
     * used to keep ground points plausible. */
    Detector(const mvt_camera_t &cam, const double volume_min[3], const double volume_max[3], const Config &cfg);

    /* One BGR frame of the camera's full size (CV_8UC3). */
    void process(const cv::Mat &bgr, Result &out);

    const Config &config() const { return cfg_; }

  private:
    struct Column {                  /* one person's column at a ground point, working pixels */
        bool valid = false;
        float axis[12][2];           /* projected axis points, floor to column top */
        float half[12];              /* half-widths of the column at those points */
        int n = 0;
        float up[2] = {0, -1};       /* unit image direction of the world's vertical */
        float height_px = 0;         /* image length of a standing person */
        float z[12];                 /* heights of the axis points, metres */
        float px_per_m = 0;          /* image length of a horizontal metre at mid-body */
        float head_offset_px = 0;    /* head sphere's rim beyond the head top, along up */
        float expected_area = 0;     /* expected silhouette area */
        double g[2] = {0, 0};        /* the ground point it stands on, metres */
    };

    bool stacked_head(const std::vector<cv::Point> &seg, const Column &c, Result &out);
    bool ground_point(float xw, float yw, double g[3]) const;
    bool project_work(const double x[3], float p[2]) const;
    void local_up(float xw, float yw, float up[2]) const;
    Column column_at(const double g[3]) const;
    static bool in_column(const Column &c, float x, float y);
    static float height_at(const Column &c, float x, float y);
    void fill_masks(Result &out);
    void find_blobs(Result &out, bool selective);
    float outline_contrast(const std::vector<cv::Point> &pix, const cv::Rect &roi);
    void measure(const std::vector<cv::Point> &pix, const Column &col, const cv::Mat &hsv, const cv::Rect &roi,
                 Blob &b, bool *at_border) const;

    mvt_camera_t cam_;
    double vmin_[3], vmax_[3];
    Config cfg_;
    cv::Ptr<cv::BackgroundSubtractor> bg_;
    cv::Mat small_, resized_, gained_, colour_, fg_raw_, fg_, tmp_, labels_, stats_, centroids_, hsv_;
    std::vector<cv::Point> near_;    /* the nearer body's pixels of a blob that holds two (stacked_head) */
    std::vector<uint8_t> rows_;      /* rows of the nearer body's column that are foreground */
    cv::Mat open_kernel_, close_kernel_, mask_tmp_, mask_bgr_, mask_hsv_;
    int wsmall_ = 0, hsmall_ = 0;
    int64_t frames_ = 0;
    std::vector<cv::Mat> boot_;      /* the first frames, for the median background */
    int history_frames_ = 1, bootstrap_frames_ = 0;
    double ref_brightness_ = -1.0;   /* mean background brightness the frames are scaled to */
    cv::Mat prev_bg_;                /* last frame's background pixels (where the gain is measured) */
    cv::Mat fg_age_;                 /* frames each working pixel has been foreground (absorb_s) */
    cv::Mat judged_, bg_age_;        /* pixels of blobs judged background this frame; frames running */
    cv::Mat bg_img_, learn_, protect_, fg_scratch_;
    cv::Mat gray_f_, gray_b_, inside_; /* outline contrast, per blob */
};

} // namespace mvdet
