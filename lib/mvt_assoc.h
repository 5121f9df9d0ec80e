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

/* Working memory of mvt_assoc_solve and mvt_assoc_solve_own (about 15 * MVT_ASSOC_MAX_COLS bytes in
 * float builds, and 2 * MVT_ASSOC_MAX_ROWS * MVT_ASSOC_MAX_COLS for the second's lists). */
typedef struct mvt_assoc_ws {
    mvt_real u[MVT_ASSOC_MAX_ROWS + 1];
    mvt_real v[MVT_ASSOC_MAX_COLS + 1];
    mvt_real minv[MVT_ASSOC_MAX_COLS + 1];
    int16_t p[MVT_ASSOC_MAX_COLS + 1];
    int16_t way[MVT_ASSOC_MAX_COLS + 1];
    uint8_t used[MVT_ASSOC_MAX_COLS + 1];
    uint8_t seen[MVT_ASSOC_MAX_COLS + 1];   /* mvt_assoc_solve_own: reached in this row's search */
    int16_t reached[MVT_ASSOC_MAX_COLS + 1]; /* mvt_assoc_solve_own: those columns */
    int16_t n_feasible[MVT_ASSOC_MAX_ROWS];  /* mvt_assoc_solve_own: each row's feasible columns */
    int16_t feasible[MVT_ASSOC_MAX_ROWS][MVT_ASSOC_MAX_COLS];
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

/* The same assignment as mvt_assoc_solve, to the bit, for a matrix whose last n_rows columns are
 * the rows' own: column n_cols - n_rows + r feasible for row r and forbidden for every other row
 * (a track's "missed"). Then a forbidden entry is never on a shortest augmenting path (a row's own
 * column is free when its search starts, at no more than the costliest feasible entry, while any
 * path through a forbidden entry costs more than the whole matching), so each search looks only at
 * its rows' feasible entries and the columns they reach instead of at every column: the same
 * choices in the same order, at a fraction of the cost when each row has few feasible entries;
 * where every row's cheapest feasible column (of equals the first) is a different one, that is the
 * assignment, taken without searching. A matrix without that structure is solved by
 * mvt_assoc_solve. Cost O(n_rows^2 * n_cols) at worst
 * (the row scans), usually far less; memory: ws only. */
mvt_err_t mvt_assoc_solve_own(const mvt_real *cost, int n_rows, int n_cols, int stride, int *row_to_col,
                              mvt_assoc_ws_t *ws);

#ifdef __cplusplus
}
#endif

#endif /* MVT_ASSOC_H */
