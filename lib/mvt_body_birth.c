/*
 * mvt_body_birth.c - new people from the blobs no track explains, from any number of views.
 *
 * Every unexplained blob (mvt_body_explain.c) seeds a candidate, and so does a merged blob whose top
 * is someone else's (mvt_body_update.c: a track's displaced head in a blob that holds its body and
 * more, the top no tracked person's); such a candidate needs a second view, and other views' merged
 * blobs join a candidate only where no unexplained blob does. Its head lies on the blob top's
 * ray; before anything else is known, at the height of a standing adult's head (body.head_height_m,
 * spread body.head_height_sd_m along the ray: the prior). The candidate is a small Kalman estimate that
 * takes, in turn:
 *   the seed's feet, where visible (mvt_body_feet_visible): the point under the head on the floor;
 *   every other observed camera: its unexplained blob nearest the candidate's predicted head inside
 *   the chi-square gate, or, where the head would be in its picture and shows no such blob, the
 *   miss;
 * and again with the other cameras first and the feet last: a blob's bottom is not its feet where
 * clothes that match the background, or anything the model does not hold, cut the legs, and feet
 * taken first would then put the head on the wrong place along the seed's ray, where the other
 * views do not see it. The likelier of the two is the candidate.
 * Its log odds of a new person against clutter start at ln(b / n): b the newcomers' heads this
 * camera expects this frame (population.birth_per_s dt p_detect), n its clutter rate. Each step adds the
 * evidence: the feet's row against a bottom anywhere below the top (MVT_BODY_P_FEET), a view's
 * blob 1 - p + p N / lambda (N the density of the blob under the candidate, which before a second
 * view is spread along the projected ray: the epipolar line's length counts against the
 * coincidence), a miss 1 - p (p the view's detection probability, lowered where a tracked body
 * covers the head), or where the view's mask shows background all around the head, the camera's
 * rate of that for people there (MVT_BODY_P_BG). So a fragment (its feet say its top is no head's
 * height), a false blob that the other views do not see, or two unrelated blobs that meet at some
 * height where other views' masks are empty, stay unborn, while
 * a person seen by one camera alone is born from their first frames.
 * Candidates are born best first while their existence is above population.exist_delete, each blob used once,
 * never inside a body already there (two bodies cannot overlap: 2 body.halfwidth_m apart at least),
 * and never from a blob that lies in a newborn's silhouette below its head (its fragment). Then
 * the frame's births and the labels of the tracks that lost their person (existence under one
 * half, or asleep) are paired all at once (label_births): a birth that could be such a person
 * (within the gate of both estimates, the label's widened by walking pace since it was placed and
 * holding the person's height, or closer than a body's width) is that person found again, and
 * takes the label; the others are new people.
 * Cost O(C D) candidates, each O(C D), and an O(B^2 (B + L)) assignment of B births to L labels;
 * memory: the workspace's candidate and label arrays.
 */
#include "mvt_body.h"

#include <math.h>
#include <string.h>

static mvt_real dot3(const mvt_real a[3], const mvt_real b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* The seed's head on its ray, with the prior on head height. 0 when the ray does not meet the
 * volume in front of the camera. */
static int ray_prior(const mvt_tracker_t *self, int k, const mvt_real uv[2], mvt_real x[3], mvt_real P[9])
{
    const mvt_tracker_config_t *c = &self->cfg;
    const mvt_camera_t *cam = &self->cams[k];
    mvt_real o[3], dir[3];
    if (mvt_cam_ray(cam, uv, o, dir) != MVT_OK) {
        return 0;
    }
    mvt_real half_diag = MVT_R(0.0), centre[3];
    for (int i = 0; i < 3; i++) {
        const mvt_real e = c->volume.max[i] - c->volume.min[i];
        half_diag += e * e;
        centre[i] = MVT_R(0.5) * (c->volume.max[i] + c->volume.min[i]);
    }
    half_diag = MVT_R(0.5) * MVT_SQRT(half_diag);
    mvt_real lam = MVT_R(-1.0), sd_par = half_diag;
    if (MVT_FABS(dir[2]) > MVT_R(1e-3)) {
        lam = (c->body.head_height_m - o[2]) / dir[2];
        sd_par = c->body.head_height_sd_m / MVT_FABS(dir[2]);
    }
    if (!(lam > MVT_R(0.3)) || !(sd_par < half_diag)) {
        /* the ray does not reach head height in front of the camera, or runs nearly level with it:
         * anywhere along it within the volume */
        const mvt_real oc[3] = {centre[0] - o[0], centre[1] - o[1], centre[2] - o[2]};
        lam = dot3(oc, dir);
        sd_par = half_diag;
        if (!(lam > MVT_R(0.3))) {
            return 0;
        }
    }
    mvt_real sd_perp = lam * cam->sigma_px / cam->fx;
    sd_perp = sd_perp > MVT_R(0.01) ? sd_perp : MVT_R(0.01);
    const mvt_real a = sd_perp * sd_perp, b = sd_par * sd_par - a;
    for (int i = 0; i < 3; i++) {
        x[i] = o[i] + lam * dir[i];
        for (int j = 0; j < 3; j++) {
            P[i * 3 + j] = (i == j ? a : MVT_R(0.0)) + b * dir[i] * dir[j];
        }
    }
    return 1;
}

/* Camera j's detection probability of a head at x (its predicted pixel uv): its p in the picture,
 * lowered where tracked bodies hide it (mvt_body_shown) or a blob that a tracked head tops may hold
 * it (as a host holds a track, mvt_body_explain.c). */
static mvt_real detect_prob(const mvt_tracker_t *self, const mvt_frame_t *frame, int j, const mvt_real x[3],
                            const mvt_real uv[2])
{
    const mvt_camera_t *cam = &self->cams[j];
    mvt_real axis[MVT_BODY_AXIS_N];
    if (!mvt_body_in_picture(cam, uv) || mvt_body_behind_occluder(self, cam, x) || !mvt_body_axis(self, cam, x, axis)) {
        return MVT_R(0.0);
    }
    /* inside a blob that a tracked head tops, below that top: that blob may hold it (a host) */
    for (int d = 0; d < self->num_meas[j]; d++) {
        const int t = self->body.head_of[j][d];
        const mvt_detection_t *det = &frame->views[j].det[d];
        if (t >= 0 && self->tracks[t].exist_lo > MVT_R(0.0) && det->v <= uv[1] &&
            mvt_trk_in_box(det->box, uv, MVT_R(0.0), MVT_R(0.0))) {
            return self->p_detect_k[j] * self->p_hidden_k[j];
        }
    }
    return self->p_detect_k[j] * mvt_body_shown(self, j, axis, -1);
}

/* The seed's visible feet fuv: their row's evidence against a bottom anywhere below the top (a
 * fragment's feet say its top is no head's height), then, inside the gate, the point under the
 * head on the floor (it fixes the distance along the seed's ray). */
static void feet_into(const mvt_tracker_t *self, int k, const mvt_detection_t *det, const mvt_real fuv[2],
                      mvt_cv_state_t *s, mvt_body_cand_t *cand)
{
    mvt_pkf_innov_t in;
    if (mvt_body_feet_innovation(self, s, k, fuv, &in) != MVT_OK) {
        return;
    }
    const mvt_real span = (mvt_real)self->cams[k].height - det->v;
    const mvt_real nv = MVT_EXP(MVT_R(-0.5) * in.y[1] * in.y[1] / in.S[2]) / MVT_SQRT(MVT_R(6.2831853) * in.S[2]);
    cand->lo += MVT_LOG(MVT_BODY_P_FEET * nv * (span > MVT_R(1.0) ? span : MVT_R(1.0)) + (MVT_R(1.0) - MVT_BODY_P_FEET));
    if (in.d2 <= self->cfg.numerics.gate_chi2) {
        (void)mvt_pkf_update(s, &in);
    }
}

/* Every observed camera but the seed's: its unexplained blob nearest the candidate's predicted head
 * inside the gate, or where there is none the nearest merged blob topped by someone other than the
 * track that took it (evidence 1 - p + p N / lambda, and the update), or the miss (1 - p). */
static void views_into(const mvt_tracker_t *self, const mvt_frame_t *frame, const int order[], int n_order, int k,
                       mvt_cv_state_t *s, mvt_body_cand_t *cand)
{
    for (int oi = 0; oi < n_order; oi++) {
        const int j = order[oi];
        if (j == k) {
            continue;
        }
        mvt_pkf_pred_t pred;
        if (mvt_pkf_predict_obs(s, &self->cams[j], MVT_PKF_JACOBIAN, &pred) != MVT_OK) {
            continue;
        }
        const mvt_real p = detect_prob(self, frame, j, s->x, pred.h);
        if (!(p > MVT_R(0.0))) {
            continue;
        }
        int best = -1;
        mvt_pkf_innov_t in, best_in;
        for (int e = 0; e < self->num_meas[j]; e++) {
            const uint8_t f = self->body.free_det[j][e];
            if (!f || mvt_pkf_innovation_from(&pred, &self->meas[j][e], NULL, &in) != MVT_OK ||
                !(in.d2 <= self->cfg.numerics.gate_chi2)) {
                continue;
            }
            /* an unexplained blob before one that tops another's body in a merged blob */
            const uint8_t fb = best >= 0 ? self->body.free_det[j][best] : 0;
            if (best < 0 || f < fb || (f == fb && in.d2 < best_in.d2)) {
                best = e;
                best_in = in;
            }
        }
        if (best < 0) {
            /* the mask is empty where the head would be: the camera's rate of that for people there */
            cand->lo += MVT_LOG(mvt_body_head_on_background(self, &frame->views[j], j, &pred) ? self->p_bg_k[j] : MVT_R(1.0) - p);
            continue;
        }
        const mvt_real lambda = mvt_body_clutter_density(self, j);
        cand->lo += MVT_LOG(MVT_R(1.0) - p + p * mvt_trk_density(&best_in) / lambda);
        if (mvt_pkf_update(s, &best_in) == MVT_OK) {
            cand->det[j] = (int16_t)best;
        }
    }
}

/* The candidate seeded by blob d of camera k. 1 when it lies in the volume. A blob's bottom is its
 * feet only when nothing hides the legs (clothes that match the floor or the wall behind them cut a
 * body above its feet as well as furniture does), so the candidate is built both ways: the feet
 * first, fixing the distance along the seed's ray before the other views are searched along it,
 * and the other views first, the feet last; the likelier of the two is the candidate (with one view,
 * or no visible feet, they are the same and built once). */
static int seed_candidate(mvt_tracker_t *self, const mvt_frame_t *frame, const int order[], int n_order, int k, int d,
                          mvt_real dt, mvt_body_cand_t *cand)
{
    const mvt_tracker_config_t *c = &self->cfg;
    const mvt_detection_t *det = &frame->views[k].det[d];
    const mvt_real uv[2] = {det->u, det->v};
    mvt_real x0[3], P0[9];
    if (!ray_prior(self, k, uv, x0, P0)) {
        return 0;
    }
    mvt_cv_state_t s;
    mvt_cv_init(&s, x0, P0, c->init_vel_std_ms * c->init_vel_std_ms, frame->utime_us);
    /* newcomers' heads this camera expects this frame; on the first frame (dt 0) people may be
     * anywhere already: one a camera */
    const mvt_real b = dt > MVT_R(0.0) ? c->population.birth_per_s * dt * c->population.p_detect : c->population.p_detect;
    cand->lo = MVT_LOG(b / self->clutter_n[k]);
    for (int j = 0; j < MVT_MAX_CAMERAS; j++) {
        cand->det[j] = -1;
    }
    cand->det[k] = (int16_t)d;
    mvt_real fuv[2];
    const int feet = mvt_body_feet_visible(self, k, det, -1, fuv);
    mvt_body_cand_t late = *cand;
    mvt_cv_state_t s_late = s;
    if (feet) {
        feet_into(self, k, det, fuv, &s, cand);
    }
    views_into(self, frame, order, n_order, k, &s, cand);
    if (feet && n_order > 1) { /* without feet, or other views, the two orders are one */
        views_into(self, frame, order, n_order, k, &s_late, &late);
        feet_into(self, k, det, fuv, &s_late, &late);
        if (late.lo > cand->lo) {
            *cand = late;
            s = s_late;
        }
    }
    for (int i = 0; i < 3; i++) {
        cand->x[i] = s.x[i];
        for (int j = 0; j < 3; j++) {
            cand->P[i * 3 + j] = s.P[i * 6 + j];
        }
    }
    return mvt_trk_inside_volume(c, cand->x) && cand->x[2] > MVT_R(0.0);
}

/* Horizontal distance between two heads, squared. */
static mvt_real dist2_xy(const mvt_real a[3], const mvt_real b[3])
{
    const mvt_real dx = a[0] - b[0], dy = a[1] - b[1];
    return dx * dx + dy * dy;
}

/* 1 when the candidate may be born: its blobs unused, no body there, its seed no newborn's
 * fragment. */
static int admissible(const mvt_tracker_t *self, const mvt_frame_t *frame, const mvt_body_cand_t *cand, int k,
                      uint8_t taken[MVT_MAX_CAMERAS][MVT_MAX_DETECTIONS], const int16_t born[], int n_born)
{
    for (int j = 0; j < self->num_cameras; j++) {
        if (cand->det[j] >= 0 && taken[j][cand->det[j]]) {
            return 0;
        }
    }
    int views = 0;
    for (int j = 0; j < self->num_cameras; j++) {
        views += cand->det[j] >= 0;
    }
    if (self->body.free_det[k][cand->det[k]] == 2 && views < 2) {
        return 0; /* a merged blob's top is its track's displaced head as much as anyone's: one view
                     does not tell them apart */
    }
    const mvt_real max_var = self->cfg.numerics.max_pos_std_m * self->cfg.numerics.max_pos_std_m;
    if (!(cand->P[0] <= max_var) || !(cand->P[4] <= max_var)) {
        return 0; /* nowhere in particular yet (one view's ray, no feet): a track so spread would end
                     at once (mvt_body_prune.c), and with it a label it took */
    }
    const mvt_real sep = MVT_R(2.0) * self->cfg.body.halfwidth_m;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        const mvt_track_t *tr = &self->tracks[t];
        if (tr->id != 0 && !tr->dormant && tr->exist_lo > MVT_R(0.0) && dist2_xy(tr->s.x, cand->x) < sep * sep) {
            return 0;
        }
    }
    const mvt_detection_t *det = &frame->views[k].det[cand->det[k]];
    const mvt_real uv[2] = {det->u, det->v};
    for (int i = 0; i < n_born; i++) {
        mvt_real axis[MVT_BODY_AXIS_N];
        if (mvt_body_axis(self, &self->cams[k], self->tracks[born[i]].s.x, axis) && mvt_body_fragment_of(axis, uv)) {
            return 0;
        }
    }
    return 1;
}

/* Track tr's estimate's position covariance, widened by walking pace's reach since a camera last
 * placed its head (hidden, asleep: nobody saw where the person walked; asleep, at least half a
 * second's, the time it takes to fall asleep). */
static void widened(const mvt_tracker_t *self, const mvt_track_t *tr, mvt_real P[9])
{
    const mvt_real *S = tr->s.P;
    const int at[9] = {0, 1, 2, 6, 7, 8, 12, 13, 14};
    for (int i = 0; i < 9; i++) {
        P[i] = S[at[i]];
    }
    mvt_real since = mvt_us_to_s(self->last_utime_us - tr->last_update_us);
    since = since > MVT_R(0.5) || !tr->dormant ? since : MVT_R(0.5);
    const mvt_real reach = self->cfg.init_vel_std_ms * since;
    P[0] += reach * reach;
    P[4] += reach * reach;
}

static void label_of(const mvt_tracker_t *self, const mvt_track_t *tr, mvt_body_label_t *L)
{
    L->id = tr->id;
    L->status = tr->status;
    L->was_shown = tr->was_shown;
    L->dormant = tr->dormant;
    L->app = tr->app;
    L->seen_z = tr->seen_z;
    L->seen_zz = tr->seen_zz;
    L->exist_lo = tr->exist_lo;
    for (int i = 0; i < 3; i++) {
        L->x[i] = tr->s.x[i];
    }
    widened(self, tr, L->P);
    if (tr->seen_zz > MVT_R(0.0)) {
        /* the head's height is the person's (a walking head's bob about it), which the motion
         * model's vertical noise forgets over an outage; as far as it wandered beyond the bob
         * lately, it is not known to be the person's */
        const mvt_real bob2 = MVT_BODY_HEAD_BOB_M * MVT_BODY_HEAD_BOB_M;
        L->x[2] = tr->seen_z;
        L->P[2] = L->P[5] = L->P[6] = L->P[7] = MVT_R(0.0);
        L->P[8] = tr->seen_zz + bob2 + (tr->z_var > bob2 ? tr->z_var - bob2 : MVT_R(0.0));
    }
}

/* Label L onto the track restarted at candidate cand: the same person, whose label, status, colour
 * and height stay while the estimate starts again. */
static void give_label(mvt_track_t *tr, const mvt_body_label_t *L, const mvt_body_cand_t *cand)
{
    tr->id = L->id;
    tr->status = L->was_shown ? MVT_TRACK_CONFIRMED : L->status; /* shown before */
    tr->was_shown = L->was_shown;
    tr->app = L->app;
    mvt_body_height_start(tr, L->seen_zz > MVT_R(0.0) ? L->seen_z : cand->x[2], /* or until two views */
                          L->seen_zz > MVT_R(0.0) ? L->seen_zz : cand->P[8]);    /* place them, the candidate's */
    tr->exist_lo = L->dormant || cand->lo > L->exist_lo ? cand->lo : L->exist_lo;
}

/* How likely candidate cand is label L's person: L's chance of being a person there (its existence)
 * times the candidate's density under L's widened estimate; -1 where the candidate is neither within
 * the 3-dof gate of both covariances nor closer than a body's width horizontally (two bodies cannot
 * overlap, and a track that lost its person is often more sure of its place than it should be). */
static mvt_real heir_score(const mvt_tracker_t *self, const mvt_body_label_t *L, const mvt_body_cand_t *cand)
{
    mvt_real det;
    const mvt_real d2 = mvt_trk_mahalanobis3(L->x, L->P, cand->x, cand->P, &det);
    const mvt_real sep = MVT_R(2.0) * self->cfg.body.halfwidth_m;
    if (!(d2 >= MVT_R(0.0)) || !(det > MVT_R(0.0)) ||
        (!(d2 < MVT_TRK_GATE3) && !(dist2_xy(L->x, cand->x) < sep * sep))) {
        return MVT_R(-1.0);
    }
    return mvt_body_prob(L->exist_lo) * MVT_EXP(MVT_R(-0.5) * d2) / MVT_SQRT(det);
}

/* The track that candidate cand continues: one whose existence has fallen under one half (it keeps
 * its label while its existence lasts), or a dormant one (mvt_body_prune.c), that heir_score allows:
 * the candidate is that person found again, not a new one. The likeliest, or -1. */
static int heir_of(const mvt_tracker_t *self, const mvt_body_cand_t *cand)
{
    int best = -1;
    mvt_real best_score = MVT_R(0.0);
    for (int t = 0; t < MVT_MAX_TARGETS; t++) {
        const mvt_track_t *tr = &self->tracks[t];
        if (tr->id == 0 || (tr->exist_lo > MVT_R(0.0) && !tr->dormant)) {
            continue;
        }
        mvt_body_label_t L;
        label_of(self, tr, &L);
        const mvt_real score = heir_score(self, &L, cand);
        if (score >= MVT_R(0.0) && (best < 0 || score > best_score)) {
            best = t;
            best_score = score;
        }
    }
    return best;
}

/* This frame's births (slots born, their candidates ws->born_cand) and the labels of the tracks that
 * lost their person (existence under one half, or asleep: ws->heirs, captured before the births),
 * paired all at once: the assignment that pairs as many births with labels as heir_score allows,
 * and of those pairings the one maximising the product of the scores. A birth paired with a label is
 * that person found again (the sleeper's slot is freed); one paired with none is a new person. One
 * by one (each candidate taking its likeliest sleeper, best candidate first) two people found again
 * in one frame, after an outage, could take each other's labels and leave a third with none. */
static void label_births(mvt_tracker_t *self, const int16_t born[], int n_born)
{
    mvt_body_ws_t *ws = &self->body;
    const int ns = ws->num_heirs, nc = ns + n_born;
    int r2c[MVT_MAX_TARGETS];
    for (int i = 0; i < n_born; i++) {
        r2c[i] = -1;
    }
    if (n_born > 0 && ns > 0) {
        uint8_t owned[MVT_MAX_TARGETS]; /* a label whose slot a birth took is that birth's */
        memset(owned, 0, sizeof(owned));
        for (int i = 0; i < n_born; i++) {
            if (ws->born_own[i] >= 0) {
                owned[ws->born_own[i]] = 1;
            }
        }
        mvt_real *cost = self->cl_cost;
        for (int i = 0; i < n_born; i++) {
            const mvt_body_cand_t *cand = &ws->cand[ws->born_cand[i]];
            for (int j = 0; j < nc; j++) {
                cost[i * nc + j] = MVT_R(-1.0);
            }
            cost[i * nc + ns + i] = MVT_R(2000.0); /* a new person: dearer than any pairing */
            for (int j = 0; j < ns; j++) {
                const mvt_real sc = heir_score(self, &ws->heirs[j], cand);
                if (sc > MVT_R(0.0) && (ws->born_own[i] < 0 ? !owned[j] : ws->born_own[i] == j)) {
                    const mvt_real c = MVT_R(1000.0) - MVT_LOG(sc);
                    cost[i * nc + j] = c < MVT_R(0.0) ? MVT_R(0.0) : (c > MVT_R(1999.0) ? MVT_R(1999.0) : c);
                }
            }
        }
        if (mvt_assoc_solve(cost, n_born, nc, nc, r2c, &self->assoc_ws) != MVT_OK) {
            for (int i = 0; i < n_born; i++) {
                r2c[i] = -1;
            }
        }
    }
    for (int i = 0; i < n_born; i++) {
        mvt_track_t *tr = &self->tracks[born[i]];
        const mvt_body_cand_t *cand = &ws->cand[ws->born_cand[i]];
        const int j = r2c[i] >= 0 && r2c[i] < ns ? r2c[i] : (ws->born_own[i] >= 0 ? ws->born_own[i] : -1);
        if (j >= 0) {
            give_label(tr, &ws->heirs[j], cand);
            if (ws->heir_slot[j] != born[i]) {
                memset(&self->tracks[ws->heir_slot[j]], 0, sizeof(self->tracks[0])); /* moved */
            }
            self->counters.reacquired++;
        } else {
            tr->id = self->next_id;
            self->next_id = self->next_id < INT32_MAX ? self->next_id + 1 : 1;
            tr->status = MVT_TRACK_TENTATIVE;
            mvt_body_height_start(tr, cand->x[2], cand->P[8]); /* the person's until two views place them */
            mvt_trk_app_reset(&tr->app);
            self->counters.births++;
        }
        for (int k = 0; k < self->num_cameras; k++) {
            if (cand->det[k] >= 0 && self->chroma_ok[k][cand->det[k]]) {
                mvt_trk_app_update(&tr->app, self->chroma[k][cand->det[k]]);
            }
        }
    }
}

void mvt_body_birth(mvt_tracker_t *self, const mvt_frame_t *frame, const int order[], int n_order, mvt_real dt)
{
    mvt_body_ws_t *ws = &self->body;
    ws->num_cand = 0;
    ws->num_heirs = 0;
    int16_t seed_cam[MVT_MAX_BIRTH_CANDIDATES];
    for (int oi = 0; oi < n_order; oi++) {
        const int k = order[oi];
        for (int d = 0; d < self->num_meas[k]; d++) {
            if (!ws->free_det[k][d]) {
                continue;
            }
            if (ws->num_cand >= MVT_MAX_BIRTH_CANDIDATES) {
                self->counters.birth_candidates_dropped++;
                continue;
            }
            if (seed_candidate(self, frame, order, n_order, k, d, dt, &ws->cand[ws->num_cand])) {
                seed_cam[ws->num_cand] = (int16_t)k;
                ws->num_cand++;
            }
        }
    }
    uint8_t taken[MVT_MAX_CAMERAS][MVT_MAX_DETECTIONS];
    memset(taken, 0, sizeof(taken));
    uint8_t done[MVT_MAX_BIRTH_CANDIDATES];
    memset(done, 0, sizeof(done));
    int16_t born[MVT_MAX_TARGETS];
    int n_born = 0;
    for (int t = 0; t < MVT_MAX_TARGETS; t++) { /* the labels that lost their person */
        const mvt_track_t *tr = &self->tracks[t];
        if (tr->id != 0 && (!(tr->exist_lo > MVT_R(0.0)) || tr->dormant)) {
            label_of(self, tr, &ws->heirs[ws->num_heirs]);
            ws->heir_slot[ws->num_heirs++] = (int16_t)t;
        }
    }
    const mvt_real lo_min = mvt_body_logit(self->cfg.population.exist_delete);
    for (;;) {
        int best = -1;
        for (int i = 0; i < ws->num_cand; i++) {
            if (!done[i] && ws->cand[i].lo > lo_min && (best < 0 || ws->cand[i].lo > ws->cand[best].lo)) {
                best = i;
            }
        }
        if (best < 0) {
            break;
        }
        done[best] = 1;
        const mvt_body_cand_t *cand = &ws->cand[best];
        if (!admissible(self, frame, cand, seed_cam[best], taken, born, n_born)) {
            continue;
        }
        /* a free slot; with none left, the likeliest sleeper's, which then can be no one else's */
        int slot = -1;
        for (int t = 0; t < MVT_MAX_TARGETS && slot < 0; t++) {
            slot = self->tracks[t].id == 0 ? t : -1;
        }
        int own = -1;
        if (slot < 0) {
            const int heir = heir_of(self, cand);
            for (int j = 0; j < ws->num_heirs && heir >= 0; j++) {
                own = ws->heir_slot[j] == heir ? j : own;
            }
            slot = own >= 0 ? heir : -1;
        }
        if (slot < 0) {
            self->counters.births_refused_full++;
            break;
        }
        mvt_track_t *tr = &self->tracks[slot];
        memset(tr, 0, sizeof(*tr));
        mvt_trk_start(self, tr, cand->x, cand->P, frame->utime_us);
        tr->id = -1; /* taken; its label is given below */
        tr->exist_lo = cand->lo;
        tr->last_update_us = frame->utime_us;
        for (int j = 0; j < self->num_cameras; j++) {
            if (cand->det[j] >= 0) {
                taken[j][cand->det[j]] = 1;
                tr->cameras_used |= 1u << j;
            }
        }
        ws->born_cand[n_born] = (int16_t)best;
        ws->born_own[n_born] = (int16_t)own;
        born[n_born++] = (int16_t)slot;
    }
    label_births(self, born, n_born);
}
