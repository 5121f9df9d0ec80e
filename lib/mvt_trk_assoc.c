/*
 * mvt_trk_assoc.c - hypothesiser and data associator of the tracker loop (one camera at a time).
 *
 * Hypotheses: each live track's predicted observation in the camera (mvt_pkf_pred_t), gated
 * against every detection. Association: global nearest neighbour by the Hungarian method on each
 * cluster of tracks linked through shared gated detections, by likelihood (a detection costs
 * d^2 + ln |S| plus its colour's -2 ln LR; a "missed" column per track costs what p_detect and the
 * view's clutter density make of a miss, miss_base), so one detection feeds at most one track and
 * a track whose prediction is wide does not take a detection that a sharper one predicted. Merged blobs: tracks whose image
 * points are closer than merge_width_m seen at their depth are unresolved in this view. When the
 * Hungarian method gives a detection to one of them and leaves an unresolved neighbour without
 * one although the detection lies in its gate too, the detection may be the two people's merged
 * blob. MVT_MERGE_NEITHER then updates neither track with it when it is ambiguous (the two
 * tracks' likelihoods differ by less than merge_ambiguity in -2 log units; the other views
 * decide), and leaves it to the assigned track otherwise (a merged region's top is one person's
 * head, and the Hungarian method already gave it to the likelier one);
 * MVT_MERGE_SHARE updates both, with the measurement covariance of unresolved tracks widened by
 * D D^T / 3 (D = the image separation to the nearest unresolved track: a uniform offset of up to
 * |D| toward it has second moment |D|^2 / 3). docs/tracking.md measures the three policies.
 */
#include <math.h>
#include <string.h>

#include "mvt_trk.h"

static int find_root(int16_t *parent, int t)
{
    while (parent[t] != t) {
        parent[t] = parent[parent[t]];
        t = parent[t];
    }
    return t;
}

/* The colour's part of the cost of giving detection d of camera k to track t, in -2 ln LR units
 * shifted by the least the track's colour cost can be (s_t = mvt_trk_app_cost_min <= 0), so that
 * every cost stays >= 0: c(t, d) - s_t, where c is -2 ln LR of the detection's chroma, and 0 (LR 1)
 * when the detection carries no colour that can be the person's alone. The "missed" column carries
 * the same shift (LR 1: no detection, no colour), so between tracks only the likelihoods count.
 * 0 with the paper's gate (a distance in other units). */
static mvt_real app_cost(const mvt_tracker_t *self, int k, int t, int d)
{
    if (self->cfg.gate == MVT_GATE_PAPER) {
        return MVT_R(0.0);
    }
    const int usable = self->chroma_ok[k][d] && self->merge_nb[t] < 0 && self->tracks[t].app.n > MVT_R(0.0);
    return (usable ? mvt_trk_app_cost(&self->tracks[t].app, self->chroma[k][d]) : MVT_R(0.0)) - self->app_shift[t];
}

/* The cost of track t missing camera k's view, in the same -2 ln likelihood-ratio units as a
 * detection's cost (d^2 + ln |S| + the colour's, below): the track is detected with p_detect, a
 * detection it does not take is clutter at the view's density lambda (ev_clutter), so giving it a
 * detection is worth -2 ln(p_detect N(y; 0, S) / lambda) against -2 ln(1 - p_detect) for missing
 * it. With the 2 pi and the terms every row shares moved here, the miss costs
 * 2 ln(p_detect / (1 - p_detect)) - 2 ln(2 pi lambda), shifted like app_cost. A track whose
 * prediction is uncertain (|S| large: coasting, hidden) spreads its likelihood thin, so it loses a
 * detection to a track that predicted it well, and takes one alone only nearer than the chi-square
 * gate (which still bounds every track). Never below 0. The part every track of camera k shares,
 * once per camera; each track's colour shift is taken off where it is used. */
static mvt_real miss_base(const mvt_tracker_t *self, int k)
{
    const mvt_tracker_config_t *c = &self->cfg;
    if (c->gate == MVT_GATE_PAPER) {
        return c->paper.delta;
    }
    const mvt_real pd = c->population.p_detect;
    const mvt_real g = MVT_R(2.0) * (MVT_LOG(pd / (MVT_R(1.0) - pd)) - MVT_LOG(MVT_R(6.2831853) * self->ev_clutter[k]));
    return g > MVT_R(0.0) ? g : MVT_R(0.0);
}

/* The spread part of a detection's cost, ln |S| (px^4) from det = |S|, floored at 0 (|S| >= r^2 >=
 * 1 px^4 with any usable pixel noise, so the floor does not bind) to keep costs non-negative. */
static mvt_real spread_cost(mvt_real det)
{
    return det > MVT_R(1.0) ? MVT_LOG(det) : MVT_R(0.0);
}

/* The second moment D D^T / 3 (packed xx xy yy) of a uniform offset of up to D = (dx, dy) pixels
 * along D: where in a merged blob its top point lies, seen from one of its heads. */
static void offset_cov(mvt_real dx, mvt_real dy, mvt_real cov[3])
{
    const mvt_real third = MVT_R(1.0) / MVT_R(3.0);
    cov[0] = dx * dx * third;
    cov[1] = dx * dy * third;
    cov[2] = dy * dy * third;
}

/* Squared image distance between two predictions and the squared merge radius in pixels. */
static int unresolved(const mvt_tracker_t *self, const mvt_camera_t *cam, int t, int u, mvt_real *d2_px)
{
    const mvt_pkf_pred_t *a = &self->pred[t], *b = &self->pred[u];
    const mvt_real dx = a->h[0] - b->h[0], dy = a->h[1] - b->h[1];
    const mvt_real depth = a->depth_m < b->depth_m ? a->depth_m : b->depth_m;
    const mvt_real w = cam->fx * self->cfg.rules.merge_width_m / depth;
    *d2_px = dx * dx + dy * dy;
    return *d2_px < w * w;
}

/* -2 log-likelihood of detection d for track t: d^2 + ln |S| (the 2 pi term cancels). Not the
 * colour: the blob this is asked of may hold both people, and its colour is then their mixture. */
static mvt_real neg2_loglik(const mvt_tracker_t *self, int k, int t, int d)
{
    mvt_pkf_innov_t in;
    if (mvt_pkf_innovation_from(&self->pred[t], &self->meas[k][d], NULL, &in) != MVT_OK) {
        return MVT_R(1e30);
    }
    return in.d2 + spread_cost(in.S[0] * in.S[2] - in.S[1] * in.S[1]);
}

/* The detection d given to u could as well be t's: the likelihoods differ by less than
 * merge_ambiguity in -2 log units. */
static int ambiguous(const mvt_tracker_t *self, int k, int t, int u, int d)
{
    return neg2_loglik(self, k, t, d) - neg2_loglik(self, k, u, d) < self->cfg.rules.merge_ambiguity;
}

/* Image order of two tracks' predicted heads: -1 when t is clearly above u (smaller v by more
 * than two standard deviations of the difference), +1 when clearly below, 0 when unclear. */
static int top_order(const mvt_tracker_t *self, int t, int u)
{
    const mvt_pkf_pred_t *a = &self->pred[t], *b = &self->pred[u];
    const mvt_real dv = a->h[1] - b->h[1];
    const mvt_real sd = MVT_SQRT(a->hph[2] + b->hph[2]);
    if (dv < MVT_R(-2.0) * sd) {
        return -1;
    }
    return dv > MVT_R(2.0) * sd ? 1 : 0;
}

/* Can camera cam have seen the track at all: its predicted image point within 3 sigma (plus the
 * pixel noise) of the picture, and the prediction's spread smaller than the picture. A head next
 * to a camera's focal plane projects far outside the picture with an image covariance that spans
 * it: the gate then admits any detection and the linearised update drags the track (a person
 * beside a wall camera was pulled 1 m by that camera's other blobs). */
static int in_picture(const mvt_camera_t *cam, const mvt_pkf_pred_t *p)
{
    const mvt_real su = MVT_SQRT(p->hph[0]), sv = MVT_SQRT(p->hph[2]);
    const mvt_real w = (mvt_real)cam->width, h = (mvt_real)cam->height;
    const mvt_real mu = MVT_R(3.0) * (su + cam->sigma_px), mv = MVT_R(3.0) * (sv + cam->sigma_px);
    return su < w && sv < h && p->h[0] >= -mu && p->h[0] <= w + mu && p->h[1] >= -mv && p->h[1] <= h + mv;
}

/* Does the blob of detection d hold the predicted heads of two or more seen people (confirmed or
 * coasting tracks)? Then its colour is their mixture, mostly the colour of the one in front, while
 * its top is the head of the one higher in the picture: its colour says nothing of anyone
 * (chroma_ok cleared for the frame). A head counts within three standard deviations of its
 * prediction (and the pixel noise) of the box. Blobs without a box: the unresolved pairs
 * (merge_nb) stand in for this. Measured on the masks' connected components (crowd, 3 seeds),
 * judged against the ground truth where the colour changed an assignment: without this rule the
 * colour was right 189 times and wrong 186, with it right 192 and wrong 174. */
static int blob_holds_two(const mvt_view_t *view, int d, const mvt_real heads[][4], int n_heads)
{
    int n = 0;
    for (int i = 0; i < n_heads && n < 2; i++) {
        n += mvt_trk_in_box(view->det[d].box, heads[i], heads[i][2], heads[i][3]); /* u, v, margins */
    }
    return n >= 2;
}

/* The predicted heads of the seen tracks in camera k (mvt_trk_seen_heads: heads, who), returned as
 * their count for the merged blobs' tests after the assignment too. */
static int hypothesise(mvt_tracker_t *self, const mvt_view_t *view, int k, const int live[], int n_live,
                       mvt_real heads[][4], int16_t who[])
{
    const mvt_tracker_config_t *c = &self->cfg;
    const mvt_camera_t *cam = &self->cams[k];
    const mvt_pkf_lin_t lin = c->filter == MVT_FILTER_PROJECTIVE ? c->lin : MVT_PKF_JACOBIAN;
    const int nd = self->num_meas[k];
    for (int i = 0; i < n_live; i++) {
        const int t = live[i];
        self->merge_nb[t] = -1;
        self->merge_wide[t] = 0;
        const mvt_err_t err = mvt_pkf_predict_obs(&self->tracks[t].s, cam, lin, &self->pred[t]);
        self->pred_ok[t] = err == MVT_OK && in_picture(cam, &self->pred[t]);
        if (self->pred_ok[t] && self->pred[t].h[0] >= MVT_R(0.0) && self->pred[t].h[1] >= MVT_R(0.0) &&
            self->pred[t].h[0] <= (mvt_real)cam->width && self->pred[t].h[1] <= (mvt_real)cam->height) {
            self->visible[t] |= 1u << k;
        }
        if (err == MVT_OK && !self->pred_ok[t]) {
            self->counters.outside_picture++;
        } else if (err == MVT_ERR_BEHIND) {
            self->counters.behind_camera++;
        } else if (err != MVT_OK) {
            self->counters.numeric_faults++;
        }
    }
    if (c->rules.merge != MVT_MERGE_OFF) {
        mvt_real best[MVT_MAX_TARGETS];
        for (int i = 0; i < n_live; i++) {
            best[live[i]] = MVT_R(0.0);
        }
        for (int i = 0; i < n_live; i++) {
            const int t = live[i];
            for (int j = i + 1; j < n_live && self->pred_ok[t]; j++) {
                const int u = live[j];
                mvt_real d2;
                if (!self->pred_ok[u] || !unresolved(self, cam, t, u, &d2)) {
                    continue;
                }
                if (self->merge_nb[t] < 0 || d2 < best[t]) {
                    self->merge_nb[t] = (int16_t)u;
                    best[t] = d2;
                }
                if (self->merge_nb[u] < 0 || d2 < best[u]) {
                    self->merge_nb[u] = (int16_t)t;
                    best[u] = d2;
                }
            }
        }
        for (int i = 0; i < n_live; i++) {
            const int t = live[i];
            if (self->merge_nb[t] < 0) {
                continue;
            }
            const mvt_pkf_pred_t *a = &self->pred[t], *b = &self->pred[self->merge_nb[t]];
            offset_cov(a->h[0] - b->h[0], a->h[1] - b->h[1], self->merge_cov[t]);
            self->merge_wide[t] = c->rules.merge == MVT_MERGE_SHARE;
        }
    }
    for (int i = 0; i < n_live; i++) { /* the colour's shift (app_cost), once per track and camera */
        self->app_shift[live[i]] = mvt_trk_app_cost_min(&self->tracks[live[i]].app);
    }
    const int n_heads = mvt_trk_seen_heads(self, k, heads, who);
    uint8_t two_checked[MVT_MAX_DETECTIONS]; /* blob_holds_two asked of detection d yet (lazily: only
                                                 gated detections' colour is used) */
    memset(two_checked, 0, sizeof(two_checked));
    for (int i = 0; i < n_live; i++) {
        const int t = live[i];
        const int tentative = self->tracks[t].status == MVT_TRACK_TENTATIVE;
        mvt_real g = MVT_R(0.0); /* sum of the gated detections' Gaussian densities, 1/px^2 */
        int any = 0;
        for (int d = 0; d < nd; d++) {
            mvt_real cost = MVT_R(-1.0);
            if (self->pred_ok[t] && self->meas_ok[k][d] && !self->used[k][d]) {
                mvt_pkf_innov_t in;
                const mvt_real *extra =
                    c->rules.merge == MVT_MERGE_SHARE && self->merge_nb[t] >= 0 ? self->merge_cov[t] : NULL;
                if (mvt_pkf_innovation_from(&self->pred[t], &self->meas[k][d], extra, &in) == MVT_OK) {
                    if (c->gate == MVT_GATE_PAPER) {
                        mvt_real dist;
                        if (mvt_pkf_paper_distance(&self->tracks[t].s, cam, c->paper.var_m2, c->paper.gamma,
                                                   &self->meas[k][d], &dist) == MVT_OK &&
                            dist <= c->paper.delta) {
                            cost = dist;
                        }
                    } else if (in.d2 <= c->numerics.gate_chi2) {
                        if (self->chroma_ok[k][d] && !two_checked[d]) {
                            two_checked[d] = 1;
                            if (blob_holds_two(view, d, (const mvt_real(*)[4])heads, n_heads)) {
                                self->chroma_ok[k][d] = 0;
                            }
                        }
                        const mvt_real det = in.S[0] * in.S[2] - in.S[1] * in.S[1];
                        cost = in.d2 + spread_cost(det) + app_cost(self, k, t, d);
                        if (tentative) {
                            g += mvt_trk_density(&in);
                        }
                    }
                }
            }
            self->cost[t][d] = cost;
            any |= cost >= MVT_R(0.0);
        }
        if (self->pred_ok[t] && nd > 0 && !any) {
            self->counters.gated_out++;
        }
        if (tentative && self->pred_ok[t]) {
            /* the likelihood ratio of the view's gated detections, a person there (detected with
             * p_detect at the Gaussian's place, or missed) against clutter spread uniformly at
             * this view's density (the integrated PDA's existence update): on average 1 for a
             * flood's random detections, far more for a person's; 1 - p_detect for an empty gate */
            const mvt_real pd = c->population.p_detect;
            self->ev_llr[t] += MVT_LOG(MVT_R(1.0) - pd + pd * g / self->ev_clutter[k]);
        }
    }
    if (!self->reacq_any) {
        return n_heads;
    }
    /* re-acquisition (mvt_trk_reacquire): a reserved detection is its track's only choice here,
     * and no other track's */
    for (int i = 0; i < n_live; i++) {
        const int t = live[i];
        const int r = self->reacq_det[t][k];
        if (r < 0) {
            continue;
        }
        for (int d = 0; d < nd; d++) {
            if (d != r) {
                self->cost[t][d] = MVT_R(-1.0);
            }
        }
        for (int j = 0; j < n_live; j++) {
            if (live[j] != t) {
                self->cost[live[j]][r] = MVT_R(-1.0);
            }
        }
    }
    return n_heads;
}

/* Solves one cluster (tracks with root r) with the Hungarian method. */
static void solve_cluster(mvt_tracker_t *self, int k, int r, const int live[], int n_live, mvt_real miss,
                          int assign[])
{
    const int nd = self->num_meas[k];
    int nr = 0, nc = 0;
    for (int i = 0; i < n_live; i++) {
        const int t = live[i];
        if (self->cluster[t] >= 0 && find_root(self->cluster, t) == r) {
            self->cl_rows[nr++] = (int16_t)t;
        }
    }
    for (int d = 0; d < nd; d++) {
        if (self->det_first[d] >= 0 && find_root(self->cluster, self->det_first[d]) == r) {
            self->cl_cols[nc++] = (int16_t)d;
        }
    }
    if (nr == 1 && nc == 1) {
        const int t = self->cl_rows[0], d = self->cl_cols[0];
        if (self->cost[t][d] <= miss - self->app_shift[t]) {
            assign[t] = d;
        }
        return;
    }
    const int ncols = nc + nr;
    for (int i = 0; i < nr; i++) {
        mvt_real *row = &self->cl_cost[i * ncols];
        for (int j = 0; j < nc; j++) {
            row[j] = self->cost[self->cl_rows[i]][self->cl_cols[j]];
        }
        for (int j = 0; j < nr; j++) {
            row[nc + j] = i == j ? miss - self->app_shift[self->cl_rows[i]] : MVT_R(-1.0);
        }
    }
    if (mvt_assoc_solve(self->cl_cost, nr, ncols, ncols, self->cl_assign, &self->assoc_ws) != MVT_OK) {
        self->counters.numeric_faults++;
        return;
    }
    for (int i = 0; i < nr; i++) {
        const int j = self->cl_assign[i];
        if (j >= 0 && j < nc) {
            assign[self->cl_rows[i]] = self->cl_cols[j];
        }
    }
}

/* A detection whose blob also holds another person's predicted head (a confirmed or coasting
 * track's, within three standard deviations of the box) is the top of a region two people share.
 * Its top is the head higher in the picture, or a point between two heads at about the same
 * height (a component's top rows span both). Seen from the track it was given to, the point is
 * its head displaced by up to D toward the other head, D the two predictions' image separation:
 * a uniform offset of second moment D D^T / 3 is added to the measurement covariance
 * (merge_cov, as MVT_MERGE_SHARE does for the tracks it updates with one detection), so the
 * update pulls the track along D only as far as the blob says. The nearest such head counts; one
 * clearly lower in the picture than the track's own (top_order) does not, the top being the
 * track's. Without it, a track whose person is hidden in a merged blob took the between-heads
 * point and jumped onto the neighbour (docs/tracking.md, "Merged
 * blobs"). */
static void widen_merged_tops(mvt_tracker_t *self, const mvt_view_t *view, const int live[], int n_live,
                              const int assign[], const mvt_real heads[][4], const int16_t who[], int n_heads)
{
    for (int i = 0; i < n_live; i++) {
        const int t = live[i], d = assign[t];
        if (d < 0 || !mvt_trk_box_ok(view->det[d].box)) {
            continue;
        }
        const mvt_real *ht = self->pred[t].h;
        mvt_real best = MVT_R(-1.0);
        for (int j = 0; j < n_heads; j++) {
            const int u = who[j];
            if (u == t || !mvt_trk_in_box(view->det[d].box, heads[j], heads[j][2], heads[j][3]) ||
                top_order(self, t, u) < 0) {
                continue;
            }
            const mvt_real dx = self->pred[u].h[0] - ht[0], dy = self->pred[u].h[1] - ht[1];
            const mvt_real d2 = dx * dx + dy * dy;
            if (best < MVT_R(0.0) || d2 < best) {
                best = d2;
                offset_cov(dx, dy, self->merge_cov[t]);
            }
        }
        self->merge_wide[t] = best > MVT_R(0.0);
    }
}

void mvt_trk_associate(mvt_tracker_t *self, const mvt_view_t *view, int k, int assign[MVT_MAX_TARGETS],
                       uint8_t merged[MVT_MAX_TARGETS])
{
    int live[MVT_MAX_TARGETS];
    int n_live = 0;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        assign[t] = -1;
        merged[t] = 0;
        self->cluster[t] = -1;
        if (self->tracks[t].id != 0) {
            live[n_live++] = t;
        }
    }
    mvt_real heads[MVT_MAX_TARGETS][4];
    int16_t who[MVT_MAX_TARGETS];
    const int n_heads = hypothesise(self, view, k, live, n_live, heads, who);

    /* clusters: tracks linked by a detection inside both gates */
    const int nd = self->num_meas[k];
    for (int d = 0; d < nd; d++) {
        self->det_first[d] = -1;
    }
    for (int i = 0; i < n_live; i++) {
        const int t = live[i];
        for (int d = 0; d < nd; d++) {
            if (self->cost[t][d] < MVT_R(0.0)) {
                continue;
            }
            if (self->cluster[t] < 0) {
                self->cluster[t] = (int16_t)t;
            }
            if (self->det_first[d] < 0) {
                self->det_first[d] = (int16_t)t;
            } else {
                const int a = find_root(self->cluster, t), b = find_root(self->cluster, self->det_first[d]);
                if (a != b) {
                    self->cluster[a] = (int16_t)b;
                }
            }
        }
    }
    const mvt_real miss = miss_base(self, k);
    for (int i = 0; i < n_live; i++) {
        const int t = live[i];
        if (self->cluster[t] >= 0 && find_root(self->cluster, t) == t) {
            solve_cluster(self, k, t, live, n_live, miss, assign);
        }
    }

    /* merged blobs: a track left without a detection whose gate holds the detection of an
     * unresolved neighbour */
    if (self->cfg.rules.merge == MVT_MERGE_TOP) {
        /* the blob's top is the higher head: a detection the assignment gave to the lower of two
         * unresolved tracks goes to the higher one when it lies in its gate */
        for (int i = 0; i < n_live; i++) {
            const int t = live[i];
            if (assign[t] >= 0 || self->merge_nb[t] < 0) {
                continue;
            }
            for (int j = 0; j < n_live; j++) {
                const int u = live[j];
                mvt_real d2;
                const int d = assign[u];
                if (u == t || d < 0 || self->cost[t][d] < MVT_R(0.0) || !unresolved(self, &self->cams[k], t, u, &d2) ||
                    top_order(self, t, u) >= 0) {
                    continue;
                }
                assign[t] = d;
                assign[u] = -1;
                self->counters.merged_top++;
                break;
            }
        }
    }
    if (self->cfg.rules.merge != MVT_MERGE_OFF) {
        int shared[MVT_MAX_TARGETS];
        for (int i = 0; i < n_live; i++) {
            const int t = live[i];
            shared[t] = -1;
            if (assign[t] >= 0 || self->merge_nb[t] < 0) {
                continue;
            }
            mvt_real best = MVT_R(0.0);
            for (int j = 0; j < n_live; j++) {
                const int u = live[j];
                mvt_real d2;
                const int d = assign[u];
                if (u == t || d < 0 || self->cost[t][d] < MVT_R(0.0) ||
                    !unresolved(self, &self->cams[k], t, u, &d2) ||
                    (self->cfg.rules.merge == MVT_MERGE_TOP && top_order(self, t, u) != 0) ||
                    (self->cfg.rules.merge != MVT_MERGE_SHARE && !ambiguous(self, k, t, u, d))) {
                    continue;
                }
                if (shared[t] < 0 || self->cost[t][d] < best) {
                    shared[t] = d;
                    best = self->cost[t][d];
                }
            }
        }
        for (int i = 0; i < n_live; i++) {
            const int t = live[i];
            if (shared[t] < 0) {
                continue;
            }
            self->used[k][shared[t]] = 1; /* explained: no birth from it */
            for (int j = 0; j < n_live; j++) {
                if (assign[live[j]] == shared[t]) {
                    merged[live[j]] = 1;
                }
            }
            merged[t] = 1;
        }
        for (int i = 0; i < n_live; i++) {
            const int t = live[i];
            if (self->cfg.rules.merge == MVT_MERGE_SHARE) {
                if (shared[t] >= 0) {
                    assign[t] = shared[t];
                }
            } else if (merged[t]) {
                self->counters.merged_ambiguous += assign[t] >= 0;
                assign[t] = -1;
            }
        }
    }
    if (self->cfg.rules.merge == MVT_MERGE_NEITHER || self->cfg.rules.merge == MVT_MERGE_TOP) {
        widen_merged_tops(self, view, live, n_live, assign, (const mvt_real(*)[4])heads, who, n_heads);
    }
    for (int i = 0; i < n_live; i++) {
        if (assign[live[i]] >= 0) {
            self->used[k][assign[live[i]]] = 1;
        }
    }
}
