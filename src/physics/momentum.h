/* momentum.h — pair terms of the SPH momentum and kinematics equations
 * (paper §3.2): the velocity gradient behind the strain rate and spin
 * (3.14–3.15), the momentum pair term (3.9) and Monaghan's artificial
 * viscosity (3.10); called by the flow bodies (flow.h). Stress convention as in stress.h (tension positive);
 * grad_i W_ij = kernel_f(r) x_ij with x_ij = x_i - x_j. */
#ifndef SPHSEG_MOMENTUM_H
#define SPHSEG_MOMENTUM_H
#include <math.h>
#include "../core/hd.h"
#include "kernel.h"

/* Adds the pair j to the velocity gradient L_ab = du_a/dx_b of particle i:
 * L -= V_j u_ij (x) grad_i W_ij (the difference form of 3.14–3.15, with the
 * sign that makes it +grad u for C_ij = u_i - u_j; cf. 3.16). L row-major 3x3. */
HD_INLINE void mom_velgrad_add(real L[9], real vol_j, const real uij[3], const real gradW[3])
{
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) L[3 * a + b] -= vol_j * uij[a] * gradW[b];
}

/* Strain rate eps = (L + L^T)/2 as (xx, yy, zz, xy, xz, yz) and spin
 * w = (L - L^T)/2 as (xy, xz, yz), eqs. (3.14)–(3.15), 1/s. */
HD_INLINE void mom_strain_spin(const real L[9], real eps[6], real w[3])
{
    eps[0] = L[0], eps[1] = L[4], eps[2] = L[8];
    eps[3] = R(0.5) * (L[1] + L[3]);
    eps[4] = R(0.5) * (L[2] + L[6]);
    eps[5] = R(0.5) * (L[5] + L[7]);
    w[0] = R(0.5) * (L[1] - L[3]);
    w[1] = R(0.5) * (L[2] - L[6]);
    w[2] = R(0.5) * (L[5] - L[7]);
}

/* Monaghan (1992) artificial viscosity, eq. (3.10), in the units of
 * sigma/rho^2 (m^5/(kg s^2)): Pi_ij = alpha c h (u_ij.x_ij) /
 * (rho_bar (r^2 + 0.01 h^2)) for approaching pairs (u_ij.x_ij < 0), else 0;
 * negative, so it acts as a pressure between approaching particles.
 * mom_av_coef is its pair-independent factor alpha c h / rho_bar, which a
 * pair loop makes once and hands to mom_av_k (a division a pair fewer; the
 * same bits as mom_av). */
HD_INLINE real mom_av_coef(real alpha, real cs, real h, real rho_i, real rho_j)
{
    return alpha * cs * h / (R(0.5) * (rho_i + rho_j));
}

HD_INLINE real mom_av_k(real coef, real h, const real uij[3], const real xij[3])
{
    real ux = uij[0] * xij[0] + uij[1] * xij[1] + uij[2] * xij[2];
    if (ux >= 0) return 0;
    real r2 = xij[0] * xij[0] + xij[1] * xij[1] + xij[2] * xij[2];
    return coef * ux / (r2 + R(0.01) * h * h);
}

HD_INLINE real mom_av(real alpha, real cs, real h, real rho_i, real rho_j, const real uij[3],
                      const real xij[3])
{
    return mom_av_k(mom_av_coef(alpha, cs, h, rho_i, rho_j), h, uij, xij);
}

/* The pair dissipation of the low-dissipation Riemann solver of Zhang, Hu &
 * Adams (2017, J. Comput. Phys. 335, 605), in the units of mom_av: the
 * acoustic Riemann problem along e_ij = x_ji / r between the left state i
 * and the right state j gives P* = (p_i + p_j)/2 + rho beta dU / 2 with
 * dU = (u_i - u_j).e_ij = -(u_ij.x_ij) / r, and their limiter
 * beta = min(eta max(dU, 0), c). So Pi_ij = -beta dU / rho for approaching
 * pairs, else 0: quadratic in the closing speed below c / eta, where
 * Monaghan's (3.10) is linear in it with the factor alpha c h / r, so that a
 * smooth shear flow (dU ~ gdot r) feels it as a viscosity eta gdot r^2, not
 * alpha c h. No c in it below the cap: it does not follow the stiffness E.
 * Against a wall (j a dummy, wall set) the acoustic Riemann problem is taken
 * unlimited, beta = c: the limiter is for the shear of the bulk, not for a
 * particle closing on a wall. */
HD_INLINE real mom_riemann(real eta, real cs, real rho, const real uij[3], const real xij[3], real r2, int wall)
{
    real ux = uij[0] * xij[0] + uij[1] * xij[1] + uij[2] * xij[2];
    if (ux >= 0 || r2 <= 0) return 0;
    real dU = -ux / sqrt_r(r2);
    real beta = wall || eta * dU >= cs ? cs : eta * dU;
    return -beta * dU * (R(1.0) / rho); /* 1/rho hoisted out of the pair loop */
}

/* The pressure diffusion of particle i from the pair j, Pa/s: the rate
 * coef w (p_j - p_i) V_j (-f) r^2 / (r^2 + eta2) r^q (q = 1 for riemann, 0
 * for delta: see flow_ctx.pdiff), added to dp_i/dt (so to -dsigma_kk/dt).
 * It is the Riemann solver's dissipation in the continuity equation
 * (u* = u_bar + (p_i - p_j) / (2 rho c) e_ij, Zhang, Hu & Adams 2017) or
 * delta-SPH's density diffusion (Molteni & Colagrossi 2009; Antuono et al.
 * 2010: delta h c sum psi_ij . grad W V_j, psi_ij = 2 (rho_j - rho_i)
 * x_ji / r^2) written for the pressure, dp = c^2 drho: both flow from high
 * to low pressure and conserve sum p_i V_i pairwise (equal V). Only the
 * isotropic part of the stress is diffused; the deviator is the rheology's.
 * dp is p_j - p_i less its hydrostatic part (flow_rates_team). */
HD_INLINE real mom_pdiff(real dp, real V_j, real f, real r2, real eta2, int riemann)
{
    real w = -f * V_j * dp;
    return riemann ? w * sqrt_r(r2) : w * r2 / (r2 + eta2);
}

/* Adds the pair j to the acceleration of i, eq. (3.9):
 * a_i += m_j (sigma_i/rho_i^2 + sigma_j/rho_j^2 + Pi_ij I) . grad_i W_ij.
 * Symmetric in (i, j) but for grad W, so m_i a_ij = -m_j a_ji. */
/* Viscous acceleration of a Newtonian fluid (Morris, Fox & Zhu 1997, eq. 8,
 * equal densities and viscosities): a_i += sum_j V_j 2 nu (x_ij . grad_i W)
 * / r^2 u_ij = sum_j V_j 2 nu f u_ij (f = (1/r) dW/dr < 0, finite at r = 0
 * for the Wendland C2 kernel, so the form needs no regularisation): the
 * velocities of neighbours pull on each other, dummies' velocities (4.1)
 * giving no slip. Morris's eta^2 = (0.1 h)^2 in the denominator (r^2 +
 * eta^2) left nu 1.5 % low at h = 1.5 dr whatever dr (docs/validation.md,
 * "Plane Poiseuille flow"); it is not used. */
HD_INLINE void mom_visc_add(real a[3], real V_j, real nu, real f, const real uij[3])
{
    real c = R(2.0) * nu * V_j * f;
    a[0] += c * uij[0], a[1] += c * uij[1], a[2] += c * uij[2];
}

/* The viscous operator's second moment on the particles' own lattice:
 * S = -(1/d) sum_j V_j f(r_ij) r_ij^2 over the square (2D) or cubic (3D)
 * lattice of spacing dr about a particle (j != i, V_j = dr^d). The integral
 * it stands for is 1 (a normalised kernel: -int f x_a x_b dV = delta_ab);
 * the sum is not (0.9974 at h = 1.5 dr, 0.9739 at 1.3 dr: a fixed-h/dr
 * floor that no refinement removes), so the fluid's viscous term takes nu /
 * S (flow_ctx.visc_norm), which makes the operator exact for a quadratic
 * velocity on that lattice. A property of the kernel, h/dr and the lattice:
 * no fitted number (docs/validation.md, "Plane Poiseuille flow"). */
HD_INLINE real mom_visc_lattice(int dim, real h, real dr)
{
    const real alpha = kernel_alpha(dim, h), vol = dim == 2 ? dr * dr : dr * dr * dr;
    const int n = (int)(R(2.0) * h / dr) + 1;
    real s = 0;
    for (int a = -n; a <= n; ++a)
        for (int b = -n; b <= n; ++b)
            for (int c = dim == 3 ? -n : 0; c <= (dim == 3 ? n : 0); ++c) {
                real r2 = dr * dr * (real)(a * a + b * b + c * c);
                if (r2 > 0) s -= vol * kernel_f(sqrt_r(r2), h, alpha) * r2;
            }
    return s / (real)dim;
}

HD_INLINE void mom_accel_add(real a[3], real m_j, const real si[6], real rho_i, const real sj[6], real rho_j,
                             real Pi, const real gradW[3])
{
    real ci = R(1.0) / (rho_i * rho_i), cj = R(1.0) / (rho_j * rho_j);
    real T[6];
    for (int c = 0; c < 6; ++c) T[c] = si[c] * ci + sj[c] * cj;
    T[0] += Pi, T[1] += Pi, T[2] += Pi;
    a[0] += m_j * (T[0] * gradW[0] + T[3] * gradW[1] + T[4] * gradW[2]);
    a[1] += m_j * (T[3] * gradW[0] + T[1] * gradW[1] + T[5] * gradW[2]);
    a[2] += m_j * (T[4] * gradW[0] + T[5] * gradW[1] + T[2] * gradW[2]);
}

/* Flow:gradient_correction: a += m_j (sigma_i gi + sigma_j gj) / rho^2 +
 * m_j Pi gradW, gi = B_i grad W_ij, gj = B_j grad W_ij (flow_rates_team):
 * the work conjugate of the corrected velocity gradient, its pair forces
 * still equal and opposite (grad W_ji = -grad W_ij). */
HD_INLINE void mom_accel_add_kgc(real a[3], real m_j, const real si[6], const real sj[6], real rho, real Pi,
                                 const real gradW[3], const real gi[3], const real gj[3])
{
    const real c = m_j * (R(1.0) / (rho * rho)), mp = m_j * Pi; /* 1/rho^2 hoisted */
    a[0] += c * (si[0] * gi[0] + si[3] * gi[1] + si[4] * gi[2] + sj[0] * gj[0] + sj[3] * gj[1] + sj[4] * gj[2]) +
            mp * gradW[0];
    a[1] += c * (si[3] * gi[0] + si[1] * gi[1] + si[5] * gi[2] + sj[3] * gj[0] + sj[1] * gj[1] + sj[5] * gj[2]) +
            mp * gradW[1];
    a[2] += c * (si[4] * gi[0] + si[5] * gi[1] + si[2] * gi[2] + sj[4] * gj[0] + sj[5] * gj[1] + sj[2] * gj[2]) +
            mp * gradW[2];
}

#endif
