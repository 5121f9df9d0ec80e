/*
 * mvt_types.h - error codes and the programmer-error assert shared by every core module.
 */
#ifndef MVT_TYPES_H
#define MVT_TYPES_H

#include <stdint.h>
#include "mvt_config.h"

/* Data errors are negative return codes; success is 0. */
typedef enum mvt_err {
    MVT_OK = 0,
    MVT_ERR_INVALID = -1,     /* argument out of range (count, size, non-finite parameter) */
    MVT_ERR_NUMERIC = -2,     /* matrix not positive definite / singular */
    MVT_ERR_BEHIND = -3,      /* point at or behind the camera, or beyond its lens model's field */
    MVT_ERR_FULL = -4,        /* a fixed-capacity pool is full */
    MVT_ERR_NONFINITE = -5,   /* NaN or infinity in the input */
    MVT_ERR_GATED = -6,       /* measurement outside the validation gate */
    MVT_ERR_DEGENERATE = -7   /* geometry too poor to solve (parallel rays, < 2 views) */
} mvt_err_t;

/* Programmer errors (NULL self, broken invariants) go through MVT_ASSERT; override it for a
 * target (e.g. to a breakpoint or a reset) by defining it before including any core header. */
#ifndef MVT_ASSERT
#include <assert.h>
#define MVT_ASSERT(x) assert(x)
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* A microsecond interval in seconds, computed in mvt_real (no double arithmetic on an FPU that
 * has only single precision; exact for intervals below 2^24 us = 16.7 s in float). */
static inline mvt_real mvt_us_to_s(int64_t us)
{
    return (mvt_real)us * MVT_R(1e-6);
}

/* Name of an error code, for logs. Never NULL. */
const char *mvt_err_str(mvt_err_t err);

#ifdef __cplusplus
}
#endif

#endif /* MVT_TYPES_H */
