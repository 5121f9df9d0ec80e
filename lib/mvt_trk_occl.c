/*
 * mvt_trk_occl.c - occlusion hypotheses of the tracker loop (after association, per camera).
 *
 * A detector that reports the top of each foreground region says nothing about a person whose
 * silhouette merged with a taller or nearer one: that person is not missed, they are hidden in
 * the other's blob. Without this step such a track coasts on its last velocity with a growing
 * covariance and is deleted after coast_max_s, although every camera that cannot see it shows
 * exactly where it may be: inside the blob's box.
 *
 * First, where camera k sent its foreground mask, a confirmed track it did not update may still be
 * seen there: a merged blob reports the top of the whole region, and a lower head that stands out
 * of the merged outline in its own column is in no detection. Such a top, nobody else's and in the
 * track's gate, is the track's measurement in that view (mask_top; docs/tracking.md, "A head that
 * stands out of a merged blob").
 *
 * Otherwise every blob of camera k that another track took (or that was withheld as a merged
 * pair's) and whose box holds the track's predicted head is a hypothesis "hidden in this blob".
 * Where camera k sent its foreground mask, the mask must also hold something near the predicted
 * head: a hidden head is foreground (merged into another's silhouette, or behind a body), and the
 * background a box spans beside and between its people hides nobody (docs/tracking.md, "Hidden
 * people"). The head then lies in the box's column band, at least body.halfwidth_m
 * (seen at the track's depth) inside the side edges, widened by the detection's pixel sigma. The
 * likeliest blob under a uniform position in the band (the prior mass of the band over its width)
 * constrains the track: its predicted column is
 * truncated to the band (mvt_cv_truncate, on the ground position: see below). A truncation moves
 * a prior that sits inside a wide band only a little, and a hidden person's prior usually does:
 * the update does not drag the track onto the blob's centre (which a Gaussian pseudo-measurement
 * at the centre would do, merging the hidden person into the visible one), it only keeps the
 * track from drifting out of the band, which bounds its covariance while it is hidden.
 *
 * The view then counts toward keeping the track alive (mvt_trk_delete: seen views plus occluded
 * views >= seen_min_views). It never counts as a hit toward confirmation, and a blob without a box
 * (all zero) explains nothing.
 *
 * Whether the blob needs the hidden person (extent_llr): a blob's box is the union of its people's
 * silhouettes, so a person hidden beside or in front of the one whose top it reports widens or
 * lowers it, and one right behind leaves no trace. The log-likelihood ratio of the box's edges,
 * with the track's predicted silhouette against without it, accumulates in need_llr (forgotten
 * over MVT_TRK_NEED_MEMORY_S); while it is positive the track's hidden life is renewed, and a track
 * nothing has needed or seen for occluded_max_s is deleted. Before, hidden life ended
 * occluded_max_s after the last frame seen, whatever the boxes said: four people queued for 20 s
 * along two cameras' axes lost two of them (random rig 12, docs/tracking.md).
 *
 * A place that nothing holds (no blob another track took, and nothing near the head at all) speaks
 * against the track (mvt_trk_delete, mvt_trk_existence). "Nothing near" is read from the camera's
 * foreground mask where it sent one, from the blobs' boxes otherwise (place_covered).
 */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "mvt_mask.h"
#include "mvt_trk.h"

/* A band holding less of the track's prior than this says the track is not hidden there. On 8
 * crowd seeds (before the contradiction step and the simulator fix) mean MOTA was 0.974 with 0.1,
 * 0.972 with 0.3, 0.970 with "the prediction within 3 sigma of the band". */
#define OCCL_MIN_MASS MVT_R(0.1)

int mvt_trk_box_ok(const mvt_real b[4])
{
    return isfinite(b[0]) && isfinite(b[1]) && isfinite(b[2]) && isfinite(b[3]) && b[2] > b[0] && b[3] > b[1];
}

int mvt_trk_in_box(const mvt_real b[4], const mvt_real uv[2], mvt_real slack_u, mvt_real slack_v)
{
    return mvt_trk_box_ok(b) && uv[0] >= b[0] - slack_u && uv[0] <= b[2] + slack_u && uv[1] >= b[1] - slack_v &&
           uv[1] <= b[3] + slack_v;
}

int mvt_trk_seen_heads(const mvt_tracker_t *self, int k, mvt_real heads[][4], int16_t who[])
{
    const mvt_camera_t *cam = &self->cams[k];
    int n = 0;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        const mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0 || !self->pred_ok[t] || tr->status == MVT_TRACK_TENTATIVE) {
            continue;
        }
        const mvt_pkf_pred_t *p = &self->pred[t];
        mvt_real *h = heads[n];
        h[0] = p->h[0];
        h[1] = p->h[1];
        if (p->lin != MVT_PKF_JACOBIAN && mvt_cam_project(cam, tr->s.x, h, NULL) != MVT_OK) {
            continue;
        }
        h[2] = MVT_R(3.0) * MVT_SQRT(p->hph[0] + cam->sigma_px * cam->sigma_px);
        h[3] = MVT_R(3.0) * MVT_SQRT(p->hph[2] + cam->sigma_px * cam->sigma_px);
        who[n++] = (int16_t)t;
    }
    return n;
}

/* Did view k send its foreground mask? */
static int has_mask(const mvt_view_t *view)
{
    return view->mask != NULL && view->mask->width > 0;
}

/* Does anything in view k hold the image point uv (slack_px either way)? Where the camera sent its
 * foreground mask, the mask's pixels answer: a blob's box is a rectangle, and a merged or shadowed
 * blob's box holds much background beside and between the people in it, where a ghost (two views'
 * fragments meeting) or a track drifted off its person would find cover. Without a mask, any
 * blob's box. */
static int place_covered(const mvt_tracker_t *self, const mvt_view_t *view, int k, const mvt_real uv[2],
                         mvt_real slack_px)
{
    if (has_mask(view)) {
        return mvt_mask_fg_near(view->mask, uv, slack_px);
    }
    for (int d = 0; d < self->num_meas[k]; d++) {
        if (mvt_trk_in_box(view->det[d].box, uv, slack_px, slack_px)) {
            return 1;
        }
    }
    return 0;
}

mvt_trk_evidence_t mvt_trk_view_evidence(const mvt_tracker_t *self, const mvt_view_t *view, int k,
                                         const mvt_real x[3], mvt_real slack_px)
{
    const mvt_camera_t *cam = &self->cams[k];
    mvt_real uv[2];
    if (mvt_cam_project(cam, x, uv, NULL) != MVT_OK || !(uv[0] >= slack_px) || !(uv[1] >= slack_px) ||
        !(uv[0] <= (mvt_real)cam->width - slack_px) || !(uv[1] <= (mvt_real)cam->height - slack_px)) {
        return MVT_TRK_NO_INFO; /* out of the picture (or too near its border to say) */
    }
    return place_covered(self, view, k, uv, slack_px) ? MVT_TRK_COVERED : MVT_TRK_EMPTY;
}

mvt_real mvt_trk_birth_radius_px(const mvt_tracker_t *self, int k)
{
    const mvt_tracker_config_t *c = &self->cfg;
    const mvt_real r = c->rules.birth_reproj_sigma * self->cams[k].sigma_px;
    return r > c->rules.birth_min_reproj_px ? r : c->rules.birth_min_reproj_px;
}

static mvt_real clamp_q(mvt_real q)
{
    return q < MVT_R(0.01) ? MVT_R(0.01) : (q > MVT_R(0.95) ? MVT_R(0.95) : q);
}

void mvt_trk_evidence_weights(mvt_tracker_t *self, const mvt_frame_t *frame)
{
    const mvt_real pd = self->cfg.population.p_detect;
    for (int k = 0; k < self->num_cameras; k++) {
        const mvt_view_t *view = &frame->views[k];
        const mvt_camera_t *cam = &self->cams[k];
        const mvt_real area = (mvt_real)cam->width * (mvt_real)cam->height;
        const mvt_real r = mvt_trk_birth_radius_px(self, k);
        int n = 0;
        self->ev_boxes[k] = 0;
        for (int d = 0; d < self->num_meas[k]; d++) {
            n += self->meas_ok[k][d];
            if (view->observed && mvt_trk_box_ok(view->det[d].box)) {
                self->ev_boxes[k] = 1;
            }
        }
        if (view->observed && view->num_offered > self->num_meas[k]) {
            n += view->num_offered - self->num_meas[k]; /* dropped by the caller: clutter all the same */
        }
        const mvt_real q_match = clamp_q(MVT_R(1.0) - MVT_EXP(-(mvt_real)n * MVT_R(3.14159265) * r * r / area));
        /* a person is detected (p_detect) or, missed, matched by clutter anyway; nobody is matched
         * by clutter only. A place looks empty when nothing covers it: with a person there only if
         * they were missed and no clutter covers it either, so that ratio is 1 - p_detect whatever
         * the clutter. (Dividing by the chance that clutter leaves the place free, as a first
         * version did, made an empty place count *for* a person once the boxes covered more of the
         * picture than p_detect.) */
        self->ev_support[k] = MVT_LOG((pd + (MVT_R(1.0) - pd) * q_match) / q_match);
        self->ev_clutter[k] = (mvt_real)(n > 1 ? n : 1) / area;
    }
    self->ev_empty = MVT_LOG(MVT_R(1.0) - pd);
}

mvt_real mvt_trk_density(const mvt_pkf_innov_t *in)
{
    const mvt_real det = in->S[0] * in->S[2] - in->S[1] * in->S[1];
    if (!(det > MVT_R(0.0)) || !(in->S[0] > MVT_R(0.0))) {
        return MVT_R(0.0);
    }
    return MVT_EXP(MVT_R(-0.5) * in->d2) / (MVT_R(6.2831853) * MVT_SQRT(det));
}

mvt_real mvt_trk_detected_llr(const mvt_tracker_t *self, int k, const mvt_pkf_innov_t *in)
{
    const mvt_real pd = self->cfg.population.p_detect;
    return MVT_LOG(MVT_R(1.0) - pd + pd * mvt_trk_density(in) / self->ev_clutter[k]);
}

void mvt_trk_existence(mvt_tracker_t *self, mvt_real dt)
{
    /* the chance that a chain switching at rate 1 / MVT_TRK_EXIST_MEMORY_S each way is in the other
     * state after dt: dt / memory for a frame, 1/2 (all forgotten) after a long gap */
    const mvt_real a = MVT_R(0.5) * (MVT_R(1.0) - MVT_EXP(MVT_R(-2.0) * dt / MVT_TRK_EXIST_MEMORY_S));
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0 || tr->status == MVT_TRACK_TENTATIVE || !(a > MVT_R(0.0))) {
            continue;
        }
        const mvt_real p = MVT_R(1.0) / (MVT_R(1.0) + MVT_EXP(-tr->exist_llr));
        const mvt_real q = p * (MVT_R(1.0) - a) + (MVT_R(1.0) - p) * a; /* in [a, 1 - a] */
        tr->exist_llr = MVT_LOG(q / (MVT_R(1.0) - q));
    }
}

/* The probability that a head predicted at h with standard deviations su, sv (pixels, uncorrelated)
 * lies in camera k's picture. */
static mvt_real in_picture(const mvt_camera_t *cam, const mvt_real h[2], mvt_real su, mvt_real sv)
{
    const mvt_real r2 = MVT_R(0.70710678118654752);
    const mvt_real pu = MVT_R(0.5) * (MVT_ERFC(-h[0] / su * r2) - MVT_ERFC(((mvt_real)cam->width - h[0]) / su * r2));
    const mvt_real pv = MVT_R(0.5) * (MVT_ERFC(-h[1] / sv * r2) - MVT_ERFC(((mvt_real)cam->height - h[1]) / sv * r2));
    return pu * pv;
}

mvt_real mvt_trk_odds(const mvt_tracker_t *self, uint32_t support, int empty)
{
    mvt_real sum = MVT_R(0.0), lo1 = MVT_R(0.0), lo2 = MVT_R(0.0);
    int n = 0;
    for (int k = 0; k < self->num_cameras; k++) {
        if (!(support & (1u << k))) {
            continue;
        }
        const mvt_real w = self->ev_support[k];
        sum += w;
        if (n == 0 || w < lo1) {
            lo2 = lo1;
            lo1 = w;
        } else if (n == 1 || w < lo2) {
            lo2 = w;
        }
        n++;
    }
    sum -= n >= 2 ? lo1 + lo2 : (n == 1 ? lo1 : MVT_R(0.0));
    return sum + (mvt_real)empty * self->ev_empty;
}

/* The slack around a track's predicted head when asking a view whether its place is empty: the
 * detection noise, twice the prediction's spread in the image, 8 px. */
static mvt_real empty_slack(const mvt_camera_t *cam, const mvt_pkf_pred_t *p)
{
    const mvt_real s2 = p->hph[0] > p->hph[2] ? p->hph[0] : p->hph[2];
    return MVT_R(3.0) * cam->sigma_px + MVT_R(2.0) * MVT_SQRT(s2) + MVT_R(8.0);
}

/* How much a silhouette's half width varies about body.halfwidth_m (arms, clothes, pose), m. */
#define OCCL_BODY_SD_M MVT_R(0.05)

/* A person's silhouette in camera k as the tracker predicts it, raw pixels: the column from the
 * head (uv) down to the feet (the ground point below it) widened by body.halfwidth_m at the head's
 * depth. 0 when the feet do not project. */
static int silhouette(const mvt_tracker_t *self, int k, const mvt_real x[3], const mvt_real head[2], mvt_real depth,
                      mvt_real sil[4])
{
    const mvt_camera_t *cam = &self->cams[k];
    const mvt_real ground[3] = {x[0], x[1], MVT_R(0.0)};
    mvt_real foot[2];
    if (mvt_cam_project(cam, ground, foot, NULL) != MVT_OK || !(depth > MVT_R(0.0))) {
        return 0;
    }
    const mvt_real w = cam->fx * self->cfg.body.halfwidth_m / depth;
    sil[0] = (head[0] < foot[0] ? head[0] : foot[0]) - w;
    sil[1] = head[1];
    sil[2] = (head[0] > foot[0] ? head[0] : foot[0]) + w;
    sil[3] = foot[1];
    return 1;
}

/* ln of the likelihood ratio of box edge e, Gaussian about a (with the track's person) or about b
 * (without), variance s2. */
static mvt_real edge_llr(mvt_real e, mvt_real a, mvt_real b, mvt_real s2)
{
    return MVT_R(0.5) * ((e - b) * (e - b) - (e - a) * (e - a)) / s2;
}

/* The seen tracks of camera k that a hidden track's blob may hold, once per camera: their predicted
 * heads (mvt_trk_seen_heads) and silhouettes (ok[i] = 0 where the feet do not project). */
typedef struct occl_others {
    int n; /* -1: not gathered yet */
    mvt_real heads[MVT_MAX_TARGETS][4];
    int16_t who[MVT_MAX_TARGETS];
    mvt_real sil[MVT_MAX_TARGETS][4];
    uint8_t ok[MVT_MAX_TARGETS];
} occl_others_t;

static void gather_others(const mvt_tracker_t *self, int k, occl_others_t *o)
{
    o->n = mvt_trk_seen_heads(self, k, o->heads, o->who);
    for (int i = 0; i < o->n; i++) {
        const int u = o->who[i];
        o->ok[i] = (uint8_t)silhouette(self, k, self->tracks[u].s.x, o->heads[i], self->pred[u].depth_m, o->sil[i]);
    }
}

/* Does blob d's box need hidden track t? The box is the union of the silhouettes of the people in
 * the blob. Its left, right and bottom edges are predicted from the other seen tracks whose heads
 * the box holds (o), with and without t's silhouette (sil_t), each edge with the detection's noise,
 * OCCL_BODY_SD_M at the depth and the prediction's spread. Returns the log-likelihood ratio of the
 * three edges, t in the blob against t absent: > 0 when the box reaches out where only t's body
 * would put it (a person hidden beside or in front of the one whose top the blob reports), < 0 when
 * t's body would stick out of it (a phantom nearer the camera than the person it hides behind), 0
 * when the others fill t's silhouette either way (a person right behind another: no information).
 * Edges at the picture's border, where the box is cut, say nothing. */
static mvt_real extent_llr(const mvt_tracker_t *self, const mvt_view_t *view, int k, int t, int d,
                           const mvt_pkf_pred_t *p, const occl_others_t *o)
{
    const mvt_camera_t *cam = &self->cams[k];
    const mvt_real *b = view->det[d].box;
    mvt_real sil_t[4], all[4] = {MVT_R(0.0), MVT_R(0.0), MVT_R(0.0), MVT_R(0.0)};
    if (!silhouette(self, k, self->tracks[t].s.x, p->h, p->depth_m, sil_t)) {
        return MVT_R(0.0);
    }
    int n = 0;
    for (int i = 0; i < o->n; i++) {
        const mvt_real *h = o->heads[i], *sil = o->sil[i];
        if (o->who[i] == t || !o->ok[i] || !mvt_trk_in_box(b, h, h[2], h[3])) {
            continue;
        }
        if (n++ == 0) {
            memcpy(all, sil, sizeof(all));
        } else {
            all[0] = sil[0] < all[0] ? sil[0] : all[0];
            all[2] = sil[2] > all[2] ? sil[2] : all[2];
            all[3] = sil[3] > all[3] ? sil[3] : all[3];
        }
    }
    if (n == 0) {
        return MVT_R(0.0); /* nobody else seen in it: the hypothesis "hidden here" is weak anyway */
    }
    const mvt_real wsd = cam->fx * OCCL_BODY_SD_M / p->depth_m;
    const mvt_real s2u = self->meas[k][d].var_px2 + wsd * wsd + p->hph[0];
    const mvt_real s2v = self->meas[k][d].var_px2 + p->hph[2];
    const mvt_real edge = MVT_R(2.0); /* px: a box edge this near the border is the picture's */
    mvt_real llr = MVT_R(0.0);
    if (b[0] > edge && sil_t[0] < all[0]) {
        llr += edge_llr(b[0], sil_t[0], all[0], s2u);
    }
    if (b[2] < (mvt_real)cam->width - edge && sil_t[2] > all[2]) {
        llr += edge_llr(b[2], sil_t[2], all[2], s2u);
    }
    if (b[3] < (mvt_real)cam->height - edge && sil_t[3] > all[3]) {
        llr += edge_llr(b[3], sil_t[3], all[3], s2v);
    }
    return llr;
}

/* A confirmed track that camera k did not update, with a foreground mask from that camera: is its
 * head a top of the silhouette in its own column? A blob's reported point is the top of the whole
 * region, so where two people's silhouettes merged the lower head is in no detection although
 * it may stand out of the outline in its own column; the track then gets that top as its
 * measurement (top_meas, top_ok), as from a detection of its own. The top must be no detection's
 * and nobody else's: not within 3 sigma of any blob's reported top (association has decided that
 * detection: given to a track, withheld as a merged pair's, or outside every gate), not inside
 * or on top of another confirmed track's predicted silhouette (where the outline may be their
 * head or body), and inside the track's chi-square gate (MVT_TRK_TOP_GATE_CHI2). Returns 1 when found. */
static int mask_top(mvt_tracker_t *self, const mvt_view_t *view, int k, int t, const mvt_pkf_pred_t *p,
                    occl_others_t *o)
{
    const mvt_camera_t *cam = &self->cams[k];
    const mvt_real s = (mvt_real)view->mask->scale;
    const mvt_real sig2 = cam->sigma_px * cam->sigma_px + s * s; /* the detector's noise and a mask pixel */
    const mvt_real sig = MVT_SQRT(sig2);
    const mvt_real su = MVT_SQRT(p->hph[0] + sig2), sv = MVT_SQRT(p->hph[2] + sig2);
    const mvt_real head_px = cam->fx * MVT_TRK_HEAD_HALFWIDTH_M / p->depth_m;
    mvt_real uv[2];
    if (!mvt_mask_top_in_band(view->mask, p->h[0], head_px + su, p->h[1] - MVT_R(3.0) * sv, p->h[1] + MVT_R(3.0) * sv,
                              cam->fx * MVT_TRK_TOP_MAX_WIDTH_M / p->depth_m + MVT_R(2.0) * s,
                              cam->fx * MVT_TRK_TOP_CLEAR_M / p->depth_m, uv)) {
        return 0;
    }
    for (int d = 0; d < self->num_meas[k]; d++) {
        const mvt_real du = uv[0] - view->det[d].u, dv = uv[1] - view->det[d].v;
        const mvt_real var = self->meas_ok[k][d] ? self->meas[k][d].var_px2 : sig2; /* undistort failed */
        if (du * du + dv * dv < MVT_R(9.0) * (sig2 + var)) {
            return 0; /* a blob's reported top: association had its say (taken, withheld, gated out) */
        }
    }
    if (o->n < 0) {
        gather_others(self, k, o);
    }
    for (int i = 0; i < o->n; i++) {
        const mvt_real *sil = o->sil[i];
        if (o->who[i] == t || !o->ok[i]) {
            continue;
        }
        /* slack: our sd across, three of their head's sd and ours up and down */
        if (mvt_trk_in_box(sil, uv, sig, o->heads[i][3] + sig)) {
            return 0;
        }
    }
    mvt_pkf_meas_t *m = &self->top_meas[t];
    mvt_pkf_innov_t in;
    if (mvt_pkf_meas_make(cam, uv, sig, m) != MVT_OK ||
        mvt_pkf_innovation_from(&self->pred[t], m, NULL, &in) != MVT_OK || !(in.d2 <= MVT_TRK_TOP_GATE_CHI2)) {
        return 0;
    }
    self->top_ok[t] = 1;
    return 1;
}

void mvt_trk_occlusion(mvt_tracker_t *self, const mvt_view_t *view, int k, const int assign[MVT_MAX_TARGETS])
{
    const mvt_tracker_config_t *c = &self->cfg;
    const mvt_camera_t *cam = &self->cams[k];
    const int nd = self->num_meas[k];
    if (!self->ev_boxes[k]) {
        return; /* a view without boxes can neither hide nor contradict */
    }
    occl_others_t others;
    others.n = -1;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0 || assign[t] >= 0 || !self->pred_ok[t]) {
            continue;
        }
        if (tr->status == MVT_TRACK_TENTATIVE) {
            /* not established, so not hidden either: a view that shows its place in no blob at all
             * speaks against it (mvt_trk_delete weighs that against the views that saw it) */
            if (mvt_trk_view_evidence(self, view, k, tr->s.x, empty_slack(cam, &self->pred[t])) == MVT_TRK_EMPTY) {
                tr->cameras_empty |= 1u << k;
            }
            continue;
        }
        /* the boxes are in raw pixels: the Jacobian prediction (the tracker's own when it uses it) */
        mvt_pkf_pred_t raw;
        const mvt_pkf_pred_t *p = &self->pred[t];
        if (p->lin != MVT_PKF_JACOBIAN) {
            if (mvt_pkf_predict_obs(&tr->s, cam, MVT_PKF_JACOBIAN, &raw) != MVT_OK) {
                continue;
            }
            p = &raw;
        }
        const mvt_real su = MVT_SQRT(p->hph[0]), sv = MVT_SQRT(p->hph[2]);
        const mvt_real half_px = cam->fx * c->body.halfwidth_m / p->depth_m;
        /* a person hidden in a blob has foreground at their head's place (their own head, merged
         * into another's silhouette, or the body in front of it): where the view sent its mask, a
         * box's background is no hiding place. The same answer says below whether the place is
         * covered at all. */
        const mvt_real slack = empty_slack(cam, p);
        const int masked = has_mask(view);
        const int fg_near = masked && mvt_mask_fg_near(view->mask, p->h, slack);
        const int hideable = !masked || fg_near;
        if (fg_near && tr->s.x[2] >= MVT_TRK_MIN_HEAD_M && mask_top(self, view, k, t, p, &others)) {
            continue; /* seen in its own column: updated with the detections (mvt_tracker.c) */
        }
        int best = -1;
        mvt_real best_lik = MVT_R(0.0), best_lo = MVT_R(0.0), best_hi = MVT_R(0.0);
        for (int d = 0; d < nd && hideable; d++) {
            const mvt_real *b = view->det[d].box;
            if (!self->used[k][d] || !mvt_trk_box_ok(b)) {
                continue;
            }
            const mvt_real sig = MVT_SQRT(self->meas[k][d].var_px2);
            /* the head lies between the box's top and bottom (3 sigma of slack) ... */
            const mvt_real slack_v = MVT_R(3.0) * MVT_SQRT(sv * sv + sig * sig);
            if (!(p->h[1] >= b[1] - slack_v) || !(p->h[1] <= b[3] + slack_v)) {
                continue;
            }
            /* ... and in the column band half a body inside the side edges */
            mvt_real lo = b[0] + half_px - sig, hi = b[2] - half_px + sig;
            if (!(hi - lo >= MVT_R(2.0) * sig)) { /* a blob narrower than a body: its middle */
                const mvt_real mid = MVT_R(0.5) * (b[0] + b[2]);
                lo = mid - sig;
                hi = mid + sig;
            }
            /* the band must agree with the track: a prior mostly outside it says the track is not
             * hidden there */
            const mvt_real r2 = MVT_R(0.70710678118654752);
            const mvt_real mass = MVT_R(0.5) * (MVT_ERFC((lo - p->h[0]) / su * r2) - MVT_ERFC((hi - p->h[0]) / su * r2));
            if (!(mass >= OCCL_MIN_MASS)) {
                continue;
            }
            const mvt_real lik = mass / (hi - lo);
            if (best < 0 || lik > best_lik) {
                best = d;
                best_lik = lik;
                best_lo = lo;
                best_hi = hi;
            }
        }
        if (best < 0) {
            /* not seen, not hidden: is anything at all near the head? */
            const int covered = masked ? fg_near : place_covered(self, view, k, p->h, slack);
            /* existence (mvt_trk_existence): with none, the person was missed, if in the picture */
            if (!covered && su > MVT_R(0.0) && sv > MVT_R(0.0)) {
                self->ev_llr[t] += MVT_LOG(MVT_R(1.0) - c->population.p_detect * in_picture(cam, p->h, su, sv));
            }
            /* in the picture, not seen and not hidden in a blob another track took: this view
             * contradicts the track (unless the detector missed the whole blob) */
            const mvt_real m = MVT_R(2.0) * sv + MVT_R(2.0) * su + MVT_R(8.0);
            if (p->h[0] >= m && p->h[0] <= (mvt_real)cam->width - m && p->h[1] >= m &&
                p->h[1] <= (mvt_real)cam->height - m) {
                tr->cameras_uncovered |= 1u << k;
                if (fg_near) {
                    tr->cameras_fg |= 1u << k; /* foreground there: weaker than background */
                }
                /* ... and if no blob at all holds the place (not too near the border to say, as
                 * mvt_trk_view_evidence), it shows the place empty */
                if (!covered && p->h[0] >= slack && p->h[1] >= slack && p->h[0] <= (mvt_real)cam->width - slack &&
                    p->h[1] <= (mvt_real)cam->height - slack) {
                    tr->cameras_empty |= 1u << k;
                }
            }
            continue;
        }
        /* the band holds the body's axis, not the head point: the constraint acts on the ground
         * position (the column's dependence on the unseen head height is dropped), so a hidden
         * track's height stays what the views last measured */
        const mvt_real Hg[3] = {p->H[0], p->H[1], MVT_R(0.0)};
        const mvt_err_t err = mvt_trk_truncate_ground(self, tr, Hg, p->h[0], MVT_R(0.0), best_lo, best_hi);
        if (err == MVT_OK) {
            tr->cameras_occluded |= 1u << k;
            self->counters.occluded_updates++;
            if (others.n < 0) {
                gather_others(self, k, &others);
            }
            tr->need_llr += extent_llr(self, view, k, t, best, p, &others);
        } else if (err != MVT_ERR_NUMERIC) {
            self->counters.numeric_faults++;
        }
    }
}

/* n^T P n over the position block, n horizontal */
static mvt_real horiz_var(const mvt_cv_state_t *s, const mvt_real n[3])
{
    const mvt_real *P = s->P;
    return n[0] * n[0] * P[0] + MVT_R(2.0) * n[0] * n[1] * P[1] + n[1] * n[1] * P[7];
}

void mvt_trk_exclusion(mvt_tracker_t *self)
{
    const mvt_tracker_config_t *c = &self->cfg;
    const int min_views = mvt_trk_min_views(self);
    for (int a = 0; a < MVT_MAX_TARGETS; a++) {
        mvt_track_t *ta = &self->tracks[a];
        if (ta->id == 0 || ta->status == MVT_TRACK_TENTATIVE) {
            continue;
        }
        for (int b = a + 1; b < MVT_MAX_TARGETS; b++) {
            mvt_track_t *tb = &self->tracks[b];
            if (tb->id == 0 || tb->status == MVT_TRACK_TENTATIVE) {
                continue;
            }
            const int poor_a = mvt_trk_popcount(ta->cameras_used) < min_views;
            const int poor_b = mvt_trk_popcount(tb->cameras_used) < min_views;
            if (!poor_a && !poor_b) {
                continue; /* both well seen: their measurements decide */
            }
            const mvt_real dx = ta->s.x[0] - tb->s.x[0], dy = ta->s.x[1] - tb->s.x[1];
            const mvt_real d = MVT_SQRT(dx * dx + dy * dy);
            if (!(d < c->rules.exclusion_m) || !(d > MVT_R(1e-6))) {
                continue; /* far enough, or on top of each other: no direction to push along */
            }
            /* n . (x_a - x_b) >= exclusion_m, n the unit horizontal separation; each poorly seen
             * track takes its share of the joint truncation (the other's variance as extra) */
            const mvt_real n[3] = {dx / d, dy / d, MVT_R(0.0)};
            const mvt_real m[3] = {-n[0], -n[1], MVT_R(0.0)};
            const mvt_real na = n[0] * ta->s.x[0] + n[1] * ta->s.x[1];
            const mvt_real nb = n[0] * tb->s.x[0] + n[1] * tb->s.x[1];
            const mvt_real va = horiz_var(&ta->s, n), vb = horiz_var(&tb->s, n);
            mvt_err_t err = MVT_OK;
            if (poor_a) {
                err = mvt_trk_truncate_ground(self, ta, n, na, vb, nb + c->rules.exclusion_m, nb + c->rules.exclusion_m + MVT_R(1e3));
                self->counters.exclusion_updates += err == MVT_OK;
            }
            if (poor_b && err != MVT_ERR_INVALID) {
                err = mvt_trk_truncate_ground(self, tb, m, -nb, va, -na + c->rules.exclusion_m, -na + c->rules.exclusion_m + MVT_R(1e3));
                self->counters.exclusion_updates += err == MVT_OK;
            }
            if (err != MVT_OK && err != MVT_ERR_NUMERIC) {
                self->counters.numeric_faults++;
            }
        }
    }
}

/* A head's height is what a camera that sees a person alone along its ray cannot tell: a track
 * updated by one view (a ceiling camera over a group that hides the person from the others) moves
 * along that ray, and its height follows the cross-covariance the ray leaves. The person's head,
 * though, stays within a few centimetres of its height while they walk or stand (the cue that
 * re-acquisition and recovery compare, MVT_TRK_HEAD_SD_M). So until two views place the track
 * again, its height is truncated to that band around the height they last placed it at (PDF
 * truncation, mvt_cv_truncate: a height inside the band is left as it is, one outside is brought
 * to its edge with the position following through the covariance). Without it, a short person
 * hidden in a group for 3 s sank to 0.3 m under the ceiling camera (tests/test_multi.c,
 * hidden_in_group) and a track whose update was weakened by a merged blob's top went below the
 * floor. A person sitting down while nobody places them is held up until two views do. */
void mvt_trk_hold_height(mvt_tracker_t *self)
{
    const int min_views = mvt_trk_min_views(self);
    static const mvt_real Hz[3] = {MVT_R(0.0), MVT_R(0.0), MVT_R(1.0)};
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0 || tr->status == MVT_TRACK_TENTATIVE || mvt_trk_popcount(tr->cameras_used) >= min_views) {
            continue;
        }
        const mvt_real w = MVT_TRK_HEIGHT_BAND * MVT_SQRT(tr->seen_zz + MVT_TRK_HEAD_SD_M * MVT_TRK_HEAD_SD_M);
        const mvt_err_t err = mvt_trk_truncate(self, tr, Hz, tr->s.x[2], tr->seen_z - w, tr->seen_z + w);
        if (err != MVT_OK && err != MVT_ERR_NUMERIC) {
            self->counters.numeric_faults++;
        }
    }
}
