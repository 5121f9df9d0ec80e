/*
 * mvt_trk_init.c - initiator of the tracker loop: births from detections that no track used.
 *
 * For every pair of observed cameras, detection pairs first pass a cheap epipolar test (distance
 * of one detection to the other's epipolar line, in pixels), then are triangulated, checked
 * against the volume and each view's reprojection error, and gather support from the nearest
 * consistent detection of every other view. The best candidates (most views, then least error)
 * are kept in a bounded list; they are accepted greedily while their detections are still free,
 * re-triangulated robustly, and refused near an existing track. A ghost (two people's rays that
 * happen to cross) rarely finds support in a third view and loses its detections to the
 * better-supported true candidates first; one that survives must still pass M-of-N confirmation.
 */
#include <math.h>
#include <string.h>

#include "mvt_trk.h"

int mvt_trk_inside_volume(const mvt_tracker_config_t *c, const mvt_real x[3])
{
    for (int i = 0; i < 3; i++) {
        if (!(x[i] >= c->volume.min[i] - c->volume.margin_m) || !(x[i] <= c->volume.max[i] + c->volume.margin_m)) {
            return 0;
        }
    }
    return 1;
}

static mvt_real birth_threshold(const mvt_tracker_config_t *c, const mvt_pkf_meas_t *m)
{
    const mvt_real t = c->rules.birth_reproj_sigma * MVT_SQRT(m->var_px2);
    return t > c->rules.birth_min_reproj_px ? t : c->rules.birth_min_reproj_px;
}

static int better(const mvt_birth_cand_t *a, const mvt_birth_cand_t *b)
{
    return a->n > b->n || (a->n == b->n && a->err_px < b->err_px);
}

static void add_candidate(mvt_tracker_t *self, const mvt_birth_cand_t *c, int count)
{
    if (self->num_cand < MVT_MAX_BIRTH_CANDIDATES) {
        self->cand[self->num_cand++] = *c;
        return;
    }
    int worst = 0;
    for (int i = 1; i < self->num_cand; i++) {
        if (better(&self->cand[worst], &self->cand[i])) {
            worst = i;
        }
    }
    self->counters.birth_candidates_dropped += (uint64_t)count;
    if (better(c, &self->cand[worst])) {
        self->cand[worst] = *c;
    }
}

/* Essential matrix of the pair: x_b^T E x_a = 0 in normalised coordinates. */
static void essential(const mvt_camera_t *a, const mvt_camera_t *b, mvt_real E[9])
{
    mvt_real R[9], t[3];
    for (int i = 0; i < 3; i++) { /* R = Rb Ra^T, t = tb - R ta */
        for (int j = 0; j < 3; j++) {
            R[i * 3 + j] = b->R[i * 3 + 0] * a->R[j * 3 + 0] + b->R[i * 3 + 1] * a->R[j * 3 + 1] +
                           b->R[i * 3 + 2] * a->R[j * 3 + 2];
        }
    }
    for (int i = 0; i < 3; i++) {
        t[i] = b->t[i] - (R[i * 3 + 0] * a->t[0] + R[i * 3 + 1] * a->t[1] + R[i * 3 + 2] * a->t[2]);
    }
    for (int j = 0; j < 3; j++) { /* E = [t]x R */
        E[0 * 3 + j] = t[1] * R[2 * 3 + j] - t[2] * R[1 * 3 + j];
        E[1 * 3 + j] = t[2] * R[0 * 3 + j] - t[0] * R[2 * 3 + j];
        E[2 * 3 + j] = t[0] * R[1 * 3 + j] - t[1] * R[0 * 3 + j];
    }
}

static int free_meas(const mvt_tracker_t *self, int k, int d)
{
    return self->meas_ok[k][d] && !self->used[k][d];
}

/* Support of point x from the other observed views: the nearest free consistent detection each;
 * a view with boxes and no such detection that shows x's place in no blob counts as empty. */
static void gather_support(const mvt_tracker_t *self, const mvt_frame_t *frame, const int order[], int n_order,
                           int a, int b, const mvt_real x[3], mvt_birth_cand_t *cand)
{
    const mvt_tracker_config_t *c = &self->cfg;
    for (int oi = 0; oi < n_order; oi++) {
        const int k = order[oi];
        if (k == a || k == b) {
            continue;
        }
        const mvt_camera_t *cam = &self->cams[k];
        mvt_real xc[3];
        mvt_cam_to_camera(cam, x, xc);
        if (!(xc[2] > MVT_R(1e-2))) {
            continue;
        }
        const mvt_real pu = xc[0] / xc[2], pv = xc[1] / xc[2];
        int bd = -1;
        mvt_real be = MVT_R(0.0);
        for (int d = 0; d < self->num_meas[k]; d++) {
            if (!free_meas(self, k, d)) {
                continue;
            }
            const mvt_pkf_meas_t *m = &self->meas[k][d];
            const mvt_real eu = cam->fx * (m->xn[0] - pu), ev = cam->fy * (m->xn[1] - pv);
            const mvt_real e = MVT_SQRT(eu * eu + ev * ev);
            if (e <= birth_threshold(c, m) && (bd < 0 || e < be)) {
                bd = d;
                be = e;
            }
        }
        if (bd >= 0) {
            cand->cam[cand->n] = (int16_t)k;
            cand->det[cand->n] = (int16_t)bd;
            cand->err_px += be;
            cand->n++;
        } else if (self->ev_boxes[k]) {
            /* no detection within the radius and no box holds the place: that view shows it empty.
             * (A view without boxes says nothing: a person merged into another's blob has no
             * detection of their own there either.) */
            const mvt_real r = mvt_trk_birth_radius_px(self, k);
            if (mvt_trk_view_evidence(self, &frame->views[k], k, x, r) == MVT_TRK_EMPTY) {
                cand->empty++;
            }
        }
    }
}

/* The birth odds of a candidate (mvt_tracker_config_t.p_detect): log >= 0 to be born. */
static int birth_odds_ok(const mvt_tracker_t *self, const mvt_birth_cand_t *cand)
{
    uint32_t support = 0u;
    for (int i = 0; i < cand->n; i++) {
        support |= 1u << cand->cam[i];
    }
    return mvt_trk_odds(self, support, cand->empty) >= MVT_R(0.0);
}

static void collect_candidates(mvt_tracker_t *self, const mvt_frame_t *frame, const int order[], int n_order,
                               int count)
{
    const mvt_tracker_config_t *c = &self->cfg;
    self->num_cand = 0;
    for (int ai = 0; ai < n_order; ai++) {
        const int a = order[ai];
        for (int bi = ai + 1; bi < n_order; bi++) {
            const int b = order[bi];
            const mvt_camera_t *cb = &self->cams[b];
            mvt_real E[9];
            essential(&self->cams[a], cb, E);
            for (int i = 0; i < self->num_meas[a]; i++) {
                if (!free_meas(self, a, i)) {
                    continue;
                }
                const mvt_pkf_meas_t *ma = &self->meas[a][i];
                mvt_real l[3];
                for (int r = 0; r < 3; r++) {
                    l[r] = E[r * 3 + 0] * ma->xn[0] + E[r * 3 + 1] * ma->xn[1] + E[r * 3 + 2];
                }
                const mvt_real ln = MVT_SQRT(l[0] * l[0] + l[1] * l[1]);
                if (!(ln > MVT_R(1e-9))) {
                    continue; /* the detection is at the epipole: no line */
                }
                const mvt_real fb = cb->fx > cb->fy ? cb->fx : cb->fy;
                for (int j = 0; j < self->num_meas[b]; j++) {
                    if (!free_meas(self, b, j)) {
                        continue;
                    }
                    const mvt_pkf_meas_t *mb = &self->meas[b][j];
                    const mvt_real epi_px = MVT_FABS(l[0] * mb->xn[0] + l[1] * mb->xn[1] + l[2]) / ln * fb;
                    if (epi_px > birth_threshold(c, ma) + birth_threshold(c, mb)) {
                        continue;
                    }
                    const mvt_tri_obs_t pair[2] = {{a, {ma->xn[0], ma->xn[1]}, ma->var_px2},
                                                   {b, {mb->xn[0], mb->xn[1]}, mb->var_px2}};
                    mvt_real x[3];
                    if (mvt_tri_linear(self->cams, pair, 2, x) != MVT_OK || !mvt_trk_inside_volume(c, x)) {
                        continue;
                    }
                    const mvt_real ea = mvt_tri_reproj_px(self->cams, &pair[0], x);
                    const mvt_real eb = mvt_tri_reproj_px(self->cams, &pair[1], x);
                    if (ea > birth_threshold(c, ma) || eb > birth_threshold(c, mb)) {
                        continue;
                    }
                    mvt_birth_cand_t cand;
                    cand.n = 2;
                    cand.empty = 0;
                    cand.cam[0] = (int16_t)a;
                    cand.det[0] = (int16_t)i;
                    cand.cam[1] = (int16_t)b;
                    cand.det[1] = (int16_t)j;
                    cand.err_px = ea + eb;
                    gather_support(self, frame, order, n_order, a, b, x, &cand);
                    if (cand.n < c->rules.birth_min_views) {
                        continue;
                    }
                    if (!birth_odds_ok(self, &cand)) {
                        self->counters.births_refuted += (uint64_t)count;
                        continue;
                    }
                    add_candidate(self, &cand, count);
                }
            }
        }
    }
}

static int near_existing_track(const mvt_tracker_t *self, const mvt_real x[3])
{
    const mvt_real r2 = self->cfg.rules.birth_min_sep_m * self->cfg.rules.birth_min_sep_m;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        const mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0) {
            continue;
        }
        const mvt_real dx = tr->s.x[0] - x[0], dy = tr->s.x[1] - x[1], dz = tr->s.x[2] - x[2];
        if (dx * dx + dy * dy + dz * dz < r2) {
            return 1;
        }
    }
    return 0;
}

/* Births a track from a candidate. Returns its slot, MVT_MAX_TARGETS when every slot is taken, -1
 * when the candidate is no place for a person (no robust point, outside the volume, near a track). */
static int birth(mvt_tracker_t *self, const mvt_frame_t *frame, const mvt_birth_cand_t *cand)
{
    const mvt_tracker_config_t *c = &self->cfg;
    for (int i = 0; i < cand->n; i++) {
        self->used[cand->cam[i]][cand->det[i]] = 1; /* consumed whatever happens next */
    }
    mvt_real x[3], cov[9];
    uint32_t inl = 0;
    if (!mvt_trk_cand_point(self, cand, x, cov, &inl) || near_existing_track(self, x)) {
        return -1;
    }
    uint32_t bits = 0;
    mvt_app_obs_t obs; /* the colour of its inlier detections */
    obs.n = 0;
    for (int i = 0; i < cand->n; i++) {
        if (inl & (1u << i)) {
            bits |= 1u << cand->cam[i];
            if (self->chroma_ok[cand->cam[i]][cand->det[i]]) {
                obs.a[obs.n][0] = self->chroma[cand->cam[i]][cand->det[i]][0];
                obs.a[obs.n][1] = self->chroma[cand->cam[i]][cand->det[i]][1];
                obs.n++;
            }
        }
    }
    mvt_trk_release_contradicted(self, x, cov, &obs, frame->utime_us); /* its person, born again? */
    int slot = -1;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        if (self->tracks[t].id == 0) {
            slot = t;
            break;
        }
    }
    if (slot < 0) {
        self->counters.births_refused_full++;
        return MVT_MAX_TARGETS;
    }
    mvt_track_t *tr = &self->tracks[slot];
    memset(tr, 0, sizeof(*tr));
    tr->status = c->rules.confirm_hits <= 1 ? MVT_TRACK_CONFIRMED : MVT_TRACK_TENTATIVE;
    tr->id = mvt_trk_recover(self, x, cov, &obs, frame->utime_us, &tr->held); /* a person lost just now? */
    if (tr->id == 0) {
        tr->id = self->next_id++;
        if (self->next_id <= 0) { /* 2^31 births: wrap to 1 rather than reuse 0 or go negative */
            self->next_id = 1;
        }
    }
    if (tr->status == MVT_TRACK_CONFIRMED) {
        mvt_trk_confirm(self, tr);
    }
    mvt_trk_start(self, tr, x, cov, frame->utime_us);
    tr->seen_z = x[2];
    tr->seen_zz = cov[8];
    mvt_trk_app_reset(&tr->app);
    if (tr->held.id != 0 && mvt_trk_app_ok(&tr->held.app)) {
        tr->app = tr->held.app; /* a recovered person's colour, as their old track knew it */
    }
    for (int i = 0; i < obs.n; i++) {
        mvt_trk_app_update(&tr->app, obs.a[i]);
    }
    tr->cameras_used = bits;
    tr->hit_history = 1u;
    tr->last_update_us = frame->utime_us;
    tr->last_explained_us = frame->utime_us;
    tr->last_consistent_us = frame->utime_us;
    tr->last_unrefuted_us = frame->utime_us;
    tr->last_needed_us = frame->utime_us;
    self->counters.births++;
    return slot;
}

void mvt_trk_candidates(mvt_tracker_t *self, const mvt_frame_t *frame, const int order[], int n_order, int count)
{
    collect_candidates(self, frame, order, n_order, count);
    /* best first (insertion sort: stable, bounded by MVT_MAX_BIRTH_CANDIDATES) */
    for (int i = 1; i < self->num_cand; i++) {
        const mvt_birth_cand_t key = self->cand[i];
        int j = i - 1;
        while (j >= 0 && better(&key, &self->cand[j])) {
            self->cand[j + 1] = self->cand[j];
            j--;
        }
        self->cand[j + 1] = key;
    }
}

int mvt_trk_cand_point(mvt_tracker_t *self, const mvt_birth_cand_t *cand, mvt_real x[3], mvt_real cov[9],
                       uint32_t *inliers)
{
    const mvt_tracker_config_t *c = &self->cfg;
    mvt_tri_obs_t obs[MVT_MAX_CAMERAS];
    for (int i = 0; i < cand->n; i++) {
        const mvt_pkf_meas_t *m = &self->meas[cand->cam[i]][cand->det[i]];
        obs[i] = (mvt_tri_obs_t){cand->cam[i], {m->xn[0], m->xn[1]}, m->var_px2};
    }
    int m = 0;
    const mvt_real thr = birth_threshold(c, &self->meas[cand->cam[0]][cand->det[0]]);
    if (mvt_tri_robust(self->cams, obs, cand->n, thr, x, inliers, &m) != MVT_OK || m < c->rules.birth_min_views ||
        !mvt_trk_inside_volume(c, x)) {
        return 0;
    }
    mvt_tri_obs_t in[MVT_MAX_CAMERAS];
    int mi = 0;
    for (int i = 0; i < cand->n; i++) {
        if (*inliers & (1u << i)) {
            in[mi++] = obs[i];
        }
    }
    return mvt_tri_covariance(self->cams, in, mi, x, cov) == MVT_OK;
}

/* The prior odds of this frame's new tracks. The existence test (mvt_trk_delete.c) errs 1 % of the
 * time per track; a flood of false alarms tries hundreds of tracks in a second, and 1 % of them
 * were confirmed ghosts (4 on the daemon's flood test). Of the tracks tried while one could be
 * confirmed (confirm_window frames), at most one is expected to be a person who just came: people
 * do not arrive five a second. With n tried, the prior odds of each are 1 : (n - 1), so its
 * evidence starts at -ln n: a Bonferroni correction of the sequential test, which changes nothing
 * while births come one at a time. n is the larger of this frame's births and the rate of the last
 * MVT_TRK_BIRTH_RATE_S (a flood's births come in bursts, between them a ghost is tried alone). */
static void birth_prior(mvt_tracker_t *self, int64_t now_us, int tried, const int born[], int n_born)
{
    const mvt_real dt = self->birth_rate_us > 0 ? mvt_us_to_s(now_us - self->birth_rate_us) : MVT_R(1e9);
    const mvt_real a = MVT_R(1.0) - MVT_EXP(-(dt > MVT_R(0.0) ? dt : MVT_R(0.0)) / MVT_TRK_BIRTH_RATE_S);
    self->birth_rate += a * ((mvt_real)tried - self->birth_rate);
    self->birth_rate_us = now_us;
    mvt_real n = self->birth_rate * (mvt_real)self->cfg.rules.confirm_window;
    n = n > (mvt_real)tried ? n : (mvt_real)tried;
    if (!(n > MVT_R(1.0))) {
        return;
    }
    const mvt_real prior = MVT_LOG(n);
    for (int i = 0; i < n_born; i++) {
        mvt_track_t *tr = &self->tracks[born[i]];
        if (tr->status == MVT_TRACK_TENTATIVE) {
            tr->exist_llr -= prior;
        }
    }
}

void mvt_trk_initiate(mvt_tracker_t *self, const mvt_frame_t *frame, const int order[], int n_order)
{
    mvt_trk_candidates(self, frame, order, n_order, 1);
    int born[MVT_MAX_TARGETS], n_born = 0, tried = 0;
    for (int i = 0; i < self->num_cand; i++) {
        const mvt_birth_cand_t *cand = &self->cand[i];
        int free_all = 1;
        for (int v = 0; v < cand->n && free_all; v++) {
            free_all = !self->used[cand->cam[v]][cand->det[v]];
        }
        if (!free_all) {
            continue;
        }
        const int slot = birth(self, frame, cand);
        tried += slot >= 0;
        if (slot >= 0 && slot < MVT_MAX_TARGETS) {
            born[n_born++] = slot;
        }
    }
    birth_prior(self, frame->utime_us, tried, born, n_born);
}
