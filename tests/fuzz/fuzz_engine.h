/*
 * fuzz_engine.h - what the libFuzzer targets share: the engine configured on $MVTRACK_FUZZ_RIG,
 * and the invariant every published track keeps (capacity, finite numbers).
 */
#ifndef FUZZ_ENGINE_H
#define FUZZ_ENGINE_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "mvtd.h"

/* mvtd_configure in mode (pf modes with 64 particles), quiet; aborts when it fails. */
static inline void fuzz_configure(mvtd_t *d, const char *mode)
{
    const char *rig = getenv("MVTRACK_FUZZ_RIG");
    if (rig == NULL) {
        fprintf(stderr, "fuzz: set MVTRACK_FUZZ_RIG to a rig file\n");
        abort();
    }
    char *argv[] = {"mvtrackd", "--rig", (char *)rig, "--mode", (char *)mode, "--particles", "64", "--in",
                    "file:///dev/null", "--out", "file:///dev/null", NULL};
    if (mvtd_configure(d, 11, argv) != MVTD_CONTINUE) {
        abort();
    }
    d->quiet = 1;
}

/* Aborts unless the last output is within capacity and every number in it is finite. */
static inline void fuzz_check_output(const mvtd_t *d)
{
    const mvt_output_t *o = &d->output;
    if (o->num_tracks < 0 || o->num_tracks > MVT_MAX_TARGETS) {
        abort();
    }
    for (int i = 0; i < o->num_tracks; i++) {
        const mvt_track_out_t *t = &o->tracks[i];
        for (int a = 0; a < 3; a++) {
            if (!isfinite(t->pos_m[a]) || !isfinite(t->vel_ms[a]) || !isfinite(t->extent_min[a]) ||
                !isfinite(t->extent_max[a])) {
                fprintf(stderr, "fuzz: track %d has a non-finite output\n", (int)t->id);
                abort();
            }
        }
        for (int a = 0; a < 6; a++) {
            if (!isfinite(t->cov_m2[a])) {
                abort();
            }
        }
    }
}

#endif /* FUZZ_ENGINE_H */
