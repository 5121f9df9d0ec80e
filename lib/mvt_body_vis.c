/*
 * mvt_body_vis.c - visibility: where each track's body shows in camera k, and the probability that
 * the camera reports its head.
 *
 * A head in the picture is reported with p_detect. A body whose silhouette touches that of another
 * body (one more likely there than not) with a higher head is hidden behind it or merged into one
 * blob with it, whose reported top is the other head: its head shows as a top of its own only with
 * the camera's learnt rate of hidden heads shown (p_hidden_k, from MVT_BODY_P_SHOWN_HIDDEN;
 * mvt_body_shown). Whether two silhouettes touch is a probability (mvt_body_touch: bodies differ in
 * width), so a head whose silhouette just reaches another's is hidden at about even odds, not
 * given up at one pixel. A head outside the picture, or behind the camera, is
 * not reported at all. Where the camera sent its foreground mask and the mask holds nothing near
 * the predicted head, nothing hides the head there (a body in front of it, or one it merged with,
 * would be foreground): it is not hidden, and is reported with p_detect; that it is missed there
 * weighs the camera's rate of empty masks at heads of people there (mvt_body_update.c). A head
 * whose line of sight from the camera passes through a static occluder the rig declares (a shelf,
 * a pillar) is not reported at all.
 */
#include "mvt_body.h"

#include "mvt_mask.h"

#include <math.h>
#include <stddef.h>

/* The bodies that may hide another in camera k: tracked, likely present, their silhouette in front
 * of the camera; with prob non-NULL, each one's probability of existence too. */
static int hiders(const mvt_tracker_t *self, int k, int16_t js[MVT_MAX_TARGETS], mvt_real *prob)
{
    int n = 0;
    for (int j = 0; j < MVT_MAX_TARGETS; j++) {
        if (self->tracks[j].id != 0 && self->tracks[j].exist_lo > MVT_R(0.0) && self->body.axis[k][j][4] > MVT_R(0.0)) {
            if (prob != NULL) {
                prob[n] = mvt_body_prob(self->tracks[j].exist_lo);
            }
            js[n++] = (int16_t)j;
        }
    }
    return n;
}

static mvt_real shown_among(const mvt_tracker_t *self, int k, const mvt_real axis[MVT_BODY_AXIS_N], int self_t,
                            const int16_t js[], const mvt_real *prob, int n)
{
    /* the others whose head is higher in the picture, listed first without a branch per body (their
     * order is the data's, a branch the processor would mispredict about every other time) */
    int16_t above[MVT_MAX_TARGETS];
    int m = 0;
    for (int i = 0; i < n; i++) {
        above[m] = (int16_t)i;
        m += (js[i] != self_t) & (self->body.axis[k][js[i]][1] <= axis[1]);
    }
    mvt_real shown = MVT_R(1.0);
    for (int q = 0; q < m; q++) {
        const int i = above[q];
        const int j = js[i];
        const mvt_real *aj = self->body.axis[k][j];
        const mvt_real touch = mvt_body_touch(aj, axis);
        if (touch > MVT_R(0.0)) {
            const mvt_real r = prob != NULL ? prob[i] : mvt_body_prob(self->tracks[j].exist_lo);
            shown *= MVT_R(1.0) - touch * r * (MVT_R(1.0) - self->p_hidden_k[k]);
        }
    }
    return shown;
}

mvt_real mvt_body_shown(const mvt_tracker_t *self, int k, const mvt_real axis[MVT_BODY_AXIS_N], int self_t)
{
    int16_t js[MVT_MAX_TARGETS];
    const int n = hiders(self, k, js, NULL);
    return shown_among(self, k, axis, self_t, js, NULL, n);
}

int mvt_body_occluded(const mvt_tracker_t *self, const mvt_real o[3], const mvt_real dir[3], mvt_real s_max)
{
    const mvt_volume_t *v = &self->cfg.volume;
    for (int b = 0; b < v->num_occluders; b++) {
        /* slabs: the interval of s inside the box on every axis */
        mvt_real s0 = MVT_R(0.0), s1 = s_max;
        for (int i = 0; i < 3 && s0 < s1; i++) {
            const mvt_real lo = v->occluder_min[b][i], hi = v->occluder_max[b][i];
            if (MVT_FABS(dir[i]) < MVT_R(1e-12)) {
                if (o[i] < lo || o[i] > hi) {
                    s1 = MVT_R(-1.0);
                }
                continue;
            }
            mvt_real a = (lo - o[i]) / dir[i], c = (hi - o[i]) / dir[i];
            if (a > c) {
                const mvt_real tmp = a;
                a = c;
                c = tmp;
            }
            s0 = a > s0 ? a : s0;
            s1 = c < s1 ? c : s1;
        }
        if (s0 < s1) {
            return 1;
        }
    }
    return 0;
}

int mvt_body_behind_occluder(const mvt_tracker_t *self, const mvt_camera_t *cam, const mvt_real x[3])
{
    const mvt_real d[3] = {x[0] - cam->centre[0], x[1] - cam->centre[1], x[2] - cam->centre[2]};
    return mvt_body_occluded(self, cam->centre, d, MVT_R(1.0));
}

int mvt_body_head_on_background(const mvt_tracker_t *self, const mvt_view_t *view, int k, const mvt_pkf_pred_t *p)
{
    if (view->mask == NULL || view->mask->width < 1 || !(p->depth_m > MVT_R(0.0))) {
        return 0;
    }
    const mvt_camera_t *cam = &self->cams[k];
    const mvt_real s2 = p->hph[0] > p->hph[2] ? p->hph[0] : p->hph[2];
    const mvt_real r = MVT_R(3.0) * cam->sigma_px + MVT_R(2.0) * MVT_SQRT(s2) +
                       cam->fx * MVT_TRK_HEAD_HALFWIDTH_M / p->depth_m;
    return !mvt_mask_fg_near(view->mask, p->h, r);
}

void mvt_body_visibility(mvt_tracker_t *self, const mvt_view_t *view, int k)
{
    if (!(self->p_detect_k[k] > MVT_R(0.0))) {
        self->p_detect_k[k] = self->cfg.population.p_detect;
    }
    if (!(self->p_hidden_k[k] > MVT_R(0.0))) {
        self->p_hidden_k[k] = MVT_BODY_P_SHOWN_HIDDEN; /* the prior */
    }
    if (!(self->p_bg_k[k] > MVT_R(0.0))) {
        self->p_bg_k[k] = MVT_BODY_P_BG; /* the prior */
    }
    const mvt_camera_t *cam = &self->cams[k];
    mvt_body_ws_t *ws = &self->body;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        mvt_track_t *tr = &self->tracks[t];
        mvt_real *sil = ws->sil[k][t];
        mvt_real *axis = ws->axis[k][t];
        ws->pd[t] = MVT_R(0.0);
        self->pred_ok[t] = 0;
        sil[0] = MVT_R(1.0);
        sil[2] = MVT_R(0.0);
        axis[4] = MVT_R(-1.0);
        if (tr->id == 0 || tr->dormant) {
            continue;
        }
        if (mvt_pkf_predict_obs(&tr->s, cam, self->cfg.lin, &self->pred[t]) != MVT_OK) {
            self->counters.behind_camera++;
            continue;
        }
        /* the Jacobian form's prediction is the head's raw projection */
        const int given = self->pred[t].lin == MVT_PKF_JACOBIAN;
        if (given) {
            ws->head[t][0] = self->pred[t].h[0];
            ws->head[t][1] = self->pred[t].h[1];
        }
        mvt_real foot[2];
        if (!mvt_body_silhouette(self, cam, tr->s.x, sil, ws->head[t], given, foot) ||
            !mvt_body_axis_at(self, cam, tr->s.x, ws->head[t], foot, axis)) {
            sil[0] = MVT_R(1.0);
            sil[2] = MVT_R(0.0);
            axis[4] = MVT_R(-1.0);
            continue;
        }
        self->pred_ok[t] = 1;
        const mvt_real *h = ws->head[t];
        if (mvt_body_in_picture(cam, h) && !mvt_body_behind_occluder(self, cam, tr->s.x)) {
            ws->pd[t] = self->p_detect_k[k];
        }
    }
    int16_t js[MVT_MAX_TARGETS];
    mvt_real prob[MVT_MAX_TARGETS];
    const int n = hiders(self, k, js, prob);
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        ws->on_bg[t] = (uint8_t)(ws->pd[t] > MVT_R(0.0) && mvt_body_head_on_background(self, view, k, &self->pred[t]));
        if (ws->pd[t] > MVT_R(0.0) && !ws->on_bg[t]) {
            ws->pd[t] *= shown_among(self, k, ws->axis[k][t], t, js, prob, n);
        }
    }
}
