/*
 * mvtd.h - the daemon's engine: configuration from the command line, LCM message handling,
 * frame assembly, tracking, publication and status. mvtrackd.c is its main(); the fuzzer, the
 * soak and the tests drive the same engine without sockets (lcm_out NULL: messages are encoded,
 * not sent).
 */
#ifndef MVTD_H
#define MVTD_H

#include <stddef.h>
#include <stdint.h>

#include <lcm/lcm.h>

#include "assembler.h"
#include "clock.h"
#include "mvt_pft.h"
#include "mvt_tracker.h"
#include "mvt_rig.h"

#define MVTD_DEFAULT_URL "udpm://239.255.76.67:7667?ttl=0"
#define MVTD_PROC_RING 512
/* Detections of one message examined before the core chooses MVT_MAX_DETECTIONS of them. */
#define MVTD_MAX_INPUT_DETECTIONS 4096
#define MVTD_CONTINUE (-1)
/* Live: a channel over this many times the frame rate within a second is shed (ingest.c). */
#define MVTD_FLOOD_FACTOR 2.0
/* Capture times accepted, microseconds: 0 .. 2^60 (about 36,000 years). */
#define MVTD_MAX_UTIME (1LL << 60)

/* Checkpoints (--state, checkpoint.c). */
#define MVTD_CKPT_VERSION 10u /* 2: tracks remember each view's displacement; 3: and the last frame
                                 no view showed their place on background; the counters count
                                 the heads measured from the masks; 4: the existence of the body
                                 model's tracks and its cameras' clutter rates; 5: and their fragment
                                 rates; 6: and their rates of hidden heads shown and
                                 how far ahead of the head the feet show; 7: and their rates of
                                 visible heads on the mask's background; 8: the particle filter's
                                 blob tracker runs the body model; 9: how long each track's place
                                 has rested on one view; 10: the rules' timers and
                                 identity records are gone */
/* A checkpoint saved longer ago than this (capture time) before the first new message describes a
 * room that has changed (people walk 2-3 m in 2 s) and is refused, s. */
#define MVTD_CKPT_MAX_AGE_S 2.0
/* Live, a checkpoint every this many frame sets: 0.2 s at 25 fps for the blob trackers (a 49 kB
 * file at the default capacities: 245 kB/s), 1 s for the particle filters (1.2 MB each at the default capacities). A
 * restart restores what was saved up to this long before the kill. */
#define MVTD_CKPT_FRAMES 5
#define MVTD_CKPT_FRAMES_PF 25
#define MVTD_ID_BLOCK 4096                /* identities leased per write of FILE.ids */
#define MVTD_ID_EPOCH_S 1700000000LL      /* live identities start above MVTD_ID_PER_S x (now - this) */
#define MVTD_ID_PER_S 4
#define MVTD_ID_FLOOR_MAX 0x60000000      /* 1.6e9: room for 5.3e8 more identities before INT32_MAX */

typedef struct mvtd_ckpt_header {
    char magic[8];                 /* "MVTCKPT" */
    uint32_t version, endian, real_size;
    uint32_t max_targets, max_particles, max_cameras, num_cameras, num_particles;
    char mode[16];                 /* --mode */
    uint64_t state_size;           /* sizeof mvt_tracker_persist_t or mvt_pft_persist_t */
    uint64_t rig_hash;             /* FNV-1a 64 of the rig file's bytes */
    int64_t capture_utime;         /* the last processed frame, cameras' clock */
    int64_t asm_offset_us, asm_last_emitted_utime; /* the frame assembler's clock */
    int32_t id_lease;              /* identities below this may have been published */
    uint32_t state_crc;            /* CRC-32 of the state that follows the header */
    uint32_t header_crc;           /* CRC-32 of the header up to this field */
    uint32_t pad;
} mvtd_ckpt_header_t;

enum mvtd_log_class {
    MVTD_LOG_UNDECODABLE, MVTD_LOG_UNKNOWN_CAMERA, MVTD_LOG_BAD_VALUE, MVTD_LOG_CAPACITY, MVTD_LOG_TIME,
    MVTD_LOG_TRACKER, MVTD_LOG_CAMERA, MVTD_LOG_CLOCK, MVTD_LOG_CHECKPOINT, MVTD_LOG_SHED, MVTD_LOG_NCLASS
};

typedef struct mvtd {
    const char *mode_name;
    const char *in_url, *out_url;
    const char *rig_path;
    const char *state_path;    /* --state FILE, or NULL */
    uint64_t rig_hash;
    int ckpt_pending;          /* a checkpoint read at start waits for the first message */
    int32_t id_lease;          /* --state: identities below it are leased (FILE.ids) */
    int64_t ckpt_failures, ckpt_skipped;
    uint64_t ckpt_failed_seen;
    char restore_note[320];    /* what happened to the checkpoint at start (status, stderr) */
    /* admission (ingest.c): per camera, messages shed by the rate bound */
    int64_t cam_shed[MVT_MAX_CAMERAS + 1]; /* [num_cameras]: channels of no rig camera */
    double cam_window_s[MVT_MAX_CAMERAS + 1];
    int32_t cam_window_n[MVT_MAX_CAMERAS + 1];
    int32_t cam_flooding[MVT_MAX_CAMERAS + 1];
    double deadline_s;
    mvt_rig_t rig;
    int pf;                    /* particle-filter mode: pft runs, tracker is unused */
    mvt_tracker_t tracker;
    mvt_pft_t *pft;
    const mvt_tracker_t *trk;  /* the blob-level tracker in use (status, detection selection) */
    int publish_particles;     /* particles per target on MVTRACK_PARTICLES, 0: none */
    int64_t masks_decoded, masks_rejected;
    mvtd_asm_t assembler;
    mvtd_clock_t clock;        /* live: each camera's clock against the others' (clock.h) */
    mvt_output_t output;
    lcm_t *lcm_in;
    lcm_t *lcm_out;            /* NULL: encode what would be published, send nothing */
    int offline;
    int verbose;
    int quiet;                 /* no stderr lines (fuzzing) */
    double start_wall_s;
    int64_t frames_processed;
    int64_t frames_at_last_status;
    int64_t bytes_encoded;     /* lcm_out NULL: size of what would have been published */
    /* rejected input by reason (never reset) */
    int64_t rej_undecodable, rej_unknown_camera, rej_bad_value, rej_over_capacity, rej_time_backwards, rej_time_ahead, rej_late,
        rej_duplicate, rej_clock;
    int64_t cam_messages[MVT_MAX_CAMERAS];
    int64_t cam_messages_at_last_status[MVT_MAX_CAMERAS];
    int64_t cam_last_frame[MVT_MAX_CAMERAS];
    int64_t cam_counter_restarts[MVT_MAX_CAMERAS];
    double cam_last_wall_s[MVT_MAX_CAMERAS];
    double last_status_wall_s;
    double last_accept_wall_s;
    float proc_ms[MVTD_PROC_RING];
    float latency_ms[MVTD_PROC_RING];
    int n_proc;
    double log_last_s[MVTD_LOG_NCLASS];
    int64_t log_suppressed[MVTD_LOG_NCLASS];
    uint64_t tracker_births_full_seen;
    uint64_t went_down_seen[MVT_MAX_CAMERAS], came_back_seen[MVT_MAX_CAMERAS], clock_jumps_seen;
    mvt_view_t scratch_view;
    mvt_detection_t input_dets[MVTD_MAX_INPUT_DETECTIONS];
} mvtd_t;

/* Parses the command line, loads the rig and initialises the tracker. Returns MVTD_CONTINUE, or
 * the exit status (0 after --help, 2 on bad arguments or rig) having printed why. No LCM yet. */
int mvtd_configure(mvtd_t *d, int argc, char **argv);

/* Opens the LCM URLs and subscribes. Returns MVTD_CONTINUE or exit status 1. */
int mvtd_open(mvtd_t *d);

/* Runs until SIGINT/SIGTERM (live) or the end of the log (file://); returns the exit status. */
int mvtd_run(mvtd_t *d);

/* One message as LCM would deliver it on channel (the handler of DETECTIONS_.*). */
void mvtd_handle(mvtd_t *d, const char *channel, const void *data, uint32_t size);

/* 0 when a camera_frame_t message's counts and string fit inside its size (see ingest.c). */
int mvtd_frame_wire_check(const void *data, uint32_t size);

/* Live mode housekeeping at wall time now: the open set's deadline, the status period. */
void mvtd_tick(mvtd_t *d);

/* Processes the frame set in hand, publishes the final status, closes LCM. */
void mvtd_finish(mvtd_t *d);

void mvtd_publish_status(mvtd_t *d);

/* --state FILE (checkpoint.c). mvtd_configure calls mvtd_ckpt_open: reads and checks the
 * checkpoint and the identity lease, starts the writer. The first message of a rig camera decides
 * whether the checkpoint is restored (mvtd_ckpt_first_message). */
void mvtd_ckpt_open(mvtd_t *d);
/* Checks a checkpoint file's bytes against this daemon (header, capacities, rig, mode, CRCs): 0 and
 * the state kept for the first message, or -1 with the reason in why. Never touches the tracker. */
int mvtd_ckpt_parse(mvtd_t *d, const void *data, size_t size, char *why, size_t why_n);
void mvtd_ckpt_first_message(mvtd_t *d, int64_t utime);
/* The header this daemon writes and accepts: times, lease and CRCs zero. */
void mvtd_ckpt_expected_header(const mvtd_t *d, mvtd_ckpt_header_t *h);
/* Before a frame's tracks are published: extends the identity lease when they reach it. */
int mvtd_ckpt_ids(mvtd_t *d);
/* Hands the current state to the writer thread (wait: until it is on disk). */
void mvtd_ckpt_save(mvtd_t *d, int wait);
void mvtd_ckpt_stats(mvtd_t *d, int64_t *written, int64_t *failed, float *age_s);
/* Saves a last time, waits for the disk, stops the writer. */
void mvtd_ckpt_close(mvtd_t *d);
uint32_t mvtd_crc32(const void *data, size_t n);

#endif /* MVTD_H */
