/*
 * clock.c - each camera's capture clock against the other cameras' (clock.h).
 */
#include "clock.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void mvtd_clock_init(mvtd_clock_t *c, int num_cameras)
{
    memset(c, 0, sizeof(*c));
    c->num_cameras = num_cameras;
}

static int cmp_i64(const void *a, const void *b)
{
    const int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

static int64_t median_of(int64_t *v, int n)
{
    qsort(v, (size_t)n, sizeof(v[0]), cmp_i64);
    return n % 2 ? v[n / 2] : v[n / 2 - 1] + (v[n / 2] - v[n / 2 - 1]) / 2;
}

/* The median over the cameras with samples of their medians, and how many they are. */
static int64_t reference(const mvtd_clock_t *c, int min_samples, int *count)
{
    int64_t m[MVT_MAX_CAMERAS];
    int n = 0;
    for (int k = 0; k < c->num_cameras; k++) {
        if (c->n[k] >= min_samples) {
            m[n++] = c->median[k];
        }
    }
    *count = n;
    return n > 0 ? median_of(m, n) : 0;
}

mvtd_clock_verdict_t mvtd_clock_observe(mvtd_clock_t *c, int cam, int64_t utime, int64_t arrival_us,
                                        int64_t half_period_us, int64_t *utime_out)
{
    *utime_out = utime;
    if (cam < 0 || cam >= c->num_cameras) {
        return MVTD_CLOCK_ACCEPT;
    }
    const int64_t smp = utime - arrival_us;
    const int64_t step = smp - c->median[cam];
    const int stepped = c->n[cam] >= MVTD_CLOCK_PROVISIONAL && (step > half_period_us || step < -half_period_us);
    c->steps[cam] = stepped ? c->steps[cam] + 1 : 0;
    if (c->steps[cam] >= MVTD_CLOCK_PROVISIONAL) {
        c->n[cam] = 0; /* the camera's clock (or all clocks) stepped: learn it again */
        c->head[cam] = 0;
        c->steps[cam] = 0;
    }
    c->sample[cam][c->head[cam]] = smp;
    c->head[cam] = (c->head[cam] + 1) % MVTD_CLOCK_N;
    if (c->n[cam] < MVTD_CLOCK_N) {
        c->n[cam]++;
    }
    int64_t tmp[MVTD_CLOCK_N];
    memcpy(tmp, c->sample[cam], (size_t)c->n[cam] * sizeof(tmp[0]));
    c->median[cam] = median_of(tmp, c->n[cam]);

    int n_ref = 0;
    const int64_t ref = reference(c, MVTD_CLOCK_PROVISIONAL, &n_ref);
    c->offset_us[cam] = c->median[cam] - ref;
    c->confident[cam] = n_ref >= 2 && c->n[cam] >= MVTD_CLOCK_MIN;
    const int64_t off = c->offset_us[cam];
    const int64_t mag = off < 0 ? -off : off;
    if (c->confident[cam]) {
        if (mag > MVTD_CLOCK_MAX_US) {
            c->refused[cam]++;
            return MVTD_CLOCK_FAR;
        }
        if (mag > MVTD_CLOCK_WARN_US) {
            *utime_out = utime - off; /* within that, delays differ as much: the assembler's half period holds it */
        }
        return MVTD_CLOCK_ACCEPT;
    }
    if (n_ref >= 2 && c->n[cam] >= MVTD_CLOCK_PROVISIONAL && mag > half_period_us) {
        c->refused[cam]++;
        return MVTD_CLOCK_LEARNING;
    }
    return MVTD_CLOCK_ACCEPT;
}

void mvtd_clock_motion_sample(mvtd_clock_t *c, int cam, const double r[2], const double udot[2])
{
    if (cam < 0 || cam >= c->num_cameras) {
        return;
    }
    c->m_n[cam] += 1.0;
    for (int a = 0; a < 2; a++) {
        c->m_u[cam][a] += udot[a];
        c->m_r[cam][a] += r[a];
    }
    c->m_uu[cam] += udot[0] * udot[0] + udot[1] * udot[1];
    c->m_ru[cam] += r[0] * udot[0] + r[1] * udot[1];
    c->m_rr[cam] += r[0] * r[0] + r[1] * r[1];
}

/* The slope d (s) of r = a - d u' over camera k's sums, and its standard error; 0 when too few. */
static int motion_lag(const mvtd_clock_t *c, int k, double *lag_s, double *se_s)
{
    const double n = c->m_n[k];
    if (n < 20.0) {
        return 0;
    }
    const double mu[2] = {c->m_u[k][0] / n, c->m_u[k][1] / n}, mr[2] = {c->m_r[k][0] / n, c->m_r[k][1] / n};
    const double suu = c->m_uu[k] - n * (mu[0] * mu[0] + mu[1] * mu[1]);
    const double sru = c->m_ru[k] - n * (mr[0] * mu[0] + mr[1] * mu[1]);
    const double srr = c->m_rr[k] - n * (mr[0] * mr[0] + mr[1] * mr[1]);
    if (!(suu > 0.0)) {
        return 0;
    }
    const double d = -sru / suu;
    double var = (srr - d * d * suu) / (2.0 * n - 3.0); /* per image axis, after the fit */
    if (!(var > 0.0)) {
        var = 0.0;
    }
    *lag_s = d;
    *se_s = sqrt(var / suu);
    return 1;
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

void mvtd_clock_motion_frame(mvtd_clock_t *c, int64_t utime_us)
{
    const double dt = c->motion_last_us > 0 && utime_us > c->motion_last_us ? (double)(utime_us - c->motion_last_us) * 1e-6
                                                                              : 0.0;
    c->motion_last_us = utime_us;
    const double keep = exp(-dt / MVTD_CLOCK_MOTION_TAU_S);
    double slope[MVT_MAX_CAMERAS], se[MVT_MAX_CAMERAS], sure[MVT_MAX_CAMERAS];
    int ok[MVT_MAX_CAMERAS], n_sure = 0;
    for (int k = 0; k < c->num_cameras; k++) {
        c->m_n[k] *= keep;
        c->m_u[k][0] *= keep;
        c->m_u[k][1] *= keep;
        c->m_r[k][0] *= keep;
        c->m_r[k][1] *= keep;
        c->m_uu[k] *= keep;
        c->m_ru[k] *= keep;
        c->m_rr[k] *= keep;
        ok[k] = motion_lag(c, k, &slope[k], &se[k]);
        if (ok[k] && se[k] * 1e6 < MVTD_CLOCK_MOTION_SE_US) {
            sure[n_sure++] = slope[k];
        }
    }
    /* against the median camera: the tracks lag by their cameras' mean lag, which every camera's
     * slope carries; with three cameras or more the median is an on-time one */
    qsort(sure, (size_t)n_sure, sizeof(sure[0]), cmp_double);
    const double ref = n_sure == 0 ? 0.0 : n_sure % 2 ? sure[n_sure / 2] : 0.5 * (sure[n_sure / 2 - 1] + sure[n_sure / 2]);
    for (int k = 0; k < c->num_cameras; k++) {
        if (ok[k]) {
            c->lag_us[k] = (slope[k] - ref) * 1e6;
            c->lag_se_us[k] = se[k] * 1e6;
        }
        c->lag_known[k] = ok[k] && n_sure >= 3 && se[k] * 1e6 < MVTD_CLOCK_MOTION_SE_US;
        const int over = c->lag_known[k] && fabs(c->lag_us[k]) > (double)MVTD_CLOCK_WARN_US &&
                         fabs(c->lag_us[k]) > 4.0 * c->lag_se_us[k];
        c->lag_over_since_us[k] = !over ? 0 : c->lag_over_since_us[k] != 0 ? c->lag_over_since_us[k] : utime_us;
    }
}
