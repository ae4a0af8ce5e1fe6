/* seg.h — segregation flux functions and segregation/diffusion coefficients
 * (paper §2.2). Concentration C is the small-grain volume fraction, in [0,1]. */
#ifndef SPHSEG_PHYS_SEG_H
#define SPHSEG_PHYS_SEG_H
#include "../core/hd.h"

/* Parameters of the flux function and of V, D (SI units). */
typedef struct seg_params {
    real A, kappa;     /* eq. (2.9); symmetric flux (2.8) is A = 1, kappa = 0 */
    int shear_model;   /* 0: constant V, D; 1: eq. (2.7) from the shear rate */
    real V, D;         /* constant model: m/s, m^2/s */
    real chi_V, chi_D; /* eq. (2.7), dimensionless */
    real d_small, d_large; /* grain diameters, m */
    real ghat[3];      /* unit vector along gravity */
    int gdot_yielded;  /* Segregation:shear_rate yielded: gdot only where stress_static_q >= 1 */
    real k_static;     /* the static yield cone's slope k(mu_s) of Material:yield (stress_yield_k) */
} seg_params;

/* F(C) = A C (1 - C)(1 - kappa C), eqs. (2.8)-(2.9). */
HD_INLINE real seg_F(const seg_params *sp, real C)
{
    return sp->A * C * (R(1.0) - C) * (R(1.0) - sp->kappa * C);
}

/* dF/dC = A (3 kappa C^2 - 2 (1 + kappa) C + 1), below eq. (2.10). */
HD_INLINE real seg_dFdC(const seg_params *sp, real C)
{
    return sp->A * (R(3.0) * sp->kappa * C * C - R(2.0) * (R(1.0) + sp->kappa) * C + R(1.0));
}

/* d_avg = d^S C + d^L (1 - C), m (§2.2, below eq. 2.7). */
HD_INLINE real seg_davg(const seg_params *sp, real C)
{
    return sp->d_small * C + sp->d_large * (R(1.0) - C);
}

/* Segregation velocity V, m/s: constant, or chi_V gdot d_avg (eq. 2.7b). */
HD_INLINE real seg_V(const seg_params *sp, real C, real gdot)
{
    return sp->shear_model ? sp->chi_V * gdot * seg_davg(sp, C) : sp->V;
}

/* Diffusivity D, m^2/s: constant, or chi_D gdot d_avg^2 (eq. 2.7a). */
HD_INLINE real seg_D(const seg_params *sp, real C, real gdot)
{
    real d = seg_davg(sp, C);
    return sp->shear_model ? sp->chi_D * gdot * d * d : sp->D;
}

/* dV/dC at fixed gdot (d_avg depends on C): for the time-step bound. */
HD_INLINE real seg_dVdC(const seg_params *sp, real gdot)
{
    return sp->shear_model ? sp->chi_V * gdot * (sp->d_small - sp->d_large) : R(0.0);
}

/* Segregation flux magnitude Q = V F, eq. (2.6), m/s. */
HD_INLINE real seg_Q(const seg_params *sp, real C, real gdot)
{
    return seg_V(sp, C, gdot) * seg_F(sp, C);
}

/* Characteristic speed |dQ/dC| = |V F' + F dV/dC|, m/s (time-step bound). */
HD_INLINE real seg_wave_speed(const seg_params *sp, real C, real gdot)
{
    real s = seg_V(sp, C, gdot) * seg_dFdC(sp, C) + seg_F(sp, C) * seg_dVdC(sp, gdot);
    return s < 0 ? -s : s;
}

/* Boundary flux f(C) = -V F n.ghat of the CSR source (eq. 4.5), with n the
 * unit normal pointing into the material; m/s. */
HD_INLINE real seg_wall_flux(const seg_params *sp, real C, real gdot, const real n[3])
{
    real ng = n[0] * sp->ghat[0] + n[1] * sp->ghat[1] + n[2] * sp->ghat[2];
    return -seg_Q(sp, C, gdot) * ng;
}

#endif
