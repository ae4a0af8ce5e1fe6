/* kernel.h — Wendland C2 smoothing kernel, paper eq. (3.3).
 * W(q) = alpha_d (1 - q/2)^4 (2q + 1) for 0 <= q <= 2, q = r/h, support 2h;
 * alpha_2 = 7/(4 pi h^2), alpha_3 = 21/(16 pi h^3). Units: 1/m^d. */
#ifndef SPHSEG_KERNEL_H
#define SPHSEG_KERNEL_H
#include "../core/hd.h"

/* Normalisation constant alpha_d of eq. (3.3) for dimension dim (2 or 3). */
HD_INLINE real kernel_alpha(int dim, real h)
{
    return dim == 2 ? R(7.0) / (R(4.0 * M_PI) * h * h)
                    : R(21.0) / (R(16.0 * M_PI) * h * h * h);
}

/* W(r) for r >= 0, eq. (3.3). */
HD_INLINE real kernel_w(real r, real h, real alpha)
{
    real q = r * (R(1.0) / h); /* 1/h: a pair loop's invariant, hoisted (a product, not a division, a pair) */
    if (q >= R(2.0)) return R(0.0);
    real a = R(1.0) - R(0.5) * q;
    real a2 = a * a;
    return alpha * a2 * a2 * (R(2.0) * q + R(1.0));
}

/* (1/r) dW/dr, so that grad_i W_ij = kernel_dwdr_over_r * x_ij with
 * x_ij = x_i - x_j; finite at r = 0. dW/dr = -5 alpha q (1 - q/2)^3 / h. */
HD_INLINE real kernel_f(real r, real h, real alpha)
{
    real q = r * (R(1.0) / h);
    if (q >= R(2.0)) return R(0.0);
    real a = R(1.0) - R(0.5) * q;
    return (-R(5.0) * alpha / (h * h)) * (a * a * a); /* the constant hoisted out of a pair loop */
}

#endif
