#include "mvt_pf.h"

#include <math.h>
#include <string.h>

#define TWO_PI MVT_R(6.283185307179586)

/* ---- random numbers ------------------------------------------------------------------------- */

uint32_t mvt_rng_u32(mvt_rng_t *rng)
{
    const uint64_t old = rng->state;
    rng->state = old * 6364136223846793005ULL + rng->inc;
    const uint32_t xorshifted = (uint32_t)(((old >> 18u) ^ old) >> 27u);
    const uint32_t rot = (uint32_t)(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
}

void mvt_rng_seed(mvt_rng_t *rng, uint64_t seed, uint64_t stream)
{
    rng->state = 0u;
    rng->inc = (stream << 1u) | 1u;
    (void)mvt_rng_u32(rng);
    rng->state += seed;
    (void)mvt_rng_u32(rng);
}

mvt_real mvt_rng_uniform(mvt_rng_t *rng)
{
    return (mvt_real)(mvt_rng_u32(rng) >> 8u) * MVT_R(5.9604644775390625e-8); /* 2^-24 */
}

void mvt_rng_normal2(mvt_rng_t *rng, mvt_real out[2])
{
    const mvt_real u1 = (mvt_real)((mvt_rng_u32(rng) >> 8u) + 1u) * MVT_R(5.9604644775390625e-8); /* (0, 1] */
    const mvt_real u2 = mvt_rng_uniform(rng);
    const mvt_real r = MVT_SQRT(MVT_R(-2.0) * MVT_LOG(u1));
    out[0] = r * MVT_COS(TWO_PI * u2);
    out[1] = r * MVT_SIN(TWO_PI * u2);
}

/* ---- likelihood tables and images ----------------------------------------------------------- */

static mvt_real log_gauss_mix(mvt_real background, mvt_real d, mvt_real sigma)
{
    const mvt_real g = MVT_EXP(MVT_R(-0.5) * (d / sigma) * (d / sigma)) / (sigma * MVT_R(2.5066282746310002));
    return MVT_LOG(background + (MVT_R(1.0) - background) * g);
}

mvt_err_t mvt_pf_tables_init(mvt_pf_tables_t *tab, const mvt_pf_model_t *m)
{
    MVT_ASSERT(tab != NULL && m != NULL);
    if (!(m->sigma_px > MVT_R(0.0)) || !(m->p_b > MVT_R(0.0)) || !(m->p_b < MVT_R(1.0)) ||
        !(m->sigma_h > MVT_R(0.0)) || !(m->sigma_h <= MVT_R(0.5)) || !(m->sigma_s > MVT_R(0.0)) ||
        !(m->sigma_s <= MVT_R(1.0)) || !(m->h_b >= MVT_R(0.0)) || !(m->h_b < MVT_R(1.0)) ||
        !(m->s_b >= MVT_R(0.0)) || !(m->s_b < MVT_R(1.0)) || !isfinite(m->sigma_px)) {
        return MVT_ERR_INVALID;
    }
    int floor_level = (int)(m->p_b * MVT_R(255.0) + MVT_R(0.5));
    floor_level = floor_level < 1 ? 1 : floor_level;
    tab->d_floor = (uint8_t)floor_level;
    for (int l = 0; l < 256; l++) {
        const int q = l < floor_level ? floor_level : l;
        tab->log_d[l] = MVT_LOG((mvt_real)q / MVT_R(255.0));
        const mvt_real bg = MVT_R(1.0) - (mvt_real)l / MVT_R(255.0);
        tab->log_bg[l] = MVT_LOG(bg > m->p_b ? bg : m->p_b);
    }
    for (int k = 0; k <= 128; k++) {
        tab->log_h[k] = log_gauss_mix(m->h_b, (mvt_real)k / MVT_R(256.0), m->sigma_h);
    }
    for (int k = 0; k < 256; k++) {
        tab->log_s[k] = log_gauss_mix(m->s_b, (mvt_real)k / MVT_R(255.0), m->sigma_s);
    }
    /* where the mask says background the pixel's colour is not the person's: the floor of both
     * terms (a small positive floor keeps the log finite even with h_B = s_B = 0) */
    const mvt_real hb = m->h_b > MVT_R(1e-6) ? m->h_b : MVT_R(1e-6);
    const mvt_real sb = m->s_b > MVT_R(1e-6) ? m->s_b : MVT_R(1e-6);
    tab->log_colour_background = MVT_LOG(hb) + MVT_LOG(sb);
    return MVT_OK;
}

void mvt_pf_image_build(mvt_pf_image_t *img, const mvt_mask_t *mask, const mvt_pf_tables_t *tab,
                        mvt_real sigma_px, mvt_pf_blur_ws_t *ws)
{
    MVT_ASSERT(img != NULL && tab != NULL && ws != NULL);
    if (mask == NULL || mask->width < 1 || mask->height < 1) {
        img->width = img->height = img->scale = 0;
        img->mask = NULL;
        return;
    }
    const int w = mask->width, hgt = mask->height;
    MVT_ASSERT(w * hgt <= MVT_MAX_MASK_PIXELS && hgt <= MVT_PF_MAX_ROWS);
    img->width = w;
    img->height = hgt;
    img->scale = mask->scale;
    img->mask = mask;

    /* integer kernel, sum kept exactly for the final division */
    const mvt_real sigma = sigma_px / (mvt_real)mask->scale;
    int radius = (int)(MVT_R(3.0) * sigma + MVT_R(0.999));
    radius = radius > MVT_PF_MAX_RADIUS ? MVT_PF_MAX_RADIUS : radius;
    uint16_t kern[2 * MVT_PF_MAX_RADIUS + 1];
    mvt_real raw[2 * MVT_PF_MAX_RADIUS + 1], raw_sum = MVT_R(0.0);
    for (int k = -radius; k <= radius; k++) {
        raw[k + radius] = sigma > MVT_R(1e-3) ? MVT_EXP(MVT_R(-0.5) * (mvt_real)(k * k) / (sigma * sigma)) : MVT_R(1.0);
        raw_sum += raw[k + radius];
    }
    uint32_t ksum = 0;
    for (int k = 0; k <= 2 * radius; k++) {
        kern[k] = (uint16_t)(raw[k] / raw_sum * MVT_R(32768.0) + MVT_R(0.5));
        ksum += kern[k];
    }
    const uint64_t norm = (uint64_t)ksum * ksum;

    /* horizontal pass, zero outside the mask; rows without foreground skipped */
    for (int y = 0; y < hgt; y++) {
        const uint8_t *src = mask->fg + y * w;
        uint16_t *dst = ws->h + y * w;
        int any = 0;
        for (int x = 0; x < w; x++) {
            any |= src[x];
        }
        ws->row_any[y] = (uint8_t)any;
        if (!any) {
            memset(dst, 0, (size_t)w * sizeof(uint16_t));
            continue;
        }
        for (int x = 0; x < w; x++) {
            const int k0 = x - radius < 0 ? radius - x : 0;
            const int k1 = x + radius >= w ? radius + (w - 1 - x) : 2 * radius;
            uint32_t acc = 0;
            for (int k = k0; k <= k1; k++) {
                acc += src[x - radius + k] ? kern[k] : 0u;
            }
            dst[x] = (uint16_t)acc;
        }
    }
    /* vertical pass; rows whose window holds no foreground are the floor */
    for (int y = 0; y < hgt; y++) {
        const int k0 = y - radius < 0 ? radius - y : 0;
        const int k1 = y + radius >= hgt ? radius + (hgt - 1 - y) : 2 * radius;
        uint8_t *out = img->d + y * w;
        int any = 0;
        for (int k = k0; k <= k1; k++) {
            any |= ws->row_any[y - radius + k];
        }
        if (!any) {
            memset(out, tab->d_floor, (size_t)w);
            continue;
        }
        for (int x = 0; x < w; x++) {
            uint32_t acc = 0;
            for (int k = k0; k <= k1; k++) {
                acc += (uint32_t)kern[k] * ws->h[(y - radius + k) * w + x];
            }
            uint64_t level = ((uint64_t)acc * 255u + norm / 2u) / norm;
            level = level > 255u ? 255u : level;
            out[x] = level < tab->d_floor ? tab->d_floor : (uint8_t)level;
        }
    }
}

void mvt_pf_fov_init(mvt_pf_fov_t *fov, const mvt_camera_t *cam, mvt_real margin)
{
    const mvt_real w = (mvt_real)(cam->width - 1), h = (mvt_real)(cam->height - 1);
    /* pinhole bounds first */
    fov->x_min = (MVT_R(0.0) - cam->cx) / cam->fx;
    fov->x_max = (w - cam->cx) / cam->fx;
    fov->y_min = (MVT_R(0.0) - cam->cy) / cam->fy;
    fov->y_max = (h - cam->cy) / cam->fy;
    if (cam->has_dist) {
        mvt_real x0 = MVT_R(1e30), x1 = MVT_R(-1e30), y0 = MVT_R(1e30), y1 = MVT_R(-1e30);
        int ok = 0;
        for (int side = 0; side < 4; side++) {
            for (int i = 0; i <= 32; i++) {
                const mvt_real f = (mvt_real)i / MVT_R(32.0);
                const mvt_real uv[2] = {side < 2 ? f * w : (side == 2 ? MVT_R(0.0) : w),
                                        side < 2 ? (side == 0 ? MVT_R(0.0) : h) : f * h};
                mvt_real xn[2];
                if (mvt_cam_undistort(cam, uv, xn) != MVT_OK) {
                    continue;
                }
                x0 = xn[0] < x0 ? xn[0] : x0;
                x1 = xn[0] > x1 ? xn[0] : x1;
                y0 = xn[1] < y0 ? xn[1] : y0;
                y1 = xn[1] > y1 ? xn[1] : y1;
                ok++;
            }
        }
        if (ok > 0) {
            fov->x_min = x0 < fov->x_min ? x0 : fov->x_min;
            fov->x_max = x1 > fov->x_max ? x1 : fov->x_max;
            fov->y_min = y0 < fov->y_min ? y0 : fov->y_min;
            fov->y_max = y1 > fov->y_max ? y1 : fov->y_max;
        }
    }
    const mvt_real mx = margin * (fov->x_max - fov->x_min), my = margin * (fov->y_max - fov->y_min);
    fov->x_min -= mx;
    fov->x_max += mx;
    fov->y_min -= my;
    fov->y_max += my;
}

/* ---- the filter ----------------------------------------------------------------------------- */

void mvt_pf_predict(mvt_pf_pool_t *p, mvt_real dt_s, const mvt_pf_noise_t *noise, mvt_rng_t *rng)
{
    MVT_ASSERT(p != NULL && noise != NULL && rng != NULL && p->n >= 1 && p->n <= MVT_MAX_PARTICLES);
    const mvt_real dt = dt_s > MVT_R(0.0) ? dt_s : MVT_R(0.0);
    const mvt_real sp = MVT_SQRT(noise->pos_m2s * dt), sv = MVT_SQRT(noise->vel_m2s3 * dt);
    const mvt_real sc = MVT_SQRT(noise->colour_1s * dt);
    const mvt_real spz = MVT_SQRT(noise->pos_z_m2s * dt), svz = MVT_SQRT(noise->vel_z_m2s3 * dt);
    for (int i = 0; i < p->n; i++) {
        mvt_real g[8];
        mvt_rng_normal2(rng, g);
        mvt_rng_normal2(rng, g + 2);
        mvt_rng_normal2(rng, g + 4);
        p->x[i] += p->vx[i] * dt + sp * g[0];
        p->y[i] += p->vy[i] * dt + sp * g[1];
        p->z[i] += p->vz[i] * dt + spz * g[2];
        p->vx[i] += sv * g[3];
        p->vy[i] += sv * g[4];
        p->vz[i] += svz * g[5];
        if (sc > MVT_R(0.0)) {
            mvt_rng_normal2(rng, g + 6);
            mvt_real hue = p->h[i] + sc * g[6];
            hue -= (mvt_real)(int)hue;
            p->h[i] = hue < MVT_R(0.0) ? hue + MVT_R(1.0) : (hue >= MVT_R(1.0) ? hue - MVT_R(1.0) : hue);
            const mvt_real s = p->s[i] + sc * g[7];
            p->s[i] = s < MVT_R(0.0) ? MVT_R(0.0) : (s > MVT_R(1.0) ? MVT_R(1.0) : s);
        }
        if (noise->z_renew > MVT_R(0.0) && mvt_rng_uniform(rng) < noise->z_renew) {
            p->z[i] = noise->z_min + (noise->z_max - noise->z_min) * mvt_rng_uniform(rng);
            p->vz[i] = MVT_R(0.0);
        }
    }
}

/* The likelihood level from which a pixel counts as foreground: halfway from the floor to 1. */
static inline uint8_t fg_threshold(const mvt_pf_tables_t *tab)
{
    return (uint8_t)(((int)tab->d_floor + 255) / 2);
}

/* Mask index of the camera-frame point (X, Y, Z), or -1: behind the camera, outside the lens
 * model's window or outside the mask. O(1). */
static inline int view_index(const mvt_camera_t *c, const mvt_pf_fov_t *f, const mvt_pf_image_t *img,
                             mvt_real X, mvt_real Y, mvt_real Z)
{
    if (!(Z > MVT_R(1e-3))) {
        return -1;
    }
    const mvt_real iz = MVT_R(1.0) / Z;
    const mvt_real xn = X * iz, yn = Y * iz;
    if (!(xn >= f->x_min && xn <= f->x_max && yn >= f->y_min && yn <= f->y_max) ||
        !(xn * xn + yn * yn <= c->field_r2)) {
        return -1;
    }
    mvt_real xd[2];
    mvt_cam_distort_value(c, xn, yn, xd);
    return mvt_pf_image_index(img, c->fx * xd[0] + c->skew * xd[1] + c->cx, c->fy * xd[1] + c->cy);
}

int mvt_pf_point_on_fg(const mvt_camera_t *cam, const mvt_pf_fov_t *fov, const mvt_pf_image_t *img,
                       const mvt_pf_tables_t *tab, const mvt_real xw[3])
{
    MVT_ASSERT(cam != NULL && fov != NULL && img != NULL && tab != NULL && xw != NULL);
    if (img->width < 1) {
        return -1;
    }
    mvt_real xc[3];
    mvt_cam_to_camera(cam, xw, xc);
    const int idx = view_index(cam, fov, img, xc[0], xc[1], xc[2]);
    if (idx < 0) {
        return -1;
    }
    return img->d[idx] > fg_threshold(tab);
}

/* Log of Eq. 11 x Eq. 13 for a particle's colour state at mask pixel idx (foreground) or the
 * background floor (also outside the image: marginalising the colour there as well, log 0,
 * measured more identity switches on rendered video, docs/particle-filter.md). */
static inline mvt_real colour_log(const mvt_pf_tables_t *tab, const mvt_mask_t *m, int idx, mvt_real h, mvt_real s)
{
    if (idx < 0 || !m->fg[idx]) {
        return tab->log_colour_background;
    }
    const int hq = (int)(h * MVT_R(256.0)) & 255;
    int dh = m->hue[idx] > hq ? m->hue[idx] - hq : hq - m->hue[idx];
    dh = dh > 128 ? 256 - dh : dh;
    const int sq = (int)(s * MVT_R(255.0) + MVT_R(0.5));
    const int ds = m->sat[idx] > sq ? m->sat[idx] - sq : sq - m->sat[idx];
    return tab->log_h[dh] + tab->log_s[ds];
}

/* D at mask pixel idx as this target may read it. Outside the image the camera saw nothing, and
 * an observation not made is marginalised out: the point reads `unseen`, the level whose log term
 * is 0 (255 for a point expected on the body, 0 for one expected on background), the same for
 * every hypothesis. Read as background, it pulled every column a camera sees only in part (head
 * above the image's top edge, feet below its bottom) into the image, onto the body's lower half;
 * at 1/2, half as hard. Where another target's claim covers the pixel: 1/2, evidence neither way.
 * *behind: 0 unclaimed, 1 claimed by a target farther than the point's camera depth z, 2 by a
 * nearer one. O(1). */
static inline uint8_t claimed_level(const uint8_t *d, const mvt_pf_claims_t *cl, int idx, mvt_real z, uint8_t unseen,
                                    int *behind)
{
    *behind = 0;
    if (idx < 0) {
        return unseen;
    }
    if (cl == NULL || cl->depth[idx] == 0u) {
        return d[idx];
    }
    *behind = cl->depth[idx] < mvt_pf_claim_depth(z) ? 2 : 1;
    return MVT_PF_LEVEL_UNKNOWN;
}

void mvt_pf_weight(mvt_pf_pool_t *p, const mvt_camera_t *cams, const mvt_pf_fov_t *fovs,
                   const mvt_pf_image_t *images, int num_cams, const mvt_pf_tables_t *tab, int use_colour,
                   const mvt_pf_body_t *body, mvt_real exponent, const mvt_pf_claims_t *claims,
                   mvt_real on_fg[], mvt_real hidden[])
{
    MVT_ASSERT(p != NULL && cams != NULL && fovs != NULL && images != NULL && tab != NULL);
    const uint8_t fg_level = fg_threshold(tab);
    for (int k = 0; k < num_cams; k++) {
        const mvt_pf_image_t *img = &images[k];
        if (on_fg != NULL) {
            on_fg[k] = MVT_R(0.0);
        }
        if (hidden != NULL) {
            hidden[k] = MVT_R(0.0);
        }
        if (img->width < 1) {
            continue;
        }
        const mvt_camera_t *c = &cams[k];
        const mvt_pf_fov_t *f = &fovs[k];
        const int colour = use_colour && img->mask->has_colour;
        const uint8_t *d = img->d;
        const mvt_pf_claims_t *cl =
            claims != NULL && claims[k].width == img->width && claims[k].height == img->height ? &claims[k] : NULL;
        /* R's third column: the camera-frame direction of world up */
        const mvt_real ux = c->R[2], uy = c->R[5], uz = c->R[8];
        int n_fg = 0, n_hidden = 0;
        for (int i = 0; i < p->n; i++) {
            const mvt_real xw[3] = {p->x[i], p->y[i], p->z[i]};
            mvt_real xc[3];
            mvt_cam_to_camera(c, xw, xc);
            mvt_real lw;
            if (body == NULL) {
                const int idx = view_index(c, f, img, xc[0], xc[1], xc[2]);
                int behind;
                const uint8_t l = claimed_level(d, cl, idx, xc[2], 255u, &behind);
                lw = tab->log_d[l];
                n_fg += !behind && idx >= 0 && d[idx] > fg_level;
                n_hidden += behind != 0 || idx < 0;
                if (colour) {
                    lw += behind == 2 ? tab->log_colour_background : colour_log(tab, img->mask, idx, p->h[i], p->s[i]);
                }
            } else {
                /* the column: points at heights z + dz are xc + dz * up */
                const mvt_real dz_above = body->above_m, dz_head = -body->head_m;
                const mvt_real dz_torso = (body->torso_frac - MVT_R(1.0)) * p->z[i];
                const mvt_real dz_legs = (body->legs_frac - MVT_R(1.0)) * p->z[i];
                const mvt_real za = xc[2] + dz_above * uz, zh = xc[2] + dz_head * uz;
                const mvt_real zt = xc[2] + dz_torso * uz, zl = xc[2] + dz_legs * uz;
                const int ia = view_index(c, f, img, xc[0] + dz_above * ux, xc[1] + dz_above * uy, za);
                const int ih = view_index(c, f, img, xc[0] + dz_head * ux, xc[1] + dz_head * uy, zh);
                const int it = view_index(c, f, img, xc[0] + dz_torso * ux, xc[1] + dz_torso * uy, zt);
                const int il = view_index(c, f, img, xc[0] + dz_legs * ux, xc[1] + dz_legs * uy, zl);
                int ba, bh, bt, bl;
                const uint8_t la = claimed_level(d, cl, ia, za, 0u, &ba);
                const uint8_t lh = claimed_level(d, cl, ih, zh, 255u, &bh);
                const uint8_t lt = claimed_level(d, cl, it, zt, 255u, &bt);
                const uint8_t ll = claimed_level(d, cl, il, zl, 255u, &bl);
                (void)ba;
                (void)bl;
                lw = tab->log_bg[la] + tab->log_d[lh] + tab->log_d[lt] + tab->log_d[ll];
                if (body->face_m > MVT_R(0.0)) {
                    const mvt_real dz_face = -body->face_m, zf = xc[2] + dz_face * uz;
                    const int iff = view_index(c, f, img, xc[0] + dz_face * ux, xc[1] + dz_face * uy, zf);
                    int bf;
                    lw += tab->log_d[claimed_level(d, cl, iff, zf, 255u, &bf)];
                }
                if (body->clear_m > MVT_R(0.0)) {
                    uint8_t top_level = 0u;
                    for (int j = 1; j <= 3; j++) {
                        const mvt_real dz = body->clear_m * (mvt_real)j / MVT_R(3.0), zc = xc[2] + dz * uz;
                        const int ic = view_index(c, f, img, xc[0] + dz * ux, xc[1] + dz * uy, zc);
                        int bc;
                        const uint8_t l = claimed_level(d, cl, ic, zc, 0u, &bc);
                        top_level = l > top_level ? l : top_level;
                    }
                    lw += tab->log_bg[top_level];
                }
                n_fg += !bh && ih >= 0 && d[ih] > fg_level;
                n_hidden += bh != 0 || ih < 0;
                if (colour) {
                    lw += bt == 2 ? tab->log_colour_background : colour_log(tab, img->mask, it, p->h[i], p->s[i]);
                }
            }
            p->w[i] += exponent * lw;
        }
        if (on_fg != NULL) {
            on_fg[k] = (mvt_real)n_fg / (mvt_real)p->n;
        }
        if (hidden != NULL) {
            hidden[k] = (mvt_real)n_hidden / (mvt_real)p->n;
        }
    }
}

mvt_real mvt_pf_normalise(mvt_pf_pool_t *p)
{
    MVT_ASSERT(p != NULL && p->n >= 1 && p->n <= MVT_MAX_PARTICLES);
    mvt_real top = p->w[0];
    int finite = 1;
    for (int i = 0; i < p->n; i++) {
        finite &= isfinite(p->w[i]) ? 1 : 0;
        top = p->w[i] > top ? p->w[i] : top;
    }
    const mvt_real uniform = MVT_R(1.0) / (mvt_real)p->n;
    if (!finite) {
        for (int i = 0; i < p->n; i++) {
            p->w[i] = uniform;
        }
        return MVT_R(0.0);
    }
    mvt_real sum = MVT_R(0.0);
    for (int i = 0; i < p->n; i++) {
        p->w[i] = MVT_EXP(p->w[i] - top);
        sum += p->w[i];
    }
    mvt_real sq = MVT_R(0.0);
    for (int i = 0; i < p->n; i++) {
        p->w[i] /= sum;
        sq += p->w[i] * p->w[i];
    }
    return MVT_R(1.0) / sq;
}

/* Heap sort of idx[0..n) by key, largest first (a min-heap whose minimum goes to the back). */
static void sift_down(const mvt_real *key, uint16_t *idx, int root, int n)
{
    for (;;) { /* at most log2(n) rounds: root doubles each time */
        int child = 2 * root + 1;
        if (child >= n) {
            return;
        }
        if (child + 1 < n && key[idx[child + 1]] < key[idx[child]]) {
            child++;
        }
        if (!(key[idx[child]] < key[idx[root]])) {
            return;
        }
        const uint16_t t = idx[root];
        idx[root] = idx[child];
        idx[child] = t;
        root = child;
    }
}

static void sort_desc(const mvt_real *key, uint16_t *idx, int n)
{
    for (int i = 0; i < n; i++) {
        idx[i] = (uint16_t)i;
    }
    for (int i = n / 2 - 1; i >= 0; i--) {
        sift_down(key, idx, i, n);
    }
    for (int end = n - 1; end > 0; end--) {
        const uint16_t t = idx[0];
        idx[0] = idx[end];
        idx[end] = t;
        sift_down(key, idx, 0, end);
    }
}

void mvt_pf_estimate(const mvt_pf_pool_t *p, mvt_real p_h, mvt_real head_quantile,
                     uint16_t order[MVT_MAX_PARTICLES], mvt_pf_estimate_t *e)
{
    MVT_ASSERT(p != NULL && e != NULL && p->n >= 1 && p->n <= MVT_MAX_PARTICLES);
    memset(e, 0, sizeof(*e));
    mvt_real c = MVT_R(0.0), s = MVT_R(0.0);
    for (int i = 0; i < p->n; i++) {
        const mvt_real w = p->w[i];
        e->mean[0] += w * p->x[i];
        e->mean[1] += w * p->y[i];
        e->mean[2] += w * p->z[i];
        e->vel[0] += w * p->vx[i];
        e->vel[1] += w * p->vy[i];
        e->vel[2] += w * p->vz[i];
        c += w * MVT_COS(TWO_PI * p->h[i]);
        s += w * MVT_SIN(TWO_PI * p->h[i]);
        e->saturation += w * p->s[i];
    }
    mvt_real hue = MVT_ATAN2(s, c) / TWO_PI;
    e->hue = hue < MVT_R(0.0) ? hue + MVT_R(1.0) : hue;
    for (int i = 0; i < p->n; i++) {
        const mvt_real d[3] = {p->x[i] - e->mean[0], p->y[i] - e->mean[1], p->z[i] - e->mean[2]};
        const mvt_real w = p->w[i];
        e->cov[0] += w * d[0] * d[0];
        e->cov[1] += w * d[0] * d[1];
        e->cov[2] += w * d[0] * d[2];
        e->cov[3] += w * d[1] * d[1];
        e->cov[4] += w * d[1] * d[2];
        e->cov[5] += w * d[2] * d[2];
    }
    /* P_H volume: the fewest heaviest particles whose weights reach p_h */
    sort_desc(p->w, order, p->n);
    mvt_real acc = MVT_R(0.0);
    int m = 0;
    for (m = 0; m < p->n && acc < p_h; m++) {
        const int i = order[m];
        const mvt_real pt[3] = {p->x[i], p->y[i], p->z[i]};
        for (int a = 0; a < 3; a++) {
            if (m == 0 || pt[a] < e->box_min[a]) {
                e->box_min[a] = pt[a];
            }
            if (m == 0 || pt[a] > e->box_max[a]) {
                e->box_max[a] = pt[a];
            }
        }
        acc += p->w[i];
    }
    e->box_count = m;
    e->head_z = e->mean[2];
    if (!(head_quantile > MVT_R(0.0))) {
        return;
    }
    /* head: the weighted quantile of z (weight above it = 1 - head_quantile) */
    sort_desc(p->z, order, p->n);
    acc = MVT_R(0.0);
    e->head_z = p->z[order[0]];
    for (int j = 0; j < p->n; j++) {
        acc += p->w[order[j]];
        e->head_z = p->z[order[j]];
        if (acc >= MVT_R(1.0) - head_quantile) {
            break;
        }
    }
}

void mvt_pf_resample(mvt_pf_pool_t *p, mvt_rng_t *rng, mvt_pf_pool_t *q)
{
    MVT_ASSERT(p != NULL && q != NULL && rng != NULL && p->n >= 1 && p->n <= MVT_MAX_PARTICLES);
    const int n = p->n;
    const mvt_real step = MVT_R(1.0) / (mvt_real)n;
    mvt_real target = mvt_rng_uniform(rng) * step;
    mvt_real cum = p->w[0];
    int j = 0;
    for (int i = 0; i < n; i++) {
        while (cum < target && j < n - 1) { /* j only grows: O(n) in total */
            j++;
            cum += p->w[j];
        }
        q->x[i] = p->x[j];
        q->y[i] = p->y[j];
        q->z[i] = p->z[j];
        q->vx[i] = p->vx[j];
        q->vy[i] = p->vy[j];
        q->vz[i] = p->vz[j];
        q->h[i] = p->h[j];
        q->s[i] = p->s[j];
        target += step;
    }
    const size_t bytes = (size_t)n * sizeof(mvt_real);
    memcpy(p->x, q->x, bytes);
    memcpy(p->y, q->y, bytes);
    memcpy(p->z, q->z, bytes);
    memcpy(p->vx, q->vx, bytes);
    memcpy(p->vy, q->vy, bytes);
    memcpy(p->vz, q->vz, bytes);
    memcpy(p->h, q->h, bytes);
    memcpy(p->s, q->s, bytes);
    for (int i = 0; i < n; i++) {
        p->w[i] = step;
    }
}
