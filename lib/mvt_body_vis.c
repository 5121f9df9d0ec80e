/*
 * mvt_body_vis.c - visibility: where each track's body shows in camera k, and the probability that
 * the camera reports its head.
 *
 * A head in the picture is reported with p_detect. A head inside the silhouette of another body
 * (one more likely there than not), not above that body's top, is either hidden behind a nearer body or
 * inside a merged blob whose reported top is the other head: it shows as a top of its own only with
 * MVT_BODY_P_SHOWN_HIDDEN. Each such body lowers the probability by its own existence. A head
 * outside the picture, or behind the camera, is not reported at all.
 */
#include "mvt_body.h"

#include <stddef.h>

void mvt_body_visibility(mvt_tracker_t *self, int k)
{
    const mvt_camera_t *cam = &self->cams[k];
    mvt_body_ws_t *ws = &self->body;
    mvt_real r[MVT_MAX_TARGETS];
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        mvt_track_t *tr = &self->tracks[t];
        mvt_real *sil = ws->sil[k][t];
        ws->pd[t] = MVT_R(0.0);
        self->pred_ok[t] = 0;
        sil[0] = MVT_R(1.0);
        sil[2] = MVT_R(0.0);
        r[t] = MVT_R(0.0);
        if (tr->id == 0) {
            continue;
        }
        r[t] = mvt_body_prob(tr->exist_lo);
        if (mvt_pkf_predict_obs(&tr->s, cam, self->cfg.lin, &self->pred[t]) != MVT_OK) {
            self->counters.behind_camera++;
            continue;
        }
        if (!mvt_body_silhouette(self, cam, tr->s.x, sil, ws->head[t])) {
            sil[0] = MVT_R(1.0);
            sil[2] = MVT_R(0.0);
            continue;
        }
        self->pred_ok[t] = 1;
        const mvt_real *h = ws->head[t];
        if (h[0] >= MVT_R(0.0) && h[1] >= MVT_R(0.0) && h[0] <= (mvt_real)cam->width - MVT_R(1.0) &&
            h[1] <= (mvt_real)cam->height - MVT_R(1.0)) {
            ws->pd[t] = self->cfg.p_detect;
        }
    }
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        if (!(ws->pd[t] > MVT_R(0.0))) {
            continue;
        }
        mvt_real shown = MVT_R(1.0);
        for (int j = 0; j < MVT_MAX_TARGETS; j++) {
            const mvt_real *sj = ws->sil[k][j];
            if (j == t || !(r[j] > MVT_R(0.5)) || !(sj[2] > sj[0])) {
                continue;
            }
            const mvt_real *h = ws->head[t];
            if (h[0] >= sj[0] && h[0] <= sj[2] && h[1] >= ws->head[j][1] && h[1] <= sj[3]) {
                shown *= MVT_R(1.0) - r[j] * (MVT_R(1.0) - MVT_BODY_P_SHOWN_HIDDEN);
            }
        }
        ws->pd[t] *= shown;
    }
}
