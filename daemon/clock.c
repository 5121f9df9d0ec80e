/*
 * clock.c - each camera's capture clock against the other cameras' (clock.h).
 */
#include "clock.h"

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
