#include "mvt_assoc.h"

#include <math.h>
#include <stddef.h>

/* Written without short-circuits, as the tests below: a branch per entry whose outcome the data
 * decides is mispredicted often, and costs more than the arithmetic. */
static int feasible(mvt_real c)
{
    return (c >= MVT_R(0.0)) & (isfinite(c) != 0);
}

/* Column j after a search step of delta: the potentials of a column in the tree and its row move,
 * any other column's distance shrinks. */
static inline void shift(mvt_assoc_ws_t *ws, int j, mvt_real delta)
{
    if (ws->used[j]) {
        ws->u[ws->p[j]] += delta;
        ws->v[j] -= delta;
    } else {
        ws->minv[j] -= delta;
    }
}

/* The augmenting path found, ending at free column j0, flipped along its way[] links. */
static void augment(mvt_assoc_ws_t *ws, int j0)
{
    do {
        const int j1 = ws->way[j0];
        ws->p[j0] = ws->p[j1];
        j0 = j1;
    } while (j0 != 0);
}

/* The columns' rows (ws->p) as each row's column; -1 where it holds a forbidden entry. */
static void matching(const mvt_real *cost, int n_rows, int n_cols, int stride, const mvt_assoc_ws_t *ws,
                     int *row_to_col)
{
    for (int r = 0; r < n_rows; r++) {
        row_to_col[r] = -1;
    }
    for (int j = 1; j <= n_cols; j++) {
        const int i = ws->p[j];
        if (i > 0 && feasible(cost[(i - 1) * stride + (j - 1)])) {
            row_to_col[i - 1] = j - 1;
        }
    }
}

mvt_err_t mvt_assoc_solve(const mvt_real *cost, int n_rows, int n_cols, int stride, int *row_to_col,
                          mvt_assoc_ws_t *ws)
{
    MVT_ASSERT(cost != NULL && row_to_col != NULL && ws != NULL);
    if (n_rows < 1 || n_rows > n_cols || n_rows > MVT_ASSOC_MAX_ROWS || n_cols > MVT_ASSOC_MAX_COLS ||
        stride < n_cols) {
        return MVT_ERR_INVALID;
    }
    /* a forbidden entry costs more than any full assignment of feasible ones */
    mvt_real worst = MVT_R(0.0);
    for (int r = 0; r < n_rows; r++) {
        for (int c = 0; c < n_cols; c++) {
            const mvt_real x = cost[r * stride + c];
            if (feasible(x) && x > worst) {
                worst = x;
            }
        }
    }
    const mvt_real big = (worst + MVT_R(1.0)) * (mvt_real)(n_rows + 1);
    const mvt_real inf = big * (mvt_real)(4 * (n_rows + 1));
    /* 1-based potentials; column 0 is the virtual start of each augmenting path */
    for (int j = 0; j <= n_cols; j++) {
        ws->v[j] = MVT_R(0.0);
        ws->p[j] = 0;
        ws->way[j] = 0;
    }
    for (int i = 0; i <= n_rows; i++) {
        ws->u[i] = MVT_R(0.0);
    }
    for (int i = 1; i <= n_rows; i++) {
        ws->p[0] = (int16_t)i;
        int j0 = 0;
        for (int j = 0; j <= n_cols; j++) {
            ws->minv[j] = inf;
            ws->used[j] = 0;
        }
        do {
            ws->used[j0] = 1;
            const int i0 = ws->p[j0];
            mvt_real delta = inf;
            int j1 = 0;
            for (int j = 1; j <= n_cols; j++) {
                if (ws->used[j]) {
                    continue;
                }
                const mvt_real a = cost[(i0 - 1) * stride + (j - 1)];
                const mvt_real cur = (feasible(a) ? a : big) - ws->u[i0] - ws->v[j];
                if (cur < ws->minv[j]) {
                    ws->minv[j] = cur;
                    ws->way[j] = (int16_t)j0;
                }
                if (ws->minv[j] < delta) {
                    delta = ws->minv[j];
                    j1 = j;
                }
            }
            if (j1 == 0) {
                return MVT_ERR_NUMERIC; /* only with non-finite arithmetic; cannot happen otherwise */
            }
            for (int j = 0; j <= n_cols; j++) {
                shift(ws, j, delta);
            }
            j0 = j1;
        } while (ws->p[j0] != 0);
        augment(ws, j0);
    }
    matching(cost, n_rows, n_cols, stride, ws, row_to_col);
    return MVT_OK;
}

mvt_err_t mvt_assoc_solve_own(const mvt_real *cost, int n_rows, int n_cols, int stride, int *row_to_col,
                              mvt_assoc_ws_t *ws)
{
    MVT_ASSERT(cost != NULL && row_to_col != NULL && ws != NULL);
    if (n_rows < 1 || n_rows > n_cols || n_rows > MVT_ASSOC_MAX_ROWS || n_cols > MVT_ASSOC_MAX_COLS ||
        stride < n_cols) {
        return MVT_ERR_INVALID;
    }
    const int own0 = n_cols - n_rows;
    mvt_real worst = MVT_R(0.0);
    for (int r = 0; r < n_rows; r++) {
        const mvt_real *row = &cost[r * stride];
        for (int c = own0; c < n_cols; c++) {
            if (feasible(row[c]) != (c - own0 == r)) {
                return mvt_assoc_solve(cost, n_rows, n_cols, stride, row_to_col, ws);
            }
        }
        int n = 0;
        for (int c = 0; c < own0; c++) {
            const int ok = feasible(row[c]);
            ws->feasible[r][n] = (int16_t)c; /* kept when feasible: the count moves past it */
            n += ok;
            worst = (ok & (row[c] > worst)) ? row[c] : worst;
        }
        ws->feasible[r][n++] = (int16_t)(own0 + r);
        worst = row[own0 + r] > worst ? row[own0 + r] : worst;
        ws->n_feasible[r] = (int16_t)n;
    }
    /* Where every row's cheapest feasible column (of equals the first) is a different one, each
     * row's search takes it at once, as mvt_assoc_solve's does: every potential is still 0 when
     * the search starts, so its reduced costs are the costs, and the column is free. That is the
     * assignment, found without the searches (the common case: each track has a blob of its own). */
    {
        int distinct = 1;
        for (int j = 0; j < n_cols; j++) {
            ws->used[j] = 0;
        }
        for (int r = 0; r < n_rows && distinct; r++) {
            const mvt_real *row = &cost[r * stride];
            int best = ws->feasible[r][0];
            for (int f = 1; f < ws->n_feasible[r]; f++) {
                const int c = ws->feasible[r][f];
                best = row[c] < row[best] ? c : best;
            }
            distinct = !ws->used[best];
            ws->used[best] = 1;
            row_to_col[r] = best;
        }
        if (distinct) {
            return MVT_OK;
        }
    }
    /* the values mvt_assoc_solve starts from; `big` itself is never needed here */
    const mvt_real inf = (worst + MVT_R(1.0)) * (mvt_real)(n_rows + 1) * (mvt_real)(4 * (n_rows + 1));
    for (int j = 0; j <= n_cols; j++) {
        ws->v[j] = MVT_R(0.0);
        ws->p[j] = 0;
        ws->way[j] = 0;
        ws->minv[j] = inf;
        ws->used[j] = 0;
        ws->seen[j] = 0;
    }
    for (int i = 0; i <= n_rows; i++) {
        ws->u[i] = MVT_R(0.0);
    }
    for (int i = 1; i <= n_rows; i++) {
        ws->p[0] = (int16_t)i;
        int j0 = 0, n = 0;
        do {
            ws->used[j0] = 1;
            const int i0 = ws->p[j0];
            const mvt_real *row = &cost[(i0 - 1) * stride];
            const int16_t *cols = ws->feasible[i0 - 1];
            for (int f = 0; f < ws->n_feasible[i0 - 1]; f++) {
                const int c = cols[f];
                const int j = c + 1;
                const mvt_real cur = row[c] - ws->u[i0] - ws->v[j];
                const int closer = (ws->used[j] == 0) & (cur < ws->minv[j]);
                ws->reached[n] = (int16_t)j; /* kept when first reached */
                n += closer & (ws->seen[j] == 0);
                ws->seen[j] = (uint8_t)(ws->seen[j] | closer);
                ws->minv[j] = closer ? cur : ws->minv[j];
                ws->way[j] = closer ? (int16_t)j0 : ws->way[j];
            }
            mvt_real delta = inf;
            int j1 = 0;
            for (int q = 0; q < n; q++) { /* the smallest, and of equals the first column, as mvt_assoc_solve */
                const int j = ws->reached[q];
                const mvt_real m = ws->minv[j];
                const int better = (ws->used[j] == 0) & ((m < delta) | (((m > delta) == 0) & (j < j1)));
                delta = better ? m : delta;
                j1 = better ? j : j1;
            }
            if (j1 == 0) {
                return MVT_ERR_NUMERIC; /* only with non-finite arithmetic; cannot happen otherwise */
            }
            shift(ws, 0, delta); /* column 0, the search's start, is always used */
            for (int q = 0; q < n; q++) {
                shift(ws, ws->reached[q], delta);
            }
            j0 = j1;
        } while (ws->p[j0] != 0);
        augment(ws, j0);
        for (int q = 0; q < n; q++) { /* back to the state a new search starts from */
            const int j = ws->reached[q];
            ws->minv[j] = inf;
            ws->used[j] = 0;
            ws->seen[j] = 0;
        }
        ws->used[0] = 0;
    }
    matching(cost, n_rows, n_cols, stride, ws, row_to_col);
    return MVT_OK;
}
