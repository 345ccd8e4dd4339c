/*
 * linalg.h: the few small dense operations the orbit code needs, for
 * matrices of at most SS_MAX_PHASES rows (row-major).
 */
#ifndef SS_LINALG_H
#define SS_LINALG_H

#include <math.h>
#include <string.h>

/* C = A B, 4x4 (C may not alias). */
static inline void mat4_mul(const double *A, const double *B, double *C) {
  for (int i = 0; i < 4; i++)
    for (int j = 0; j < 4; j++) {
      double s = 0;
      for (int k = 0; k < 4; k++)
        s += A[4 * i + k] * B[4 * k + j];
      C[4 * i + j] = s;
    }
}

/* y = A x (+ y if acc), 4x4. */
static inline void mat4_vec(const double *A, const double *x, double *y,
                            int acc) {
  for (int i = 0; i < 4; i++) {
    double s = acc ? y[i] : 0;
    for (int k = 0; k < 4; k++)
      s += A[4 * i + k] * x[k];
    y[i] = s;
  }
}

/* LU factorisation with partial pivoting of the n x n matrix A in place.
 * Returns 0, or -1 when a pivot is below rtol times the largest entry. */
static inline int lu_factor(double *A, int n, int *piv, double rtol) {
  double amax = 0;
  for (int i = 0; i < n * n; i++)
    amax = fmax(amax, fabs(A[i]));
  if (!(amax > 0))
    return -1;
  for (int k = 0; k < n; k++) {
    int p = k;
    for (int i = k + 1; i < n; i++)
      if (fabs(A[n * i + k]) > fabs(A[n * p + k]))
        p = i;
    piv[k] = p;
    if (!(fabs(A[n * p + k]) > rtol * amax))
      return -1;
    if (p != k)
      for (int j = 0; j < n; j++) {
        double t = A[n * k + j];
        A[n * k + j] = A[n * p + j];
        A[n * p + j] = t;
      }
    for (int i = k + 1; i < n; i++) {
      double l = A[n * i + k] /= A[n * k + k];
      for (int j = k + 1; j < n; j++)
        A[n * i + j] -= l * A[n * k + j];
    }
  }
  return 0;
}

/* Solve with the factors of lu_factor(); b is overwritten with x. */
static inline void lu_solve(const double *LU, int n, const int *piv,
                            double *b) {
  for (int k = 0; k < n; k++) {
    double t = b[piv[k]];
    b[piv[k]] = b[k];
    b[k] = t;
  }
  for (int i = 1; i < n; i++)
    for (int j = 0; j < i; j++)
      b[i] -= LU[n * i + j] * b[j];
  for (int i = n - 1; i >= 0; i--) {
    for (int j = i + 1; j < n; j++)
      b[i] -= LU[n * i + j] * b[j];
    b[i] /= LU[n * i + i];
  }
}

#endif
