/*
 * mvt_trk.h - the steps of mvt_tracker_step, one module each (internal to the core).
 *
 * Each step reads and writes the tracker's per-frame workspaces; none allocates or prints.
 */
#ifndef MVT_TRK_H
#define MVT_TRK_H

#include "mvt_tracker.h"

/* Hypothesise + associate for camera k (tracks already predicted to the camera's capture time):
 * fills assign[t] with the detection that updates track t (or -1) and merged[t] with 1 when that
 * detection is shared with unresolved tracks (its covariance is widened by merge_cov[t]). Marks
 * the assigned detections used. O(T * D) gating + O(cluster^2 * (cluster + D)) assignment. */
void mvt_trk_associate(mvt_tracker_t *self, int k, int assign[MVT_MAX_TARGETS], uint8_t merged[MVT_MAX_TARGETS]);

/* Confirmation, coasting and deletion after the frame's updates. O(T). */
void mvt_trk_delete(mvt_tracker_t *self, int64_t now_us);

/* Births from detections no track used that agree in >= birth_min_views views. order[] are the
 * observed cameras. O(C^2 D^2) cheap epipolar tests + O(candidates * C * D). */
void mvt_trk_initiate(mvt_tracker_t *self, const mvt_frame_t *frame, const int order[], int n_order);

/* The track's position is within the volume extended by volume_margin_m. */
int mvt_trk_inside_volume(const mvt_tracker_config_t *c, const mvt_real x[3]);

#endif /* MVT_TRK_H */
