/* dem.h — the bodies of the DEM grains and their coupling with the SPH fluid
 * (Markauskas, Kruggel-Emden, Sivanesapillai & Steeb 2016, "the DEM paper"
 * below), one formula each, HD_INLINE so that a GPU pass can call them as
 * the CPU's (src/dem/dem.c) does:
 *   contacts  linear spring-dashpot normal force, linear tangential spring
 *             limited by Coulomb friction with its history (§2, eq. 2);
 *   gravity   the gradual gravity of eqs. (3)-(4);
 *   fraction  the fluid fraction eps_a (15) with the wall correction (16)
 *             for the code's kernel (the paper's eq. 17 is the cubic
 *             spline's; here the same integral of the Wendland C2 kernel);
 *   drag      Di Felice's drag (19), (21), (22) and the interaction force
 *             with the pressure gradient (23);
 *   rigid     a rigid body of grains (DEM:motion rigid): its inertia
 *             tensor, spin update and turn.
 * SI units throughout; a grain is a sphere of diameter d (3D and 2D alike:
 * in 2D the grains are spheres whose centres stay in the x-y plane). */
#ifndef SPHSEG_DEM_H
#define SPHSEG_DEM_H
#include <math.h>
#include "../core/hd.h"
#include "kernel.h"

typedef struct dem_params {
    real kn, kt;  /* normal and tangential spring stiffness, N/m */
    real gn;      /* normal damping coefficient, kg/s (dem_damping from the restitution) */
    real mu;      /* Coulomb friction coefficient of a contact */
    real d, rho;  /* grain diameter (m) and density (kg/m^3) */
} dem_params;

/* Volume (m^3) and mass (kg) of a grain of diameter d and density rho. */
HD_INLINE real dem_volume(real d) { return R(M_PI / 6.0) * d * d * d; }

/* Normal damping coefficient gamma (kg/s) of the linear spring-dashpot
 * m* x'' + gamma x' + k x = 0 that gives the restitution coefficient e
 * (0 < e <= 1) for the reduced mass m*: gamma = -2 ln(e) sqrt(m* k) /
 * sqrt(pi^2 + ln^2 e) (the damped oscillator's half period; Ting & Corkan
 * 1992, the DEM paper's ref. [28] model). */
HD_INLINE real dem_damping(real e, real mstar, real k)
{
    real le = (real)log((double)e);
    return -R(2.0) * le * sqrt_r(mstar * k) / sqrt_r(R(M_PI * M_PI) + le * le);
}

/* The contact time (s) of the linear spring-dashpot, pi / sqrt(k/m* -
 * (gamma / 2m*)^2): the DEM step is a fiftieth of it (dem.c). */
HD_INLINE real dem_contact_time(real k, real mstar, real gamma)
{
    real w2 = k / mstar - (gamma / (R(2.0) * mstar)) * (gamma / (R(2.0) * mstar));
    return R(M_PI) / sqrt_r(w2);
}

/* The force on grain i of one contact (§2): normal unit n (from the partner
 * to i), overlap delta > 0, relative velocity of the contact point vrel =
 * v_i - v_j + (w_i r_i + w_j r_j) x n (r_i, r_j the lever arms, a wall's 0),
 * the tangential spring's elongation xi[3] (the history, updated here by
 * dt: rotated into the contact plane, grown by the tangential slip, cut
 * back to the Coulomb limit). F = (kn delta - gn vn) n + Ft,
 * Ft = -kt xi limited to mu |Fn|. The normal force is not let pull
 * (F_n >= 0). Returns |F_n|. */
HD_INLINE real dem_contact(const dem_params *c, const real n[3], real delta, const real vrel[3], real xi[3],
                           real dt, real F[3])
{
    real vn = vrel[0] * n[0] + vrel[1] * n[1] + vrel[2] * n[2];
    real fn = c->kn * delta - c->gn * vn;
    if (fn < 0) fn = 0;
    real vt[3] = {vrel[0] - vn * n[0], vrel[1] - vn * n[1], vrel[2] - vn * n[2]};
    real xn = xi[0] * n[0] + xi[1] * n[1] + xi[2] * n[2];
    for (int a = 0; a < 3; ++a) xi[a] += -xn * n[a] + vt[a] * dt; /* into the contact plane, then the slip */
    real ft[3] = {-c->kt * xi[0], -c->kt * xi[1], -c->kt * xi[2]};
    real ftm = sqrt_r(ft[0] * ft[0] + ft[1] * ft[1] + ft[2] * ft[2]), lim = c->mu * fn;
    if (ftm > lim && ftm > 0) { /* sliding: the spring held at the Coulomb limit */
        real s = lim / ftm;
        for (int a = 0; a < 3; ++a) ft[a] *= s, xi[a] = -ft[a] / c->kt;
    }
    for (int a = 0; a < 3; ++a) F[a] = fn * n[a] + ft[a];
    return fn;
}

/* The gradual gravity factor xi(t) of eq. (4), 1 after t_damp (or when
 * t_damp <= 0). */
HD_INLINE real dem_gravity_ramp(double t, double t_damp)
{
    if (!(t_damp > 0) || t >= t_damp) return R(1.0);
    return (real)(0.5 * (sin(M_PI * (-0.5 + t / t_damp)) + 1.0));
}

/* The gravity on a grain, eq. (3): V g [rho_f + (rho_s - rho_f) xi(t)], N;
 * with eq. (23)'s buoyancy -V rho_f g the net is V g (rho_s - rho_f) xi. */
HD_INLINE void dem_gravity(real V, const real g[3], real rho_f, real rho_s, real ramp, real F[3])
{
    real m = V * (rho_f + (rho_s - rho_f) * ramp);
    F[0] = m * g[0], F[1] = m * g[1], F[2] = m * g[2];
}

/* Di Felice's drag on a grain, eqs. (19), (21), (22): with the relative
 * velocity u = u_f - v (m/s), the fluid fraction eps at the grain, the
 * kinematic viscosity nu: Re = eps |u| d / nu, C_d = (0.63 + 4.8 / sqrt
 * Re)^2, chi = 3.7 - 0.65 exp(-(1.5 - log10 Re)^2 / 2), F = C_d rho_f pi
 * d^2 u |u| eps^(2 - chi) / 8 (N). Zero at u = 0. */
HD_INLINE void dem_drag(real d, real rho_f, real nu, real eps, const real u[3], real F[3])
{
    real um = sqrt_r(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    F[0] = F[1] = F[2] = 0;
    if (!(um > 0)) return;
    real Re = eps * um * d / nu;
    real cd = R(0.63) + R(4.8) / sqrt_r(Re);
    cd *= cd;
    real l = R(1.5) - (real)log10((double)Re);
    real chi = R(3.7) - R(0.65) * (real)exp((double)(-l * l / R(2.0)));
    real c = R(0.125) * cd * rho_f * R(M_PI) * d * d * um * (real)pow((double)eps, (double)(R(2.0) - chi));
    F[0] = c * u[0], F[1] = c * u[1], F[2] = c * u[2];
}

/* The interaction force on a grain, eq. (23): F_D / eps - V rho_f g, N
 * (the drag and the fluid's pressure gradient, which here is the
 * hydrostatic one plus what the grains' drag sets up). */
HD_INLINE void dem_interaction(const real FD[3], real eps, real V, real rho_f, const real g[3], real F[3])
{
    for (int a = 0; a < 3; ++a) F[a] = FD[a] / eps - V * rho_f * g[a];
}

/* The share of the kernel's integral that lies on the material's side of a
 * plane wall at distance y >= 0 from the point, Gamma of eq. (16) for the
 * code's kernel (kernel.h; the paper's eq. 17 is the same integral of the
 * cubic spline): 1 - int_{z > y} W dV, the cut-off cap being 2 pi int_y^2h
 * W(r) r (r - y) dr in 3D and 2 int_y^2h W(r) r acos(y/r) dr in 2D, by
 * 8-point Gauss-Legendre over [y, 2h] (exact in 3D: a polynomial of degree
 * 7). Between 1/2 (on the wall) and 1 (y >= 2h). */
HD_INLINE real dem_gamma_wall(int dim, real y, real h)
{
    const real R2 = R(2.0) * h;
    if (y >= R2) return R(1.0);
    if (y < 0) y = 0;
    const double gx[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363};
    const double gw[4] = {0.3626837833783620, 0.3137066238706820, 0.2223810344533745, 0.1012285362903763};
    const real alpha = kernel_alpha(dim, h);
    double mid = 0.5 * ((double)R2 + (double)y), half = 0.5 * ((double)R2 - (double)y), cap = 0;
    for (int q = 0; q < 8; ++q) {
        double r = mid + (q < 4 ? -gx[q & 3] : gx[q & 3]) * half, w = gw[q & 3] * half;
        double W = (double)kernel_w((real)r, h, alpha);
        cap += dim == 3 ? w * 2.0 * M_PI * W * r * (r - (double)y) : w * 2.0 * W * r * acos((double)y / r);
    }
    return (real)(1.0 - cap);
}

/* The fluid fraction at a fluid particle, eqs. (15)-(16): eps = 1 -
 * sum_i V_i W_ai / Gamma_a, from the grain sum s = sum_i V_i W_ai and the
 * wall correction gamma; kept above eps_min (a grain on a fluid particle
 * would drive it to or below 0, where eq. 19 has no meaning). */
HD_INLINE real dem_fraction(real s, real gamma, real eps_min)
{
    real e = R(1.0) - s / gamma;
    return e < eps_min ? eps_min : e;
}

/* A rigid body of spheres (DEM:motion rigid): the share of one sphere of
 * mass m and own moment of inertia I0 (2/5 m r^2) at r from the body's
 * centre in its inertia tensor, m (|r|^2 1 - r r^T) + I0 1, added to
 * J[9] (row-major), kg m^2. */
HD_INLINE void dem_inertia_add(real m, real I0, const real r[3], real J[9])
{
    const real rr = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
    for (int q = 0; q < 3; ++q)
        for (int b = 0; b < 3; ++b) J[3 * q + b] += m * ((q == b ? rr : R(0.0)) - r[q] * r[b]) + (q == b ? I0 : R(0.0));
}

/* The angular velocity w (rad/s) of a rigid body of inertia tensor J[9]
 * (positive definite) after its angular momentum J w grew by the torque T
 * over dt: w <- J^-1 (J w + T dt), J inverted by its cofactors. */
HD_INLINE void dem_spin_update(const real J[9], const real T[3], real dt, real w[3])
{
    real L[3], B[9];
    for (int q = 0; q < 3; ++q) L[q] = J[3 * q] * w[0] + J[3 * q + 1] * w[1] + J[3 * q + 2] * w[2] + T[q] * dt;
    B[0] = J[4] * J[8] - J[5] * J[7], B[1] = J[2] * J[7] - J[1] * J[8], B[2] = J[1] * J[5] - J[2] * J[4];
    B[3] = J[5] * J[6] - J[3] * J[8], B[4] = J[0] * J[8] - J[2] * J[6], B[5] = J[2] * J[3] - J[0] * J[5];
    B[6] = J[3] * J[7] - J[4] * J[6], B[7] = J[1] * J[6] - J[0] * J[7], B[8] = J[0] * J[4] - J[1] * J[3];
    const real det = J[0] * B[0] + J[1] * B[3] + J[2] * B[6];
    for (int q = 0; q < 3; ++q) w[q] = (B[3 * q] * L[0] + B[3 * q + 1] * L[1] + B[3 * q + 2] * L[2]) / det;
}

/* r turned by the angle |w| dt about w (Rodrigues' formula) into rn: a
 * point of a rigid body spinning at w, over dt, about its centre. */
HD_INLINE void dem_turn(const real w[3], real dt, const real r[3], real rn[3])
{
    const real wm = sqrt_r(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
    if (!(wm > 0)) {
        rn[0] = r[0], rn[1] = r[1], rn[2] = r[2];
        return;
    }
    const real k[3] = {w[0] / wm, w[1] / wm, w[2] / wm}, c = (real)cos((double)(wm * dt)), sn = (real)sin((double)(wm * dt));
    const real kr[3] = {k[1] * r[2] - k[2] * r[1], k[2] * r[0] - k[0] * r[2], k[0] * r[1] - k[1] * r[0]};
    const real kd = k[0] * r[0] + k[1] * r[1] + k[2] * r[2];
    for (int q = 0; q < 3; ++q) rn[q] = r[q] * c + kr[q] * sn + k[q] * kd * (R(1.0) - c);
}

#endif
