/*
 * clock.h - each camera's capture clock against the other cameras', from when its frames arrive.
 *
 * A camera's sample is (capture time it stamped) - (wall time its message arrived here). Cameras on
 * one clock differ in these only by their detection and transport delays; a camera whose clock is
 * off differs by that much more. Each camera keeps its last MVTD_CLOCK_N samples; its offset is the
 * median of its samples minus the median over the cameras of theirs (so one camera off among
 * several is measured against the rest, and the delays' noise is a median's). The estimate is
 * confident from MVTD_CLOCK_MIN samples, with two cameras or more. MVTD_CLOCK_PROVISIONAL samples in a
 * row more than half a frame period from the camera's median are a step of its clock (or of every
 * camera's: the assembler re-bases those), not a late message: the camera learns again from them.
 *
 * What the daemon does with it (live only: a log's arrival times are the replay's), for a message:
 *   confident, |offset| <= MVTD_CLOCK_WARN_US  accepted as stamped (cameras' delays differ as
 *                                              much; half a frame period absorbs it)
 *   confident, |offset| <= MVTD_CLOCK_MAX_US   accepted, its capture time corrected by the offset
 *                                              (frame sets are assembled and the tracker predicts
 *                                              on the corrected time)
 *   confident, |offset| >  MVTD_CLOCK_MAX_US   refused: no correction is trusted that far
 *   learning, the provisional offset (from MVTD_CLOCK_PROVISIONAL samples) beyond half a frame
 *   period                                     refused until confident: it would open frame sets
 *                                              the other cameras' messages then arrive late for
 *   otherwise                                  accepted as stamped
 * A difference in detection delay between cameras is measured as an offset too: the correction
 * then aligns frames by when they were detected, which a shared clock does not need.
 * Static memory: MVT_MAX_CAMERAS x MVTD_CLOCK_N samples.
 */
#ifndef MVTD_CLOCK_H
#define MVTD_CLOCK_H

#include <stdint.h>

#include "mvt_config.h"

#define MVTD_CLOCK_N 50              /* samples kept per camera: 2 s at 25 fps */
#define MVTD_CLOCK_MIN 25            /* samples before an offset is trusted */
#define MVTD_CLOCK_PROVISIONAL 3     /* samples before a learning camera can be held back */
#define MVTD_CLOCK_WARN_US 10000     /* reported once per camera beyond this (10 ms) */
#define MVTD_CLOCK_MAX_US 500000     /* corrected up to this; beyond, refused */

typedef enum mvtd_clock_verdict {
    MVTD_CLOCK_ACCEPT = 0,   /* *utime_out is the time to use */
    MVTD_CLOCK_LEARNING = 1, /* refused while its offset is learnt */
    MVTD_CLOCK_FAR = 2       /* refused: the clock is more than MVTD_CLOCK_MAX_US off */
} mvtd_clock_verdict_t;

typedef struct mvtd_clock {
    int num_cameras;
    int64_t sample[MVT_MAX_CAMERAS][MVTD_CLOCK_N];
    int n[MVT_MAX_CAMERAS];      /* samples held, <= MVTD_CLOCK_N */
    int head[MVT_MAX_CAMERAS];
    int64_t median[MVT_MAX_CAMERAS];
    int64_t offset_us[MVT_MAX_CAMERAS];
    int confident[MVT_MAX_CAMERAS];
    int warned[MVT_MAX_CAMERAS]; /* 0, or the verdict last reported (1: re-timed, 2: refused) */
    int64_t refused[MVT_MAX_CAMERAS];
    int steps[MVT_MAX_CAMERAS];  /* samples in a row off the camera's median by over half a period */
} mvtd_clock_t;

void mvtd_clock_init(mvtd_clock_t *c, int num_cameras);

/* Camera cam's message stamped utime arrived at wall time arrival_us: records the sample, updates
 * the estimate, and says what to do with the message (*utime_out: its time, corrected when the
 * estimate is confident). half_period_us: half the rig's frame period. */
mvtd_clock_verdict_t mvtd_clock_observe(mvtd_clock_t *c, int cam, int64_t utime, int64_t arrival_us,
                                        int64_t half_period_us, int64_t *utime_out);

#endif /* MVTD_CLOCK_H */
