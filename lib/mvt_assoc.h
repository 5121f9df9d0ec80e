/*
 * mvt_assoc.h - minimum-cost one-to-one assignment (the Hungarian method in its shortest
 * augmenting path form, Jonker-Volgenant style potentials) with a caller-owned static workspace.
 *
 * The tracker uses it per camera and per cluster of tracks that compete for detections (global
 * nearest neighbour): rows are tracks, columns are detections plus one "missed" column per track.
 */
#ifndef MVT_ASSOC_H
#define MVT_ASSOC_H

#include "mvt_types.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MVT_ASSOC_MAX_ROWS MVT_MAX_TARGETS
#define MVT_ASSOC_MAX_COLS (MVT_MAX_DETECTIONS + MVT_MAX_TARGETS)

/* Working memory of mvt_assoc_solve (about 12 * MVT_ASSOC_MAX_COLS bytes in float builds). */
typedef struct mvt_assoc_ws {
    mvt_real u[MVT_ASSOC_MAX_ROWS + 1];
    mvt_real v[MVT_ASSOC_MAX_COLS + 1];
    mvt_real minv[MVT_ASSOC_MAX_COLS + 1];
    int16_t p[MVT_ASSOC_MAX_COLS + 1];
    int16_t way[MVT_ASSOC_MAX_COLS + 1];
    uint8_t used[MVT_ASSOC_MAX_COLS + 1];
} mvt_assoc_ws_t;

/* Assigns each of n_rows rows to a distinct column of the n_rows x n_cols cost matrix (row-major,
 * row r at cost + r * stride) so that the sum of the chosen costs is minimal. Entries < 0 or
 * non-finite are forbidden: a row whose every feasible choice is forbidden gets -1 (the solver
 * never prefers a forbidden entry over a feasible one, since a forbidden entry costs more than
 * every feasible assignment together).
 * 1 <= n_rows <= n_cols, n_rows <= MVT_ASSOC_MAX_ROWS, n_cols <= MVT_ASSOC_MAX_COLS, else
 * MVT_ERR_INVALID. row_to_col[r] receives the column of row r or -1.
 * Cost O(n_rows^2 * n_cols); memory: ws only. */
mvt_err_t mvt_assoc_solve(const mvt_real *cost, int n_rows, int n_cols, int stride, int *row_to_col,
                          mvt_assoc_ws_t *ws);

#ifdef __cplusplus
}
#endif

#endif /* MVT_ASSOC_H */
