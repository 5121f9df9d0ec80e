/*
 * mvt_body_explain.c - what each of camera k's blobs is: a track's head, a fragment of a tracked
 * body, or unexplained (clutter, or a person nobody tracks yet).
 *
 * Heads: one global assignment per camera (mvt_assoc_solve_own, rows the tracks in front of the
 * camera, columns the blobs and one "missed" column per track). Track t exists and shows its head
 * with probability r p, r its existence, p its detection probability here (mvt_body_vis.c); the head
 * is then the blob at innovation y with the motion model's density (mvt_body_head_density: the
 * person's N(y; 0, S) inside the chi-square gate, or displaced within outlier_radius_px), while
 * clutter lies anywhere in the picture with density lambda (mvt_body_clutter_density). Giving blob
 * d to track t rather than leaving t missed and d clutter gains ln(r p N / lambda) - ln(1 - r p);
 * the assignment maximises the sum of the gains.
 * Fragments: each blob's top has a density of the bodies' fragments (mvt_body_fragment_density:
 * the camera's learnt fragments per body over the silhouette and the floor by the feet). A blob
 * left over whose top lies on a tracked silhouette past its head, or by its feet, is part of that
 * body (a torso under a hole, legs, a head split from its shoulders, a shadow) when that density
 * beats clutter's: it is nobody's head and no new person. Among several such bodies the likeliest
 * present takes it.
 * Merged blobs: a track left with neither whose predicted head lies in the box of a blob another
 * body explains (its head or its fragment tops it), under that top, and on the blob's foreground
 * where the camera sent its mask, may be inside that blob: the blob is its host. Of several such
 * blobs (neighbours' boxes overlap), the one holding most of its silhouette hosts it, whatever the
 * order the camera lists them in.
 * Mask tops: a shown track with no blob for its head takes the mask's top in its own column as
 * its head where there is one (mask_head); one whose blob's top lies clearly below that top, within
 * a head's height, takes it too, and the blob is its piece under a cut.
 * Cost O(T D) gating + O(T^2 (T + D)) assignment + the mask tops' bands; memory: the tracker's
 * workspaces.
 */
#include "mvt_body.h"

#include "mvt_mask.h"

#include <math.h>
#include <stddef.h>

/* The area of silhouette sil (u0 v0 u1 v1) inside box b, px^2: of several blobs that may hold a
 * body, the one holding most of it hosts it (blobs of people side by side overlap). */
static mvt_real silhouette_inside(const mvt_real sil[4], const mvt_real b[4])
{
    const mvt_real w = (sil[2] < b[2] ? sil[2] : b[2]) - (sil[0] > b[0] ? sil[0] : b[0]);
    const mvt_real hh = (sil[3] < b[3] ? sil[3] : b[3]) - (sil[1] > b[1] ? sil[1] : b[1]);
    return w > MVT_R(0.0) && hh > MVT_R(0.0) ? w * hh : MVT_R(0.0);
}

/* Gains are offset by this constant to make the solver's costs non-negative (it forbids < 0). */
#define GAIN_OFFSET MVT_R(1000.0)

/* Track t, likely present: where camera k sent its foreground mask, the head is the mask's top in
 * its own column when there is one (a blob reports
 * one top, the top-most of the region, so the head of a person merged with another, or cut from
 * its body by a hole, is in no blob's point but stands out of the outline). The top must be no
 * blob's reported point (association had its say) and on no other likely-present body's
 * silhouette (where the outline is that body's). Asked of a track with no blob for its head, and of
 * one whose blob's top may be a cut below its head. Fills ws->top[t] and uv (raw pixels); 1 when
 * found. */
static int mask_head(mvt_tracker_t *self, const mvt_view_t *view, int k, int t, mvt_real uv[2])
{
    const mvt_camera_t *cam = &self->cams[k];
    const mvt_track_t *tr = &self->tracks[t];
    mvt_body_ws_t *ws = &self->body;
    mvt_pkf_pred_t p = self->pred[t]; /* the mask is in raw pixels: the Jacobian form's prediction */
    if (view->mask == NULL || view->mask->width < 1 || tr->s.x[2] < MVT_TRK_MIN_HEAD_M ||
        (p.lin != MVT_PKF_JACOBIAN && mvt_pkf_predict_obs(&tr->s, cam, MVT_PKF_JACOBIAN, &p) != MVT_OK)) {
        return 0;
    }
    const mvt_real s = (mvt_real)view->mask->scale;
    const mvt_real sig2 = cam->sigma_px * cam->sigma_px + s * s; /* the detector's noise and a mask pixel */
    const mvt_real sig = MVT_SQRT(sig2);
    const mvt_real su = MVT_SQRT(p.hph[0] + sig2), sv = MVT_SQRT(p.hph[2] + sig2);
    const mvt_real px_per_m = cam->fx / p.depth_m;
    if (!mvt_mask_fg_near(view->mask, p.h, MVT_R(3.0) * su) ||
        !mvt_mask_top_in_band(view->mask, p.h[0], px_per_m * MVT_TRK_HEAD_HALFWIDTH_M + su, p.h[1] - MVT_R(3.0) * sv,
                              p.h[1] + MVT_R(3.0) * sv, px_per_m * MVT_TRK_TOP_MAX_WIDTH_M + MVT_R(2.0) * s,
                              px_per_m * MVT_TRK_TOP_CLEAR_M, uv)) {
        return 0;
    }
    for (int d = 0; d < self->num_meas[k]; d++) {
        const mvt_real du = uv[0] - view->det[d].u, dv = uv[1] - view->det[d].v;
        const mvt_real var = self->meas_ok[k][d] ? self->meas[k][d].var_px2 : sig2;
        if (du * du + dv * dv < MVT_R(9.0) * (sig2 + var)) {
            return 0;
        }
    }
    for (int j = 0; j < MVT_MAX_TARGETS; j++) {
        if (j != t && self->tracks[j].id != 0 && self->pred_ok[j] && self->tracks[j].exist_lo > MVT_R(0.0) &&
            mvt_body_on_silhouette(ws->axis[k][j], uv, sig)) {
            return 0;
        }
    }
    mvt_pkf_innov_t in;
    if (mvt_pkf_meas_make(cam, uv, sig, &ws->top[t]) != MVT_OK ||
        mvt_pkf_innovation_from(&self->pred[t], &ws->top[t], NULL, &in) != MVT_OK || !(in.d2 <= MVT_TRK_TOP_GATE_CHI2)) {
        return 0;
    }
    return 1;
}

void mvt_body_explain(mvt_tracker_t *self, const mvt_view_t *view, int k)
{
    mvt_body_ws_t *ws = &self->body;
    const int nd = self->num_meas[k];
    int16_t rows[MVT_MAX_TARGETS];
    int nr = 0;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        ws->assign[t] = -1;
        ws->frag[t] = -1;
        ws->host[t] = -1;
        ws->top_ok[t] = 0;
        if (self->tracks[t].id != 0 && self->pred_ok[t]) {
            rows[nr++] = (int16_t)t;
        }
    }
    for (int d = 0; d < MVT_MAX_DETECTIONS; d++) {
        ws->owner[d] = -1;
        ws->head_of[k][d] = -1;
    }
    {
        /* this frame's blobs (all the camera sent, kept or not) beyond the heads it may show */
        int shown = 0;
        for (int i = 0; i < nr; i++) {
            shown += ws->pd[rows[i]] > MVT_R(0.0);
        }
        const int sent = view->num_offered > nd ? view->num_offered : nd;
        ws->clutter_now[k] = sent > shown ? (mvt_real)(sent - shown) : MVT_R(0.0);
    }
    const mvt_real lambda = mvt_body_clutter_density(self, k);
    /* each blob's top as a fragment of the bodies likely present that it lies on: each such body's
     * density (mvt_body_fragment_density) is its scale over its silhouette, found once per body;
     * first against the box its fragments lie in (most blobs are far from most bodies) */
    for (int d = 0; d < nd; d++) {
        ws->frag_dens[d] = MVT_R(0.0);
    }
    for (int i = 0; i < nr; i++) {
        const int t = rows[i];
        if (!mvt_body_fragment_possible(self, k, t)) {
            continue;
        }
        const mvt_real scale = mvt_body_fragment_scale(self, k, t);
        const mvt_real *ax = ws->axis[k][t];
        mvt_real box[4];
        mvt_body_fragment_bounds(ax, box);
        /* the blobs in the box listed first, without a branch per blob (which the processor
         * would mispredict often: whether a blob lies there is the data's) */
        int16_t near[MVT_MAX_DETECTIONS];
        int n_near = 0;
        for (int d = 0; d < nd; d++) {
            const mvt_real u = view->det[d].u, v = view->det[d].v;
            near[n_near] = (int16_t)d;
            n_near += (self->meas_ok[k][d] != 0) & (u >= box[0]) & (u <= box[2]) & (v >= box[1]) & (v <= box[3]);
        }
        for (int q = 0; q < n_near; q++) {
            const int d = near[q];
            const mvt_real uv[2] = {view->det[d].u, view->det[d].v};
            if (mvt_body_fragment_of(ax, uv)) {
                ws->frag_dens[d] += scale;
            }
        }
    }
    if (nr > 0 && nd > 0) {
        /* The assignment: a row per track with a blob it may have made (its gain over a miss),
         * detections' columns then one miss column per row, open to that row alone. A track with no
         * such blob takes its miss, the only column open to it, which no other row can reach: it is
         * left out of the solve, which changes no other row's assignment. */
        const int stride = nd + nr;
        mvt_real *cost = self->cl_cost;
        int16_t live[MVT_MAX_TARGETS];
        int nl = 0;
        const int chi2 = self->cfg.gate == MVT_GATE_CHI2;
        const mvt_real r_out2 = self->cfg.motion.outlier_radius_px * self->cfg.motion.outlier_radius_px;
        for (int i = 0; i < nr; i++) {
            const int t = rows[i];
            const mvt_real rp = mvt_body_prob(self->tracks[t].exist_lo) * ws->pd[t];
            if (!(rp > MVT_R(0.0))) {
                continue;
            }
            const mvt_real miss = MVT_LOG(MVT_R(1.0) - rp);
            mvt_real *row = &cost[nl * stride];
            int any = 0;
            for (int d = 0; d < nd; d++) {
                row[d] = MVT_R(-1.0);
            }
            const mvt_pkf_pred_t *pr = &self->pred[t];
            /* a blob farther than the displaced radius and than the gate could reach along S's
             * longest axis (its largest eigenvalue is at most its trace) has density 0 here:
             * skipped before its innovation is computed, the same assignment at a fraction of the
             * cost (most blobs are far from most heads) */
            const mvt_real gate = self->cfg.numerics.gate_chi2;
            const mvt_real far2 = chi2 ? MVT_R(1.01) * gate * (pr->hph[0] + pr->hph[2]) : MVT_R(-1.0);
            /* (listed first without a branch per blob, as the fragments' above) */
            int16_t near[MVT_MAX_DETECTIONS];
            int n_near = 0;
            const int jac = pr->lin == MVT_PKF_JACOBIAN;
            for (int d = 0; d < nd; d++) {
                const mvt_real *z = jac ? self->meas[k][d].raw : self->meas[k][d].ideal;
                const mvt_real y0 = z[0] - pr->h[0], y1 = z[1] - pr->h[1];
                const mvt_real y2 = y0 * y0 + y1 * y1;
                const int far = chi2 & (y2 > r_out2) & (y2 > far2 + MVT_R(2.02) * gate * self->meas[k][d].var_px2);
                near[n_near] = (int16_t)d;
                n_near += (self->meas_ok[k][d] != 0) & !far;
            }
            for (int q = 0; q < n_near; q++) {
                const int d = near[q];
                mvt_pkf_innov_t in;
                if (mvt_pkf_innovation_from(pr, &self->meas[k][d], NULL, &in) != MVT_OK) {
                    continue;
                }
                const mvt_real dens = mvt_body_head_density(self, &in, mvt_body_gated(self, t, k, d, &in));
                if (!(dens > MVT_R(0.0))) {
                    continue;
                }
                mvt_real gain = MVT_LOG(rp * dens / lambda) - miss;
                if (!(gain > MVT_R(0.0))) {
                    continue;
                }
                gain = gain < GAIN_OFFSET ? gain : GAIN_OFFSET;
                row[d] = GAIN_OFFSET - gain;
                any = 1;
            }
            if (any) {
                live[nl++] = (int16_t)t;
            }
        }
        int r2c[MVT_MAX_TARGETS];
        for (int i = 0; i < nl; i++) {
            for (int j = 0; j < nl; j++) {
                cost[i * stride + nd + j] = i == j ? GAIN_OFFSET : MVT_R(-1.0);
            }
        }
        if (nl > 0 && mvt_assoc_solve_own(cost, nl, nd + nl, stride, r2c, &self->assoc_ws) == MVT_OK) {
            for (int i = 0; i < nl; i++) {
                if (r2c[i] >= 0 && r2c[i] < nd) {
                    ws->assign[live[i]] = (int16_t)r2c[i];
                    ws->owner[r2c[i]] = live[i];
                    ws->head_of[k][r2c[i]] = live[i];
                }
            }
        }
    }
    /* fragments among the blobs left over */
    for (int d = 0; d < nd; d++) {
        if (ws->owner[d] >= 0 || !self->meas_ok[k][d]) {
            continue;
        }
        const mvt_real uv[2] = {view->det[d].u, view->det[d].v};
        int best = -1;
        for (int i = 0; i < nr; i++) {
            const int t = rows[i];
            if (mvt_body_fragment_of(ws->axis[k][t], uv) &&
                (best < 0 || self->tracks[t].exist_lo > self->tracks[best].exist_lo)) {
                best = t;
            }
        }
        if (best >= 0 && ws->frag_dens[d] >= lambda) { /* a fragment rather than clutter */
            ws->owner[d] = (int16_t)best;
            if (ws->frag[best] < 0) {
                ws->frag[best] = (int16_t)d;
            }
            self->counters.fragments++;
        } else {
            ws->free_det[k][d] = 1;
        }
    }
    /* merged blobs: a track left without its head or a fragment whose predicted head lies in the
     * box of a blob that another body likely present explains (its head or a fragment of it tops
     * the blob), under that top, and on the blob's foreground where the camera sent its mask, may
     * be inside it */
    const int masked = view->mask != NULL && view->mask->width > 0;
    for (int i = 0; i < nr; i++) {
        const int t = rows[i];
        if (ws->assign[t] >= 0 || ws->frag[t] >= 0 || !(self->tracks[t].exist_lo > MVT_R(0.0))) {
            continue; /* a track not yet likely present earns its existence from its own blobs */
        }
        const mvt_real *h = ws->head[t];
        mvt_real best = MVT_R(-1.0);
        for (int d = 0; d < nd; d++) {
            const int o = ws->owner[d];
            const mvt_detection_t *det = &view->det[d];
            if (o < 0 || o == t || !(self->tracks[o].exist_lo > MVT_R(0.0)) || det->v > h[1] ||
                !mvt_trk_in_box(det->box, h, MVT_R(0.0), MVT_R(0.0))) {
                continue;
            }
            const mvt_real held = silhouette_inside(ws->sil[k][t], det->box);
            if (held > best) {
                best = held;
                ws->host[t] = (int16_t)d;
            }
        }
        const mvt_real r_fg = MVT_R(3.0) * self->cams[k].sigma_px; /* the head's own pixels */
        if (ws->host[t] >= 0 && masked && !mvt_mask_fg_near(view->mask, h, r_fg)) {
            ws->host[t] = -1; /* the mask shows background at the head: no body hidden there */
        }
    }
    /* heads that stand out of the mask where no blob reports them; a blob given as a head whose top
     * lies clearly below such a head in the track's own column is not the head's (a head top has
     * background above it): it is the body's piece under a cut, and the mask's top is the head */
    for (int i = 0; i < nr; i++) {
        const int t = rows[i];
        const int32_t st = self->tracks[t].status;
        if (!(self->tracks[t].exist_lo > MVT_R(0.0)) || (st != MVT_TRACK_CONFIRMED && st != MVT_TRACK_COASTING)) {
            continue;
        }
        mvt_real uv[2];
        const int d = ws->assign[t];
        if (d < 0) {
            ws->top_ok[t] = (uint8_t)mask_head(self, view, k, t, uv);
        } else if (masked && mask_head(self, view, k, t, uv)) {
            const mvt_real s = (mvt_real)view->mask->scale;
            const mvt_real sig = MVT_SQRT(self->cams[k].sigma_px * self->cams[k].sigma_px + s * s);
            const mvt_real gap = view->det[d].v - uv[1];
            const mvt_real head_px = self->cams[k].fx * MVT_TRK_TOP_CLEAR_M / self->pred[t].depth_m;
            if (gap > MVT_R(3.0) * sig && gap < head_px + MVT_R(3.0) * sig) {
                ws->assign[t] = -1;
                ws->head_of[k][d] = -1;
                ws->frag[t] = (int16_t)d; /* owner stays t */
                ws->top_ok[t] = 1;
                self->counters.fragments++;
            }
        }
    }
}
