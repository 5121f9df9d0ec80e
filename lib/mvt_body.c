/*
 * mvt_body.c - one model of a person: a frame's steps in order (mvt_body.h), and the body's
 * geometry that they share (silhouette, feet).
 */
#include "mvt_body.h"

#include <math.h>
#include <string.h>

mvt_real mvt_body_logit(mvt_real p)
{
    return MVT_LOG(p / (MVT_R(1.0) - p));
}

void mvt_body_height_start(mvt_track_t *tr, mvt_real z, mvt_real zz)
{
    tr->seen_z = z;
    tr->seen_zz = zz;
    tr->z_mean = z;
    tr->z_var = MVT_R(0.0);
}

mvt_real mvt_body_prob(mvt_real lo)
{
    return MVT_R(1.0) / (MVT_R(1.0) + MVT_EXP(-lo));
}

int mvt_body_silhouette(const mvt_tracker_t *self, const mvt_camera_t *cam, const mvt_real x[3], mvt_real box[4],
                        mvt_real head[2], int head_given, mvt_real foot[2])
{
    if (!head_given && mvt_cam_project(cam, x, head, NULL) != MVT_OK) {
        return 0;
    }
    /* the body's half width across the line of sight, horizontally */
    mvt_real side[2] = {-(x[1] - cam->centre[1]), x[0] - cam->centre[0]};
    const mvt_real n = MVT_SQRT(side[0] * side[0] + side[1] * side[1]);
    const mvt_real w = self->cfg.body.halfwidth_m;
    if (n > MVT_R(1e-6)) {
        side[0] *= w / n;
        side[1] *= w / n;
    } else {
        side[0] = w;
        side[1] = MVT_R(0.0);
    }
    box[0] = box[2] = head[0];
    box[1] = box[3] = head[1];
    if (foot != NULL) {
        foot[0] = head[0]; /* a camera looking down steeply past the feet: the head alone */
        foot[1] = head[1];
    }
    for (int i = 1; i < 6; i++) { /* i = 0, the head's centre, is `head`; i = 3 the floor under it */
        const mvt_real s = (i % 3 == 0) ? MVT_R(0.0) : (i % 3 == 1 ? MVT_R(1.0) : MVT_R(-1.0));
        const mvt_real p[3] = {i == 3 ? x[0] : x[0] + s * side[0], i == 3 ? x[1] : x[1] + s * side[1],
                               i < 3 ? x[2] : MVT_R(0.0)};
        mvt_real uv[2];
        if (mvt_cam_project(cam, p, uv, NULL) != MVT_OK) {
            continue; /* feet behind a camera that looks down steeply: the head's edges bound it */
        }
        if (i == 3 && foot != NULL) {
            foot[0] = uv[0];
            foot[1] = uv[1];
        }
        box[0] = uv[0] < box[0] ? uv[0] : box[0];
        box[1] = uv[1] < box[1] ? uv[1] : box[1];
        box[2] = uv[0] > box[2] ? uv[0] : box[2];
        box[3] = uv[1] > box[3] ? uv[1] : box[3];
    }
    return 1;
}

int mvt_body_axis(const mvt_tracker_t *self, const mvt_camera_t *cam, const mvt_real x[3], mvt_real axis[MVT_BODY_AXIS_N])
{
    mvt_real head[2];
    return mvt_cam_project(cam, x, head, NULL) == MVT_OK && mvt_body_axis_at(self, cam, x, head, NULL, axis);
}

int mvt_body_axis_at(const mvt_tracker_t *self, const mvt_camera_t *cam, const mvt_real x[3], const mvt_real head[2],
                     const mvt_real foot_uv[2], mvt_real axis[MVT_BODY_AXIS_N])
{
    const mvt_real foot[3] = {x[0], x[1], MVT_R(0.0)};
    const mvt_real mid[3] = {x[0], x[1], MVT_R(0.5) * x[2]};
    mvt_real fuv[2];
    const mvt_real depth = mvt_cam_depth(cam, mid);
    if (!(depth > MVT_R(0.0))) {
        return 0;
    }
    axis[0] = head[0];
    axis[1] = head[1];
    if (foot_uv != NULL) {
        fuv[0] = foot_uv[0];
        fuv[1] = foot_uv[1];
    } else if (mvt_cam_project(cam, foot, fuv, NULL) != MVT_OK) {
        fuv[0] = axis[0]; /* a camera looking down steeply past the feet: the head alone */
        fuv[1] = axis[1];
    }
    axis[2] = fuv[0];
    axis[3] = fuv[1];
    axis[4] = cam->fx * self->cfg.body.halfwidth_m / depth;
    const mvt_real foot_depth = mvt_cam_depth(cam, foot);
    axis[5] = foot_depth > MVT_R(0.0) ? cam->fx * MVT_BODY_SHADOW_M / foot_depth : MVT_R(0.0);
    return 1;
}

/* Squared distance from point p to the segment a-b. */
static mvt_real point_seg_d2(const mvt_real p[2], const mvt_real a[2], const mvt_real b[2])
{
    const mvt_real ab[2] = {b[0] - a[0], b[1] - a[1]};
    const mvt_real len2 = ab[0] * ab[0] + ab[1] * ab[1];
    mvt_real s = len2 > MVT_R(0.0) ? ((p[0] - a[0]) * ab[0] + (p[1] - a[1]) * ab[1]) / len2 : MVT_R(0.0);
    s = s < MVT_R(0.0) ? MVT_R(0.0) : (s > MVT_R(1.0) ? MVT_R(1.0) : s);
    const mvt_real d[2] = {p[0] - a[0] - s * ab[0], p[1] - a[1] - s * ab[1]};
    return d[0] * d[0] + d[1] * d[1];
}

static mvt_real cross2(const mvt_real o[2], const mvt_real a[2], const mvt_real b[2])
{
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}

mvt_real mvt_body_touch(const mvt_real a[MVT_BODY_AXIS_N], const mvt_real b[MVT_BODY_AXIS_N])
{
    const mvt_real w = a[4] + b[4]; /* the mean width: half of each full width */
    const mvt_real sd = MVT_BODY_WIDTH_SD * MVT_SQRT(a[4] * a[4] + b[4] * b[4]);
    const mvt_real reach = w + MVT_R(4.0) * sd; /* beyond it the chance is under 4e-5 */
    const mvt_real *a0 = a, *a1 = a + 2, *b0 = b, *b1 = b + 2;
    /* boxes of the axes, apart by more than the reach: no contact (most pairs) */
    if ((a0[0] < a1[0] ? a0[0] : a1[0]) - reach > (b0[0] > b1[0] ? b0[0] : b1[0]) ||
        (b0[0] < b1[0] ? b0[0] : b1[0]) - reach > (a0[0] > a1[0] ? a0[0] : a1[0]) ||
        (a0[1] < a1[1] ? a0[1] : a1[1]) - reach > (b0[1] > b1[1] ? b0[1] : b1[1]) ||
        (b0[1] < b1[1] ? b0[1] : b1[1]) - reach > (a0[1] > a1[1] ? a0[1] : a1[1])) {
        return MVT_R(0.0);
    }
    /* crossing axes */
    const mvt_real d1 = cross2(a0, a1, b0), d2 = cross2(a0, a1, b1), d3 = cross2(b0, b1, a0), d4 = cross2(b0, b1, a1);
    if (((d1 > MVT_R(0.0) && d2 < MVT_R(0.0)) || (d1 < MVT_R(0.0) && d2 > MVT_R(0.0))) &&
        ((d3 > MVT_R(0.0) && d4 < MVT_R(0.0)) || (d3 < MVT_R(0.0) && d4 > MVT_R(0.0)))) {
        return MVT_R(1.0);
    }
    mvt_real m = point_seg_d2(a0, b0, b1);
    mvt_real e = point_seg_d2(a1, b0, b1);
    m = e < m ? e : m;
    e = point_seg_d2(b0, a0, a1);
    m = e < m ? e : m;
    e = point_seg_d2(b1, a0, a1);
    m = e < m ? e : m;
    if (!(sd > MVT_R(0.0))) {
        return m < w * w ? MVT_R(1.0) : MVT_R(0.0);
    }
    if (m >= reach * reach) {
        return MVT_R(0.0);
    }
    /* P(gap < w) with w ~ N(a4 + b4, sd^2) */
    return MVT_R(0.5) * MVT_ERFC((MVT_SQRT(m) - w) / (sd * MVT_R(1.41421356)));
}

int mvt_body_on_body_below_head(const mvt_real axis[MVT_BODY_AXIS_N], const mvt_real uv[2])
{
    /* along the axis from the head toward the feet (which lie above the head in the picture of a
     * camera that looks down on the body's far side), past the head's share, up to the feet */
    const mvt_real ab[2] = {axis[2] - axis[0], axis[3] - axis[1]};
    const mvt_real len2 = ab[0] * ab[0] + ab[1] * ab[1];
    if (!(len2 > MVT_R(0.0))) {
        return 0;
    }
    const mvt_real len = MVT_SQRT(len2);
    const mvt_real s = ((uv[0] - axis[0]) * ab[0] + (uv[1] - axis[1]) * ab[1]) / len2;
    return s >= MVT_BODY_FRAGMENT_BELOW && s <= MVT_R(1.0) + axis[4] / len &&
           point_seg_d2(uv, axis, axis + 2) <= axis[4] * axis[4];
}

int mvt_body_fragment_of(const mvt_real axis[MVT_BODY_AXIS_N], const mvt_real uv[2])
{
    /* the floor by the feet */
    const mvt_real fu = uv[0] - axis[2], fv = uv[1] - axis[3];
    if (fu * fu + fv * fv <= axis[5] * axis[5]) {
        return 1;
    }
    /* the body: within its half width of the axis' box first (most blobs are far from most bodies) */
    const mvt_real w = axis[4];
    const mvt_real u0 = axis[0] < axis[2] ? axis[0] : axis[2], u1 = axis[0] < axis[2] ? axis[2] : axis[0];
    const mvt_real v0 = axis[1] < axis[3] ? axis[1] : axis[3], v1 = axis[1] < axis[3] ? axis[3] : axis[1];
    if (uv[0] < u0 - w || uv[0] > u1 + w || uv[1] < v0 - w || uv[1] > v1 + w) {
        return 0;
    }
    return mvt_body_on_body_below_head(axis, uv);
}

void mvt_body_fragment_bounds(const mvt_real axis[MVT_BODY_AXIS_N], mvt_real box[4])
{
    const mvt_real w = axis[4], r = axis[5] + MVT_R(1.0); /* the disc's box a pixel wider, for rounding */
    const mvt_real u0 = axis[0] < axis[2] ? axis[0] : axis[2], u1 = axis[0] < axis[2] ? axis[2] : axis[0];
    const mvt_real v0 = axis[1] < axis[3] ? axis[1] : axis[3], v1 = axis[1] < axis[3] ? axis[3] : axis[1];
    box[0] = u0 - w < axis[2] - r ? u0 - w : axis[2] - r;
    box[1] = v0 - w < axis[3] - r ? v0 - w : axis[3] - r;
    box[2] = u1 + w > axis[2] + r ? u1 + w : axis[2] + r;
    box[3] = v1 + w > axis[3] + r ? v1 + w : axis[3] + r;
}

mvt_real mvt_body_silhouette_area(const mvt_real axis[MVT_BODY_AXIS_N])
{
    const mvt_real w = axis[4], r = axis[5];
    const mvt_real len = MVT_SQRT((axis[2] - axis[0]) * (axis[2] - axis[0]) + (axis[3] - axis[1]) * (axis[3] - axis[1]));
    const mvt_real area = MVT_R(2.0) * w * len + MVT_R(3.14159265) * (w * w + r * r);
    return area > MVT_R(1.0) ? area : MVT_R(1.0);
}

int mvt_body_fragment_possible(const mvt_tracker_t *self, int k, int t)
{
    const mvt_track_t *tr = &self->tracks[t];
    return tr->id != 0 && !tr->dormant && tr->exist_lo > MVT_R(0.0) && self->body.axis[k][t][4] > MVT_R(0.0);
}

mvt_real mvt_body_fragment_scale(const mvt_tracker_t *self, int k, int t)
{
    if (!mvt_body_fragment_possible(self, k, t)) {
        return MVT_R(0.0);
    }
    return mvt_body_prob(self->tracks[t].exist_lo) * self->frag_n[k] / mvt_body_silhouette_area(self->body.axis[k][t]);
}

mvt_real mvt_body_fragment_density(const mvt_tracker_t *self, int k, int t, const mvt_real uv[2])
{
    return mvt_body_fragment_of(self->body.axis[k][t], uv) ? mvt_body_fragment_scale(self, k, t) : MVT_R(0.0);
}

int mvt_body_on_silhouette(const mvt_real axis[MVT_BODY_AXIS_N], const mvt_real uv[2], mvt_real slack_px)
{
    const mvt_real w = axis[4] + slack_px;
    return point_seg_d2(uv, axis, axis + 2) <= w * w;
}

int mvt_body_gated(const mvt_tracker_t *self, int t, int k, int d, const mvt_pkf_innov_t *in)
{
    const mvt_tracker_config_t *c = &self->cfg;
    if (c->gate == MVT_GATE_PAPER) {
        mvt_real dist;
        return mvt_pkf_paper_distance(&self->tracks[t].s, &self->cams[k], c->paper.var_m2, c->paper.gamma,
                                      &self->meas[k][d], &dist) == MVT_OK &&
               dist <= c->paper.delta;
    }
    return in->d2 <= c->numerics.gate_chi2;
}

mvt_real mvt_body_head_density(const mvt_tracker_t *self, const mvt_pkf_innov_t *in, int gated)
{
    const mvt_imm_config_t *m = &self->cfg.motion;
    const mvt_real r = m->outlier_radius_px;
    const mvt_real y2 = in->y[0] * in->y[0] + in->y[1] * in->y[1];
    const mvt_real displaced = y2 <= r * r ? m->p_outlier / (MVT_R(3.14159265) * r * r) : MVT_R(0.0);
    const mvt_real own = gated ? mvt_trk_density(in) : MVT_R(0.0);
    return (MVT_R(1.0) - m->p_outlier) * own + displaced;
}

int mvt_body_near_side_wall(const mvt_tracker_config_t *c, const mvt_real x[3])
{
    return x[0] < c->volume.min[0] + c->volume.exit_margin_m || x[0] > c->volume.max[0] - c->volume.exit_margin_m ||
           x[1] < c->volume.min[1] + c->volume.exit_margin_m || x[1] > c->volume.max[1] - c->volume.exit_margin_m;
}

int mvt_body_in_picture(const mvt_camera_t *cam, const mvt_real uv[2])
{
    return uv[0] >= MVT_R(0.0) && uv[1] >= MVT_R(0.0) && uv[0] <= (mvt_real)cam->width - MVT_R(1.0) &&
           uv[1] <= (mvt_real)cam->height - MVT_R(1.0);
}

mvt_real mvt_body_clutter_density(const mvt_tracker_t *self, int k)
{
    const mvt_camera_t *cam = &self->cams[k];
    const mvt_real now = self->body.clutter_now[k];
    return (now > self->clutter_n[k] ? now : self->clutter_n[k]) / ((mvt_real)cam->width * (mvt_real)cam->height);
}

int mvt_body_feet_visible(const mvt_tracker_t *self, int k, const mvt_detection_t *det, int self_t, mvt_real uv[2])
{
    const mvt_camera_t *cam = &self->cams[k];
    const mvt_real *b = det->box;
    if (!mvt_trk_box_ok(b) || b[0] < MVT_BODY_EDGE_PX || b[2] > (mvt_real)cam->width - MVT_R(1.0) - MVT_BODY_EDGE_PX ||
        b[3] > (mvt_real)cam->height - MVT_R(1.0) - MVT_BODY_EDGE_PX) {
        return 0;
    }
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        const mvt_real *s = self->body.sil[k][t];
        if (!(s[2] > s[0])) {
            continue; /* no body there */
        }
        /* another body likely present whose silhouette's box meets the blob's (one test) */
        const mvt_track_t *tr = &self->tracks[t];
        if (mvt_trk_boxes_overlap(b, s) & (t != self_t) & (tr->id != 0) & (tr->exist_lo > MVT_R(0.0))) {
            return 0;
        }
    }
    uv[0] = MVT_R(0.5) * (b[0] + b[2]);
    uv[1] = b[3];
    /* furniture the rig declares between the camera and the floor there: the bottom is its edge */
    if (self->cfg.volume.num_occluders > 0) {
        mvt_real o[3], dir[3];
        if (mvt_cam_ray(cam, uv, o, dir) != MVT_OK || !(dir[2] < MVT_R(0.0)) ||
            mvt_body_occluded(self, o, dir, -o[2] / dir[2])) {
            return 0;
        }
    }
    return 1;
}

mvt_err_t mvt_body_feet_innovation(const mvt_tracker_t *self, const mvt_cv_state_t *s, int k, const mvt_real uv[2],
                                   mvt_pkf_innov_t *in)
{
    const mvt_camera_t *cam = &self->cams[k];
    mvt_cv_state_t f = *s;
    f.x[2] = MVT_R(0.0);
    /* the blob's lowest point is the body's point on the floor nearest the camera, the camera's
     * learnt distance ahead of the head's vertical */
    const mvt_real ahead = self->foot_ahead_k[k] > MVT_R(0.0) ? self->foot_ahead_k[k] : MVT_BODY_FOOT_AHEAD_M;
    const mvt_real to_cam[2] = {cam->centre[0] - s->x[0], cam->centre[1] - s->x[1]};
    const mvt_real n = MVT_SQRT(to_cam[0] * to_cam[0] + to_cam[1] * to_cam[1]);
    if (n > ahead) {
        f.x[0] += ahead * to_cam[0] / n;
        f.x[1] += ahead * to_cam[1] / n;
    }
    mvt_pkf_pred_t p;
    mvt_err_t err = mvt_pkf_predict_obs(&f, cam, MVT_PKF_JACOBIAN, &p);
    if (err != MVT_OK) {
        return err;
    }
    /* the feet do not move with the head's height */
    p.H[2] = MVT_R(0.0);
    p.H[5] = MVT_R(0.0);
    const mvt_real *P = s->P;
    mvt_real hp[2][3];
    for (int r = 0; r < 2; r++) {
        for (int c = 0; c < 3; c++) {
            hp[r][c] = p.H[r * 3 + 0] * P[0 * 6 + c] + p.H[r * 3 + 1] * P[1 * 6 + c];
        }
    }
    p.hph[0] = hp[0][0] * p.H[0] + hp[0][1] * p.H[1];
    p.hph[1] = hp[0][0] * p.H[3] + hp[0][1] * p.H[4];
    p.hph[2] = hp[1][0] * p.H[3] + hp[1][1] * p.H[4];
    /* the feet's spread about that point: the camera's learnt one, else the body's prior */
    const mvt_real sd = self->foot_var_k[k] > MVT_R(0.0) ? MVT_SQRT(self->foot_var_k[k]) : self->cfg.body.foot_sd_m;
    const mvt_real spread_px = cam->fx * sd / p.depth_m;
    mvt_pkf_meas_t m;
    err = mvt_pkf_meas_make(cam, uv, MVT_SQRT(cam->sigma_px * cam->sigma_px + spread_px * spread_px), &m);
    if (err != MVT_OK) {
        return err;
    }
    return mvt_pkf_innovation_from(&p, &m, NULL, in);
}

/* Whether some camera's picture shows the head at x. */
static int in_some_picture(const mvt_tracker_t *self, const mvt_real x[3])
{
    for (int k = 0; k < self->num_cameras; k++) {
        mvt_real uv[2];
        if (mvt_cam_project(&self->cams[k], x, uv, NULL) == MVT_OK && mvt_body_in_picture(&self->cams[k], uv)) {
            return 1;
        }
    }
    return 0;
}

void mvt_body_existence(mvt_tracker_t *self, mvt_real dt)
{
    const mvt_tracker_config_t *c = &self->cfg;
    if (!(dt > MVT_R(0.0))) {
        return;
    }
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0 || tr->dormant) {
            continue;
        }
        const mvt_real *x = tr->s.x;
        /* a person leaves the watched region through a side wall of the volume or through the
         * edge of every camera's picture (cameras that watch part of a larger space) */
        const int leaving = mvt_body_near_side_wall(c, x) || !in_some_picture(self, x);
        const mvt_real hazard = MVT_R(1.0) / c->population.stay_s + (leaving ? MVT_R(1.0) / c->population.exit_s : MVT_R(0.0));
        const mvt_real ps = MVT_EXP(-dt * hazard);
        /* r' = ps r: odds' = ps r / (1 - ps r) = ps / ((1 - ps) (1 + odds^-1) + ps odds^-1 ... ), written
         * with 1 - r = 1 / (1 + e^lo) so that a track near certainty keeps its precision in float */
        const mvt_real one_minus_r = MVT_R(1.0) / (MVT_R(1.0) + MVT_EXP(tr->exist_lo));
        const mvt_real r = MVT_R(1.0) - one_minus_r;
        const mvt_real den = (MVT_R(1.0) - ps) * r + one_minus_r;
        tr->exist_lo = MVT_LOG(ps * r / den);
    }
}

/* Learns camera k's clutter rate from this frame's unexplained blobs. */
static void learn_clutter(mvt_tracker_t *self, int k, mvt_real dt)
{
    int n = 0;
    for (int d = 0; d < self->num_meas[k]; d++) {
        n += self->body.free_det[k][d] == 1; /* a displaced head's blob is its person's */
    }
    const mvt_real a = dt > MVT_R(0.0) ? MVT_R(1.0) - MVT_EXP(-dt / MVT_BODY_CLUTTER_S) : MVT_R(0.0);
    mvt_real c = self->clutter_n[k] + a * ((mvt_real)n - self->clutter_n[k]);
    /* the prior never leaves the model: a camera that has shown no false blob for a while still may */
    const mvt_real lo = MVT_R(0.1) * self->cfg.population.clutter_per_frame;
    self->clutter_n[k] = c < lo ? lo : c;
}

/* Camera k's fragments per body likely present, learnt from this frame's explanations. */
static void learn_fragments(mvt_tracker_t *self, int k, mvt_real dt)
{
    const mvt_body_ws_t *ws = &self->body;
    int bodies = 0, frags = 0;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        bodies += self->tracks[t].id != 0 && !self->tracks[t].dormant && self->tracks[t].exist_lo > MVT_R(0.0) &&
                  ws->axis[k][t][4] > MVT_R(0.0) && mvt_body_in_picture(&self->cams[k], ws->axis[k][t]);
    }
    for (int d = 0; d < self->num_meas[k]; d++) {
        frags += ws->owner[d] >= 0 && ws->head_of[k][d] < 0;
    }
    if (bodies == 0 || !(dt > MVT_R(0.0))) {
        return;
    }
    const mvt_real a = MVT_R(1.0) - MVT_EXP(-dt * (mvt_real)bodies / MVT_BODY_CLUTTER_S);
    const mvt_real f = self->frag_n[k] + a * ((mvt_real)frags / (mvt_real)bodies - self->frag_n[k]);
    self->frag_n[k] = f < MVT_BODY_FRAGMENTS_MIN ? MVT_BODY_FRAGMENTS_MIN : f;
}

void mvt_body_step(mvt_tracker_t *self, const mvt_frame_t *frame, const int order[], int n_order, mvt_real dt)
{
    for (int k = 0; k < self->num_cameras; k++) {
        if (!(self->clutter_n[k] > MVT_R(0.0))) {
            self->clutter_n[k] = self->cfg.population.clutter_per_frame;
        }
        if (!(self->frag_n[k] > MVT_R(0.0))) {
            self->frag_n[k] = MVT_BODY_FRAGMENTS_PRIOR;
        }
        for (int t = 0; t < MVT_MAX_TARGETS; t++) {
            self->body.sil[k][t][0] = MVT_R(1.0);
            self->body.sil[k][t][2] = MVT_R(0.0); /* not in the picture until the camera's pass */
            self->body.axis[k][t][4] = MVT_R(-1.0);
        }
        memset(self->body.free_det[k], 0, sizeof(self->body.free_det[k]));
        self->body.clutter_now[k] = MVT_R(0.0);
        for (int d = 0; d < MVT_MAX_DETECTIONS; d++) {
            self->body.head_of[k][d] = -1;
        }
    }
    mvt_body_existence(self, dt);
    const mvt_real typical = self->frame_dt_s;
    const int outage = dt * self->cfg.init_vel_std_ms > MVT_R(2.0) * self->cfg.body.halfwidth_m &&
                       dt > MVT_BODY_GAP_FRAMES * typical;
    if (outage) {
        /* nobody watched for longer than a person takes to walk a body's width, and for several of
         * the rig's frame intervals (the daemon was down, every camera dropped): where each person
         * is now is the views' to say, and who is who the heights' and the reach's
         * (mvt_body_birth.c: the persons found again, paired all at once) */
        for (int t = 0; t < MVT_MAX_TARGETS; t++) {
            mvt_track_t *tr = &self->tracks[t];
            if (tr->id != 0 && !tr->dormant && tr->was_shown) {
                tr->dormant = 1;
                tr->status = MVT_TRACK_TENTATIVE;
            }
        }
    }
    if (dt > MVT_R(0.0)) {
        /* the typical interval: follows a shorter one at once, a longer one slowly, a gap not */
        if (!(typical > MVT_R(0.0)) || dt < typical) {
            self->frame_dt_s = dt;
        } else if (dt <= MVT_BODY_GAP_FRAMES * typical) {
            self->frame_dt_s = typical + MVT_R(0.05) * (dt - typical);
        }
    }
    for (int oi = 0; oi < n_order; oi++) {
        const int k = order[oi];
        const mvt_view_t *view = &frame->views[k];
        for (int t = 0; t < MVT_MAX_TARGETS; t++) {
            if (self->tracks[t].id != 0) {
                mvt_trk_predict_pos(self, &self->tracks[t], view->utime_us);
            }
        }
        mvt_body_visibility(self, view, k);
        mvt_body_explain(self, view, k);
        mvt_body_update(self, view, k, dt);
        learn_clutter(self, k, dt);
        learn_fragments(self, k, dt);
    }
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        if (self->tracks[t].id != 0) {
            mvt_trk_settle(self, &self->tracks[t]);
            mvt_trk_predict(self, &self->tracks[t], frame->utime_us);
        }
    }
    if (self->cfg.filter == MVT_FILTER_TRIANGULATE) {
        mvt_body_triangulate(self);
    }
    mvt_body_regather(self, dt);
    mvt_body_one_view(self, frame);
    mvt_body_birth(self, frame, order, n_order, dt);
    mvt_body_prune(self);
}
