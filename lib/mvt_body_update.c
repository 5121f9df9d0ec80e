/*
 * mvt_body_update.c - camera k's evidence into each track: its state and its existence.
 *
 * State: the head that explain gave the track updates it (the PKF in the configured linearisation,
 * through the motion model) when it lies inside the chi-square gate; a displaced one (beyond the
 * gate, within the motion model's outlier radius) is evidence that the person is there, not of
 * where, and where its blob is merged with someone else's body (merged_with, tracked_top) its top
 * may seed a birth. A head the model expects another body to hide or merge (mvt_body_shown: it
 * shows as a top of its own with probability p / p_detect) takes its blob with the motion model's
 * prior of a displaced point raised to 1 - (p / p_detect) (1 - p_outlier): such a blob's top is
 * more often where the nearer body's outline ends, or the merged region's, than the head. How often
 * hidden heads still show is learnt per camera (learn_detection). Every head is noted per view
 * (mvt_trk_onset_seen): one that jumped off the view's last while two other views placed the person
 * begins a displacement of that view, which stands in for the view's memory of displacement while
 * fewer views place the person (mvt_trk_update_head).
 * The feet: where the blob's bottom shows them (feet_shown: visible, the body standing in the
 * picture, nothing of it below the blob), it weighs whether the top is the head or displaced
 * (feet_ratio: a displaced blob carries its bottom with its top, or its bottom is the body's feet
 * where the estimate puts them; the person's own head and feet move together as the estimate's
 * error says) and, the head taken, measures the body's point on the floor nearest the camera
 * (update_feet). Each camera learns from people two views place (learn_feet) how far that point
 * lies ahead of the head's vertical, how widely bottoms scatter about it and how often a bottom is
 * the feet at all, and the feet weigh accordingly. They fix the distance along the head's ray,
 * which one view leaves open and a view's burst can slide.
 * After every camera (mvt_body_regather), a track whose heads in three or more views agree on one
 * point beyond its gate, two or more of them judged displaced, outnumbering the views that place it
 * elsewhere, starts again at that point once they have agreed longer than that many independent
 * displacements last together: independent displacements do not agree for long, and the track
 * was where it was for a wrong reason (one view's distance along its ray, the height prior's or
 * feet a box misplaced; two views that took other things for its head). Then (mvt_body_one_view)
 * the person's height: the head's height the last frame two views placed it (or its birth's); a
 * person shown before whom one view places takes it as a measurement of the head's (a walking
 * head's bob about it), and any other track fewer than two views place keeps its head within
 * MVT_BODY_HEIGHT_BAND spreads of it (a truncation): one view's update slides the head along the
 * ray, and the height with it.
 * Existence (the integrated PDA's recursion with this camera's detection probability p):
 *   head detected with density N (its own, or    odds *= 1 - p + p N / (lambda + phi), phi the
 *   displaced: mvt_body_head_density)            density of other bodies' fragments at the blob
 *                                                (mvt_body_fragment_density): a blob that may be a
 *                                                piece of someone else says less of this person
 *   head missed, its top in the mask in its own  odds unchanged; the top updates the state
 *   column (mvt_body_explain.c)
 *   head missed, a fragment of the body in view  odds unchanged (the body is there; its head's
 *                                                blob is not, for reasons the model does not hold),
 *                                                and the head's column stays between its sides
 *   head missed inside a merged blob (its host)   odds *= 1 - p MVT_BODY_P_SHOWN_HIDDEN times the
 *                                                likelihood ratio of the blob's extent (extent_llr);
 *                                                the head's column stays between the blob's sides,
 *                                                and each edge of the blob that its silhouette alone
 *                                                puts there measures that edge (host_edges)
 *   head missed where the mask shows background   odds *= the camera's learnt rate of visible heads
 *   all around it (mvt_body_head_on_background)   of people there on its mask's background
 *                                                (MVT_BODY_P_BG): a mask is dense evidence, a
 *                                                missing blob top is not
 *   head missed                                   odds *= 1 - p
 * The triangulate-then-KF baseline (--mode kf) runs the same lifecycle: its heads inside the gate
 * are placed here and triangulated after every camera (mvt_body_triangulate: the robust inliers'
 * linear least-squares point and first-order covariance, one 3D update), and the per-view pixel
 * measurements (the mask's tops, a host's edges, the feet) are left out, so that the comparison
 * with the projective filter isolates the estimator.
 * Cost O(T) updates; memory: none beyond the tracker.
 */
#include "mvt_body.h"

#include "mvt_mask.h"
#include "mvt_tri.h"

#include <math.h>
#include <stddef.h>

/* How often camera k's blob bottoms where feet may show are the feet (learn_feet). */
static mvt_real p_feet(const mvt_tracker_t *self, int k)
{
    return self->p_feet_k[k] > MVT_R(0.0) ? self->p_feet_k[k] : MVT_BODY_P_FEET;
}

/* The body with axis ax goes on below blob det's bottom (a hole or a band of background cut it):
 * another blob tops a piece of it lower down, or the mask shows foreground on its axis between
 * that bottom and the feet (a half width above them, where a shadow may join). */
static int body_below(const mvt_view_t *view, const mvt_real ax[MVT_BODY_AXIS_N], const mvt_detection_t *det)
{
    const mvt_real v0 = det->box[3] + MVT_BODY_EDGE_PX, v1 = ax[3] - ax[4];
    if (!(v1 > v0)) {
        return 0;
    }
    for (int d = 0; d < view->num_detections; d++) {
        const mvt_detection_t *o = &view->det[d];
        const mvt_real uv[2] = {o->u, o->v};
        if (o != det && o->v > v0 && o->v < v1 && mvt_body_on_silhouette(ax, uv, MVT_R(0.0))) {
            return 1;
        }
    }
    const struct mvt_mask *m = view->mask;
    if (m == NULL || m->width == 0) {
        return 0;
    }
    const mvt_real slope = (ax[2] - ax[0]) / (ax[3] - ax[1]);
    const mvt_real step = (mvt_real)m->scale;
    for (mvt_real v = v0 + step; v < v1; v += step) {
        const mvt_real uv[2] = {ax[0] + slope * (v - ax[1]), v};
        if (mvt_mask_fg_near(m, uv, step)) {
            return 1;
        }
    }
    return 0;
}

/* Whether camera k's blob det, track t's head, shows the feet at its bottom (uv: the box's bottom
 * centre): they are visible (mvt_body_feet_visible: not cut by the picture or furniture, no other
 * body on the blob), the body stands in the picture (its floor point lower than its head by more
 * than its width; seen from above, the blob's lowest point is a shoulder's rim) and does not go on
 * below the blob (body_below). */
static int feet_shown(const mvt_tracker_t *self, const mvt_view_t *view, int t, int k, const mvt_detection_t *det,
                      mvt_real uv[2])
{
    const mvt_real *ax = self->body.axis[k][t];
    const mvt_real *sil = self->body.sil[k][t];
    return ax[3] - ax[1] > MVT_R(2.0) * ax[4] && sil[2] > sil[0] && mvt_body_feet_visible(self, k, det, t, uv) &&
           !body_below(view, ax, det);
}

/* The feet at uv as a measurement of track t's body (mvt_body_feet_innovation). Across, the box's
 * bottom centre is the centre of the silhouette's box, which for a body slanted in the picture lies
 * between its head and its feet: the innovation is taken against it. */
static int feet_innovation(const mvt_tracker_t *self, const mvt_track_t *tr, int t, int k, const mvt_real uv[2],
                           mvt_pkf_innov_t *in)
{
    const mvt_real *ax = self->body.axis[k][t];
    const mvt_real *sil = self->body.sil[k][t];
    if (mvt_body_feet_innovation(self, &tr->s, k, uv, in) != MVT_OK) {
        return 0;
    }
    in->y[0] -= MVT_R(0.5) * (sil[0] + sil[2]) - ax[2];
    return mvt_pkf_innov_d2(in) == MVT_OK;
}

/* Track t's feet in camera k (f: their innovation before the head's update moved the estimate
 * from x0) update it, inside the gate, as the body's point with the camera's learnt rate of bottoms
 * that are feet (else anywhere within the outlier radius). The innovation is carried to the
 * updated estimate along its Jacobian: the feet's rows do not change over a head's update. */
static void update_feet(mvt_tracker_t *self, mvt_track_t *tr, int k, const mvt_pkf_innov_t *f, const mvt_real x0[3])
{
    mvt_pkf_innov_t in = *f;
    const mvt_real dx[3] = {tr->s.x[0] - x0[0], tr->s.x[1] - x0[1], tr->s.x[2] - x0[2]};
    for (int r = 0; r < 2; r++) {
        const mvt_real *H = &in.H[r * 3];
        in.y[r] -= H[0] * dx[0] + H[1] * dx[1] + H[2] * dx[2];
    }
    mvt_real hp[6], hph[3];
    mvt_pkf_hph(in.H, tr->s.P, hp, hph);
    in.S[0] = hph[0] + in.r;
    in.S[1] = hph[1];
    in.S[2] = hph[2] + in.r;
    if (mvt_pkf_innov_d2(&in) != MVT_OK || !(in.d2 <= self->cfg.numerics.gate_chi2)) {
        return;
    }
    if (mvt_trk_update_pixels_robust(self, tr, &in, MVT_R(1.0) - p_feet(self, k)) == MVT_OK) {
        self->counters.foot_updates++;
    } else {
        self->counters.numeric_faults++;
    }
}

/* Track t, placed by two or more views this frame (their heads fix its place): for each of those
 * views whose blob shows its feet (feet_shown), where the bottom's ray meets the floor, ahead of the
 * head's vertical toward the camera. Within -MVT_BODY_FOOT_AHEAD_MAX_M..2 MVT_BODY_FOOT_AHEAD_MAX_M
 * it is the feet: learnt into the camera's distance ahead (foot_ahead_k) and its spread
 * (foot_var_k); how often it is, into the camera's rate of bottoms that are feet (p_feet_k). */
static void learn_feet(mvt_tracker_t *self, const mvt_track_t *tr, int t, const mvt_frame_t *frame)
{
    for (int k = 0; k < self->num_cameras; k++) {
        if (!(tr->cameras_placed & (1u << k))) {
            continue;
        }
        const mvt_camera_t *cam = &self->cams[k];
        for (int d = 0; d < self->num_meas[k]; d++) {
            mvt_real uv[2], o[3], dir[3];
            if (self->body.head_of[k][d] != t || !feet_shown(self, &frame->views[k], t, k, &frame->views[k].det[d], uv) ||
                mvt_cam_ray(cam, uv, o, dir) != MVT_OK || !(dir[2] < MVT_R(-1e-3))) {
                continue;
            }
            const mvt_real lam = -o[2] / dir[2];
            const mvt_real g[2] = {o[0] + lam * dir[0] - tr->s.x[0], o[1] + lam * dir[1] - tr->s.x[1]};
            const mvt_real to_cam[2] = {cam->centre[0] - tr->s.x[0], cam->centre[1] - tr->s.x[1]};
            const mvt_real n = MVT_SQRT(to_cam[0] * to_cam[0] + to_cam[1] * to_cam[1]);
            if (!(n > MVT_R(0.5))) {
                continue;
            }
            const mvt_real ahead = (g[0] * to_cam[0] + g[1] * to_cam[1]) / n;
            const int feet = ahead > -MVT_BODY_FOOT_AHEAD_MAX_M && ahead < MVT_R(2.0) * MVT_BODY_FOOT_AHEAD_MAX_M;
            const mvt_real pp = p_feet(self, k);
            const mvt_real np = pp + ((feet ? MVT_R(1.0) : MVT_R(0.0)) - pp) / MVT_BODY_FOOT_AHEAD_N;
            self->p_feet_k[k] = np < MVT_BODY_P_FEET_MIN ? MVT_BODY_P_FEET_MIN : (np > MVT_BODY_PD_MAX ? MVT_BODY_PD_MAX : np);
            if (!feet) {
                continue; /* not this body's feet (another's legs, a shadow, a cut): no sample */
            }
            mvt_real *f = &self->foot_ahead_k[k];
            const mvt_real prev = *f > MVT_R(0.0) ? *f : MVT_BODY_FOOT_AHEAD_M;
            const mvt_real sd0 = self->cfg.body.foot_sd_m;
            const mvt_real pv = self->foot_var_k[k] > MVT_R(0.0) ? self->foot_var_k[k] : sd0 * sd0;
            const mvt_real nv = pv + ((ahead - prev) * (ahead - prev) - pv) / MVT_BODY_FOOT_AHEAD_N;
            const mvt_real lo = MVT_BODY_FOOT_SD_MIN_M * MVT_BODY_FOOT_SD_MIN_M;
            const mvt_real hi = MVT_BODY_FOOT_AHEAD_MAX_M * MVT_BODY_FOOT_AHEAD_MAX_M;
            self->foot_var_k[k] = nv < lo ? lo : (nv > hi ? hi : nv);
            mvt_real next = prev + (ahead - prev) / MVT_BODY_FOOT_AHEAD_N;
            next = next < MVT_R(1e-3) ? MVT_R(1e-3)
                                      : (next > MVT_BODY_FOOT_AHEAD_MAX_M ? MVT_BODY_FOOT_AHEAD_MAX_M : next);
            *f = next;
        }
    }
}

static void mark_placed(mvt_track_t *tr, int k);

/* 1 when views obs[0..m) meet at x within their pixels' noise alone: the weighted squared
 * residuals within chi-square's 1 % point for 2m - 3 degrees of freedom (m >= 3; two views always
 * meet as far as this test can tell). worst: the view farthest from x, weighted. */
static int residuals_agree(const mvt_tracker_t *self, const mvt_tri_obs_t obs[], int m, const mvt_real x[3], int *worst)
{
    static const mvt_real chi2_1pc[17] = {MVT_R(0.0),  MVT_R(0.0),  MVT_R(0.0),  MVT_R(11.3), MVT_R(15.1), MVT_R(18.5),
                                          MVT_R(21.7), MVT_R(24.7), MVT_R(27.7), MVT_R(30.6), MVT_R(33.4), MVT_R(36.2),
                                          MVT_R(38.9), MVT_R(41.6), MVT_R(44.3), MVT_R(47.0), MVT_R(49.6)};
    mvt_real r2 = MVT_R(0.0), w2 = MVT_R(-1.0);
    for (int i = 0; i < m; i++) {
        const mvt_real r = mvt_tri_reproj_px(self->cams, &obs[i], x);
        const mvt_real e = r * r / obs[i].var_px2;
        r2 += e;
        if (e > w2) {
            w2 = e;
            *worst = i;
        }
    }
    return m < 3 || (m <= 16 && r2 <= chi2_1pc[m]);
}

/* Track t's heads this frame, two or more of them displaced (beyond the gate), that meet at one point
 * at a person's height, away from the track, with every view that places the track there too: three
 * or more views that agree to their pixel noise (agree[0..m), their point x and its covariance).
 * A displaced head lands anywhere in the outlier radius, so displaced heads that agree with a third
 * view to a few pixels say the person is there; the views that place the track elsewhere then took
 * something else for its head (a piece of its body, another person's top), as unlikely per view, so
 * the agreeing displaced views must outnumber them; displaced views that do not meet the others are
 * displaced by something else, and neither. 1 when they agree so; n_disp_out and n_out_out: how many
 * displaced views agree, and how many placing views disagree. */
static int heads_agree_elsewhere(mvt_tracker_t *self, const mvt_track_t *tr, int t, mvt_tri_obs_t agree[MVT_MAX_CAMERAS],
                                 int *m_out, int *n_disp_out, int *n_out_out, mvt_real x[3], mvt_real cov[9])
{
    const mvt_tracker_config_t *c = &self->cfg;
    mvt_tri_obs_t obs[MVT_MAX_CAMERAS];
    uint8_t placed[MVT_MAX_CAMERAS];
    int n = 0, n_disp = 0;
    for (int k = 0; k < self->num_cameras; k++) {
        for (int d = 0; d < self->num_meas[k]; d++) {
            if (self->body.head_of[k][d] != t || !self->meas_ok[k][d]) {
                continue;
            }
            obs[n].cam = k;
            obs[n].xn[0] = self->meas[k][d].xn[0];
            obs[n].xn[1] = self->meas[k][d].xn[1];
            obs[n].var_px2 = self->meas[k][d].var_px2;
            placed[n] = (uint8_t)((tr->cameras_used >> (unsigned)k) & 1u);
            n_disp += !placed[n];
            n++;
            break;
        }
    }
    if (n_disp < 2) {
        return 0;
    }
    /* the displaced views first (their point; while they do not meet within their pixels' noise, the
     * one farthest from it is displaced by something else, and left out, down to two), then the
     * placing views that agree with it */
    int m = 0;
    for (int i = 0; i < n; i++) {
        if (!placed[i]) {
            agree[m++] = obs[i];
        }
    }
    for (;;) {
        if (mvt_tri_linear(self->cams, agree, m, x) != MVT_OK || mvt_tri_refine(self->cams, agree, m, 5, x) != MVT_OK) {
            return 0;
        }
        int worst = 0;
        if (residuals_agree(self, agree, m, x, &worst)) {
            break; /* always so with two views */
        }
        agree[worst] = agree[--m];
    }
    const int n_agree_disp = m;
    int n_out = 0;
    for (int i = 0; i < n; i++) {
        if (!placed[i]) {
            continue;
        }
        const mvt_real r = mvt_tri_reproj_px(self->cams, &obs[i], x);
        if (r * r <= c->numerics.gate_chi2 * obs[i].var_px2) {
            agree[m++] = obs[i];
        } else {
            n_out++;
        }
    }
    int worst = 0;
    if (m < 3 || n_agree_disp <= n_out || mvt_tri_refine(self->cams, agree, m, 5, x) != MVT_OK ||
        !residuals_agree(self, agree, m, x, &worst)) {
        return 0;
    }
    const mvt_real dz = x[2] - c->body.head_height_m;
    if (!(MVT_FABS(dz) <= MVT_R(3.0) * c->body.head_height_sd_m) || !mvt_trk_inside_volume(c, x) ||
        mvt_tri_covariance(self->cams, agree, m, x, cov) != MVT_OK) {
        return 0;
    }
    /* away from the track: beyond the chi-square gate of its position's own spread (3 dof, 1 %) */
    mvt_real Pt[9];
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            Pt[i * 3 + j] = tr->s.P[i * 6 + j];
        }
    }
    if (!(mvt_trk_mahalanobis3(tr->s.x, Pt, x, cov, NULL) > MVT_R(11.3))) {
        return 0; /* within it, or a singular spread (< 0) */
    }
    *m_out = m;
    *n_disp_out = n_agree_disp;
    *n_out_out = n_out;
    return 1;
}

/* Track tr starts again at the point x (covariance cov) that the views agree[0..m) place it at,
 * keeping its identity: what this frame's views said is now theirs. The agreeing ones placed it,
 * undisplaced (their memories start again); the others' updates went into the estimate left
 * behind. */
static void regather(mvt_tracker_t *self, mvt_track_t *tr, const mvt_tri_obs_t agree[], int m, const mvt_real x[3],
                     const mvt_real cov[9])
{
    mvt_trk_start(self, tr, x, cov, tr->s.utime_us);
    mvt_body_height_start(tr, x[2], cov[8]);
    tr->cameras_used = 0u;
    tr->cameras_placed = 0u;
    for (int i = 0; i < m; i++) {
        const int k = agree[i].cam;
        tr->view[k].p = MVT_R(0.0);
        tr->view[k].y[0] = tr->view[k].y[1] = MVT_R(0.0);
        tr->view[k].utime_us = tr->s.utime_us;
        tr->onset[k].confirmed_us = 0;
        mark_placed(tr, k);
    }
    tr->one_view_s = MVT_R(0.0);
    tr->agree_s = MVT_R(0.0);
}

void mvt_body_regather(mvt_tracker_t *self, mvt_real dt)
{
    /* n independent displacements, each lasting outlier_persist_s on average (exponentially), last
     * together outlier_persist_s / n on average: views whose displaced heads agree elsewhere for
     * longer than that, net of the frames they did not, are believed. Pieces of one body cut alike in
     * every view (a torso's top under a head of the background's colour) agree for a moment, a
     * person the track left agrees frame after frame. A track whose place rested on one view for
     * twice a displacement's mean duration (it may stand anywhere along that view's ray) believes at
     * once heads that all agree, the placing view's too. */
    const mvt_real persist_s = self->cfg.motion.outlier_persist_s;
    int heads[MVT_MAX_TARGETS] = {0}, displaced[MVT_MAX_TARGETS] = {0};
    for (int k = 0; k < self->num_cameras; k++) {
        for (int d = 0; d < self->num_meas[k]; d++) {
            const int t = self->body.head_of[k][d];
            if (t >= 0 && self->meas_ok[k][d]) {
                heads[t]++;
                displaced[t] += (int)!((self->tracks[t].cameras_used >> (unsigned)k) & 1u);
            }
        }
    }
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0) {
            continue;
        }
        tr->one_view_s = mvt_trk_popcount(tr->cameras_placed) >= 2 ? MVT_R(0.0) : tr->one_view_s + dt;
        mvt_tri_obs_t agree[MVT_MAX_CAMERAS];
        mvt_real x[3], cov[9];
        int m = 0, n_disp = 0, n_out = 0;
        if (tr->dormant || heads[t] < 3 || displaced[t] < 2 ||
            !heads_agree_elsewhere(self, tr, t, agree, &m, &n_disp, &n_out, x, cov)) {
            tr->agree_s = tr->agree_s > dt ? tr->agree_s - dt : MVT_R(0.0);
            continue;
        }
        tr->agree_s += dt;
        if (tr->agree_s >= persist_s / (mvt_real)n_disp ||
            (n_out == 0 && tr->one_view_s >= MVT_R(2.0) * persist_s)) {
            regather(self, tr, agree, m, x, cov);
        }
    }
}

void mvt_body_one_view(mvt_tracker_t *self, const mvt_frame_t *frame)
{
    static const mvt_real Hz[3] = {MVT_R(0.0), MVT_R(0.0), MVT_R(1.0)};
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0 || tr->dormant) {
            continue;
        }
        if (mvt_trk_popcount(tr->cameras_placed) >= 2) {
            tr->seen_z = tr->s.x[2]; /* the person's height, where two views' rays meet */
            tr->seen_zz = tr->s.P[14];
            /* the running mean and variance of those heights, over about MVT_BODY_HEIGHT_MEMORY_S
             * (nothing to weigh before the rig's frame interval is known) */
            const mvt_real dt = self->frame_dt_s;
            const mvt_real a = dt > MVT_R(0.0) ? dt / (MVT_BODY_HEIGHT_MEMORY_S + dt) : MVT_R(0.0);
            const mvt_real d = tr->seen_z - tr->z_mean;
            tr->z_mean += a * d;
            tr->z_var = (MVT_R(1.0) - a) * (tr->z_var + a * d * d);
            learn_feet(self, tr, t, frame);
            continue;
        }
        if (tr->cameras_used != 0u && tr->was_shown) {
            /* one view placed a person shown before: their height is a measurement of the head's
             * (a walking head bobs MVT_BODY_HEAD_BOB_M about it). One view's ray leaves the distance
             * along it free, and the height fixes it: without it the head slides along the ray,
             * and the height with it. The x and y rows carry no information (their variance is a
             * room's, not a body's). */
            const mvt_real big = MVT_R(1e4);
            const mvt_real z[3] = {tr->s.x[0], tr->s.x[1], tr->seen_z};
            const mvt_real R[9] = {big, MVT_R(0.0), MVT_R(0.0), MVT_R(0.0), big, MVT_R(0.0), MVT_R(0.0), MVT_R(0.0),
                                   tr->seen_zz + MVT_BODY_HEAD_BOB_M * MVT_BODY_HEAD_BOB_M};
            const mvt_err_t err = mvt_trk_update_point(self, tr, z, R);
            if (err != MVT_OK && err != MVT_ERR_NUMERIC) {
                self->counters.numeric_faults++;
            }
            continue;
        }
        /* nobody placed it, or a track not yet shown: the head's height stays within the person's
         * (a truncation) */
        const mvt_real w = MVT_BODY_HEIGHT_BAND * MVT_SQRT(tr->seen_zz + MVT_BODY_HEAD_BOB_M * MVT_BODY_HEAD_BOB_M);
        const mvt_err_t err = mvt_trk_truncate(self, tr, Hz, tr->s.x[2], tr->seen_z - w, tr->seen_z + w);
        if (err != MVT_OK && err != MVT_ERR_NUMERIC) {
            self->counters.numeric_faults++;
        }
    }
}

void mvt_body_triangulate(mvt_tracker_t *self)
{
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0 || tr->dormant || mvt_trk_popcount(tr->cameras_placed) < 2) {
            continue;
        }
        mvt_tri_obs_t obs[MVT_MAX_CAMERAS];
        int n = 0;
        for (int k = 0; k < self->num_cameras; k++) {
            if (!(tr->cameras_placed & (1u << k))) {
                continue;
            }
            for (int d = 0; d < self->num_meas[k]; d++) {
                if (self->body.head_of[k][d] == t) {
                    obs[n].cam = k;
                    obs[n].xn[0] = self->meas[k][d].xn[0];
                    obs[n].xn[1] = self->meas[k][d].xn[1];
                    obs[n].var_px2 = self->meas[k][d].var_px2;
                    n++;
                    break;
                }
            }
        }
        if (n < 2) {
            continue;
        }
        /* the views that agree within the heads' gate */
        uint32_t bits = 0u;
        const mvt_err_t err =
            mvt_trk_update_triangulated(self, tr, obs, n, MVT_SQRT(self->cfg.numerics.gate_chi2 * obs[0].var_px2), &bits);
        if (err == MVT_OK) {
            tr->cameras_used = bits;
            tr->cameras_placed = bits;
            self->counters.updates++;
        } else if (err != MVT_ERR_DEGENERATE) {
            self->counters.numeric_faults++;
        }
    }
}

/* The blob's colour is the person's when no other body's silhouette overlaps its box. */
static int alone_in_blob(const mvt_tracker_t *self, int k, int t, const mvt_real box[4])
{
    for (int j = 0; j < MVT_MAX_TARGETS; j++) {
        const mvt_real *s = self->body.sil[k][j];
        if (!(s[2] > s[0])) {
            continue; /* no body there */
        }
        /* one test, not several (branches the data decide are mispredicted often) */
        if ((j != t) & (self->tracks[j].id != 0) & mvt_trk_boxes_overlap(box, s)) {
            return 0;
        }
    }
    return 1;
}

/* Track t inside merged blob d of camera k, or owning fragment d: its head's column lies between
 * the blob's sides (a truncation of the prediction's image column, mvt_cv_truncate). */
static void keep_in_blob(mvt_tracker_t *self, mvt_track_t *tr, int k, const mvt_detection_t *det)
{
    mvt_pkf_pred_t p;
    if (!mvt_trk_box_ok(det->box) || mvt_pkf_predict_obs(&tr->s, &self->cams[k], MVT_PKF_JACOBIAN, &p) != MVT_OK) {
        return;
    }
    if (mvt_trk_truncate(self, tr, p.H, p.h[0], det->box[0], det->box[2]) != MVT_OK) {
        self->counters.numeric_faults++;
    } else {
        self->counters.occluded_updates++;
    }
}

/* How much a silhouette's edge varies about the body's (arms, clothes, pose), m at its depth. */
#define EXTENT_SD_M MVT_R(0.05)

/* ln of the likelihood ratio of box edge e about a (with the track's body) or about b (without):
 * Gaussian with variance s2 where the silhouette is whole, anywhere over n pixels with probability
 * q where the segmentation broke it (a cut or a hole moves an edge anywhere). */
static mvt_real edge_llr(mvt_real e, mvt_real a, mvt_real b, mvt_real s2, mvt_real q, mvt_real n)
{
    const mvt_real g = (MVT_R(1.0) - q) / MVT_SQRT(MVT_R(2.0) * MVT_R(3.14159265) * s2), u = q / n;
    const mvt_real la = g * MVT_EXP(MVT_R(-0.5) * (e - a) * (e - a) / s2) + u;
    const mvt_real lb = g * MVT_EXP(MVT_R(-0.5) * (e - b) * (e - b) / s2) + u;
    return MVT_LOG(la / lb);
}

/* Track t hosted by blob d of camera k: the blob's box is the union of the silhouettes of the people
 * in it. Its left, right and bottom edges predicted from the other likely-present bodies whose heads
 * the box holds, with and without t's silhouette, each with the blob's noise, EXTENT_SD_M at t's
 * depth and t's predicted spread: the log-likelihood ratio of t in the blob against t absent. > 0
 * where the box reaches out where only t's body puts it (a person beside or in front of the one
 * whose top the blob reports), < 0 where t's body would stick out of it, 0 where the others fill
 * t's silhouette either way (right behind another: no information). Edges at the picture's border,
 * where the box is cut, say nothing. */
/* The union of the silhouettes of the likely-present bodies other than t whose heads blob d of
 * camera k holds (u0 v0 u1 v1; u1 < u0 when there is none). */
static void others_in_blob(const mvt_tracker_t *self, int k, int t, const mvt_real b[4], mvt_real all[4])
{
    const mvt_body_ws_t *ws = &self->body;
    all[0] = MVT_R(1.0);
    all[1] = MVT_R(0.0);
    all[2] = MVT_R(0.0);
    all[3] = MVT_R(0.0);
    int n = 0;
    for (int j = 0; j < MVT_MAX_TARGETS; j++) {
        const mvt_real *sj = ws->sil[k][j];
        if (j == t || self->tracks[j].id == 0 || self->tracks[j].dormant || !(self->tracks[j].exist_lo > MVT_R(0.0)) ||
            !(sj[2] > sj[0]) || !mvt_trk_in_box(b, ws->axis[k][j], MVT_R(0.0), MVT_R(0.0))) {
            continue;
        }
        if (n++ == 0) {
            all[0] = sj[0];
            all[2] = sj[2];
            all[3] = sj[3];
        } else {
            all[0] = sj[0] < all[0] ? sj[0] : all[0];
            all[2] = sj[2] > all[2] ? sj[2] : all[2];
            all[3] = sj[3] > all[3] ? sj[3] : all[3];
        }
    }
}

/* A hosting blob's edges' noise about the silhouette's: the blob's pixels, EXTENT_SD_M at t's depth
 * and (s2u, s2v) t's predicted spread; q the chance that an edge is the segmentation's, not the
 * body's: this camera's fragments per body. */
typedef struct {
    mvt_real r;    /* px^2, without t's spread */
    mvt_real s2u;  /* px^2, horizontal edges' innovation variance */
    mvt_real s2v;  /* px^2, the bottom's */
    mvt_real q;
} edge_noise_t;

static edge_noise_t edge_noise(const mvt_tracker_t *self, int k, int t, int d)
{
    const mvt_camera_t *cam = &self->cams[k];
    const mvt_pkf_pred_t *p = &self->pred[t];
    const mvt_real wsd = cam->fx * EXTENT_SD_M / p->depth_m;
    const mvt_real var = self->meas_ok[k][d] ? self->meas[k][d].var_px2 : cam->sigma_px * cam->sigma_px;
    const mvt_real fq = self->frag_n[k] < MVT_R(0.9) ? self->frag_n[k] : MVT_R(0.9);
    edge_noise_t n;
    n.r = var + wsd * wsd;
    n.s2u = n.r + p->hph[0];
    n.s2v = n.r + p->hph[2];
    n.q = fq > MVT_BODY_FRAGMENTS_MIN ? fq : MVT_BODY_FRAGMENTS_MIN;
    return n;
}

/* Track t hosted by blob d of camera k: the blob's box is the union of the silhouettes of the people
 * in it. Its left, right and bottom edges predicted from the other likely-present bodies whose heads
 * the box holds, with and without t's silhouette, each with the blob's noise, EXTENT_SD_M at t's
 * depth and t's predicted spread: the log-likelihood ratio of t in the blob against t absent. > 0
 * where the box reaches out where only t's body puts it (a person beside or in front of the one
 * whose top the blob reports), < 0 where t's body would stick out of it, 0 where the others fill
 * t's silhouette either way (right behind another: no information). Edges at the picture's border,
 * where the box is cut, say nothing. */
static mvt_real extent_llr(const mvt_camera_t *cam, const mvt_real b[4], const mvt_real sil_t[4], const mvt_real all[4],
                           const edge_noise_t *e)
{
    const edge_noise_t en = *e;
    const mvt_real W = (mvt_real)cam->width, H = (mvt_real)cam->height;
    mvt_real llr = MVT_R(0.0);
    if (b[0] > MVT_BODY_EDGE_PX && sil_t[0] < all[0]) {
        llr += edge_llr(b[0], sil_t[0], all[0], en.s2u, en.q, W);
    }
    if (b[2] < W - MVT_R(1.0) - MVT_BODY_EDGE_PX && sil_t[2] > all[2]) {
        llr += edge_llr(b[2], sil_t[2], all[2], en.s2u, en.q, W);
    }
    if (b[3] < H - MVT_R(1.0) - MVT_BODY_EDGE_PX && sil_t[3] > all[3]) {
        llr += edge_llr(b[3], sil_t[3], all[3], en.s2v, en.q, H);
    }
    return llr;
}

/* H P H^T of one row H on the position of the 6-state covariance P. */
static mvt_real hph3(const mvt_real H[3], const mvt_real P[36])
{
    mvt_real v = MVT_R(0.0);
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++) {
            v += H[r] * P[r * 6 + c] * H[c];
        }
    }
    return v;
}

/* One edge of a hosting blob that t's silhouette alone puts there (innovation y, row H of the
 * position, noise r, innovation variance s2): a scalar measurement of t, taken when the edge is
 * more likely the body's than the segmentation's (the Gaussian against q spread over n pixels) and
 * inside the gate. The other row of the pixel update is empty (H 0, innovation 0). */
static void update_edge(mvt_tracker_t *self, mvt_track_t *tr, const mvt_real Hrow[3], mvt_real y, mvt_real r,
                        mvt_real s2, mvt_real q, mvt_real n)
{
    const mvt_real g = (MVT_R(1.0) - q) * MVT_EXP(MVT_R(-0.5) * y * y / s2) / MVT_SQRT(MVT_R(6.2831853) * s2);
    if (!(y * y <= MVT_BODY_EDGE_GATE * s2) || !(g > q / n)) {
        return;
    }
    mvt_pkf_innov_t in;
    in.y[0] = y;
    in.y[1] = MVT_R(0.0);
    for (int c = 0; c < 3; c++) {
        in.H[c] = Hrow[c];
        in.H[3 + c] = MVT_R(0.0);
    }
    in.r = r;
    in.S[0] = s2;
    in.S[1] = MVT_R(0.0);
    in.S[2] = r;
    in.d2 = y * y / s2;
    if (mvt_trk_update_pixels(self, tr, &in) == MVT_OK) {
        self->counters.occluded_updates++;
    } else {
        self->counters.numeric_faults++;
    }
}

/* Edge e lies nearer t's predicted edge a than the others' b: t's body, not theirs, explains it. */
static int nearer(mvt_real e, mvt_real a, mvt_real b)
{
    return (e - a) * (e - a) < (e - b) * (e - b);
}

/* Track t hosted by blob d of camera k: each of the box's edges that t's silhouette alone puts there
 * (it reaches beyond every other body the blob holds by two spreads, and the edge lies nearer t's
 * than theirs) measures that edge of t's silhouette: the sides its column, the bottom its feet (the
 * body's point on the floor nearest the camera), which a merged blob shows when t is the nearest
 * body in it. */
static void host_edges(mvt_tracker_t *self, mvt_track_t *tr, int k, const mvt_real b[4], const mvt_real sil_t[4],
                       const mvt_real all[4], const edge_noise_t *e)
{
    const mvt_camera_t *cam = &self->cams[k];
    const edge_noise_t en = *e;
    mvt_pkf_pred_t p; /* raw pixels, as the silhouettes */
    if (mvt_pkf_predict_obs(&tr->s, cam, MVT_PKF_JACOBIAN, &p) != MVT_OK) {
        return;
    }
    const mvt_real W = (mvt_real)cam->width, Hpx = (mvt_real)cam->height;
    const mvt_real *Hu = p.H;
    const mvt_real margin = MVT_R(2.0) * MVT_SQRT(en.s2u);
    const mvt_real x0[3] = {tr->s.x[0], tr->s.x[1], tr->s.x[2]};
    if (b[0] > MVT_BODY_EDGE_PX && sil_t[0] < all[0] - margin && nearer(b[0], sil_t[0], all[0])) {
        update_edge(self, tr, Hu, b[0] - sil_t[0], en.r, en.s2u, en.q, W);
    }
    if (b[2] < W - MVT_R(1.0) - MVT_BODY_EDGE_PX && sil_t[2] > all[2] + margin && nearer(b[2], sil_t[2], all[2])) {
        /* after the left side's update: its shift of the prediction, and the spread it left */
        const mvt_real shift =
            Hu[0] * (tr->s.x[0] - x0[0]) + Hu[1] * (tr->s.x[1] - x0[1]) + Hu[2] * (tr->s.x[2] - x0[2]);
        update_edge(self, tr, Hu, b[2] - sil_t[2] - shift, en.r, en.r + hph3(Hu, tr->s.P), en.q, W);
    }
    if (b[3] < Hpx - MVT_R(1.0) - MVT_BODY_EDGE_PX && sil_t[3] > all[3] + MVT_R(2.0) * MVT_SQRT(en.s2v) &&
        nearer(b[3], sil_t[3], all[3])) {
        const mvt_real uv[2] = {MVT_R(0.5) * (sil_t[0] + sil_t[2]), b[3]};
        mvt_pkf_innov_t in;
        if (mvt_body_feet_innovation(self, &tr->s, k, uv, &in) == MVT_OK) {
            const mvt_real Hv[3] = {in.H[3], in.H[4], in.H[5]};
            update_edge(self, tr, Hv, in.y[1], in.r, in.S[2], en.q, Hpx);
        }
    }
}

/* Track t hosted by blob d of camera k: the box's evidence for its existence (extent_llr, from the
 * prediction) is returned, then the edges that are its body's measure it (host_edges). */
static mvt_real hosted(mvt_tracker_t *self, mvt_track_t *tr, const mvt_view_t *view, int k, int t, int d)
{
    const mvt_real *b = view->det[d].box, *sil_t = self->body.sil[k][t];
    if (!mvt_trk_box_ok(b) || !(sil_t[2] > sil_t[0]) || !(self->pred[t].depth_m > MVT_R(0.0))) {
        return MVT_R(0.0);
    }
    mvt_real all[4];
    others_in_blob(self, k, t, b, all);
    if (!(all[2] > all[0])) {
        return MVT_R(0.0);
    }
    const edge_noise_t en = edge_noise(self, k, t, d);
    const mvt_real llr = extent_llr(&self->cams[k], b, sil_t, all, &en);
    if (self->cfg.filter == MVT_FILTER_PROJECTIVE) {
        host_edges(self, tr, k, b, sil_t, all, &en);
    }
    return llr;
}

/* A blob that holds the body's predicted head and is wider than its silhouette by half a body or
 * more holds someone else as well (a merged blob): where its top is not this body's head (beyond
 * the gate), it is that other person's, who may be a newcomer nobody tracks yet (mvt_body_birth.c
 * seeds from it). A burst, a whole silhouette displaced, is one body wide; another person's own
 * blob does not hold this head. */
static int merged_with(const mvt_real sil[4], const mvt_real head[2], const mvt_real box[4])
{
    const mvt_real w = sil[2] - sil[0];
    return w > MVT_R(0.0) && mvt_trk_box_ok(box) && box[2] - box[0] > MVT_R(1.5) * w &&
           mvt_trk_in_box(box, head, MVT_R(0.0), MVT_R(0.0));
}

/* Blob d's top is a tracked person's: inside the gate of a track other than t likely present (that
 * person's head), or on a likely-present body's silhouette below its head (a piece of it, where the
 * segmentation cut the merged region). Either way no newcomer's head. */
static int tracked_top(const mvt_tracker_t *self, const mvt_view_t *view, int k, int d, int t)
{
    const mvt_real uv[2] = {view->det[d].u, view->det[d].v};
    for (int j = 0; j < MVT_MAX_TARGETS; j++) {
        mvt_pkf_innov_t in;
        if (self->tracks[j].id == 0 || !self->pred_ok[j] || !(self->tracks[j].exist_lo > MVT_R(0.0))) {
            continue;
        }
        if (mvt_body_fragment_of(self->body.axis[k][j], uv) ||
            (j != t && mvt_pkf_innovation_from(&self->pred[j], &self->meas[k][d], NULL, &in) == MVT_OK &&
             in.d2 <= self->cfg.numerics.gate_chi2)) {
            return 1;
        }
    }
    return 0;
}

/* Camera k updated track t's head; it placed it unless the motion model judged the head displaced. */
static void mark_placed(mvt_track_t *tr, int k)
{
    tr->cameras_used |= 1u << k;
    if (tr->view[k].p < MVT_R(0.5)) {
        tr->cameras_placed |= 1u << k;
    }
}

/* Learns camera k's detection probability from this frame: each track likely present whose head
 * the model expects to be shown (no body over it) is a trial, its head's blob a hit. The tracks
 * whose heads it expects hidden (mvt_body_shown) are trials of the rate at which hidden heads still
 * show, per p_detect. Where the camera sent its mask, the heads in view and not hidden of people two
 * other views placed the frame before are trials of the rate at which the mask shows background all
 * around a head that is there (p_bg_k). */
static void learn_detection(mvt_tracker_t *self, int k, int masked, mvt_real dt)
{
    const mvt_body_ws_t *ws = &self->body;
    int n = 0, hits = 0, n_hidden = 0, hits_hidden = 0, n_bg = 0, hits_bg = 0;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        const mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0 || !(ws->pd[t] > MVT_R(0.0))) {
            continue;
        }
        /* the mask's trials: heads in view, not hidden, of people two other views placed */
        if (masked && (ws->on_bg[t] || ws->pd[t] > MVT_R(0.5) * self->p_detect_k[k]) &&
            mvt_trk_popcount(tr->cameras_placed_prev & ~(1u << k)) >= 2) {
            n_bg++;
            hits_bg += ws->on_bg[t];
        }
        if (!(tr->exist_lo > MVT_R(0.0))) {
            continue;
        }
        if (ws->pd[t] > MVT_R(0.5) * self->p_detect_k[k]) {
            n++;
            hits += ws->assign[t] >= 0;
        } else {
            n_hidden++;
            hits_hidden += ws->assign[t] >= 0;
        }
    }
    if (!(dt > MVT_R(0.0))) {
        return;
    }
    if (n_hidden > 0) {
        const mvt_real a = MVT_R(1.0) - MVT_EXP(-dt * (mvt_real)n_hidden / MVT_BODY_PD_S);
        const mvt_real rate = (mvt_real)hits_hidden / (mvt_real)n_hidden / self->p_detect_k[k];
        mvt_real q = self->p_hidden_k[k] + a * (rate - self->p_hidden_k[k]);
        q = q < MVT_BODY_P_SHOWN_HIDDEN ? MVT_BODY_P_SHOWN_HIDDEN
                                        : (q > MVT_BODY_P_SHOWN_HIDDEN_MAX ? MVT_BODY_P_SHOWN_HIDDEN_MAX : q);
        self->p_hidden_k[k] = q;
    }
    if (n_bg > 0) {
        const mvt_real a = MVT_R(1.0) - MVT_EXP(-dt * (mvt_real)n_bg / MVT_BODY_PD_S);
        mvt_real q = self->p_bg_k[k] + a * ((mvt_real)hits_bg / (mvt_real)n_bg - self->p_bg_k[k]);
        q = q < MVT_BODY_P_BG_MIN ? MVT_BODY_P_BG_MIN : (q > MVT_BODY_P_BG_MAX ? MVT_BODY_P_BG_MAX : q);
        self->p_bg_k[k] = q;
    }
    if (n == 0) {
        return;
    }
    const mvt_real a = MVT_R(1.0) - MVT_EXP(-dt * (mvt_real)n / MVT_BODY_PD_S);
    mvt_real p = self->p_detect_k[k] + a * ((mvt_real)hits / (mvt_real)n - self->p_detect_k[k]);
    p = p < MVT_BODY_PD_MIN ? MVT_BODY_PD_MIN : (p > MVT_BODY_PD_MAX ? MVT_BODY_PD_MAX : p);
    self->p_detect_k[k] = p;
}

/* 2-D Gaussian density of e under the packed covariance (xx xy yy) (mvt_trk_density); 0 where it
 * is not positive definite. */
static mvt_real gauss2(const mvt_real e[2], const mvt_real S[3])
{
    mvt_pkf_innov_t g;
    g.y[0] = e[0];
    g.y[1] = e[1];
    g.S[0] = S[0];
    g.S[1] = S[1];
    g.S[2] = S[2];
    return mvt_pkf_innov_d2(&g) == MVT_OK ? mvt_trk_density(&g) : MVT_R(0.0);
}

/* What the blob's bottom (feet_shown; fp: the feet's innovation) says of whether its top is track
 * t's head (h: the head's innovation) or displaced, as a likelihood ratio. A head that is the person's has them where the same error of the estimate puts them: the feet's
 * innovation given the head's is Gaussian with mean C^T S_h^-1 y_h and covariance S_f - C^T S_h^-1 C
 * (C = H_h P H_f^T, the estimate's error seen by both). A displaced head is either a whole blob
 * displaced (an occluder's burst, a misplaced segment: its bottom moved by the head's offset, to
 * both points' noise) or a top that is not the head (the bottom is the body's feet, where the
 * estimate puts them), equally likely; and any bottom may not be the feet at all (legs cut by
 * clothes the colour of the background, a shadow), with the camera's learnt probability
 * (learn_feet), anywhere in the picture. */
static mvt_real feet_ratio(const mvt_tracker_t *self, const mvt_track_t *tr, int k, const mvt_pkf_innov_t *h,
                           const mvt_pkf_innov_t *fp)
{
    const mvt_pkf_innov_t f = *fp;
    mvt_real hp[6]; /* H_h P */
    mvt_pkf_hph(h->H, tr->s.P, hp, NULL);
    mvt_real C[2][2]; /* C[r][q] = (H_h P H_f^T)[r][q] */
    for (int r = 0; r < 2; r++) {
        for (int q = 0; q < 2; q++) {
            C[r][q] = hp[r * 3 + 0] * f.H[q * 3 + 0] + hp[r * 3 + 1] * f.H[q * 3 + 1] + hp[r * 3 + 2] * f.H[q * 3 + 2];
        }
    }
    const mvt_real dh = h->S[0] * h->S[2] - h->S[1] * h->S[1];
    if (!(dh > MVT_R(0.0))) {
        return MVT_R(1.0);
    }
    const mvt_real Si[3] = {h->S[2] / dh, -h->S[1] / dh, h->S[0] / dh};
    /* G = C^T S_h^-1 (2x2) */
    mvt_real G[2][2];
    for (int q = 0; q < 2; q++) {
        G[q][0] = C[0][q] * Si[0] + C[1][q] * Si[1];
        G[q][1] = C[0][q] * Si[1] + C[1][q] * Si[2];
    }
    const mvt_real e_own[2] = {f.y[0] - (G[0][0] * h->y[0] + G[0][1] * h->y[1]),
                               f.y[1] - (G[1][0] * h->y[0] + G[1][1] * h->y[1])};
    const mvt_real S_own[3] = {f.S[0] - (G[0][0] * C[0][0] + G[0][1] * C[1][0]),
                               f.S[1] - (G[0][0] * C[0][1] + G[0][1] * C[1][1]),
                               f.S[2] - (G[1][0] * C[0][1] + G[1][1] * C[1][1])};
    const mvt_real e_rigid[2] = {f.y[0] - h->y[0], f.y[1] - h->y[1]};
    const mvt_real S_rigid[3] = {f.S[0] + h->S[0] - MVT_R(2.0) * C[0][0], f.S[1] + h->S[1] - C[0][1] - C[1][0],
                                 f.S[2] + h->S[2] - MVT_R(2.0) * C[1][1]};
    const mvt_camera_t *cam = &self->cams[k];
    const mvt_real pf = p_feet(self, k);
    const mvt_real anywhere = (MVT_R(1.0) - pf) / ((mvt_real)cam->width * (mvt_real)cam->height);
    const mvt_real own = pf * gauss2(e_own, S_own) + anywhere;
    const mvt_real displaced = pf * MVT_R(0.5) * (gauss2(e_rigid, S_rigid) + gauss2(f.y, f.S)) + anywhere;
    const mvt_real lr = own / displaced;
    return isfinite(lr) && lr > MVT_R(0.0) ? lr : MVT_R(1.0);
}

void mvt_body_update(mvt_tracker_t *self, const mvt_view_t *view, int k, mvt_real dt)
{
    learn_detection(self, k, view->mask != NULL && view->mask->width > 0, dt);
    const mvt_body_ws_t *ws = &self->body;
    const mvt_real lambda = mvt_body_clutter_density(self, k);
    /* the projective filter updates here; kf places the heads for mvt_body_triangulate */
    const int projective = self->cfg.filter == MVT_FILTER_PROJECTIVE;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0 || tr->dormant) {
            continue;
        }
        const mvt_real p = ws->pd[t];
        const int d = ws->assign[t];
        if (d < 0 && ws->top_ok[t] && projective) {
            /* the head stands out of the mask in its own column: placed, and present */
            mvt_pkf_innov_t in;
            if (mvt_pkf_innovation_from(&self->pred[t], &ws->top[t], NULL, &in) != MVT_OK ||
                mvt_trk_update_pkf(self, tr, k, &in, NULL) != MVT_OK) {
                self->counters.numeric_faults++;
                continue;
            }
            mark_placed(tr, k);
            self->counters.mask_top_updates++;
            continue;
        }
        if (d < 0) {
            if (ws->host[t] >= 0) {
                keep_in_blob(self, tr, k, &view->det[ws->host[t]]);
                tr->exist_lo += MVT_LOG(MVT_R(1.0) - p * MVT_BODY_P_SHOWN_HIDDEN) + hosted(self, tr, view, k, t, ws->host[t]);
            } else if (ws->frag[t] >= 0) {
                keep_in_blob(self, tr, k, &view->det[ws->frag[t]]); /* the piece holds the body's column */
            } else if (ws->on_bg[t]) {
                tr->exist_lo += MVT_LOG(self->p_bg_k[k]); /* the mask is empty where the head would be */
            } else {
                tr->exist_lo += MVT_LOG(MVT_R(1.0) - p);
            }
            continue;
        }
        mvt_pkf_innov_t in;
        mvt_err_t err = mvt_pkf_innovation_from(&self->pred[t], &self->meas[k][d], NULL, &in);
        if (err == MVT_OK) {
            const mvt_real uv[2] = {view->det[d].u, view->det[d].v};
            const mvt_real other = ws->frag_dens[d] - mvt_body_fragment_density(self, k, t, uv);
            const mvt_real alt = lambda + (other > MVT_R(0.0) ? other : MVT_R(0.0)); /* clutter or another's piece */
            const int gated = mvt_body_gated(self, t, k, d, &in);
            tr->exist_lo += MVT_LOG(MVT_R(1.0) - p + p * mvt_body_head_density(self, &in, gated) / alt);
            if (projective) {
                mvt_trk_onset_seen(self, tr, k, &in, self->meas[k][d].ideal, gated);
            }
            if (!gated) {
                self->counters.gated_out++; /* displaced: evidence of the person, not of where */
                if (merged_with(ws->sil[k][t], ws->head[t], view->det[d].box) && !tracked_top(self, view, k, d, t)) {
                    self->body.free_det[k][d] = 2; /* a merged blob topped by someone else */
                }
                continue;
            }
            /* the head shows here with probability p / p_detect (mvt_body_shown); a blob at a head
             * the model expects hidden is more likely another part of the body (its top where the
             * nearer body's outline ends, or the merged region's) */
            const mvt_real pk = self->p_detect_k[k];
            if (projective) {
                /* the blob's bottom, where it shows the feet, weighs whether its top is the head
                 * (feet_ratio) and, if so, measures the feet */
                mvt_real fuv[2];
                mvt_pkf_innov_t fin;
                const int feet = feet_shown(self, view, t, k, &view->det[d], fuv) &&
                                 feet_innovation(self, tr, t, k, fuv, &fin);
                const mvt_real x0[3] = {tr->s.x[0], tr->s.x[1], tr->s.x[2]};
                err = mvt_trk_update_head(self, tr, k, &in, NULL, pk > MVT_R(0.0) && p < pk ? p / pk : MVT_R(1.0),
                                          feet ? feet_ratio(self, tr, k, &in, &fin) : MVT_R(1.0));
                if (err == MVT_OK) {
                    mvt_trk_onset_judged(tr, k);
                }
                if (feet && err == MVT_OK && tr->view[k].p < MVT_R(0.5)) {
                    update_feet(self, tr, k, &fin, x0);
                }
            }
        }
        if (err != MVT_OK) {
            self->counters.numeric_faults++;
            continue;
        }
        mark_placed(tr, k);
        if (projective) {
            self->counters.updates++; /* kf's: mvt_body_triangulate, after every camera */
        }
        const mvt_detection_t *det = &view->det[d];
        if (self->chroma_ok[k][d] && mvt_trk_box_ok(det->box) && alone_in_blob(self, k, t, det->box)) {
            mvt_trk_app_update(&tr->app, self->chroma[k][d]);
        }
    }
}
