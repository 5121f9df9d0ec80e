/*
 * options.c - mvtrackd's command line: --help, parsing, the rig and the tracker's configuration.
 */
#include "engine.h"

#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void usage(FILE *f)
{
    fprintf(f,
            "usage: mvtrackd --rig RIG.yaml [--in URL] [--out URL] [--mode MODE] [options]\n"
            "\n"
            "Fuses per-camera detections (LCM channels DETECTIONS_<camera>, mvtrack.camera_frame_t)\n"
            "into 3D tracks published on TRACKS (mvtrack.tracks_t) every frame set, and its health\n"
            "on MVTRACK_STATUS (mvtrack.status_t) about once a second.\n");
    fprintf(f,
            "\n"
            "Input and output:\n"
            "  --rig FILE          camera rig, OpenCV FileStorage YAML (required)\n"
            "  --in URL            LCM input (default %s);\n"
            "                      'file://LOG.lcm?speed=0' processes a log as fast as possible and\n"
            "                      exits 0 at its end\n"
            "  --out URL           LCM output (default: the input URL; required for file:// input,\n"
            "                      e.g. 'file://OUT.lcm?mode=w')\n"
            "  --state FILE        save the tracker to FILE every 0.2 s (1 s in pf modes) and at exit\n"
            "                      (atomically: FILE.tmp, fsync, rename) and restore it at start when\n"
            "                      it matches this build, rig and mode and the first camera message is\n"
            "                      at most 2 s after it: people keep their identities\n"
            "                      across a restart. Identities are leased in FILE.ids and never\n"
            "                      reused; anything unusable is refused with one line, clean start\n"
            "  --deadline-ms X     live mode: process an incomplete frame set this long after its\n"
            "                      first message (default 20)\n"
            "  --sigma-px X        pixel noise for cameras without sigma_px in the rig (default 2)\n"
            "  --verbose           print a line per status period\n"
            "  --help              this text\n",
            MVTD_DEFAULT_URL);
    fprintf(f,
            "\n"
            "Tracking:\n"
            "  --mode MODE         pkf (default): projective Kalman filter fusing every camera's pixels\n"
            "                                     directly in 3D, linearised with the projection's\n"
            "                                     Jacobian (the EKF form; measured best, see README);\n"
            "                                     where blobs carry hue/saturation, each track\n"
            "                                     learns its person's colour and reports it in\n"
            "                                     track_t\n"
            "                      ekf          same as pkf\n"
            "                      pkf-paper    the paper's literal H (Eq. 18), OpenCV pixel origin\n"
            "                      pkf-centred  Eq. 18 with pixels centred on the principal point\n"
            "                      kf           baseline: triangulate per frame, then a 3D Kalman filter\n"
            "                      pf           particle filter per person weighted by the cameras'\n"
            "                                   foreground masks, and their hue/saturation when sent\n"
            "                                   (MS+C; MS when a camera sends no colour); needs masks\n"
            "                      pf-ms        the same, motion masks only (colour ignored)\n"
            "                      Tracks are born, kept and ended by one model of a person (pf: in\n"
            "                      the blob tracker that proposes its births): a head over a body\n"
            "                      with its silhouette in every view, blobs explained as heads,\n"
            "                      fragments or clutter, births from any number of views with a\n"
            "                      prior on head height and the feet where visible, and a\n"
            "                      probability of existence that confirms and deletes (kf: the\n"
            "                      heads its views place, triangulated, update the track)\n"

            "  --motion imm|cv     pkf modes' motion model: imm (default), an interacting multiple\n"
            "                      model of standing, walking, turning and sitting people that\n"
            "                      needs no tuning; cv: one constant-velocity model with --q\n"
            "  --motion-models M   imm: the bank, KIND:QXY:QZ:LEAVE;... KIND is still or cv for\n"
            "                      every axis, or XY/Z (cv/still: walks and holds its height);\n"
            "                      still: q is the diffusion m^2/s; cv: q is the white\n"
            "                      acceleration m^2/s^3; LEAVE: rate 1/s. Default\n"
            "                      still:2.5e-5:2.5e-5:0.2;cv/still:0.3:4e-4:0.3;\n"
            "                      cv:3:0.1:1.5;still/cv:2.5e-5:1:1.3\n"
            "  --outlier-persist S imm: a camera's displaced detection (an occluding or merged blob)\n"
            "                      stays displaced S seconds on average, by about the same offset;\n"
            "                      a view whose detections keep that offset is discounted while\n"
            "                      two other views place the person (default 0.5; 0: each frame's\n"
            "                      detection is judged on its own)\n"
            "  --q QX,QY,QZ        cv: white-acceleration density m^2/s^3 per axis (default\n"
            "                      0.5,0.5,0.05; tools/mvtrack learn-q estimates it); implies cv\n"
            "  --gate chi2|paper   association gate: innovation chi-square (default) or the paper's\n"
            "                      projected ellipsoid (Eq. 22-26)\n"
            "  --gate-chi2 X       chi-square threshold, 2 dof (default 13.8)\n"
            "  --rt-priority PRIO  handle frame sets with real-time priority PRIO (SCHED_FIFO,\n"
            "                      1..99), before any other program on the machine gets a core (a\n"
            "                      browser, a detector); needs root or CAP_SYS_NICE (exit 2 without)\n");
    fprintf(f,
            "\n"
            "The particle filter (--mode pf, pf-ms):\n"
            "  --particles N       pf: particles per person, 16..%d (default %d)\n"
            "  --particle-model column|point\n"
            "                      pf: column (default): a particle is a head-top hypothesis, each\n"
            "                      camera scores the body under it and the background above it;\n"
            "                      point: the paper's, a particle is a point of the body\n"
            "  --pixels shared|independent\n"
            "                      pf: shared (default): each camera's pixels are shared out between\n"
            "                      the people, strongest first; pixels one person explains are no\n"
            "                      evidence for another, and a person behind another is hidden there,\n"
            "                      not missing; independent: every filter reads every pixel\n"
            "  --seed N            pf: random number seed (default 1); same seed, same output\n"
            "  --publish-particles N\n"
            "                      pf: publish N particles per person on MVTRACK_PARTICLES\n"
            "                      (mvtrack.particles_t; default 0 = none)\n"
            "  --exclusion M       pf: two people's heads are at least M metres apart horizontally:\n"
            "                      particles closer to another person's centre are penalised, so two\n"
            "                      filters cannot share one body (default 0.5; 0: the paper's\n"
            "                      independent filters)\n"
            "  --recover S         pf: a person whose filter lost them keeps their identity S seconds,\n"
            "                      for a filter born from the same blob track (default 3, 0 = off)\n",
            MVT_MAX_PARTICLES, MVT_MAX_PARTICLES);
    fprintf(f,
            "\n"
            "Identities: live, they start above 4 x (seconds since 2023-11-14 22:13 UTC), above any\n"
            "earlier run's that gave fewer than 4 per second; with --state, above every one published\n"
            "before (the lease); offline without --state, from 1.\n"
            "Input rate: live, a DETECTIONS_ channel sending more than twice the rig's frame rate\n"
            "within a second is shed (not decoded, counted in MVTRACK_STATUS) until it calms down.\n"
            "Clocks: live, each camera's capture clock is measured against the others' from when its\n"
            "frames arrive (MVTRACK_STATUS cameras[k].clock_offset_ms); beyond 10 ms its frames are\n"
            "re-timed by it, beyond 0.5 s refused. How late walking people show in its frames against\n"
            "the tracks is measured too (cameras[k].clock_tracks_lag_ms: a detector or network slower\n"
            "than the others'), and said once beyond 10 ms.\n"
            "\n"
            "Exit status: 0 after SIGINT/SIGTERM or at the end of a file:// log; 2 on bad arguments\n"
            "or rig; 1 when LCM cannot be opened.\n");
}

/* "still:1e-4:1e-4:0.2;cv/still:0.3:4e-4:0.3;still/cv:2.5e-5:1:1.3" -> an IMM bank. */
static int parse_models(const char *s, mvt_imm_config_t *c)
{
    mvt_imm_config_t out;
    mvt_imm_config_default(&out); /* the outlier model stays; the bank is replaced */
    out.n = 0;
    memset(out.model, 0, sizeof(out.model));
    const char *p = s;
    while (*p != '\0') {
        if (out.n == MVT_IMM_MODELS) {
            return -1;
        }
        mvt_imm_model_t *m = &out.model[out.n];
        /* KIND: one kind for every axis, or the horizontal and the vertical kind, XY/Z */
        mvt_motion_kind_t k[2];
        for (int part = 0; part < 2; part++) {
            if (strncmp(p, "still", 5) == 0) {
                k[part] = MVT_MOTION_STILL;
                p += 5;
            } else if (strncmp(p, "cv", 2) == 0) {
                k[part] = MVT_MOTION_CV;
                p += 2;
            } else {
                return -1;
            }
            if (part == 0 && *p == '/') {
                p++;
                continue;
            }
            if (part == 0) {
                k[1] = k[0];
            }
            break;
        }
        if (*p != ':') {
            return -1;
        }
        p++;
        m->kind[0] = m->kind[1] = k[0];
        m->kind[2] = k[1];
        double v[3];
        for (int i = 0; i < 3; i++) {
            char *end = NULL;
            v[i] = strtod(p, &end);
            if (end == p || (i < 2 && *end != ':') || (i == 2 && *end != ';' && *end != '\0')) {
                return -1;
            }
            p = *end == '\0' ? end : end + 1;
        }
        m->q[0] = m->q[1] = (mvt_real)v[0];
        m->q[2] = (mvt_real)v[1];
        m->leave_hz = (mvt_real)v[2];
        out.n++;
    }
    if (mvt_imm_config_check(&out) != MVT_OK) {
        return -1;
    }
    *c = out;
    return 0;
}

static int parse_q(const char *s, mvt_real q[3])
{
    double a, b, c;
    char extra;
    if (sscanf(s, "%lf,%lf,%lf%c", &a, &b, &c, &extra) != 3 || !(a > 0) || !(b > 0) || !(c > 0) || !isfinite(a) ||
        !isfinite(b) || !isfinite(c)) {
        return -1;
    }
    q[0] = (mvt_real)a;
    q[1] = (mvt_real)b;
    q[2] = (mvt_real)c;
    return 0;
}

static int parse_pos(const char *s, double *out)
{
    char *end = NULL;
    errno = 0;
    const double v = strtod(s, &end);
    if (errno != 0 || end == s || *end != '\0' || !(v > 0.0) || !isfinite(v)) {
        return -1;
    }
    *out = v;
    return 0;
}

/* Parses a positive option value; prints why not and returns -1 on failure. */
static int option_pos(const char *opt_name, const char *arg, double *out)
{
    if (parse_pos(arg, out) != 0) {
        fprintf(stderr, "mvtrackd: %s needs a positive number, got '%s'\n", opt_name, arg);
        return -1;
    }
    return 0;
}

/* Parses a number option in [lo, hi] (unit: what it measures, for the message); prints why not and
 * returns -1 on failure. */
static int option_range(const char *opt_name, const char *arg, double lo, double hi, const char *unit, double *out)
{
    char *end = NULL;
    const double v = strtod(arg, &end);
    if (end == arg || *end != '\0' || !(v >= lo) || !(v <= hi)) {
        fprintf(stderr, "mvtrackd: %s needs %s in [%g, %g], got '%s'\n", opt_name, unit, lo, hi, arg);
        return -1;
    }
    *out = v;
    return 0;
}

/* Parses an integer option in [lo, hi]; prints why not and returns -1 on failure. */
static int option_int(const char *opt_name, const char *arg, long lo, long hi, long *out)
{
    char *end = NULL;
    errno = 0;
    const long v = strtol(arg, &end, 10);
    if (errno != 0 || end == arg || *end != '\0' || v < lo || v > hi) {
        fprintf(stderr, "mvtrackd: %s needs an integer in %ld..%ld, got '%s'\n", opt_name, lo, hi, arg);
        return -1;
    }
    *out = v;
    return 0;
}

/* Index of arg among names, or -1 after printing the allowed values. */
static int option_choice(const char *opt_name, const char *arg, const char *const names[], int n)
{
    for (int i = 0; i < n; i++) {
        if (strcmp(arg, names[i]) == 0) {
            return i;
        }
    }
    fprintf(stderr, "mvtrackd: unknown %s '%s' (", opt_name, arg);
    for (int i = 0; i < n; i++) {
        fprintf(stderr, "%s%s", i ? ", " : "", names[i]);
    }
    fprintf(stderr, ")\n");
    return -1;
}

int mvtd_configure(mvtd_t *d, int argc, char **argv)
{
    const char *rig_path = NULL, *in_url = MVTD_DEFAULT_URL, *out_url = NULL, *mode = "pkf", *gate = "chi2",
               *particle_model = "column",
               *state_path = NULL, *motion = NULL, *models = NULL, *pixels = "shared";
    int q_given = 0;
    double sigma_px = 2.0, deadline_ms = 20.0, gate_chi2 = 13.8;
    mvt_real q[3] = {MVT_R(0.5), MVT_R(0.5), MVT_R(0.05)};
    static const struct option opts[] = {
        {"rig", required_argument, 0, 'r'},      {"in", required_argument, 0, 'i'},
        {"out", required_argument, 0, 'o'},      {"mode", required_argument, 0, 'm'},
        {"gate", required_argument, 0, 'g'},     {"gate-chi2", required_argument, 0, 'c'},
        {"q", required_argument, 0, 'q'},        {"sigma-px", required_argument, 0, 's'},
        {"deadline-ms", required_argument, 0, 'd'}, {"verbose", no_argument, 0, 'v'},
        {"help", no_argument, 0, 'h'},
        {"particles", required_argument, 0, 'P'}, {"exclusion", required_argument, 0, 'X'},
        {"seed", required_argument, 0, 'S'},     {"publish-particles", required_argument, 0, 'Q'},
        {"particle-model", required_argument, 0, 'B'}, {"state", required_argument, 0, 'T'},
        {"motion", required_argument, 0, 'N'},   {"motion-models", required_argument, 0, 'W'},
        {"pixels", required_argument, 0, 'x'},   {"recover", required_argument, 0, 'R'},
        {"outlier-persist", required_argument, 0, 'L'}, 
        {"rt-priority", required_argument, 0, 'F'},
        {0, 0, 0, 0}};
    int opt;
    optind = 1; /* callable more than once (tests, fuzzer) */
    long particles = MVT_MAX_PARTICLES, seed = 1, publish_particles = 0, rt_priority = 0;
    double exclusion_m = -1.0; /* mode-dependent default */
    double recover_s = -1.0;   /* the library's default */
    double persist_s = -1.0;   /* the library's default */
    while ((opt = getopt_long(argc, argv, "r:i:o:m:g:c:q:s:d:vhP:X:S:Q:B:T:N:W:x:R:L:", opts, NULL)) != -1) {
        switch (opt) {
        case 'r': rig_path = optarg; break;
        case 'i': in_url = optarg; break;
        case 'o': out_url = optarg; break;
        case 'm': mode = optarg; break;
        case 'g': gate = optarg; break;
        case 'B': particle_model = optarg; break;
        case 'T': state_path = optarg; break;
        case 'N': motion = optarg; break;
        case 'W': models = optarg; break;
        case 'x': pixels = optarg; break;
        case 'c':
            if (option_pos("--gate-chi2", optarg, &gate_chi2) != 0) {
                return 2;
            }
            break;
        case 'q':
            if (parse_q(optarg, q) != 0) {
                fprintf(stderr, "mvtrackd: --q needs three positive numbers QX,QY,QZ, got '%s'\n", optarg);
                return 2;
            }
            q_given = 1;
            break;
        case 's':
            if (option_pos("--sigma-px", optarg, &sigma_px) != 0) {
                return 2;
            }
            break;
        case 'd':
            if (option_pos("--deadline-ms", optarg, &deadline_ms) != 0) {
                return 2;
            }
            break;
        case 'P':
            if (option_int("--particles", optarg, 16, MVT_MAX_PARTICLES, &particles) != 0) {
                return 2;
            }
            break;
        case 'S':
            if (option_int("--seed", optarg, 0, 2147483647L, &seed) != 0) {
                return 2;
            }
            break;
        case 'Q':
            if (option_int("--publish-particles", optarg, 0, MVT_MAX_PARTICLES, &publish_particles) != 0) {
                return 2;
            }
            break;
        case 'F':
            if (option_int("--rt-priority", optarg, 1, 99, &rt_priority) != 0) {
                return 2;
            }
            break;
        case 'X':
            if (option_range("--exclusion", optarg, 0.0, 10.0, "metres", &exclusion_m) != 0) {
                return 2;
            }
            break;
        case 'R':
            if (option_range("--recover", optarg, 0.0, 3600.0, "seconds", &recover_s) != 0) {
                return 2;
            }
            break;
        case 'L':
            if (option_range("--outlier-persist", optarg, 0.0, 60.0, "seconds", &persist_s) != 0) {
                return 2;
            }
            break;
        case 'v': d->verbose = 1; break;
        case 'h': usage(stdout); return 0;
        default: usage(stderr); return 2;
        }
    }
    if (optind < argc) {
        fprintf(stderr, "mvtrackd: unexpected argument '%s'\n", argv[optind]);
        usage(stderr);
        return 2;
    }
    if (rig_path == NULL) {
        fprintf(stderr, "mvtrackd: --rig is required\n");
        usage(stderr);
        return 2;
    }
    mvt_tracker_config_t cfg;
    mvt_tracker_config_default(&cfg);
    static const char *const modes[] = {"pkf", "ekf", "pkf-paper", "pkf-centred", "kf", "pf", "pf-ms"};
    static const char *const gates[] = {"chi2", "paper"};
    static const char *const particle_models[] = {"column", "point"};
    const int mi = option_choice("--mode", mode, modes, 7);
    const int gi = option_choice("--gate", gate, gates, 2);
    const int bi = option_choice("--particle-model", particle_model, particle_models, 2);
    static const char *const motions[] = {"imm", "cv"};
    const int vi = motion == NULL ? (q_given ? 1 : 0) : option_choice("--motion", motion, motions, 2);
    static const char *const pixel_uses[] = {"shared", "independent"};
    const int xi = option_choice("--pixels", pixels, pixel_uses, 2);
    if (mi < 0 || gi < 0 || bi < 0 || vi < 0 || xi < 0) {
        return 2;
    }
    if (mi < 5 && (exclusion_m >= 0.0 || recover_s >= 0.0)) {
        fprintf(stderr, "mvtrackd: --exclusion and --recover are the particle filter's (--mode pf, pf-ms)\n");
        return 2;
    }
    if (vi == 0 && q_given) {
        fprintf(stderr, "mvtrackd: --q sets the single model's noise; it does not go with --motion imm\n");
        return 2;
    }
    static const mvt_pkf_lin_t mode_lin[] = {MVT_PKF_JACOBIAN, MVT_PKF_JACOBIAN, MVT_PKF_PAPER,
                                             MVT_PKF_PAPER_CENTRED, MVT_PKF_JACOBIAN, MVT_PKF_JACOBIAN,
                                             MVT_PKF_JACOBIAN};
    cfg.lin = mode_lin[mi];
    cfg.filter = mi == 4 ? MVT_FILTER_TRIANGULATE : MVT_FILTER_PROJECTIVE;
    cfg.gate = gi == 0 ? MVT_GATE_CHI2 : MVT_GATE_PAPER;
    cfg.numerics.gate_chi2 = (mvt_real)gate_chi2;
    if (exclusion_m < 0.0) { /* measured default: docs/particle-filter.md */
        exclusion_m = 0.5;
    }
    if (vi == 1) {
        mvt_imm_config_single(&cfg.motion, q);
    } else if (models != NULL && parse_models(models, &cfg.motion) != 0) {
        fprintf(stderr, "mvtrackd: --motion-models needs up to %d models KIND:QXY:QZ:LEAVE separated by ';' "
                        "(KIND still, cv or XY/Z such as cv/still, q > 0, leave rate >= 0 per second), got '%s'\n", MVT_IMM_MODELS, models);
        return 2;
    }
    if (persist_s >= 0.0) {
        cfg.motion.outlier_persist_s = (mvt_real)persist_s;
    }
    d->mode_name = mode;

    char err[512];
    if (mvt_rig_load(rig_path, sigma_px, &d->rig, err, sizeof(err)) != 0) {
        fprintf(stderr, "mvtrackd: %s\n", err);
        return 2;
    }
    if (!d->rig.volume_given) {
        fprintf(stderr, "mvtrackd: rig has no volume_min/volume_max; using the camera centres' box\n");
    }
    for (int i = 0; i < 3; i++) {
        cfg.volume.min[i] = (mvt_real)d->rig.volume_min[i];
        cfg.volume.max[i] = (mvt_real)d->rig.volume_max[i];
    }
    cfg.volume.num_occluders = d->rig.num_occluders; /* the body model's static occluders */
    for (int o = 0; o < d->rig.num_occluders; o++) {
        for (int i = 0; i < 3; i++) {
            cfg.volume.occluder_min[o][i] = (mvt_real)d->rig.occluder_min[o][i];
            cfg.volume.occluder_max[o][i] = (mvt_real)d->rig.occluder_max[o][i];
        }
    }
    mvt_camera_t cams[MVT_MAX_CAMERAS];
    for (int k = 0; k < d->rig.num_cameras; k++) {
        if (mvt_cam_init(&cams[k], &d->rig.params[k]) != MVT_OK) {
            fprintf(stderr, "mvtrackd: camera %s: invalid calibration\n", d->rig.names[k]);
            return 2;
        }
    }
    d->pf = mi >= 5;
    d->publish_particles = (int)publish_particles;
    d->trk = &d->tracker;
    if (d->pf) {
        static mvt_pft_t pft; /* ~1.5 MB at the default capacities: static, not on the stack */
        mvt_pft_config_t pcfg;
        mvt_pft_config_default(&pcfg);
        pcfg.det = cfg;
        /* the particle filter's blob tracker (the body model) only proposes births */
        pcfg.num_particles = (int)particles;
        pcfg.use_colour = mi == 5;
        pcfg.column = bi == 0;
        pcfg.share_pixels = xi == 0;
        pcfg.exclusion_m = (mvt_real)exclusion_m;
        if (recover_s >= 0.0) {
            pcfg.recover_s = (mvt_real)recover_s;
        }
        pcfg.seed = (uint64_t)seed;
        if (mvt_pft_init(&pft, &pcfg, cams, d->rig.num_cameras) != MVT_OK) {
            fprintf(stderr, "mvtrackd: invalid particle-filter configuration\n");
            return 2;
        }
        d->pft = &pft;
        d->trk = &pft.det;
    } else if (mvt_tracker_init(&d->tracker, &cfg, cams, d->rig.num_cameras) != MVT_OK) {
        fprintf(stderr, "mvtrackd: invalid tracker configuration\n");
        return 2;
    }
    if (rt_priority > 0) {
        /* the frame sets are handled before anything else on the machine wants a core: a browser
         * or a detector beside the daemon cannot delay them (the checkpoint writer goes back to
         * normal scheduling, checkpoint.c) */
        const struct sched_param sp = {.sched_priority = (int)rt_priority};
        if (sched_setscheduler(0, SCHED_FIFO, &sp) != 0) {
            fprintf(stderr,
                    "mvtrackd: --rt-priority %ld: %s (needs root or CAP_SYS_NICE; or let systemd set "
                    "CPUSchedulingPolicy=fifo)\n",
                    rt_priority, strerror(errno));
            return 2;
        }
    }
    d->offline = strncmp(in_url, "file://", 7) == 0;
    if (out_url == NULL) {
        if (d->offline) {
            fprintf(stderr, "mvtrackd: file:// input needs --out (a log opened for reading cannot publish)\n");
            return 2;
        }
        out_url = in_url;
    }
    d->in_url = in_url;
    d->out_url = out_url;
    d->deadline_s = deadline_ms * 1e-3;
    mvtd_asm_init(&d->assembler, d->rig.num_cameras, d->rig.frame_rate, mvtd_on_frame, d);
    mvtd_clock_init(&d->clock, d->rig.num_cameras);
    d->rig_path = rig_path;
    d->state_path = state_path;
    mvtd_ckpt_open(d);
    d->start_wall_s = mvtd_wall_s();
    d->last_status_wall_s = d->start_wall_s;
    return MVTD_CONTINUE;
}
