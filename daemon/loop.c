/*
 * loop.c - the socket side: LCM opened and subscribed, the live loop (one poll over LCM, signals,
 * the frame-set deadline and the status period) or the offline loop over a log, and shutdown.
 */
#define _GNU_SOURCE /* signalfd, timerfd */
#include "engine.h"

#include <errno.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <sys/signalfd.h>
#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

static void on_detections(const lcm_recv_buf_t *rbuf, const char *channel, void *ctx)
{
    mvtd_handle(ctx, channel, rbuf->data, rbuf->data_size);
}

static lcm_subscription_t *g_sub;

/* Multicast input without recv_buf_size gets 4 MB: a frame set of foreground masks is a few
 * hundred UDP fragments, more than a default socket buffer holds while the tracker works. */
static const char *with_recv_buf(const char *url)
{
    static char buf[1024];
    if (strncmp(url, "udpm://", 7) != 0 || strstr(url, "recv_buf_size=") != NULL ||
        strlen(url) + 32 >= sizeof(buf)) {
        return url;
    }
    snprintf(buf, sizeof(buf), "%s%crecv_buf_size=4194304", url, strchr(url, '?') != NULL ? '&' : '?');
    return buf;
}

int mvtd_open(mvtd_t *d)
{
    if (strcmp(d->out_url, d->in_url) == 0) {
        d->out_url = d->in_url = with_recv_buf(d->in_url);
    } else {
        d->in_url = with_recv_buf(d->in_url);
    }
    d->lcm_in = lcm_create(d->in_url);
    if (d->lcm_in == NULL) {
        fprintf(stderr, "mvtrackd: cannot open LCM input '%s'\n", d->in_url);
        return 1;
    }
    if (strcmp(d->out_url, d->in_url) == 0) {
        d->lcm_out = d->lcm_in;
    } else {
        d->lcm_out = lcm_create(d->out_url);
        if (d->lcm_out == NULL) {
            fprintf(stderr, "mvtrackd: cannot open LCM output '%s'\n", d->out_url);
            lcm_destroy(d->lcm_in);
            d->lcm_in = NULL;
            return 1;
        }
    }
    g_sub = lcm_subscribe(d->lcm_in, "DETECTIONS_.*", on_detections, d);
    if (!d->offline) {
        lcm_subscription_set_queue_capacity(g_sub, 256);
    }
    if (d->rig.num_occluders > 0) {
        fprintf(stderr, "mvtrackd: %d cameras, mode %s, %d static occluders, in %s, out %s\n", d->rig.num_cameras,
                d->mode_name, d->rig.num_occluders, d->in_url, d->out_url);
    } else {
        fprintf(stderr, "mvtrackd: %d cameras, mode %s, in %s, out %s\n", d->rig.num_cameras, d->mode_name, d->in_url,
                d->out_url);
    }
    return MVTD_CONTINUE;
}

void mvtd_tick(mvtd_t *d)
{
    if (!d->offline) {
        mvtd_asm_poll(&d->assembler, mvtd_wall_s(), d->deadline_s);
    }
    if (mvtd_wall_s() - d->last_status_wall_s >= 1.0) {
        mvtd_publish_status(d);
        if (d->verbose) {
            fprintf(stderr, "mvtrackd: %lld frames, %lld complete, %lld partial\n", (long long)d->frames_processed,
                    (long long)d->assembler.counters.sets_complete, (long long)d->assembler.counters.sets_partial);
        }
    }
}

static int run_offline(mvtd_t *d, int sig_fd)
{
    while (lcm_handle(d->lcm_in) == 0) {
        mvtd_tick(d);
        struct signalfd_siginfo si;
        if (read(sig_fd, &si, sizeof(si)) == (ssize_t)sizeof(si)) {
            break; /* SIGINT/SIGTERM: stop reading the log */
        }
    }
    return 0;
}

/* Arms the one-shot deadline timer for the open frame set (disarms it when none is open). */
static void arm_deadline(mvtd_t *d, int timer_fd)
{
    struct itimerspec its;
    memset(&its, 0, sizeof(its));
    const double dl = mvtd_asm_time_to_deadline(&d->assembler, mvtd_wall_s(), d->deadline_s);
    if (dl > -1e29) {
        const double w = dl > 1e-6 ? dl : 1e-6; /* zero would disarm */
        its.it_value.tv_sec = (time_t)w;
        its.it_value.tv_nsec = (long)((w - (double)its.it_value.tv_sec) * 1e9);
    }
    timerfd_settime(timer_fd, 0, &its, NULL);
}

/* Live: one poll() over the LCM socket, the signals (signalfd), the frame-set deadline and the
 * status period (timerfds). Every wake-up drains LCM completely before anything else. */
static int run_live(mvtd_t *d, int sig_fd)
{
    const int deadline_fd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
    const int status_fd = timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
    if (deadline_fd < 0 || status_fd < 0) {
        perror("mvtrackd: timerfd_create");
        return 1;
    }
    const struct itimerspec second = {{1, 0}, {1, 0}};
    timerfd_settime(status_fd, 0, &second, NULL);
    struct pollfd pfd[4] = {{lcm_get_fileno(d->lcm_in), POLLIN, 0}, {sig_fd, POLLIN, 0}, {deadline_fd, POLLIN, 0},
                            {status_fd, POLLIN, 0}};
    int rc = 0;
    for (;;) {
        arm_deadline(d, deadline_fd);
        const int pr = poll(pfd, 4, -1);
        if (pr < 0) {
            if (errno == EINTR) {
                continue;
            }
            perror("mvtrackd: poll");
            rc = 1;
            break;
        }
        if (pfd[0].revents & POLLIN) {
            while (lcm_handle_timeout(d->lcm_in, 0) > 0) { /* drain everything queued */
            }
        }
        uint64_t expirations;
        if (pfd[2].revents & POLLIN) {
            (void)read(deadline_fd, &expirations, sizeof(expirations));
        }
        if (pfd[3].revents & POLLIN) {
            (void)read(status_fd, &expirations, sizeof(expirations));
        }
        mvtd_tick(d);
        if (pfd[1].revents & POLLIN) {
            struct signalfd_siginfo si;
            if (read(sig_fd, &si, sizeof(si)) == (ssize_t)sizeof(si)) {
                fprintf(stderr, "mvtrackd: %s: finishing the frame in hand\n", strsignal((int)si.ssi_signo));
                break;
            }
        }
    }
    close(deadline_fd);
    close(status_fd);
    return rc;
}

int mvtd_run(mvtd_t *d)
{
    sigset_t mask;
    sigemptyset(&mask);
    sigaddset(&mask, SIGINT);
    sigaddset(&mask, SIGTERM);
    sigprocmask(SIG_BLOCK, &mask, NULL);
    signal(SIGPIPE, SIG_IGN);
    const int sig_fd = signalfd(-1, &mask, SFD_NONBLOCK | SFD_CLOEXEC);
    if (sig_fd < 0) {
        perror("mvtrackd: signalfd");
        return 1;
    }
    const int rc = d->offline ? run_offline(d, sig_fd) : run_live(d, sig_fd);
    close(sig_fd);
    return rc;
}

void mvtd_finish(mvtd_t *d)
{
    mvtd_asm_flush(&d->assembler); /* the frame in hand */
    mvtd_ckpt_close(d);            /* the last state, on disk before exit */
    mvtd_publish_status(d);
    if (!d->quiet) {
        fprintf(stderr,
                "mvtrackd: done: %lld frames (%llu complete, %llu partial); rejected: %lld undecodable, %lld unknown "
                "camera, %lld bad value, %lld over capacity, %lld time backwards, %lld late, %lld duplicate\n",
                (long long)d->frames_processed, (unsigned long long)d->assembler.counters.sets_complete,
                (unsigned long long)d->assembler.counters.sets_partial, (long long)d->rej_undecodable,
                (long long)d->rej_unknown_camera, (long long)d->rej_bad_value, (long long)d->rej_over_capacity,
                (long long)d->rej_time_backwards, (long long)d->rej_late, (long long)d->rej_duplicate);
    }
    if (d->lcm_in != NULL) {
        lcm_unsubscribe(d->lcm_in, g_sub);
        if (d->lcm_out != d->lcm_in) {
            lcm_destroy(d->lcm_out);
        }
        lcm_destroy(d->lcm_in);
        d->lcm_in = d->lcm_out = NULL;
    }
}
