/*
 * embed_example.c - the C core from a program of your own (docs/embedding.md walks through it).
 *
 * Four calibrated cameras in the corners of a 6 x 5 m room (numbers as a rig file holds them), one
 * person walking across it. Each frame the program hands the tracker what every camera detected
 * (here: the person's head projected through the camera model, as a detector would report it),
 * steps the tracker once, and reads the tracks back. No heap, no I/O in the core: the program owns
 * every buffer and decides where text goes.
 *
 * The tests build it twice: on the host (tests/CMakeLists.txt, embed_example) and for a Cortex-M
 * under QEMU (tests/mcu, embed_example_mcu). It returns 0 when the person was tracked with one
 * identity within 10 cm from the third frame on.
 */
#include "embed_example.h"

#include "mvt_camera.h"
#include "mvt_tracker.h"

/* The tracker is about 170 kB at the default capacities (lib/mvt_config.h): static storage, not
 * the stack. */
static mvt_tracker_t tracker;
static mvt_frame_t frame;
static mvt_output_t out;
static mvt_camera_t cams[4];

/* From the rig file (camera_matrix, distortion_coefficients, rvec, tvec, sigma_px): the smart room
 * of the simulations, its four corner cameras 2.5 m high. */
static const mvt_real K[9] = {MVT_R(420.0), MVT_R(0.0), MVT_R(383.5), MVT_R(0.0), MVT_R(420.0), MVT_R(287.5), MVT_R(0.0), MVT_R(0.0), MVT_R(1.0)};
static const mvt_real DIST[5] = {MVT_R(-0.22), MVT_R(0.06), MVT_R(0.0005), MVT_R(-0.0004), MVT_R(-0.006)};
static const mvt_real RVEC[4][3] = {{MVT_R(1.881434), MVT_R(-0.887188), MVT_R(0.547908)}, {MVT_R(1.881434), MVT_R(0.887188), MVT_R(-0.547908)},
                                    {MVT_R(1.001461), MVT_R(2.123769), MVT_R(-1.311595)}, {MVT_R(1.001461), MVT_R(-2.123769), MVT_R(1.311595)}};
static const mvt_real TVEC[4][3] = {{MVT_R(0.020304), MVT_R(2.553421), MVT_R(1.042654)}, {MVT_R(-3.837393), MVT_R(0.480436), MVT_R(5.181804)},
                                    {MVT_R(-0.020304), MVT_R(-0.943983), MVT_R(8.025957)}, {MVT_R(3.837393), MVT_R(1.129002), MVT_R(3.886807)}};

static char *put_int(char *p, long v)
{
    char digits[24];
    int n = 0;
    if (v < 0) {
        *p++ = '-';
        v = -v;
    }
    do {
        digits[n++] = (char)('0' + v % 10);
        v /= 10;
    } while (v > 0);
    while (n > 0) {
        *p++ = digits[--n];
    }
    return p;
}

/* Writes v with 3 decimals (the core has no printf; neither need the program). */
static char *put_real(char *p, mvt_real v)
{
    if (v < MVT_R(0.0)) {
        *p++ = '-';
        v = -v;
    }
    const long milli = (long)(v * MVT_R(1000.0) + MVT_R(0.5));
    p = put_int(p, milli / 1000);
    *p++ = '.';
    *p++ = (char)('0' + (milli / 100) % 10);
    *p++ = (char)('0' + (milli / 10) % 10);
    *p++ = (char)('0' + milli % 10);
    return p;
}

static char *put_text(char *p, const char *s)
{
    while (*s != '\0') {
        *p++ = *s++;
    }
    return p;
}

int mvt_embed_example(void (*print)(const char *line))
{
    /* 1. The cameras, from their calibration. */
    for (int k = 0; k < 4; k++) {
        mvt_camera_params_t p = {0};
        for (int i = 0; i < 9; i++) {
            p.camera_matrix[i] = K[i];
        }
        for (int i = 0; i < 5; i++) {
            p.dist[i] = DIST[i];
        }
        for (int i = 0; i < 3; i++) {
            p.rvec[i] = RVEC[k][i];
            p.tvec[i] = TVEC[k][i];
        }
        p.width = 768;
        p.height = 576;
        p.sigma_px = MVT_R(2.0);
        if (mvt_cam_init(&cams[k], &p) != MVT_OK) {
            print("camera rejected\n");
            return 1;
        }
    }

    /* 2. The tracker: defaults (the body model, the IMM motion bank), the room's volume. */
    mvt_tracker_config_t cfg;
    mvt_tracker_config_default(&cfg);
    const mvt_real vmin[3] = {MVT_R(0.0), MVT_R(0.0), MVT_R(0.0)}, vmax[3] = {MVT_R(6.0), MVT_R(5.0), MVT_R(2.5)};
    for (int i = 0; i < 3; i++) {
        cfg.volume.min[i] = vmin[i];
        cfg.volume.max[i] = vmax[i];
    }
    if (mvt_tracker_init(&tracker, &cfg, cams, 4) != MVT_OK) {
        print("configuration rejected\n");
        return 1;
    }

    /* 3. Frames at 25 fps: a person (head top 1.75 m) walks from (1, 1) towards (5, 4) at 1 m/s. */
    int failures = 0;
    int32_t id_seen = 0;
    for (int f = 0; f < 100; f++) {
        const int64_t utime = 1700000000000000LL + (int64_t)f * 40000;
        const mvt_real s = (mvt_real)f * MVT_R(0.04); /* seconds */
        const mvt_real head[3] = {MVT_R(1.0) + MVT_R(0.8) * s, MVT_R(1.0) + MVT_R(0.6) * s, MVT_R(1.75)};
        frame.utime_us = utime;
        for (int k = 0; k < 4; k++) {
            mvt_view_t *v = &frame.views[k];
            v->observed = 1; /* the camera reported, with or without detections */
            v->utime_us = utime;
            v->num_detections = 0;
            v->num_offered = 0;
            v->mask = 0;
            mvt_real uv[2];
            if (mvt_cam_project(&cams[k], head, uv, 0) != MVT_OK || uv[0] < MVT_R(0.0) || uv[1] < MVT_R(0.0) ||
                uv[0] > MVT_R(767.0) || uv[1] > MVT_R(575.0)) {
                continue;
            }
            mvt_detection_t *d = &v->det[v->num_detections++];
            d->u = uv[0];
            d->v = uv[1];
            d->sigma_px = MVT_R(0.0); /* the camera's default */
            d->score = MVT_R(1.0);
            d->hue = d->saturation = MVT_R(-1.0); /* no colour */
            d->box[0] = d->box[1] = d->box[2] = d->box[3] = MVT_R(0.0); /* no box */
            v->num_offered = v->num_detections;
        }

        /* 4. One step, and the tracks. */
        if (mvt_tracker_step(&tracker, &frame, &out) != MVT_OK) {
            print("step failed\n");
            return 1;
        }
        for (int t = 0; t < out.num_tracks; t++) {
            const mvt_track_out_t *tr = &out.tracks[t];
            const mvt_real dx = tr->pos_m[0] - head[0], dy = tr->pos_m[1] - head[1], dz = tr->pos_m[2] - head[2];
            const int off = dx * dx + dy * dy + dz * dz > MVT_R(0.1) * MVT_R(0.1);
            if (f >= 2 && tr->status == MVT_TRACK_CONFIRMED) {
                failures += off || (id_seen != 0 && tr->id != id_seen);
                id_seen = tr->id;
            }
            if (f % 25 == 0) {
                char line[96], *p = line;
                p = put_text(p, "frame ");
                p = put_int(p, f);
                p = put_text(p, "  track ");
                p = put_int(p, (long)tr->id);
                p = put_text(p, tr->status == MVT_TRACK_CONFIRMED ? " confirmed at " : " tentative at ");
                for (int i = 0; i < 3; i++) {
                    p = put_real(p, tr->pos_m[i]);
                    *p++ = i < 2 ? ' ' : '\n';
                }
                *p = '\0';
                print(line);
            }
        }
        if (f >= 2 && out.num_tracks != 1) {
            failures++;
        }
    }
    print(failures == 0 ? "embed example: one person, one identity, within 10 cm\n"
                        : "embed example: FAILED\n");
    return failures == 0 ? 0 : 1;
}
