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
 * A difference in detection or transport delay between cameras is measured as an offset too; the
 * tracks tell it apart (below).
 *
 * What the tracks say (live, mvtd_clock_motion_sample): a camera whose frames carry a time later
 * than their true capture by d shows each moving person where they were d earlier. A track fuses
 * its cameras, so it lags by about their mean d; camera k's residuals r (detection minus the
 * track's head projected at the view's time) then follow the head's image velocity u' as
 * r = a - (d_k - mean d) u', with a a constant offset of the blob's top from the head. The
 * least-squares slope over the camera's residuals (a regression with intercept, forgotten over
 * MVTD_CLOCK_MOTION_TAU_S), minus the median camera's, is its lag against the others, with a
 * standard error from the residuals' scatter; known once that error is under
 * MVTD_CLOCK_MOTION_SE_US for three cameras or more (with two, which one is late is not known).
 * It measures what arrival times cannot: a camera whose detector or network is slower than the
 * others' has its frames assembled by when they arrive (above), so they are used that much late,
 * and the tracks show it. It is reported (MVTRACK_STATUS) and said once when it has stayed beyond
 * MVTD_CLOCK_WARN_US (and four errors) for MVTD_CLOCK_MOTION_WARN_US (the first seconds' tracks,
 * with velocities still unsure, can mislead it), not corrected: the time its frames were captured is earlier than the frame set they arrive in,
 * and the tracker, which moves forward from set to set, cannot use a view before its last one.
 * Static memory: MVT_MAX_CAMERAS x MVTD_CLOCK_N samples and 9 sums.
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
#define MVTD_CLOCK_MOTION_TAU_S 20.0 /* the tracks' evidence is forgotten over this, s */
#define MVTD_CLOCK_MOTION_SE_US 3000 /* the tracks' lag is known once its standard error is under this */
#define MVTD_CLOCK_MOTION_WARN_US 10000000 /* ... and said once it has stayed beyond MVTD_CLOCK_WARN_US this long */

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
    /* what the tracks say: sums of the regression r = a - d u' (count, u', r, u'.u', r.u', r.r),
     * and the estimate */
    double m_n[MVT_MAX_CAMERAS], m_u[MVT_MAX_CAMERAS][2], m_r[MVT_MAX_CAMERAS][2];
    double m_uu[MVT_MAX_CAMERAS], m_ru[MVT_MAX_CAMERAS], m_rr[MVT_MAX_CAMERAS];
    double lag_us[MVT_MAX_CAMERAS], lag_se_us[MVT_MAX_CAMERAS]; /* d against the median camera's, its error */
    int lag_known[MVT_MAX_CAMERAS];          /* lag_se_us under MVTD_CLOCK_MOTION_SE_US */
    int64_t lag_over_since_us[MVT_MAX_CAMERAS]; /* frame time since which the lag is known beyond
                                                 MVTD_CLOCK_WARN_US and four errors (0: it is not) */
    int lag_warned[MVT_MAX_CAMERAS];
    int64_t motion_last_us;                  /* frame time of the last mvtd_clock_motion_frame */
} mvtd_clock_t;

void mvtd_clock_init(mvtd_clock_t *c, int num_cameras);

/* Camera cam's message stamped utime arrived at wall time arrival_us: records the sample, updates
 * the estimate, and says what to do with the message (*utime_out: its time, corrected when the
 * estimate is confident). half_period_us: half the rig's frame period. */
mvtd_clock_verdict_t mvtd_clock_observe(mvtd_clock_t *c, int cam, int64_t utime, int64_t arrival_us,
                                        int64_t half_period_us, int64_t *utime_out);

/* One moving track's residual in camera cam: r (px) = the detection it took minus its head
 * projected at the view's time, udot (px/s) its head's image velocity there. The track must not
 * follow this camera (other cameras placed it), or its residual says nothing of time. */
void mvtd_clock_motion_sample(mvtd_clock_t *c, int cam, const double r[2], const double udot[2]);

/* After a frame set's samples (frame time utime_us, assembler time): forgets over
 * MVTD_CLOCK_MOTION_TAU_S and updates each camera's lag estimate. */
void mvtd_clock_motion_frame(mvtd_clock_t *c, int64_t utime_us);

#endif /* MVTD_CLOCK_H */
