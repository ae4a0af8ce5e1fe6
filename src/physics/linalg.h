/* linalg.h — tiny dense solves for the C1-consistent gradients (App. E), the
 * product of a symmetric 3x3 tensor with a vector and its largest eigenvalue. */
#ifndef SPHSEG_LINALG_H
#define SPHSEG_LINALG_H
#include <math.h>
#include "../core/hd.h"

/* b = S v, S symmetric stored as (xx, yy, zz, xy, xz, yz): the
 * renormalised pair gradients of the conservative scheme (seg_Lbar) and the
 * corrected kernel gradient (Flow:gradient_correction, flow_rates_team). */
HD_INLINE void linalg_sym_apply(const real S[6], const real v[3], real b[3])
{
    b[0] = S[0] * v[0] + S[3] * v[1] + S[4] * v[2];
    b[1] = S[3] * v[0] + S[1] * v[1] + S[5] * v[2];
    b[2] = S[4] * v[0] + S[5] * v[1] + S[2] * v[2];
}

/* The largest eigenvalue of the symmetric 3x3 m (xx, yy, zz, xy, xz, yz),
 * by the trigonometric form of the characteristic cubic (Smith 1961): the corrected gradient's blend (flow_kgc_store). */
HD_INLINE real linalg_sym_eig_max(const real m[6])
{
    const real q = (m[0] + m[1] + m[2]) / R(3.0);
    const real off = m[3] * m[3] + m[4] * m[4] + m[5] * m[5];
    const real d0 = m[0] - q, d1 = m[1] - q, d2 = m[2] - q;
    const real p2 = d0 * d0 + d1 * d1 + d2 * d2 + R(2.0) * off;
    if (!(p2 > 0)) return q;
    const real pp = sqrt_r(p2 / R(6.0)), ip = R(1.0) / pp;
    const real b0 = d0 * ip, b1 = d1 * ip, b2 = d2 * ip, b3 = m[3] * ip, b4 = m[4] * ip, b5 = m[5] * ip;
    real r = R(0.5) * (b0 * (b1 * b2 - b5 * b5) - b3 * (b3 * b2 - b5 * b4) + b4 * (b3 * b5 - b1 * b4));
    r = r < R(-1.0) ? R(-1.0) : (r > R(1.0) ? R(1.0) : r);
    return q + R(2.0) * pp * (real)cos(acos((double)r) / 3.0);
}

/* Solve A X = B in place for n <= 4 unknowns and nrhs <= 4 right-hand sides
 * (A row-major n x n, B row-major n x nrhs), Gaussian elimination with partial
 * pivoting. Returns 0, or 1 if A is singular relative to tol * max|A|. */
HD_INLINE int linalg_solve(int n, real *A, real *B, int nrhs, real tol)
{
    real amax = 0;
    for (int k = 0; k < n * n; ++k) amax = A[k] > amax ? A[k] : (-A[k] > amax ? -A[k] : amax);
    if (amax == 0) return 1;
    for (int c = 0; c < n; ++c) {
        int piv = c;
        for (int r = c + 1; r < n; ++r) {
            real a = A[r * n + c] < 0 ? -A[r * n + c] : A[r * n + c];
            real b = A[piv * n + c] < 0 ? -A[piv * n + c] : A[piv * n + c];
            if (a > b) piv = r;
        }
        real pv = A[piv * n + c];
        if ((pv < 0 ? -pv : pv) <= tol * amax) return 1;
        if (piv != c) {
            for (int k = 0; k < n; ++k) { real t = A[c * n + k]; A[c * n + k] = A[piv * n + k]; A[piv * n + k] = t; }
            for (int k = 0; k < nrhs; ++k) { real t = B[c * nrhs + k]; B[c * nrhs + k] = B[piv * nrhs + k]; B[piv * nrhs + k] = t; }
        }
        for (int r = c + 1; r < n; ++r) {
            real f = A[r * n + c] / pv;
            for (int k = c; k < n; ++k) A[r * n + k] -= f * A[c * n + k];
            for (int k = 0; k < nrhs; ++k) B[r * nrhs + k] -= f * B[c * nrhs + k];
        }
    }
    for (int r = n - 1; r >= 0; --r)
        for (int k = 0; k < nrhs; ++k) {
            real s = B[r * nrhs + k];
            for (int c = r + 1; c < n; ++c) s -= A[r * n + c] * B[c * nrhs + k];
            B[r * nrhs + k] = s / A[r * n + r];
        }
    return 0;
}

#endif
