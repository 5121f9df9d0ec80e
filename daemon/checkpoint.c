/*
 * checkpoint.c - --state FILE: the tracker survives the daemon's restart.
 *
 * Saving. Live, every MVTD_CKPT_FRAMES frame sets (0.2 s; 1 s in pf modes) and at shutdown, the
 * tracker's persistent state (mvt_tracker_save / mvt_pft_save: tracks, particles, identities,
 * clock, counters) and the frame assembler's clock go to FILE: written to FILE.tmp by a writer
 * thread (fsync can take tens of milliseconds; the frame loop never waits for the disk), fsync'ed,
 * renamed over FILE, the directory fsync'ed. Offline, at the end of the log only. A crash at any moment leaves the previous checkpoint or the new one, whole.
 * Nothing is saved before the first frame of a run: a daemon restarted with no camera sending
 * must not replace a good checkpoint with an empty one.
 *
 * Restoring. At start FILE is read and checked: header (magic, format version, byte order,
 * sizeof of the real type and of the state, capacities, camera count, mode, particles), a hash
 * of the rig file's bytes, and CRC-32s of header and state. A checkpoint that passes waits for
 * the first camera message: restored when that message's capture time is no earlier than the
 * checkpoint's and at most MVTD_CKPT_MAX_AGE_S later (older states describe a room that has changed),
 * then checked value by value by the core (mvt_*_resume), which copies nothing unless all of it
 * is sound. Everything else is refused with one log line and a clean start. The time the daemon
 * was down counts as unobserved, not as "unseen" (see mvt_tracker_resume).
 *
 * Identities. An id is never reused within a run (docs/interfaces.md); across restarts mvtrackd promises
 * the same. With --state, identities are leased in blocks of MVTD_ID_BLOCK: before a frame's
 * tracks carry an identity at or above the lease, the new lease is written (FILE.ids, fsync'ed)
 * and only then published. A restart continues above the lease from FILE.ids or from the
 * checkpoint's header, whichever is higher, so an identity published between the last checkpoint
 * and a kill -9 is never given again. Live, with or without --state, identities also start above
 * MVTD_ID_PER_S x (wall-clock seconds since MVTD_ID_EPOCH_S): a restart with no usable file at all
 * stays above every identity of a previous run that gave fewer than MVTD_ID_PER_S identities per
 * second of its life. Offline (file:// input) without --state, identities start at 1 (the same
 * log gives the same TRACKS).
 */
#define _GNU_SOURCE /* O_CLOEXEC, pthread */
#include "engine.h"

#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#define CKPT_MAGIC "MVTCKPT"
#define CKPT_ENDIAN 0x01020304u

/* The state of either tracker, as saved. */
typedef union ckpt_state {
    mvt_tracker_persist_t trk;
    mvt_pft_persist_t pft;
} ckpt_state_t;

typedef struct ckpt_file {
    mvtd_ckpt_header_t h;
    ckpt_state_t state;
} ckpt_file_t;

/* One daemon per process uses --state: its buffers are static (the PF state is about 1.2 MB). */
static ckpt_file_t g_loaded;  /* read at start, waiting for the first message */
static ckpt_file_t g_out;     /* handed to the writer thread */

static struct {
    pthread_mutex_t mu;
    pthread_cond_t cv;
    pthread_t thread;
    int started, busy, stop;
    char path[4096], tmp[4200];
    size_t size;
    /* written by the writer, read under mu */
    uint64_t written, failed;
    int last_errno;
    double last_ok_wall_s;
} g_w = {.mu = PTHREAD_MUTEX_INITIALIZER, .cv = PTHREAD_COND_INITIALIZER};

static uint32_t g_crc_table[256];
static pthread_once_t g_crc_once = PTHREAD_ONCE_INIT;

static void crc_table_init(void)
{
    for (uint32_t i = 0; i < 256; i++) {
        uint32_t c = i;
        for (int k = 0; k < 8; k++) {
            c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
        }
        g_crc_table[i] = c;
    }
}

/* CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320; zlib's crc32), a byte at a time by table. */
uint32_t mvtd_crc32(const void *data, size_t n)
{
    pthread_once(&g_crc_once, crc_table_init);
    const uint8_t *p = data;
    uint32_t c = 0xffffffffu;
    for (size_t i = 0; i < n; i++) {
        c = g_crc_table[(c ^ p[i]) & 0xffu] ^ (c >> 8);
    }
    return ~c;
}

/* FNV-1a 64 of a file's bytes; 0 when it cannot be read. */
static uint64_t file_hash(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        return 0;
    }
    uint64_t h = 0xcbf29ce484222325ull;
    uint8_t buf[65536];
    size_t n;
    while ((n = fread(buf, 1, sizeof(buf), f)) > 0) {
        for (size_t i = 0; i < n; i++) {
            h = (h ^ buf[i]) * 0x100000001b3ull;
        }
    }
    fclose(f);
    return h;
}

static size_t state_size(const mvtd_t *d)
{
    return d->pf ? sizeof(mvt_pft_persist_t) : sizeof(mvt_tracker_persist_t);
}

static int32_t published_next_id(const mvtd_t *d)
{
    return d->pf ? d->pft->next_id : d->tracker.next_id;
}

static void reserve_ids(mvtd_t *d, int32_t first)
{
    if (d->pf) {
        mvt_pft_reserve_ids(d->pft, first);
    } else {
        mvt_tracker_reserve_ids(&d->tracker, first);
    }
}

void mvtd_ckpt_expected_header(const mvtd_t *d, mvtd_ckpt_header_t *h)
{
    memset(h, 0, sizeof(*h));
    memcpy(h->magic, CKPT_MAGIC, sizeof(CKPT_MAGIC));
    h->version = MVTD_CKPT_VERSION;
    h->endian = CKPT_ENDIAN;
    h->real_size = (uint32_t)sizeof(mvt_real);
    h->max_targets = MVT_MAX_TARGETS;
    h->max_particles = MVT_MAX_PARTICLES;
    h->max_cameras = MVT_MAX_CAMERAS;
    h->num_cameras = (uint32_t)d->rig.num_cameras;
    h->num_particles = d->pf ? (uint32_t)d->pft->cfg.num_particles : 0u;
    snprintf(h->mode, sizeof(h->mode), "%s", d->mode_name);
    h->state_size = (uint64_t)state_size(d);
    h->rig_hash = d->rig_hash;
}

static uint32_t header_crc(const mvtd_ckpt_header_t *h)
{
    return mvtd_crc32(h, offsetof(mvtd_ckpt_header_t, header_crc));
}

int mvtd_ckpt_parse(mvtd_t *d, const void *data, size_t size, char *why, size_t why_n)
{
    mvtd_ckpt_header_t want, h;
    mvtd_ckpt_expected_header(d, &want);
    if (size < sizeof(h)) {
        snprintf(why, why_n, "%zu bytes, shorter than its header (truncated?)", size);
        return -1;
    }
    memcpy(&h, data, sizeof(h));
    if (memcmp(h.magic, CKPT_MAGIC, sizeof(CKPT_MAGIC)) != 0) {
        snprintf(why, why_n, "not an mvtrackd checkpoint");
        return -1;
    }
    if (header_crc(&h) != h.header_crc) {
        snprintf(why, why_n, "header checksum wrong (corrupted)");
        return -1;
    }
    if (h.version != want.version || h.endian != want.endian || h.real_size != want.real_size) {
        snprintf(why, why_n, "format %u (byte order %08x, %u-byte reals), this build writes %u (%08x, %u)", h.version,
                 h.endian, h.real_size, want.version, want.endian, want.real_size);
        return -1;
    }
    if (h.max_targets != want.max_targets || h.max_particles != want.max_particles ||
        h.max_cameras != want.max_cameras || h.state_size != want.state_size) {
        snprintf(why, why_n, "capacities %u targets, %u particles, %u cameras, %llu-byte state; this build %u, %u, %u, %llu",
                 h.max_targets, h.max_particles, h.max_cameras, (unsigned long long)h.state_size, want.max_targets,
                 want.max_particles, want.max_cameras, (unsigned long long)want.state_size);
        return -1;
    }
    if (h.rig_hash != want.rig_hash || h.num_cameras != want.num_cameras) {
        snprintf(why, why_n, "saved with another rig file (%u cameras, hash %016llx; now %u, %016llx)", h.num_cameras,
                 (unsigned long long)h.rig_hash, want.num_cameras, (unsigned long long)want.rig_hash);
        return -1;
    }
    h.mode[sizeof(h.mode) - 1] = '\0';
    if (strcmp(h.mode, want.mode) != 0 || h.num_particles != want.num_particles) {
        snprintf(why, why_n, "saved by mode %s with %u particles, this daemon runs %s with %u", h.mode, h.num_particles,
                 want.mode, want.num_particles);
        return -1;
    }
    const size_t n = state_size(d);
    if (size != sizeof(h) + n) {
        snprintf(why, why_n, "%zu bytes, expected %zu (truncated or extended)", size, sizeof(h) + n);
        return -1;
    }
    if (mvtd_crc32((const uint8_t *)data + sizeof(h), n) != h.state_crc) {
        snprintf(why, why_n, "state checksum wrong (corrupted)");
        return -1;
    }
    /* the clocks: capture time = assembler time - offset, and the tracker's clock is the time of the
     * last frame set the assembler emitted (every difference then stays far from int64 overflow) */
    if (h.capture_utime < 0 || h.capture_utime > MVTD_MAX_UTIME || h.asm_offset_us < -MVTD_MAX_UTIME ||
        h.asm_offset_us > MVTD_MAX_UTIME || h.asm_last_emitted_utime < 0 ||
        h.asm_last_emitted_utime > 2 * MVTD_MAX_UTIME || h.asm_last_emitted_utime - h.asm_offset_us != h.capture_utime ||
        h.id_lease <= 0) {
        snprintf(why, why_n, "times or identity lease out of range");
        return -1;
    }
    g_loaded.h = h;
    memcpy(&g_loaded.state, (const uint8_t *)data + sizeof(h), n);
    const int64_t clock = d->pf ? g_loaded.state.pft.last_utime_us : g_loaded.state.trk.last_utime_us;
    if (clock != h.asm_last_emitted_utime || (d->pf && g_loaded.state.pft.det.last_utime_us != clock)) {
        snprintf(why, why_n, "the tracker's clock disagrees with the frame assembler's");
        return -1;
    }
    d->ckpt_pending = 1;
    return 0;
}

/* The identity lease of a file whose header is sound, even when its state cannot be used (stale,
 * other mode): the identities it published are still taken. 0 when there is none. */
static int32_t lease_of_header(const void *data, size_t size)
{
    mvtd_ckpt_header_t h;
    if (size < sizeof(h)) {
        return 0;
    }
    memcpy(&h, data, sizeof(h));
    if (memcmp(h.magic, CKPT_MAGIC, sizeof(CKPT_MAGIC)) != 0 || header_crc(&h) != h.header_crc ||
        h.version != MVTD_CKPT_VERSION || h.endian != CKPT_ENDIAN || h.id_lease <= 0) {
        return 0;
    }
    return h.id_lease;
}

/* FILE.ids: "mvtrackd-ids LEASE CRC\n". 0 when missing or damaged. */
static int32_t read_lease_file(const char *path)
{
    FILE *f = fopen(path, "r");
    if (f == NULL) {
        return 0;
    }
    char line[128] = "";
    const int ok = fgets(line, sizeof(line), f) != NULL;
    fclose(f);
    long long lease = 0;
    unsigned crc = 0;
    char tag[16];
    if (!ok || sscanf(line, "%15s %lld %x", tag, &lease, &crc) != 3 || strcmp(tag, "mvtrackd-ids") != 0 ||
        lease <= 0 || lease > INT32_MAX) {
        return 0;
    }
    const int32_t v = (int32_t)lease;
    return mvtd_crc32(&v, sizeof(v)) == crc ? v : 0;
}

/* Writes data to path atomically and durably: path.tmp, fsync, rename, fsync of the directory. */
static int write_atomic(const char *path, const char *tmp, const void *data, size_t n)
{
    const int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) {
        return -1;
    }
    const uint8_t *p = data;
    size_t left = n;
    while (left > 0) {
        const ssize_t w = write(fd, p, left);
        if (w < 0 && errno == EINTR) {
            continue;
        }
        if (w <= 0) {
            const int e = errno;
            close(fd);
            unlink(tmp);
            errno = e;
            return -1;
        }
        p += w;
        left -= (size_t)w;
    }
    if (fsync(fd) != 0 || close(fd) != 0) {
        const int e = errno;
        unlink(tmp);
        errno = e;
        return -1;
    }
    if (rename(tmp, path) != 0) {
        const int e = errno;
        unlink(tmp);
        errno = e;
        return -1;
    }
    char dir[4096];
    snprintf(dir, sizeof(dir), "%s", path);
    char *slash = strrchr(dir, '/');
    if (slash == dir) {
        slash[1] = '\0';
    } else if (slash != NULL) {
        *slash = '\0';
    } else {
        snprintf(dir, sizeof(dir), ".");
    }
    const int dfd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dfd >= 0) {
        (void)fsync(dfd); /* the rename itself made durable (best effort: some filesystems refuse) */
        close(dfd);
    }
    return 0;
}

static int write_lease_file(const mvtd_t *d, int32_t lease)
{
    char path[4200], tmp[4300], line[64];
    snprintf(path, sizeof(path), "%s.ids", d->state_path);
    snprintf(tmp, sizeof(tmp), "%s.ids.tmp", d->state_path);
    const int n = snprintf(line, sizeof(line), "mvtrackd-ids %d %08x\n", (int)lease, mvtd_crc32(&lease, sizeof(lease)));
    return write_atomic(path, tmp, line, (size_t)n);
}

static void *writer_main(void *arg)
{
    (void)arg;
    /* disk writes at normal priority, whatever the daemon runs at (--rt-priority) */
    const struct sched_param sp = {.sched_priority = 0};
    (void)pthread_setschedparam(pthread_self(), SCHED_OTHER, &sp);
    pthread_mutex_lock(&g_w.mu);
    for (;;) {
        while (!g_w.busy && !g_w.stop) {
            pthread_cond_wait(&g_w.cv, &g_w.mu);
        }
        if (!g_w.busy) {
            break; /* stop, nothing pending */
        }
        const size_t n = g_w.size;
        pthread_mutex_unlock(&g_w.mu);
        g_out.h.state_crc = mvtd_crc32(&g_out.state, n - sizeof(g_out.h));
        g_out.h.header_crc = header_crc(&g_out.h);
        const int rc = write_atomic(g_w.path, g_w.tmp, &g_out, n); /* g_out is ours while busy */
        const int e = errno;
        pthread_mutex_lock(&g_w.mu);
        if (rc == 0) {
            g_w.written++;
            g_w.last_ok_wall_s = mvtd_wall_s();
        } else {
            g_w.failed++;
            g_w.last_errno = e;
        }
        g_w.busy = 0;
        pthread_cond_broadcast(&g_w.cv);
    }
    pthread_mutex_unlock(&g_w.mu);
    return NULL;
}

/* Identities from the wall clock: above those of any earlier run that gave fewer than
 * MVTD_ID_PER_S per second. */
static int32_t clock_id_floor(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    const long long s = (long long)ts.tv_sec - MVTD_ID_EPOCH_S;
    if (s <= 0) {
        return 1;
    }
    const long long v = 1 + s * MVTD_ID_PER_S;
    return v > MVTD_ID_FLOOR_MAX ? MVTD_ID_FLOOR_MAX : (int32_t)v;
}

static int read_file(const char *path, uint8_t **data, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        return -1;
    }
    const size_t cap = sizeof(ckpt_file_t) + 1; /* anything longer is refused by its size anyway */
    uint8_t *buf = malloc(cap);
    if (buf == NULL) {
        fclose(f);
        return -1;
    }
    *size = fread(buf, 1, cap, f);
    fclose(f);
    *data = buf;
    return 0;
}

void mvtd_ckpt_open(mvtd_t *d)
{
    int32_t first = d->offline ? 1 : clock_id_floor();
    d->restore_note[0] = '\0';
    if (d->state_path == NULL) {
        reserve_ids(d, first);
        return;
    }
    d->rig_hash = file_hash(d->rig_path);
    char ids_path[4200];
    snprintf(ids_path, sizeof(ids_path), "%s.ids", d->state_path);
    const int32_t lease_file = read_lease_file(ids_path);
    first = lease_file > first ? lease_file : first;
    uint8_t *data = NULL;
    size_t size = 0;
    if (read_file(d->state_path, &data, &size) != 0) {
        snprintf(d->restore_note, sizeof(d->restore_note), "no checkpoint (%s): clean start", strerror(errno));
    } else {
        const int32_t lease_ck = lease_of_header(data, size);
        first = lease_ck > first ? lease_ck : first;
        char why[256];
        if (mvtd_ckpt_parse(d, data, size, why, sizeof(why)) != 0) {
            snprintf(d->restore_note, sizeof(d->restore_note), "checkpoint refused: %s; clean start", why);
        } else {
            snprintf(d->restore_note, sizeof(d->restore_note), "checkpoint read, waiting for the first message");
        }
    }
    free(data);
    if (!d->ckpt_pending && !d->quiet) {
        fprintf(stderr, "mvtrackd: %s: %s\n", d->state_path, d->restore_note);
    }
    reserve_ids(d, first);
    d->id_lease = first;
    snprintf(g_w.path, sizeof(g_w.path), "%s", d->state_path);
    snprintf(g_w.tmp, sizeof(g_w.tmp), "%s.tmp", d->state_path);
    /* the writer takes no signal: SIGINT/SIGTERM go to the loop's signalfd (a thread that left
     * them unblocked would die of the default action, with the frame in hand lost) */
    sigset_t all, old;
    sigfillset(&all);
    pthread_sigmask(SIG_SETMASK, &all, &old);
    if (!g_w.started && pthread_create(&g_w.thread, NULL, writer_main, NULL) == 0) {
        g_w.started = 1;
    }
    pthread_sigmask(SIG_SETMASK, &old, NULL);
}

void mvtd_ckpt_first_message(mvtd_t *d, int64_t utime)
{
    if (!d->ckpt_pending) {
        return;
    }
    d->ckpt_pending = 0;
    const mvtd_ckpt_header_t *h = &g_loaded.h;
    const double coast_s = MVTD_CKPT_MAX_AGE_S;
    const int64_t age = utime - h->capture_utime;
    const int64_t period = 2 * d->assembler.half_period_us;
    mvt_err_t err = MVT_ERR_INVALID;
    if (age < -period / 2) {
        snprintf(d->restore_note, sizeof(d->restore_note),
                 "checkpoint refused: saved at capture time %lld, after the first message's %lld (the cameras' clock "
                 "went back, or another input); clean start",
                 (long long)h->capture_utime, (long long)utime);
    } else if ((double)age > coast_s * 1e6) {
        snprintf(d->restore_note, sizeof(d->restore_note),
                 "checkpoint refused: stale, saved %.2f s of capture time before the first message (at most "
                 "%.1f s); clean start",
                 (double)age * 1e-6, coast_s);
    } else {
        /* the frames between the last saved and the first new one were never seen */
        const int64_t unobserved = age > period ? age - period : 0;
        err = d->pf ? mvt_pft_resume(d->pft, &g_loaded.state.pft, unobserved)
                    : mvt_tracker_resume(&d->tracker, &g_loaded.state.trk, unobserved);
        if (err != MVT_OK) {
            snprintf(d->restore_note, sizeof(d->restore_note),
                     "checkpoint refused: its state has invalid values (a track or particle); clean start");
        }
    }
    if (err == MVT_OK) {
        reserve_ids(d, d->id_lease);
        mvtd_asm_t *a = &d->assembler;
        a->offset_us = h->asm_offset_us;
        a->have_closed = 1;
        a->last_emitted_utime = h->asm_last_emitted_utime;
        a->last_closed_ref = h->asm_last_emitted_utime;
        int n = 0;
        for (int t = 0; t < MVT_MAX_TARGETS; t++) {
            n += (d->pf ? d->pft->targets[t].id : d->tracker.tracks[t].id) != 0;
        }
        snprintf(d->restore_note, sizeof(d->restore_note),
                 "restored %d tracks saved %.2f s of capture time before the first message", n, (double)age * 1e-6);
    }
    if (!d->quiet) {
        fprintf(stderr, "mvtrackd: %s: %s\n", d->state_path != NULL ? d->state_path : "checkpoint", d->restore_note);
    }
}

int mvtd_ckpt_ids(mvtd_t *d)
{
    if (d->state_path == NULL || published_next_id(d) < d->id_lease) {
        return 0;
    }
    const int32_t next = published_next_id(d);
    const int32_t lease = next > INT32_MAX - MVTD_ID_BLOCK ? INT32_MAX : next + MVTD_ID_BLOCK;
    if (write_lease_file(d, lease) != 0) {
        mvtd_log(d, MVTD_LOG_CHECKPOINT, "%s.ids: cannot write the identity lease (%s)", d->state_path,
                 strerror(errno));
        d->ckpt_failures++;
        return -1;
    }
    d->id_lease = lease;
    return 0;
}

void mvtd_ckpt_save(mvtd_t *d, int wait)
{
    if (d->state_path == NULL || d->frames_processed == 0 || !g_w.started) {
        return;
    }
    pthread_mutex_lock(&g_w.mu);
    while (wait && g_w.busy) {
        pthread_cond_wait(&g_w.cv, &g_w.mu);
    }
    if (g_w.busy) { /* the disk is slower than a second: skip this one */
        d->ckpt_skipped++;
        pthread_mutex_unlock(&g_w.mu);
        return;
    }
    mvtd_ckpt_expected_header(d, &g_out.h);
    g_out.h.capture_utime = d->assembler.last_emitted_utime - d->assembler.offset_us;
    g_out.h.asm_offset_us = d->assembler.offset_us;
    g_out.h.asm_last_emitted_utime = d->assembler.last_emitted_utime;
    g_out.h.id_lease = d->id_lease > published_next_id(d) ? d->id_lease : published_next_id(d);
    if (d->pf) {
        mvt_pft_save(d->pft, &g_out.state.pft);
    } else {
        mvt_tracker_save(&d->tracker, &g_out.state.trk);
    }
    g_w.size = sizeof(g_out.h) + state_size(d); /* the writer computes the CRCs */
    g_w.busy = 1;
    pthread_cond_broadcast(&g_w.cv);
    while (wait && g_w.busy) {
        pthread_cond_wait(&g_w.cv, &g_w.mu);
    }
    pthread_mutex_unlock(&g_w.mu);
}

void mvtd_ckpt_stats(mvtd_t *d, int64_t *written, int64_t *failed, float *age_s)
{
    pthread_mutex_lock(&g_w.mu);
    *written = (int64_t)g_w.written;
    *failed = (int64_t)g_w.failed + d->ckpt_failures;
    *age_s = g_w.written > 0 ? (float)(mvtd_wall_s() - g_w.last_ok_wall_s) : -1.0f;
    const uint64_t failed_now = g_w.failed;
    const int e = g_w.last_errno;
    pthread_mutex_unlock(&g_w.mu);
    if (failed_now > d->ckpt_failed_seen) {
        d->ckpt_failed_seen = failed_now;
        mvtd_log(d, MVTD_LOG_CHECKPOINT, "%s: checkpoint not written (%s)", d->state_path, strerror(e));
    }
}

void mvtd_ckpt_close(mvtd_t *d)
{
    if (d->state_path == NULL || !g_w.started) {
        return;
    }
    mvtd_ckpt_save(d, 1);
    pthread_mutex_lock(&g_w.mu);
    g_w.stop = 1;
    pthread_cond_broadcast(&g_w.cv);
    pthread_mutex_unlock(&g_w.mu);
    pthread_join(g_w.thread, NULL);
    g_w.started = 0;
    g_w.stop = 0;
}
