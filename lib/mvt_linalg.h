/*
 * mvt_linalg.h - the few dense small-matrix routines the core needs (row-major, n <= 8).
 * Every routine is O(n^3) or less with n a compile-time-bounded size; no allocation.
 */
#ifndef MVT_LINALG_H
#define MVT_LINALG_H

#include "mvt_types.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MVT_LA_MAX_N 8

/* In-place Cholesky A = L L^T of a symmetric n x n matrix (upper triangle ignored, lower
 * triangle overwritten with L). Returns MVT_ERR_NUMERIC when a pivot is <= 0 or not finite. */
mvt_err_t mvt_la_cholesky(int n, mvt_real *a);

/* Solves (L L^T) x = b for x, overwriting b; l from mvt_la_cholesky. O(n^2). */
void mvt_la_chol_solve(int n, const mvt_real *l, mvt_real *b);

/* Inverse of a symmetric positive-definite 2x2 packed as (xx, xy, yy). MVT_ERR_NUMERIC if not PD. */
mvt_err_t mvt_la_inv2_sym(const mvt_real s[3], mvt_real inv[3]);

/* Inverse of a general 3x3 matrix. MVT_ERR_NUMERIC when |det| < 100 eps times the product of the
 * row norms (its Hadamard bound): the matrix is numerically singular. */
mvt_err_t mvt_la_inv3(const mvt_real a[9], mvt_real inv[9]);

/* Rotation matrix from a Rodrigues vector (axis * angle, radians), as cv::Rodrigues. */
void mvt_la_rodrigues(const mvt_real rvec[3], mvt_real r[9]);

/* 1 when every one of the n values is finite. */
int mvt_la_all_finite(const mvt_real *x, int n);

#ifdef __cplusplus
}
#endif

#endif /* MVT_LINALG_H */
