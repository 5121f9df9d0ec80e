/*
 * mvt_rig.h - loads a rig file (docs/interfaces.md section 2: OpenCV FileStorage YAML) into core camera
 * parameters. C interface, implemented with cv::FileStorage.
 *
 * A host-side adapter over the core, not part of it (the core reads no files): built as its own
 * library, mvtrack_rig, which the daemon, the detector and the benches link.
 */
#ifndef MVT_RIG_H
#define MVT_RIG_H

#include <stddef.h>

#include "mvt_camera.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MVT_RIG_NAME_MAX 64

typedef struct mvt_rig {
    int num_cameras;
    char names[MVT_MAX_CAMERAS][MVT_RIG_NAME_MAX];
    mvt_camera_params_t params[MVT_MAX_CAMERAS];
    double volume_min[3], volume_max[3]; /* metres */
    int volume_given;                    /* 0: derived from the camera centres */
    double frame_rate;                   /* Hz */
    int num_occluders;                   /* static occluders (optional key `occluders`) */
    char occluder_names[MVT_MAX_OCCLUDERS > 0 ? MVT_MAX_OCCLUDERS : 1][MVT_RIG_NAME_MAX];
    double occluder_min[MVT_MAX_OCCLUDERS > 0 ? MVT_MAX_OCCLUDERS : 1][3]; /* metres */
    double occluder_max[MVT_MAX_OCCLUDERS > 0 ? MVT_MAX_OCCLUDERS : 1][3];
} mvt_rig_t;

/* Reads and checks path. Returns 0, or -1 with a one-line reason in err. */
int mvt_rig_load(const char *path, double default_sigma_px, mvt_rig_t *rig, char *err, size_t err_len);

/* Rig index of a camera name, or -1. */
int mvt_rig_find(const mvt_rig_t *rig, const char *name);

#ifdef __cplusplus
}
#endif

#endif /* MVT_RIG_H */
