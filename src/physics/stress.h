/* stress.h — the regularized mu(I) elastoplastic model of the paper (§2.3,
 * §2.4, App. C): elastic moduli, mu(I) (2.13–2.14), the yield surfaces
 * (Material:yield: the paper's Drucker–Prager cone 2.11–2.12, or the
 * tensorial mu(I) law of Jop, Forterre & Pouliquen 2006), the Jaumann-rate
 * elastic trial stress and the one-step return mappings with tension cut-off.
 * Called by the flow bodies (flow.h).
 *
 * Conventions: stress is a symmetric tensor stored as (xx, yy, zz, xy, xz,
 * yz), Pa, tension positive; the pressure p = -tr(sigma)/3 is positive in
 * compression (the sign that makes f = sqrt(J2) - k_mu p of (2.11) a
 * cone opening into compression). Velocity gradient L_ab = du_a/dx_b; strain
 * rate eps = (L + L^T)/2, spin w = (L - L^T)/2, both 1/s. */
#ifndef SPHSEG_STRESS_H
#define SPHSEG_STRESS_H
#include <math.h>
#include "../core/hd.h"
#include "options.h"

typedef struct mat_params {
    real G, K;         /* shear and bulk moduli, Pa */
    real rho_s;        /* intrinsic grain density, kg/m^3 (inertial number) */
    real mu_s, mu_d;   /* static and dynamic friction (2.13) */
    real I0;           /* reference inertial number (2.13) */
    real lambda;       /* regularization of (2.14), 1/s; 0.001 in the paper */
    /* Material:mu_law partial (Barker & Gray 2017): mu = sqrt(pr_alpha /
     * ln(pr_A / I)) below I = pr_IN1 (stress_partial_law); pr_IN1 = 0: off */
    real pr_alpha, pr_A, pr_IN1;
} mat_params;

/* Shear and bulk moduli from Young's modulus E (Pa) and Poisson's ratio nu. */
HD_INLINE void stress_moduli(real E, real nu, real *G, real *K)
{
    *G = E / (R(2.0) * (R(1.0) + nu));
    *K = E / (R(3.0) * (R(1.0) - R(2.0) * nu));
}

/* Elastic sound speed sqrt((K + 4G/3)/rho), m/s (the c_s of 3.10 and 3.19). */
HD_INLINE real stress_sound_speed(real G, real K, real rho)
{
    return sqrt_r((K + R(4.0) / R(3.0) * G) / rho);
}

/* p = -tr(sigma)/3, Pa, positive in compression. */
HD_INLINE real stress_pressure(const real s[6]) { return -(s[0] + s[1] + s[2]) / R(3.0); }

/* J2 = s:s/2 of the deviator s = sigma + p I, Pa^2. */
HD_INLINE real stress_J2(const real s[6])
{
    real p = stress_pressure(s);
    real d0 = s[0] + p, d1 = s[1] + p, d2 = s[2] + p;
    return R(0.5) * (d0 * d0 + d1 * d1 + d2 * d2) + s[3] * s[3] + s[4] * s[4] + s[5] * s[5];
}

/* Shear-rate magnitude gdot = sqrt(2 e:e) of the deviatoric strain rate e
 * (below eq. 2.7), 1/s; eps stored like stress. */
HD_INLINE real stress_shear_rate(const real e[6])
{
    real v = (e[0] + e[1] + e[2]) / R(3.0);
    real d0 = e[0] - v, d1 = e[1] - v, d2 = e[2] - v;
    real ee = d0 * d0 + d1 * d1 + d2 * d2 + R(2.0) * (e[3] * e[3] + e[4] * e[4] + e[5] * e[5]);
    return sqrt_r(R(2.0) * ee);
}

/* k_mu = 3 mu / sqrt(9 + 12 mu^2), eq. (2.12). */
HD_INLINE real stress_kmu(real mu) { return R(3.0) * mu / sqrt_r(R(9.0) + R(12.0) * mu * mu); }

/* Regularized mu(I), eq. (2.14): mu_s + (mu_d - mu_s) gdot /
 * (I0 sqrt(p / (rho_s d^2)) + sqrt(gdot^2 + lambda^2)); finite at gdot = 0
 * (gives mu_s) and at p = 0 (gives mu_s + (mu_d - mu_s) gdot / |..|).
 * With the partial regularisation (pr_IN1 > 0) and p > 0, at I = sqrt(gdot^2
 * + lambda^2) d / sqrt(p / rho_s) < pr_IN1 instead sqrt(pr_alpha / ln(pr_A /
 * I)) (Barker & Gray 2017; continuous at pr_IN1 to the unregularized mu(I),
 * from which (2.14) differs there by O(lambda^2 / gdot^2)). lambda regularises
 * this law at gdot -> 0 as it does (2.14): unregularised, mu -> 0 there with
 * an infinite slope, so in a bed at rest mu would follow the round-off of
 * gdot (the CPU and GPU backends then part by 1e-4 in 60 steps of the drum,
 * tests/validate_gpu.py); with it, mu(gdot = 0) = mu(I_lambda) > 0 (0.30 for
 * Table 1 at p = 100 Pa), smooth in gdot, and no static yield remains. */
HD_INLINE real stress_mu(const mat_params *m, real gdot, real p, real davg)
{
    real pp = p > 0 ? p : R(0.0);
    if (m->pr_IN1 > 0 && pp > 0) {
        real I = sqrt_r(gdot * gdot + m->lambda * m->lambda) * davg / sqrt_r(pp / m->rho_s);
        if (I < m->pr_IN1)
            return I > 0 ? sqrt_r(m->pr_alpha / (real)log((double)(m->pr_A / I))) : R(0.0);
    }
    real den = m->I0 * sqrt_r(pp / (m->rho_s * davg * davg)) +
               sqrt_r(gdot * gdot + m->lambda * m->lambda);
    if (!(den > 0)) return m->mu_s; /* lambda = 0 at gdot = 0, p = 0: the unregularized limit */
    return m->mu_s + (m->mu_d - m->mu_s) * gdot / den;
}

/* The well-posedness criterion of incompressible mu(I) in 2D (Barker et
 * al. 2015; Barker & Gray 2017, eq. 3.9) for the unregularized mu(I) =
 * mu_s + (mu_d - mu_s) I / (I0 + I): with nu = I mu'(I) / mu(I),
 * C(I) = 4 nu^2 - 4 nu + mu^2 (1 - nu / 2)^2, well posed where C < 0
 * (docs/granular.md "Well-posedness"). Host only, at setup. */
static inline double stress_wellposed_C(double I, double mu_s, double mu_d, double I0)
{
    double mu = mu_s + (mu_d - mu_s) * I / (I0 + I);
    double nu = I * (mu_d - mu_s) * I0 / ((I0 + I) * (I0 + I)) / mu;
    return 4 * nu * nu - 4 * nu + mu * mu * (1 - nu / 2) * (1 - nu / 2);
}

/* Barker & Gray's (2017) partial regularisation for Table-1-like mu(I):
 * I_N1, the lower edge of the well-posed window (the first sign change of
 * stress_wellposed_C from + to - scanning up from I = 1e-8, then bisected
 * in log I), and A = I_N1 exp(alpha / mu(I_N1)^2), so that
 * sqrt(alpha / ln(A / I)) is continuous with mu(I) at I_N1. Returns 0, or
 * -1 where there is no such edge in [1e-8, 1e4] (never well posed, or
 * already well posed at 1e-8: nothing to regularise); host only,
 * at setup (tools/analysis/inertial_range.py computes the same). */
static inline int stress_partial_law(double mu_s, double mu_d, double I0, double alpha, double *IN1, double *A)
{
    const int n = 4000;
    double a = 1e-8;
    *IN1 = *A = 0;
    for (int k = 1; k <= n; ++k) {
        double b = pow(10.0, -8.0 + 12.0 * k / n);
        if (stress_wellposed_C(b, mu_s, mu_d, I0) < 0) {
            if (k == 1 && stress_wellposed_C(a, mu_s, mu_d, I0) < 0) break; /* no ill-posed low I */
            for (int it = 0; it < 200; ++it) {
                double m = sqrt(a * b);
                if (stress_wellposed_C(m, mu_s, mu_d, I0) < 0) b = m;
                else a = m;
            }
            double I = sqrt(a * b), mu = mu_s + (mu_d - mu_s) * I / (I0 + I);
            *IN1 = I, *A = I * exp(alpha / (mu * mu));
            return 0;
        }
        a = b;
    }
    return -1;
}

/* Elastic trial increment rate of (C1): w sigma - sigma w + 2 G e + K tr(eps) I,
 * with e the deviatoric strain rate. (2.16) writes K eps_v with eps_v =
 * tr(eps)/3 as defined below (2.7); linear elasticity needs K tr(eps), which
 * is what is used. w: (xy, xz, yz) components of the spin (w_yx = -w_xy). */
HD_INLINE void stress_rate_elastic(const real s[6], const real eps[6], const real w[3], real G, real K,
                                   real out[6])
{
    real S[3][3] = {{s[0], s[3], s[4]}, {s[3], s[1], s[5]}, {s[4], s[5], s[2]}};
    real W[3][3] = {{0, w[0], w[1]}, {-w[0], 0, w[2]}, {-w[1], -w[2], 0}};
    real J[3][3];
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
            real t = 0;
            for (int c = 0; c < 3; ++c) t += W[a][c] * S[c][b] - S[a][c] * W[c][b];
            J[a][b] = t;
        }
    real tr = eps[0] + eps[1] + eps[2];
    out[0] = J[0][0] + R(2.0) * G * (eps[0] - tr / R(3.0)) + K * tr;
    out[1] = J[1][1] + R(2.0) * G * (eps[1] - tr / R(3.0)) + K * tr;
    out[2] = J[2][2] + R(2.0) * G * (eps[2] - tr / R(3.0)) + K * tr;
    out[3] = J[0][1] + R(2.0) * G * eps[3];
    out[4] = J[0][2] + R(2.0) * G * eps[4];
    out[5] = J[1][2] + R(2.0) * G * eps[5];
}

/* One-step return mapping (App. C) for the cohesionless Drucker–Prager cone
 * with the non-associated potential g = sqrt(J2) (2.15), applied to a trial
 * stress in place. Returns 0 elastic, 1 returned to the cone, 2 apex.
 *  - apex / tension cut-off: a trial pressure p <= 0 (grains cannot carry
 *    tension, as at a free surface) maps to the apex, sigma = 0;
 *  - otherwise, if f = sqrt(J2) - k_mu p > 0, the deviator is scaled onto the
 *    cone, s = s* k_mu p / sqrt(J2*), keeping p (g has no volumetric part). */
HD_INLINE int stress_return_map(real s[6], real kmu)
{
    real p = stress_pressure(s);
    if (p <= 0) {
        for (int c = 0; c < 6; ++c) s[c] = 0;
        return 2;
    }
    real tau = sqrt_r(stress_J2(s));
    if (tau <= kmu * p) return 0;
    real r = kmu * p / tau;
    for (int c = 0; c < 3; ++c) s[c] = -p + r * (s[c] + p);
    for (int c = 3; c < 6; ++c) s[c] *= r;
    return 1;
}

/* The yield surfaces of Material:yield, both cones sqrt(J2) = k p in the
 * code's J2 = s:s/2 (stress_J2) for a friction mu = mu(I) of (2.14):
 *   YIELD_DRUCKER_PRAGER  k = k_mu(mu) = 3 mu / sqrt(9 + 12 mu^2), eq. (2.12),
 *                         the paper's; in simple shear tau_xy / p = k_mu(mu)
 *                         (0.3495 = tan 19.3 deg at mu_s 0.382);
 *   YIELD_MU_I            k = mu: the law tau_ij = mu(I) p D_ij / |D| of Jop,
 *                         Forterre & Pouliquen (2006), |tau| = sqrt(tau_ij tau_ij / 2)
 *                         = sqrt(J2) <= mu(I) p; in simple shear tau_xy / p = mu
 *                         (tan 20.9 deg at mu_s), Pouliquen's (1999) onset.
 * sqrt(J2) is the full 3x3 deviator's, so in 2D plane strain s_zz counts; in
 * steady isochoric simple shear the flow rule drives s_zz and s_xx - s_yy to
 * O(tau^2 / G) and sqrt(J2) = |tau_xy| (tests/test_stress.c). */

/* The slope k of the yield cone sqrt(J2) = k p for friction mu (above). */
HD_INLINE real stress_yield_k(int yield, real mu) { return yield == YIELD_MU_I ? mu : stress_kmu(mu); }

/* sqrt(J2) / (k p) for the static cone's slope k = k(mu_s): under 1 strictly
 * inside it (the stress of an unyielded, elastic point, whatever the rate,
 * as mu(I) >= mu_s), 1 and over on or past it; 1 where p <= 0 (the apex, a
 * free surface's grains). The bed damping's weight (flow.h) and
 * Segregation:shear_rate yielded (seg_kern.h) read it. */
HD_INLINE real stress_static_q(const real s[6], real k)
{
    const real p = stress_pressure(s);
    if (!(p > 0)) return R(1.0);
    return sqrt_r(stress_J2(s)) / (k * p);
}

/* The return mapping of Material:yield `yield` at friction mu = mu(I), in
 * place, with the returns of stress_return_map (0 elastic, 1 returned, 2
 * apex) and its tension cut-off (a trial p <= 0 goes to the apex sigma = 0).
 * For YIELD_MU_I a trial outside |tau| = sqrt(J2) <= mu p is returned
 * radially onto it, the deviator scaled by mu p / sqrt(J2*) at the trial
 * pressure: radial because the JFP law's flow direction is the deviator
 * itself (tau parallel to D; with the elastic part, the plastic strain rate
 * parallel to s, the potential g = sqrt(J2) of 2.15), and isochoric, so p is
 * kept. Both surfaces are cones about the hydrostatic axis, so the one radial
 * return serves both, with its own slope. */
HD_INLINE int stress_return_yield(real s[6], int yield, real mu)
{
    return stress_return_map(s, stress_yield_k(yield, mu));
}

/* Time step of (3.19): chi_CFL min(sqrt(h / a_max), h / c_s), s. */
HD_INLINE real stress_dt(real chi, real h, real amax, real cs)
{
    real a = amax > 0 ? sqrt_r(h / amax) : (real)1e30;
    real b = h / cs;
    return chi * (a < b ? a : b);
}

#endif
