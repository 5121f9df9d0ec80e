/*
 * log.c - the daemon's clocks and its rate-limited stderr.
 */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#include "engine.h"

#include <stdarg.h>
#include <stdio.h>
#include <time.h>

double mvtd_wall_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

int64_t mvtd_wall_utime(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}


int mvtd_log(mvtd_t *d, enum mvtd_log_class cls, const char *fmt, ...)
{
    const double now = mvtd_wall_s();
    if (d->quiet || now - d->log_last_s[cls] < 1.0) {
        d->log_suppressed[cls]++;
        return 0;
    }
    d->log_last_s[cls] = now;
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "mvtrackd: ");
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    if (d->log_suppressed[cls] > 0) {
        fprintf(stderr, " (+%lld similar suppressed)", (long long)d->log_suppressed[cls]);
        d->log_suppressed[cls] = 0;
    }
    fputc('\n', stderr);
    return 1;
}
