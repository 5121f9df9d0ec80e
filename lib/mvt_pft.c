#include "mvt_pft.h"

#include <math.h>
#include <string.h>

#include "mvt_trk.h"

void mvt_pft_config_default(mvt_pft_config_t *c)
{
    MVT_ASSERT(c != NULL);
    memset(c, 0, sizeof(*c));
    mvt_tracker_config_default(&c->det); /* the blob tracker proposes births: the body model */
    c->model.sigma_px = MVT_R(4.0);
    c->model.p_b = MVT_R(0.2);
    c->model.sigma_h = MVT_R(0.05);
    c->model.sigma_s = MVT_R(0.1);
    c->model.h_b = MVT_R(0.5);
    c->model.s_b = MVT_R(0.5);
    c->noise.pos_m2s = MVT_R(0.02);
    c->noise.vel_m2s3 = MVT_R(1.0);
    c->noise.colour_1s = MVT_R(0.005);
    c->noise.z_renew = MVT_R(0.2);
    c->noise.pos_z_m2s = MVT_R(0.002);
    c->noise.vel_z_m2s3 = MVT_R(0.01);
    c->noise.z_min = MVT_R(0.0);
    c->noise.z_max = MVT_R(2.2);
    c->column = 1;
    c->body.above_m = MVT_R(0.06);
    c->body.head_m = MVT_R(0.06);
    c->body.torso_frac = MVT_R(0.7);
    c->body.legs_frac = MVT_R(0.3);
    c->body.min_top_m = MVT_R(1.1);
    c->body.face_m = MVT_R(0.16);
    c->body.clear_m = MVT_R(0.9);
    c->num_particles = MVT_MAX_PARTICLES;
    c->use_colour = 1;
    c->lik_exponent = MVT_R(0.5);
    c->ess_fraction = MVT_R(0.5);
    c->p_h = MVT_R(0.95);
    c->head_quantile = MVT_R(0.97);
    c->exclusion_m = MVT_R(0.5);
    c->exclusion_log = MVT_R(8.0);
    c->birth_sep_m = MVT_R(0.5);
    c->birth_min_height_m = MVT_R(1.0);
    c->birth_xy_std_m = MVT_R(0.1);
    c->dup_dist_m = MVT_R(0.2);
    c->support_fraction = MVT_R(0.25);
    c->support_min_views = 2;
    c->lost_s = MVT_R(0.5);
    c->confirm_frames = 5;
    c->tentative_lost_s = MVT_R(0.2);
    c->recover_s = MVT_R(3.0);
    c->share_pixels = 1;
    c->body_radius_m = MVT_R(0.25);
    c->seed = 1u;
}

static int in_range(mvt_real x, mvt_real lo, mvt_real hi)
{
    return x >= lo && x <= hi;
}

mvt_err_t mvt_pft_init(mvt_pft_t *self, const mvt_pft_config_t *cfg, const mvt_camera_t *cams, int num_cameras)
{
    MVT_ASSERT(self != NULL && cfg != NULL && cams != NULL);
    const mvt_pf_noise_t *q = &cfg->noise;
    if (cfg->num_particles < 16 || cfg->num_particles > MVT_MAX_PARTICLES || !(q->pos_m2s >= MVT_R(0.0)) ||
        !(q->vel_m2s3 >= MVT_R(0.0)) || !(q->colour_1s >= MVT_R(0.0)) ||
        !in_range(q->z_renew, MVT_R(0.0), MVT_R(1.0)) || !(q->z_max >= q->z_min) || !isfinite(q->z_min) ||
        !isfinite(q->z_max) || !isfinite(q->pos_m2s) ||
        !isfinite(q->vel_m2s3) || !isfinite(q->colour_1s) || !(q->pos_z_m2s >= MVT_R(0.0)) ||
        !(q->vel_z_m2s3 >= MVT_R(0.0)) || !isfinite(q->pos_z_m2s) || !isfinite(q->vel_z_m2s3) || !(cfg->ess_fraction > MVT_R(0.0)) ||
        !in_range(cfg->ess_fraction, MVT_R(0.0), MVT_R(1.0)) || !(cfg->p_h > MVT_R(0.0)) ||
        !in_range(cfg->p_h, MVT_R(0.0), MVT_R(1.0)) || !(cfg->head_quantile > MVT_R(0.0)) ||
        !in_range(cfg->head_quantile, MVT_R(0.0), MVT_R(1.0)) || !in_range(cfg->exclusion_m, MVT_R(0.0), MVT_R(10.0)) ||
        !in_range(cfg->exclusion_log, MVT_R(0.0), MVT_R(1e3)) || !(cfg->birth_sep_m > MVT_R(0.0)) || !isfinite(cfg->birth_min_height_m) ||
        !(cfg->birth_xy_std_m > MVT_R(0.0)) || !in_range(cfg->dup_dist_m, MVT_R(0.0), MVT_R(10.0)) ||
        !(cfg->support_fraction > MVT_R(0.0)) || !in_range(cfg->support_fraction, MVT_R(0.0), MVT_R(1.0)) ||
        cfg->support_min_views < 1 || !(cfg->lost_s > MVT_R(0.0)) || !isfinite(cfg->lost_s) ||
        !isfinite(cfg->birth_sep_m) || !(cfg->lik_exponent > MVT_R(0.0)) || !(cfg->lik_exponent <= MVT_R(1.0)) || !isfinite(cfg->birth_xy_std_m) ||
        !(cfg->recover_s >= MVT_R(0.0)) || !isfinite(cfg->recover_s)) {
        return MVT_ERR_INVALID;
    }
    const mvt_pf_body_t *b = &cfg->body;
    if ((cfg->column != 0 && cfg->column != 1) || (cfg->share_pixels != 0 && cfg->share_pixels != 1) ||
        !in_range(cfg->body_radius_m, MVT_R(0.01), MVT_R(2.0)) || cfg->confirm_frames < 1 || !(cfg->tentative_lost_s > MVT_R(0.0)) ||
        !isfinite(cfg->tentative_lost_s) || !in_range(b->min_top_m, MVT_R(0.0), MVT_R(10.0))) {
        return MVT_ERR_INVALID;
    }
    if (cfg->column && (!in_range(b->above_m, MVT_R(1e-3), MVT_R(1.0)) || !in_range(b->head_m, MVT_R(1e-3), MVT_R(1.0)) ||
                        !in_range(b->face_m, MVT_R(0.0), MVT_R(1.0)) || !in_range(b->clear_m, MVT_R(0.0), MVT_R(3.0)) ||
                        !in_range(b->torso_frac, MVT_R(0.01), MVT_R(0.99)) || !in_range(b->legs_frac, MVT_R(0.01), MVT_R(0.99)))) {
        return MVT_ERR_INVALID;
    }
    memset(self, 0, sizeof(*self));
    self->cfg = *cfg;
    if (mvt_pf_tables_init(&self->tab, &cfg->model) != MVT_OK) {
        return MVT_ERR_INVALID;
    }
    const mvt_err_t err = mvt_tracker_init(&self->det, &cfg->det, cams, num_cameras);
    if (err != MVT_OK) {
        return err;
    }
    for (int k = 0; k < num_cameras; k++) {
        mvt_pf_fov_init(&self->fovs[k], &self->det.cams[k], MVT_R(0.05));
    }
    mvt_rng_seed(&self->rng, cfg->seed, 0x6d7674726b5066ULL);
    self->next_id = 1;
    return MVT_OK;
}

static int popcount(uint32_t x)
{
    int n = 0;
    for (; x != 0u; x &= x - 1u) { /* at most 32 rounds */
        n++;
    }
    return n;
}

/* A new target around a confirmed blob track: head-top hypotheses around its head point (column
 * model) or points of the body below it (point model); colour sampled from the pixels the scored
 * points project onto. */
static void birth(mvt_pft_t *self, mvt_pft_target_t *t, const mvt_track_out_t *src, int64_t now_us)
{
    const mvt_pft_config_t *c = &self->cfg;
    mvt_pf_pool_t *p = &t->pool;
    const int num_cams = self->det.num_cameras;
    memset(t, 0, sizeof(*t) - sizeof(t->pool));
    t->id = 0;
    for (int r = 0; r < MVT_MAX_TARGETS && src->id > 0; r++) { /* the same person, lost by the filter */
        if (self->lost[r].id != 0 && self->lost[r].blob_id == src->id && self->lost[r].until_us >= now_us) {
            t->id = self->lost[r].id;
            t->recover_until_us = self->lost[r].until_us;
            self->lost[r].id = 0;
            break;
        }
    }
    if (t->id == 0) {
        t->id = self->next_id;
        self->next_id = self->next_id == INT32_MAX ? 1 : self->next_id + 1;
    }
    t->blob_id = src->id;
    t->status = c->confirm_frames > 1 ? MVT_TRACK_TENTATIVE : MVT_TRACK_CONFIRMED;
    t->last_supported_us = now_us;
    p->n = c->num_particles;
    const mvt_real top = src->pos_m[2] > MVT_R(0.2) ? src->pos_m[2] : MVT_R(0.2);
    for (int i = 0; i < p->n; i++) {
        mvt_real g[6];
        mvt_rng_normal2(&self->rng, g);
        mvt_rng_normal2(&self->rng, g + 2);
        mvt_rng_normal2(&self->rng, g + 4);
        p->x[i] = src->pos_m[0] + c->birth_xy_std_m * g[0];
        p->y[i] = src->pos_m[1] + c->birth_xy_std_m * g[1];
        p->z[i] = c->column ? top + c->birth_xy_std_m * g[4] : MVT_R(0.05) + (top - MVT_R(0.05)) * mvt_rng_uniform(&self->rng);
        p->vx[i] = src->vel_ms[0] + MVT_R(0.2) * g[2];
        p->vy[i] = src->vel_ms[1] + MVT_R(0.2) * g[3];
        p->vz[i] = MVT_R(0.0);
        p->h[i] = mvt_rng_uniform(&self->rng);
        p->s[i] = mvt_rng_uniform(&self->rng);
        p->w[i] = MVT_R(1.0) / (mvt_real)p->n;
        for (int j = 0; j < num_cams; j++) {
            const int k = (i + j) % num_cams;
            const mvt_pf_image_t *img = &self->images[k];
            if (img->width < 1 || !img->mask->has_colour) {
                continue;
            }
            /* the colour state scores the particle (point model) or the torso point (column) */
            const mvt_real xw[3] = {p->x[i], p->y[i], c->column ? c->body.torso_frac * p->z[i] : p->z[i]};
            mvt_real uv[2];
            if (mvt_cam_project(&self->det.cams[k], xw, uv, NULL) != MVT_OK) {
                continue;
            }
            const int idx = mvt_pf_image_index(img, uv[0], uv[1]);
            if (idx < 0 || !img->mask->fg[idx]) {
                continue;
            }
            p->h[i] = ((mvt_real)img->mask->hue[idx] + mvt_rng_uniform(&self->rng)) / MVT_R(256.0);
            p->s[i] = (mvt_real)img->mask->sat[idx] / MVT_R(255.0);
            break;
        }
    }
    /* a first estimate so that the exclusion prior and output have something this frame */
    mvt_pf_estimate(p, c->p_h, c->column ? MVT_R(0.0) : c->head_quantile, self->order, &t->est);
    self->counters.births++;
}

/* The head: scanning down the column above the particles' mean (x, y), the first height that
 * projects onto foreground (D above the midpoint of p_B and 1) in at least half of the cameras
 * that sent masks (at least one). The particles fill the body's core: where the mask's blur makes
 * every view uncertain (the top of the head), few of them survive. O(steps * C). */
static mvt_real column_top(const mvt_pft_t *self, const mvt_real xy[2], mvt_real fallback, int masks)
{
    const mvt_pf_noise_t *q = &self->cfg.noise;
    const int need = masks > 1 ? (masks + 1) / 2 : 1;
    const mvt_real step = MVT_R(0.01);
    const int steps = (int)((q->z_max - q->z_min) / step);
    for (int j = 0; j <= steps && j < 4096; j++) {
        const mvt_real xw[3] = {xy[0], xy[1], q->z_max - step * (mvt_real)j};
        int votes = 0;
        for (int k = 0; k < self->det.num_cameras; k++) {
            votes += mvt_pf_point_on_fg(&self->det.cams[k], &self->fovs[k], &self->images[k], &self->tab, xw) > 0;
        }
        if (votes >= need) {
            return xw[2];
        }
    }
    return fallback;
}

/* a (of strength sa) before b (of strength sb): stronger, then confirmed or coasting before
 * tentative, then the older identity (lower id: identities count up) */
static int goes_first(const mvt_pft_target_t *a, mvt_real sa, const mvt_pft_target_t *b, mvt_real sb)
{
    const int ta = a->status == MVT_TRACK_TENTATIVE, tb = b->status == MVT_TRACK_TENTATIVE;
    if (sa > sb || sa < sb) {
        return sa > sb;
    }
    return ta != tb ? ta < tb : a->id < b->id;
}

static int stronger(const mvt_pft_target_t *a, const mvt_pft_target_t *b)
{
    return goes_first(a, a->strength, b, b->strength);
}

/* Strength with this frame's evidence folded in, before weighting: the share of the cameras that
 * see it in which three points of its predicted body (legs, middle, torso) mostly fall on
 * foreground, smoothed into strength as the weighting will. A target whose person has just left
 * (or a ghost) ranks after a person seen where predicted, however alike their histories. The
 * strength itself is not changed. O(C). */
static mvt_real rank_strength(const mvt_pft_t *self, int t, mvt_real dt)
{
    const mvt_pft_target_t *a = &self->targets[t];
    const mvt_real *m = self->centre[t];
    const mvt_real frac[3] = {MVT_R(0.3), MVT_R(0.5), MVT_R(0.7)}; /* of the head top's height */
    int seen = 0, on = 0;
    for (int k = 0; k < self->det.num_cameras; k++) {
        int n_seen = 0, n_on = 0;
        for (int j = 0; j < 3; j++) {
            const mvt_real xw[3] = {m[0], m[1], frac[j] * a->est.head_z};
            const int r = mvt_pf_point_on_fg(&self->det.cams[k], &self->fovs[k], &self->images[k], &self->tab, xw);
            n_seen += r >= 0;
            n_on += r > 0;
        }
        seen += n_seen > 0;
        on += n_seen > 0 && 2 * n_on > n_seen;
    }
    if (seen == 0) {
        return a->strength;
    }
    return a->strength + (MVT_R(1.0) - MVT_EXP(-dt)) * ((mvt_real)on / (mvt_real)seen - a->strength);
}

/* The order the targets are weighted in when pixels are shared out, strongest first
 * (rank_strength, then confirmed before tentative, then the older). A target that lost its person,
 * or a ghost, has had little support for a while, or none this frame, and comes after the
 * person's own target, so it cannot take that person's pixels. Insertion sort, O(T^2 + T C);
 * sort 0: slot order. Returns the number of live targets. */
static int rank_targets(mvt_pft_t *self, int sort, mvt_real dt)
{
    int n = 0;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        if (self->targets[t].id != 0) {
            self->rank_key[t] = sort ? rank_strength(self, t, dt) : MVT_R(0.0);
            self->rank[n++] = (int16_t)t;
        }
    }
    for (int i = 1; i < n && sort; i++) {
        const int16_t cur = self->rank[i];
        int j = i - 1;
        for (; j >= 0; j--) { /* the weaker ones move right */
            const int16_t o = self->rank[j];
            if (goes_first(&self->targets[o], self->rank_key[o], &self->targets[cur], self->rank_key[cur])) {
                break;
            }
            self->rank[j + 1] = o;
        }
        self->rank[j + 1] = cur;
    }
    return n;
}

/* Claims target a's silhouette in every camera with an image: the mask box of a vertical cylinder
 * of body_radius_m from the floor to just above its head top (the box of 8 points on its rims
 * that project), at the camera depth of its middle; the nearer claim keeps a pixel. A camera
 * where the head top does not project claims nothing. O(C + box pixels). */
static void claim_silhouette(mvt_pft_t *self, const mvt_pft_target_t *a)
{
    const mvt_pft_config_t *c = &self->cfg;
    const mvt_real r = c->body_radius_m;
    const mvt_real x = a->est.mean[0], y = a->est.mean[1];
    const mvt_real top = a->est.head_z + (c->column ? c->body.above_m : MVT_R(0.0));
    for (int k = 0; k < self->det.num_cameras; k++) {
        mvt_pf_claims_t *cl = &self->claims[k];
        const mvt_pf_image_t *img = &self->images[k];
        const mvt_camera_t *cam = &self->det.cams[k];
        if (cl->width < 1) {
            continue;
        }
        const mvt_real head[3] = {x, y, top};
        mvt_real uv[2];
        if (mvt_cam_project(cam, head, uv, NULL) != MVT_OK) {
            continue;
        }
        mvt_real u0 = uv[0], u1 = uv[0], v0 = uv[1], v1 = uv[1];
        static const int8_t dir[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
        for (int j = 0; j < 8; j++) {
            const mvt_real p[3] = {x + r * (mvt_real)dir[j & 3][0], y + r * (mvt_real)dir[j & 3][1],
                                   j < 4 ? top : MVT_R(0.0)};
            if (mvt_cam_project(cam, p, uv, NULL) == MVT_OK) {
                u0 = uv[0] < u0 ? uv[0] : u0;
                u1 = uv[0] > u1 ? uv[0] : u1;
                v0 = uv[1] < v0 ? uv[1] : v0;
                v1 = uv[1] > v1 ? uv[1] : v1;
            }
        }
        const mvt_real mid[3] = {x, y, MVT_R(0.5) * top};
        mvt_real xc[3];
        mvt_cam_to_camera(cam, mid, xc);
        const uint8_t dq = mvt_pf_claim_depth(xc[2]);
        const mvt_real s = (mvt_real)img->scale;
        const mvt_real fu0 = (u0 + MVT_R(0.5)) / s, fu1 = (u1 + MVT_R(0.5)) / s;
        const mvt_real fv0 = (v0 + MVT_R(0.5)) / s, fv1 = (v1 + MVT_R(0.5)) / s;
        if (!(fu1 >= MVT_R(0.0) && fv1 >= MVT_R(0.0) && fu0 < (mvt_real)cl->width && fv0 < (mvt_real)cl->height)) {
            continue; /* off the picture (also catches non-finite boxes) */
        }
        const int c0 = fu0 > MVT_R(0.0) ? (int)fu0 : 0, r0 = fv0 > MVT_R(0.0) ? (int)fv0 : 0;
        const int c1 = fu1 < (mvt_real)(cl->width - 1) ? (int)fu1 : cl->width - 1;
        const int r1 = fv1 < (mvt_real)(cl->height - 1) ? (int)fv1 : cl->height - 1;
        for (int row = r0; row <= r1; row++) {
            uint8_t *line = &cl->depth[row * cl->width];
            for (int col = c0; col <= c1; col++) {
                line[col] = line[col] == 0u || line[col] > dq ? dq : line[col];
            }
        }
    }
}

/* Starts the log weights of the target ranked r-th: particles horizontally within exclusion_m of
 * another person lose up to exclusion_log. Independent targets: every other target, at its
 * predicted centre. Shared pixels: only the targets weighted before it (the stronger ones), at
 * their new estimates; a weaker target does not push a stronger one off its person. */
static void exclusion_prior(mvt_pft_t *self, int r, int shared)
{
    const mvt_pft_config_t *c = &self->cfg;
    const int ti = self->rank[r];
    mvt_pf_pool_t *p = &self->targets[ti].pool;
    for (int i = 0; i < p->n; i++) {
        p->w[i] = MVT_R(0.0);
    }
    if (!(c->exclusion_m > MVT_R(0.0)) || !(c->exclusion_log > MVT_R(0.0))) {
        return;
    }
    const mvt_real r2 = c->exclusion_m * c->exclusion_m;
    for (int j = 0; j < (shared ? r : MVT_MAX_TARGETS); j++) {
        const int o = shared ? self->rank[j] : j;
        if (o == ti || self->targets[o].id == 0) {
            continue;
        }
        const mvt_real *m = shared ? self->targets[o].est.mean : self->centre[o];
        for (int i = 0; i < p->n; i++) {
            const mvt_real dx = p->x[i] - m[0], dy = p->y[i] - m[1];
            const mvt_real d2 = dx * dx + dy * dy;
            if (d2 < r2) {
                p->w[i] -= c->exclusion_log * (MVT_R(1.0) - d2 / r2);
            }
        }
    }
}

/* Keeps identity id, followed on blob track blob_id, for recovery until until_us (the oldest
 * record gives way when all are in use). O(MVT_MAX_TARGETS). */
static void keep_identity(mvt_pft_t *self, int32_t id, int32_t blob_id, int64_t until_us, int64_t now_us)
{
    int slot = 0;
    for (int r = 0; r < MVT_MAX_TARGETS; r++) {
        if (self->lost[r].id == 0 || self->lost[r].until_us < now_us) {
            slot = r;
            break;
        }
        if (self->lost[r].until_us < self->lost[slot].until_us) {
            slot = r;
        }
    }
    self->lost[slot].id = id;
    self->lost[slot].blob_id = blob_id;
    self->lost[slot].until_us = until_us;
}

/* A target about to be deleted: a confirmed one lost by the filter keeps its identity for
 * recover_s; a tentative one holding a recovered identity gives it back until its deadline. */
static void release_identity(mvt_pft_t *self, const mvt_pft_target_t *a, int64_t now_us)
{
    const mvt_pft_config_t *c = &self->cfg;
    if (!(c->recover_s > MVT_R(0.0)) || a->blob_id <= 0) {
        return;
    }
    if (a->status == MVT_TRACK_TENTATIVE) {
        if (a->recover_until_us >= now_us) {
            keep_identity(self, a->id, a->blob_id, a->recover_until_us, now_us);
        }
        return;
    }
    keep_identity(self, a->id, a->blob_id, now_us + (int64_t)(c->recover_s * MVT_R(1e6)), now_us);
}

/* Each target notes the confirmed blob track nearest to it horizontally, within birth_sep_m
 * (identity recovery's key). O(T * blob tracks). */
static void follow_blob_tracks(mvt_pft_t *self)
{
    const mvt_real sep2 = self->cfg.birth_sep_m * self->cfg.birth_sep_m;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        mvt_pft_target_t *a = &self->targets[t];
        mvt_real best = sep2;
        for (int i = 0; i < self->det_out.num_tracks && a->id != 0; i++) {
            const mvt_track_out_t *bt = &self->det_out.tracks[i];
            const mvt_real dx = a->est.mean[0] - bt->pos_m[0], dy = a->est.mean[1] - bt->pos_m[1];
            if (bt->status != MVT_TRACK_TENTATIVE && dx * dx + dy * dy < best) {
                best = dx * dx + dy * dy;
                a->blob_id = bt->id;
            }
        }
    }
}

static void delete_targets(mvt_pft_t *self, int64_t now_us)
{
    const mvt_pft_config_t *c = &self->cfg;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        mvt_pft_target_t *a = &self->targets[t];
        if (a->id == 0) {
            continue;
        }
        const mvt_real unseen_s = mvt_us_to_s(now_us - a->last_supported_us);
        if (a->status == MVT_TRACK_TENTATIVE && unseen_s > c->tentative_lost_s) {
            release_identity(self, a, now_us);
            a->id = 0;
            self->counters.deleted_tentative++;
            continue;
        }
        if (unseen_s > c->lost_s) {
            release_identity(self, a, now_us);
            a->id = 0;
            self->counters.deleted_lost++;
            continue;
        }
        const mvt_real pos[3] = {a->est.mean[0], a->est.mean[1], a->est.head_z};
        if (!mvt_trk_inside_volume(&c->det, pos)) {
            a->id = 0;
            self->counters.deleted_outside++;
        }
    }
    const mvt_real d2max = c->dup_dist_m * c->dup_dist_m;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        mvt_pft_target_t *a = &self->targets[t];
        for (int u = t + 1; u < MVT_MAX_TARGETS && a->id != 0; u++) {
            mvt_pft_target_t *b = &self->targets[u];
            if (b->id == 0) {
                continue;
            }
            const mvt_real dx = a->est.mean[0] - b->est.mean[0], dy = a->est.mean[1] - b->est.mean[1];
            if (dx * dx + dy * dy < d2max) {
                mvt_pft_target_t *weaker = stronger(a, b) ? b : a;
                weaker->id = 0;
                self->counters.deleted_duplicate++;
            }
        }
    }
}

static void output(const mvt_pft_t *self, int64_t utime_us, mvt_output_t *out)
{
    out->utime_us = utime_us;
    out->num_tracks = 0;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        const mvt_pft_target_t *a = &self->targets[t];
        if (a->id == 0) {
            continue;
        }
        mvt_track_out_t *o = &out->tracks[out->num_tracks++];
        o->id = a->id;
        o->status = a->status;
        o->pos_m[0] = a->est.mean[0];
        o->pos_m[1] = a->est.mean[1];
        o->pos_m[2] = a->est.head_z;
        memcpy(o->vel_ms, a->est.vel, sizeof(o->vel_ms));
        memcpy(o->cov_m2, a->est.cov, sizeof(o->cov_m2));
        memcpy(o->extent_min, a->est.box_min, sizeof(o->extent_min));
        memcpy(o->extent_max, a->est.box_max, sizeof(o->extent_max));
        o->cameras_used = a->cameras_used;
        o->hue = self->cfg.use_colour ? a->est.hue : MVT_R(-1.0);
        o->saturation = self->cfg.use_colour ? a->est.saturation : MVT_R(-1.0);
    }
}

mvt_err_t mvt_pft_step(mvt_pft_t *self, const mvt_frame_t *frame, mvt_output_t *out)
{
    MVT_ASSERT(self != NULL && frame != NULL);
    const mvt_pft_config_t *c = &self->cfg;
    const int num_cams = self->det.num_cameras;
    if (self->have_time && frame->utime_us < self->last_utime_us) {
        self->counters.frames_time_backwards++;
        return MVT_ERR_INVALID;
    }
    const mvt_real dt = self->have_time ? mvt_us_to_s(frame->utime_us - self->last_utime_us) : MVT_R(0.0);
    self->last_utime_us = frame->utime_us;
    self->have_time = 1;
    self->counters.frames++;

    int masks = 0, colour = 0;
    for (int k = 0; k < num_cams; k++) {
        const mvt_view_t *v = &frame->views[k];
        const struct mvt_mask *m = v->observed ? v->mask : NULL;
        if (v->observed && (m == NULL || m->width < 1)) {
            self->counters.views_without_mask++;
        }
        mvt_pf_image_build(&self->images[k], m, &self->tab, c->model.sigma_px, &self->blur);
        masks += self->images[k].width > 0;
        colour += self->images[k].width > 0 && m->has_colour;
    }
    (void)colour;
    (void)mvt_tracker_step(&self->det, frame, &self->det_out);

    /* predicted centres for the exclusion prior (from last frame's estimates) */
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        const mvt_pft_target_t *a = &self->targets[t];
        for (int i = 0; i < 3; i++) {
            self->centre[t][i] = a->est.mean[i] + a->est.vel[i] * dt;
        }
    }
    /* pixels shared out: the targets are weighted strongest first, each reading what the ones
     * before it left unexplained */
    const int shared = c->share_pixels && masks > 0;
    for (int k = 0; k < num_cams; k++) {
        mvt_pf_claims_t *cl = &self->claims[k];
        cl->width = shared ? self->images[k].width : 0;
        cl->height = shared ? self->images[k].height : 0;
        if (cl->width > 0) {
            memset(cl->depth, 0, (size_t)cl->width * (size_t)cl->height);
        }
    }
    const int live = rank_targets(self, shared, dt);
    /* head-top hypotheses keep their height: no renewal over the body */
    mvt_pf_noise_t noise = c->noise;
    noise.z_renew = c->column ? MVT_R(0.0) : noise.z_renew;
    if (!c->column) { /* the point model's particles are points of the body: isotropic */
        noise.pos_z_m2s = noise.pos_m2s;
        noise.vel_z_m2s3 = noise.vel_m2s3;
    }
    for (int r = 0; r < live; r++) {
        mvt_pft_target_t *a = &self->targets[self->rank[r]];
        mvt_pf_predict(&a->pool, dt, &noise, &self->rng);
        if (c->column) { /* head tops below the lowest one are reflected above it */
            const mvt_real lo = c->body.min_top_m;
            for (int i = 0; i < a->pool.n; i++) {
                if (a->pool.z[i] < lo) {
                    a->pool.z[i] = lo + (lo - a->pool.z[i]);
                    a->pool.vz[i] = -a->pool.vz[i];
                }
            }
        }
        exclusion_prior(self, r, shared);
        mvt_real on_fg[MVT_MAX_CAMERAS], hidden[MVT_MAX_CAMERAS];
        mvt_pf_weight(&a->pool, self->det.cams, self->fovs, self->images, num_cams, &self->tab, c->use_colour,
                      c->column ? &c->body : NULL, c->lik_exponent, shared ? self->claims : NULL, on_fg, hidden);
        a->ess = mvt_pf_normalise(&a->pool);
        if (!(a->ess > MVT_R(0.0))) {
            self->counters.numeric_faults++;
        }
        mvt_pf_estimate(&a->pool, c->p_h, c->column ? MVT_R(0.0) : c->head_quantile, self->order, &a->est);
        if (masks > 0 && !c->column) {
            a->est.head_z = column_top(self, a->est.mean, a->est.head_z, masks);
        }
        /* a view supports the target when enough of its head hypotheses are on foreground that no
         * nearer target explains; a view where most are behind a nearer target's pixels or outside
         * the image cannot see the head and does not count against it */
        a->cameras_used = 0u;
        int visible = 0;
        for (int k = 0; k < num_cams; k++) {
            const int has = self->images[k].width > 0;
            a->cameras_used |= on_fg[k] >= c->support_fraction && has ? 1u << k : 0u;
            const int is_hidden = has && hidden[k] >= MVT_R(0.5);
            visible += has && !is_hidden;
            self->counters.views_hidden += (uint64_t)is_hidden;
        }
        int need = c->support_min_views < visible ? c->support_min_views : visible;
        need = need > 0 ? need : 1;
        const int supported = masks > 0 && popcount(a->cameras_used) >= need;
        const mvt_real share = visible > 0 ? (mvt_real)popcount(a->cameras_used) / (mvt_real)visible : MVT_R(0.0);
        a->strength += (MVT_R(1.0) - MVT_EXP(-dt)) * ((share < MVT_R(1.0) ? share : MVT_R(1.0)) - a->strength);
        if (supported) {
            a->last_supported_us = frame->utime_us;
            a->supported_frames += a->supported_frames < c->confirm_frames;
        }
        if (a->status != MVT_TRACK_TENTATIVE || a->supported_frames >= c->confirm_frames) {
            if (a->status == MVT_TRACK_TENTATIVE && a->recover_until_us != 0) {
                self->counters.identities_recovered++; /* confirmed: the identity is back */
            }
            a->recover_until_us = 0;
            a->status = supported ? MVT_TRACK_CONFIRMED : MVT_TRACK_COASTING;
        }
        if (a->ess < c->ess_fraction * (mvt_real)a->pool.n) {
            mvt_pf_resample(&a->pool, &self->rng, &self->scratch);
            self->counters.resamples++;
        }
        if (shared) {
            claim_silhouette(self, a);
        }
    }
    follow_blob_tracks(self);
    delete_targets(self, frame->utime_us);

    /* births from confirmed blob tracks that no particle target explains */
    const mvt_real sep2 = c->birth_sep_m * c->birth_sep_m;
    for (int i = 0; i < self->det_out.num_tracks && masks > 0; i++) {
        const mvt_track_out_t *bt = &self->det_out.tracks[i];
        if (bt->status != MVT_TRACK_CONFIRMED || bt->pos_m[2] < c->birth_min_height_m) {
            continue;
        }
        int near = 0, free_slot = -1;
        for (int t = 0; t < MVT_MAX_TARGETS; t++) {
            const mvt_pft_target_t *a = &self->targets[t];
            if (a->id == 0) {
                free_slot = free_slot < 0 ? t : free_slot;
                continue;
            }
            const mvt_real dx = a->est.mean[0] - bt->pos_m[0], dy = a->est.mean[1] - bt->pos_m[1];
            near |= dx * dx + dy * dy < sep2;
        }
        if (near) {
            continue;
        }
        if (free_slot < 0) {
            self->counters.births_refused_full++;
            continue;
        }
        birth(self, &self->targets[free_slot], bt, frame->utime_us);
    }
    if (out != NULL) {
        output(self, frame->utime_us, out);
    }
    return MVT_OK;
}
