/* flow.h — the granular-flow bodies shared by the CPU (src/cpu/backend_cpu.c)
 * and GPU drivers, one particle per call, gather style (a particle sums over
 * its neighbours and writes only its own entries):
 *   flow_wall     dummy velocity (4.1/4.2) and stress (4.3) from the
 *                 material in its support;
 *   flow_rates    velocity gradient, strain rate and spin (3.14–3.15),
 *                 acceleration (3.9) with the stabilisation of
 *                 Flow:stabilization (Monaghan's artificial viscosity 3.10,
 *                 the low-dissipation Riemann solver, or delta-SPH pressure
 *                 diffusion: momentum.h) and gravity, shear rate, Jaumann
 *                 elastic stress rate (C1);
 *   flow_advance  x, u, sigma = start-of-step value + a * rate, then the
 *                 one-step return mapping (App. C) with mu(I) (2.14) onto
 *                 the yield surface of Material:yield;
 *   flow_shepard  the Shepard filter (3.12) into dsig (scratch).
 * Density is constant (the paper's incompressible bulk, §2.1: 2.3 is not
 * solved), so m_j = rho V_j. Stress is tension positive (stress.h). */
#ifndef SPHSEG_FLOW_H
#define SPHSEG_FLOW_H
#include <math.h>
#include "../core/particles.h"
#include "grid.h"
#include "linalg.h"
#include "momentum.h"
#include "options.h"
#include "seg.h"
#include "seg_kern.h"
#include "shift.h"
#include "sph.h"
#include "stress.h"
#include "wall.h"

/* Flow:stabilization (src/scene/scene_keys.h): what damps the acoustic noise. */

typedef struct flow_ctx {
    sph_ctx k;
    mat_params m;
    real rho;      /* bulk density, kg/m^3 */
    real cs;       /* elastic sound speed, m/s (3.10, 3.19) */
    real v_stick;  /* a Coulomb wall's sticking speed (wall_coulomb), m/s: COULOMB_STICK c_s (physics/wall.h) */
    int contact;   /* Walls:coulomb_force particles: the Coulomb walls whose friction acts on the particles
                    * (wall_prim.contact 1..contact; flow_contact_team); 0: none, the stage does not run */
    int stab;      /* Flow:stabilization: STAB_MONAGHAN (the paper's 3.10) | STAB_RIEMANN | STAB_DELTA */
    real alpha_av; /* Monaghan coefficient of (3.10), monaghan only; 0 switches it off */
    real eta_r;    /* riemann: the limiter's eta (Zhang, Hu & Adams 2017: 3) */
    real bed_alpha; /* riemann: Flow:bed_damping, Monaghan's alpha on unyielded material pairs
                     * (stress_static_q q < 1), weighted by 1 - max(q_i, q_j): full in a bed at rest
                     * far inside the static cone, none at or past yield (the flowing layer), so the
                     * rheology alone sets the flow; mom_av vanishes on a rigid rotation, so the bed's
                     * turning with the drum is not damped; 0 = off */
    real bed_k;     /* the static yield cone's slope k(mu_s) of Material:yield (stress_yield_k) */
    int filter_mls; /* Flow:stress_filter mls: the first-order filter (flow_shepard_team); 0 = Shepard (3.12) */
    int kgc;        /* Flow:gradient_correction on: B_i grad W in the velocity gradient and the stress
                     * divergence (flow_kgc_team, flow_rates_team); 0 = the paper's grad W */
    real kgc_det;   /* Flow:gradient_correction_det: below it B blends toward I (flow_kgc_store) */
    real pdiff;    /* the pressure diffusion's coefficient (mom_pdiff): riemann with
                    * Flow:riemann_diffusion on K / (rho c_s); delta 2 delta h c_s; 0 = none */
    real g[3];     /* gravity, m/s^2 */
    real damping;  /* zeta of the settling term -zeta u, 1/s (0 when off) */
    int yield;     /* the yield surface (Material:yield): YIELD_DRUCKER_PRAGER (0, the paper's
                    * k_mu cone) | YIELD_MU_I (sqrt(J2) = mu(I) p), stress.h */
    seg_params sp; /* d_avg = d^S C + d^L (1 - C) for mu(I) */
    wall_geom w;
    real nu;       /* Newtonian fluid (Material:model newtonian): kinematic viscosity eta / rho,
                    * m^2/s; 0 for the granular material. The fluid's stress is the pressure
                    * alone (m.G = 0: no shear stress, the return mapping with k_mu = 0 keeps it
                    * isotropic and cuts tension), and the viscous force is Morris et al.'s
                    * (1997) pair term (mom_visc_add) */
    real visc_norm; /* 1 / mom_visc_lattice(dim, h, dr): the viscous term's lattice moment (momentum.h) */
    real p_back;    /* Flow:background_pressure excluded (Newtonian fluid): 2 p0 / rho^2, added to the pair's
                     * Pi of (3.9), which then sees sigma + p0 I: a uniform p0 exerts no force; else 0 */
} flow_ctx;

/* The pressure diffusion's coefficient flow_ctx.pdiff (mom_pdiff) from the
 * bulk modulus K, the density rho, the sound speed cs and the kernel's h:
 * riemann with its diffusion on, K / (rho c_s), the acoustic Riemann
 * solver's continuity dissipation written for the pressure (dp = (K / rho)
 * drho); delta, 2 delta h c_s (Antuono et al. 2010); else 0 (none). */
HD_INLINE real flow_pdiff_coef(int stab, int riemann_diffusion, real delta, real K, real rho, real cs, real h)
{
    if (stab == STAB_RIEMANN) return riemann_diffusion ? K / (rho * cs) : R(0.0);
    if (stab == STAB_DELTA) return R(2.0) * delta * h * cs;
    return R(0.0);
}

/* Dummy d's velocity and stress from the sums over the material in its
 * support (ws.w = 0: none in reach, the wall's velocity and zero stress). */
HD_INLINE void flow_wall_set(size_t d, particles_t *p, const flow_ctx *c, const wall_sums *wsp)
{
    const wall_sums ws = *wsp;
    real xd[3] = {p->x[0][d], p->x[1][d], p->x[2][d]};
    /* the velocity and normal of d's wall (p->wall, set by setup) at d */
    real uw[3], n[3], ud[3], sd[6];
    wall_velocity_at(wall_of(&c->w, p->wall[d]), xd, uw);
    int free_slip = wall_normal_of(&c->w, p->wall[d], xd, n);
    if (ws.w > 0) {
        wall_velocity(&ws, uw, n, free_slip, ud);
        wall_stress(&ws, sd);
        /* (4.3) extrapolates with the hydrostatic term, which turns tensile
         * for a dummy above the material it sees (a wall that reaches past
         * a free surface); grains carry no tension: the cut-off of the
         * return mapping applies to the wall stress too */
        if (stress_pressure(sd) <= 0)
            for (int q = 0; q < 6; ++q) sd[q] = 0;
        const real mu_w = wall_of(&c->w, p->wall[d])->mu_w;
        if (mu_w > 0) wall_coulomb(&ws, uw, n, mu_w, c->v_stick, ud, sd);
    } else {
        for (int a = 0; a < 3; ++a) ud[a] = uw[a];
        for (int q = 0; q < 6; ++q) sd[q] = 0;
    }
    for (int a = 0; a < 3; ++a) p->v[a][d] = ud[a];
    for (int q = 0; q < 6; ++q) p->sig[q][d] = sd[q];
}

/* A dummy that no material particle can reach (none in its neighbour list
 * with a Verlet skin): flow_wall_team's result without the neighbour loop,
 * the same code path, so the same bits. */
HD_INLINE void flow_wall_none(size_t d, particles_t *p, const flow_ctx *c)
{
    const wall_sums ws = {0, {0, 0, 0}, {0, 0, 0, 0, 0, 0}, {0, 0, 0}};
    flow_wall_set(d, p, c, &ws);
}

/* Is dummy d's wall loop due until the list's next build: a material
 * particle in its neighbour list (within 2h + skin: none other reaches d
 * before the build), or a list row that overflowed (scanned at use)? Else
 * flow_wall_none gives its result. Each backend marks its dummies with it at
 * a list build (gpu_marks, gpu/gpu_nbr.cu; nlist_build, src/cpu/nlist.c). */
HD_INLINE int flow_wall_reached(size_t d, const particles_t *p, const grid_view *g)
{
    if (g->ncnt && g->ncnt[d] > g->nl_cap) return 1;
    int r = 0;
    NBR_BEGIN(g, p->x, d, j)
        r |= p->kind[j] == KIND_MATERIAL;
    NBR_END
    return r;
}

/* Dummy particle d: velocity and stress extrapolated from the material in
 * its support (paper §4.1). A dummy with no material in reach takes the
 * wall velocity and zero stress. Lane `lane` of a team of nlanes (hd.h);
 * lane 0 writes. */
HD_INLINE void flow_wall_team(size_t d, particles_t *p, const grid_view *g, const flow_ctx *c, int lane,
                              int nlanes)
{
    const sph_ctx *k = &c->k;
    wall_sums ws = {0, {0, 0, 0}, {0, 0, 0, 0, 0, 0}, {0, 0, 0}};
    real xd[3] = {p->x[0][d], p->x[1][d], p->x[2][d]}, aw[3], geff[3];
    wall_accel(&c->w, p->wall[d], xd, aw);
    for (int a = 0; a < 3; ++a) geff[a] = c->g[a] - aw[a];
    NBR_BEGIN_T(g, p->x, d, m, lane, nlanes)
        if (p->kind[m] != KIND_MATERIAL) continue;
        real xdm[3];
        real r2 = grid_pair(k->dim, p->x, d, m, xdm);
        if (r2 >= k->support2) continue;
        real W = kernel_w(sqrt_r(r2), k->h, k->alpha);
        real um[3] = {p->v[0][m], p->v[1][m], p->v[2][m]};
        real sm[6] = {p->sig[0][m], p->sig[1][m], p->sig[2][m], p->sig[3][m], p->sig[4][m], p->sig[5][m]};
        wall_add(&ws, W, p->vol[m], c->rho * p->vol[m], um, sm, geff, xdm);
    NBR_END
    team_sum(&ws.w, 1, nlanes);
    team_sum(ws.u, 3, nlanes);
    team_sum(ws.s, 6, nlanes);
    team_sum(ws.gr, 3, nlanes);
    if (lane == 0) flow_wall_set(d, p, c, &ws);
}

HD_INLINE void flow_wall(size_t d, particles_t *p, const grid_view *g, const flow_ctx *c)
{
    flow_wall_team(d, p, g, c, 0, 1);
}

/* Flow:gradient_correction: B_i from the summed moment m (xx, yy, zz, xy,
 * xz, yz) of M_i = sum_j V_j x_ji (x) grad_i W_ij, into p->B. The measure of
 * how far the support is cut is the product of M_i's two smallest principal
 * moments: det M_i in 2D, det M_i / lambda_max(M_i) in 3D. So a support cut
 * in the x-y plane alone (a flat free surface, a wall, anything uniform
 * along z) gets the 2D measure in 3D, the out-of-plane moment (the tangential
 * one, 0.75 under a flat surface at h = 1.5 dr) not counted; det M_i alone
 * would count it and blend a 3D surface more than the same surface in 2D
 * (w 0.47 against 0.62 in the top row; tests/test_flow.c test_kgc_plane_strain).
 * Where the measure d >= det0, B_i = M_i^-1; below it B_i = w M_i^-1 +
 * (1 - w) I, w = d / det0, which stays bounded as det M_i -> 0 (w M^-1 =
 * adj(M) / (det0 lambda_max) in 3D, adj(M) / det0 in 2D), the blend
 * SPHinXsys uses; det M_i <= 0 (no neighbours) gives I. */
HD_INLINE void flow_kgc_store(size_t i, const particles_t *p, int dim, const real m[6], real det0)
{
    real b[6] = {1, 1, 1, 0, 0, 0}, adj[6] = {0, 0, 0, 0, 0, 0}, det;
    if (dim == 2) {
        det = m[0] * m[1] - m[3] * m[3];
        adj[0] = m[1], adj[1] = m[0], adj[3] = -m[3];
    } else {
        adj[0] = m[1] * m[2] - m[5] * m[5], adj[1] = m[0] * m[2] - m[4] * m[4], adj[2] = m[0] * m[1] - m[3] * m[3];
        adj[3] = m[4] * m[5] - m[3] * m[2], adj[4] = m[3] * m[5] - m[4] * m[1], adj[5] = m[3] * m[4] - m[0] * m[5];
        det = m[0] * adj[0] + m[3] * adj[3] + m[4] * adj[4];
    }
    if (det > 0) {
        /* d, the product of the two smallest moments, is at least det0 (w = 1) where
         * det >= det0 tr M in 3D (lambda_max <= tr M): the eigenvalue (a cos and an
         * acos) is taken only where the support may be cut */
        real w = R(1.0), a = R(1.0) / det; /* w M^-1 = (w / det) adj */
        if (dim == 2 ? det < det0 : det < det0 * (m[0] + m[1] + m[2])) {
            const real lmax = dim == 2 ? R(1.0) : linalg_sym_eig_max(m), d = det / lmax;
            if (d < det0) w = d / det0, a = R(1.0) / (det0 * lmax);
        }
        for (int q = 0; q < 6; ++q) b[q] = a * adj[q] + (R(1.0) - w) * (q < dim ? R(1.0) : R(0.0));
        if (dim == 2) b[2] = 1, b[4] = b[5] = 0;
    }
    for (int q = 0; q < 6; ++q) p->B[q][i] = b[q];
}

/* Flow:gradient_correction: B_i of material particle i (flow_kgc_store) over
 * the neighbours the flow rates sum, material and dummy; grad W = f x_ij, so
 * M_i = -sum_j V_j f_ij x_ij (x) x_ij, seg_moment_team's moment over every
 * neighbour (seg_renorm_team sums the material only; = I in the bulk of a
 * regular lattice, tests/test_kernel.c; tests/test_flow.c test_kgc_*). Lane
 * `lane` of a team of nlanes (hd.h); lane 0 writes. */
HD_INLINE void flow_kgc_team(size_t i, const particles_t *p, const grid_view *g, const flow_ctx *c, int lane,
                             int nlanes)
{
    real m[6] = {0, 0, 0, 0, 0, 0};
    seg_moment_team(i, p, g, &c->k, 0, lane, nlanes, m);
    if (lane != 0) return;
    flow_kgc_store(i, p, c->k.dim, m, c->kgc_det);
}

/* The bed damping's weight of particle i (Flow:bed_damping): stress_static_q
 * of its stress, 1 where there is none (off, or a dummy). flow_rates_body
 * reads it per pair from an array the backend made with this before the
 * pass (the CPU; the GPU's list forms, gpu_bed_q), or computes it per pair
 * (the GPU's staged pass, whose neighbours are tile slots): the same bits. */
HD_INLINE real flow_bed_q(size_t i, const particles_t *p, const flow_ctx *c)
{
    if (!(c->bed_alpha > 0) || p->kind[i] != KIND_MATERIAL) return R(1.0);
    const real s[6] = {p->sig[0][i], p->sig[1][i], p->sig[2][i], p->sig[3][i], p->sig[4][i], p->sig[5][i]};
    return stress_static_q(s, c->bed_k);
}

/* What flow_rates reads of neighbour j besides its position. */
HD_INLINE void flow_load_j(const particles_t *p, size_t j, real uj[3], real sj[6], real *volj)
{
    for (int d = 0; d < 3; ++d) uj[d] = p->v[d][j];
    for (int q = 0; q < 6; ++q) sj[q] = p->sig[q][j];
    *volj = p->vol[j];
}

/* flow_rates_body's spec: FLOW_SPEC_ANY reads every switch of the flow_ctx
 * at run time; FLOW_SPEC_RIEMANN stands for the granular flow under riemann
 * without pressure diffusion or background pressure (the drum scenes' flow,
 * Run:preset converged and fast), whose switches the GPU's flow pass then
 * knows at compile time (a template constant, gpu_pairs.cu): the other
 * stabilisations' and the fluid's branches leave its code, the same
 * arithmetic in the same order. flow_spec_of says which a run may take: a
 * new run-time switch of the pair loop is read at the top of flow_rates_body,
 * fixed there under FLOW_SPEC_RIEMANN only where flow_spec_of checks it
 * (tests/test_flow.c test_flow_spec, test_bed_q_array). */
enum { FLOW_SPEC_ANY = 0, FLOW_SPEC_RIEMANN = 1 };

HD_INLINE int flow_spec_of(const flow_ctx *c)
{
    const int riemann = c->stab == STAB_RIEMANN && !(c->pdiff > 0) && c->p_back == 0 && !(c->nu > 0);
    return riemann ? FLOW_SPEC_RIEMANN : FLOW_SPEC_ANY;
}

/* Material particle i: acc (3.9 + g), dsig (C1) and gdot from the current
 * positions, velocities and stresses of i and its neighbours (material and
 * dummy). Returns |acc|. Lane `lane` of a team of nlanes (hd.h): lane 0
 * writes and returns |acc|, the others return 0. With renorm set, also the
 * conservative scheme's L_i (seg_renorm_team: the same pairs, the same sums
 * in the same order), which then costs no neighbour pass of its own. With
 * kgc set (Flow:gradient_correction; p->B made by flow_kgc_team for i and its
 * material neighbours), the velocity gradient is L B_i and the stress
 * divergence its work conjugate, m_j (sigma_i B_i + sigma_j B_j) grad W / rho^2,
 * a dummy j taking B_i; the GPU passes kgc as a template constant. With sh
 * given (not NULL), the shift of a step of length sdt comes with it
 * (shift_team's sums over the same pairs, shift_finish, which takes L, before
 * the correction, as its velocity gradient): Run:integrator
 * leapfrog's midpoint pass (src/sim/integrate.c), fused. Neighbour j's
 * fields are read through NBR_BEGIN_TJ's jp at jj (the GPU's staged pass:
 * a tile of shared memory). bq: flow_bed_q of every particle, store and
 * ghosts, indexed as the store (so not with a tile), or NULL: the bed
 * damping's weight computed per pair. spec: FLOW_SPEC_ANY, or
 * FLOW_SPEC_RIEMANN where flow_spec_of(c) gives it (a compile-time constant
 * on the GPU). */
HD_INLINE real flow_rates_body(size_t i, particles_t *p, const grid_view *g, const flow_ctx *c, int lane,
                               int nlanes, int renorm, int kgc, const shift_ctx *sh, real sdt, const real *bq,
                               int spec)
{
    const sph_ctx *k = &c->k;
    /* the switches, constants where spec says (flow_spec_of) */
    const int stab = spec == FLOW_SPEC_RIEMANN ? STAB_RIEMANN : c->stab;
    const real pdiff = spec == FLOW_SPEC_RIEMANN ? R(0.0) : c->pdiff;
    const real p_back = spec == FLOW_SPEC_RIEMANN ? R(0.0) : c->p_back;
    const real nu = spec == FLOW_SPEC_RIEMANN ? R(0.0) : c->nu;
    real L[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0}, a[3] = {0, 0, 0}, m[6] = {0, 0, 0, 0, 0, 0};
    real si[6] = {p->sig[0][i], p->sig[1][i], p->sig[2][i], p->sig[3][i], p->sig[4][i], p->sig[5][i]};
    /* i's own values read once (the compiler cannot hoist them out of the
     * loop through the particles_t pointers); j's before or after the
     * distance test by SPH_EARLY_LOADS (hd.h) */
    const real xi[3] = {p->x[0][i], p->x[1][i], p->x[2][i]}, ui[3] = {p->v[0][i], p->v[1][i], p->v[2][i]};
    const real pi = stress_pressure(si);
    const real qi = c->bed_alpha > 0 ? stress_static_q(si, c->bed_k) : R(1.0);
    real pd = R(0.0); /* the pressure diffusion, Pa/s (riemann, delta) */
    real Bi[6] = {1, 1, 1, 0, 0, 0}; /* Flow:gradient_correction (kgc: the caller's c->kgc) */
    if (kgc)
        for (int q = 0; q < 6; ++q) Bi[q] = p->B[q][i];
    /* mom_av's factors, made once (mom_av_coef) */
    const real av_coef = mom_av_coef(c->alpha_av, c->cs, k->h, c->rho, c->rho);
    const real bed_coef = mom_av_coef(c->bed_alpha, c->cs, k->h, c->rho, c->rho);
    shift_sums ss;
    if (sh) shift_sums_zero(&ss);
    NBR_BEGIN_TJ(g, p, i, j, jj, jp, lane, nlanes)
        if (j == i) continue;
        real uj[3], sj[6], volj = 0;
        if (SPH_EARLY_LOADS) flow_load_j(jp, jj, uj, sj, &volj);
        real xij[3];
        real r2 = grid_pair_xi(k->dim, xi, jp->x, jj, xij);
        if (r2 >= k->support2) continue;
        if (!SPH_EARLY_LOADS) flow_load_j(jp, jj, uj, sj, &volj);
        const real r = sqrt_r(r2);
        const int jmat = jp->kind[jj] == KIND_MATERIAL; /* read once: four uses below */
        real f = kernel_f(r, k->h, k->alpha);
        if (sh) shift_pair_add(&ss, sh, r, r2, f, volj, xij, sj, si);
        if (renorm && jmat) seg_renorm_add(m, k->dim, -f * volj, xij);
        real gradW[3] = {f * xij[0], f * xij[1], f * xij[2]};
        real uij[3] = {ui[0] - uj[0], ui[1] - uj[1], ui[2] - uj[2]};
        mom_velgrad_add(L, volj, uij, gradW);
        real Pi = R(0.0);
        if (stab == STAB_MONAGHAN) {
            if (c->alpha_av > 0) Pi = mom_av_k(av_coef, k->h, uij, xij);
        } else {
            if (stab == STAB_RIEMANN)
                Pi = mom_riemann(c->eta_r, c->cs, c->rho, uij, xij, r2, !jmat);
            if (c->bed_alpha > 0 && qi < R(1.0) && jmat) {
                const real qj = bq ? bq[jj] : stress_static_q(sj, c->bed_k), w = R(1.0) - (qi > qj ? qi : qj);
                if (w > 0) Pi += w * mom_av_k(bed_coef, k->h, uij, xij);
            }
            /* the pressure difference less its hydrostatic part rho g.x_ji (Fourtakas et al.
             * 2019): a free surface, where the support is cut, is not driven by rho g */
            if (pdiff > 0) {
                const real dpH = c->rho * (c->g[0] * xij[0] + c->g[1] * xij[1] + c->g[2] * xij[2]);
                pd += mom_pdiff(stress_pressure(sj) - pi + dpH, volj, f, r2, k->eta2, stab == STAB_RIEMANN);
            }
        }
        if (p_back != 0) Pi += p_back;
        if (kgc) { /* V_j (sigma_i B_i + sigma_j B_j) grad W / rho, the dissipation on grad W */
            real Bj[6], gi[3], gj[3];
            for (int q = 0; q < 6; ++q) Bj[q] = jmat ? jp->B[q][jj] : Bi[q];
            linalg_sym_apply(Bi, gradW, gi);
            linalg_sym_apply(Bj, gradW, gj);
            mom_accel_add_kgc(a, c->rho * volj, si, sj, c->rho, Pi, gradW, gi, gj);
        } else {
            mom_accel_add(a, c->rho * volj, si, c->rho, sj, c->rho, Pi, gradW);
        }
        if (nu > 0) mom_visc_add(a, volj, nu * c->visc_norm, f, uij);
    NBR_END
    team_sum(L, 9, nlanes);
    team_sum(a, 3, nlanes);
    if (pdiff > 0) team_sum(&pd, 1, nlanes);
    if (renorm) team_sum(m, 6, nlanes);
    if (sh) shift_finish(i, p, sh, sdt, &ss, L, ui, lane, nlanes); /* L: the shift's velocity gradient */
    if (lane != 0) return R(0.0);
    if (renorm) seg_renorm_store(i, p, k->dim, m);
    real eps[6], w[3], ds[6];
    if (kgc) { /* L B_i: (u_ij (x) grad W) B_i = u_ij (x) B_i grad W, B_i symmetric */
        real LB[9];
        for (int a2 = 0; a2 < 3; ++a2) linalg_sym_apply(Bi, &L[3 * a2], &LB[3 * a2]);
        for (int q = 0; q < 9; ++q) L[q] = LB[q];
    }
    mom_strain_spin(L, eps, w);
    stress_rate_elastic(si, eps, w, c->m.G, c->m.K, ds);
    if (pdiff > 0) {
        const real dp = pdiff * pd; /* dp_i/dt += dp: sigma_kk -= dp */
        ds[0] -= dp, ds[1] -= dp, ds[2] -= dp;
    }
    for (int q = 0; q < 6; ++q) p->dsig[q][i] = ds[q];
    for (int d = 0; d < 3; ++d) p->acc[d][i] = a[d] + c->g[d] - c->damping * p->v[d][i];
    p->gdot[i] = stress_shear_rate(eps);
    real a2 = p->acc[0][i] * p->acc[0][i] + p->acc[1][i] * p->acc[1][i] + p->acc[2][i] * p->acc[2][i];
    return sqrt_r(a2);
}

HD_INLINE real flow_rates_team(size_t i, particles_t *p, const grid_view *g, const flow_ctx *c, int lane,
                               int nlanes, int renorm, int kgc)
{
    return flow_rates_body(i, p, g, c, lane, nlanes, renorm, kgc, (const shift_ctx *)0, R(0.0), (const real *)0,
                           FLOW_SPEC_ANY);
}

HD_INLINE real flow_rates(size_t i, particles_t *p, const grid_view *g, const flow_ctx *c)
{
    return flow_rates_team(i, p, g, c, 0, 1, 0, c->kgc);
}

/* Walls:coulomb_force particles: the friction of the Coulomb walls acts on
 * each material particle i, after its flow rates (acc) are made. A layer at
 * the tension cut-off (sigma = 0: a sheet a grain or two thick ahead of a
 * collapse's deposit) meets a dummy wall only through the stabilisation's
 * pair term, whose normal part carries its weight and whose tangential part
 * is a viscous drag, not Coulomb's; the dummy's own friction (wall_coulomb),
 * mu_w times the dummy's normal stress, is then none (docs/validation.md,
 * "Column collapse"). So here the force per unit mass that the dummies of
 * each contact wall exert on i, a_w = flow_rates_body's pair terms over them
 * (stress, stabilisation, the fluid's viscosity; a dummy's B is B_i), is split
 * along the wall's normal n at x_i (into the material) into N = a_w.n and the
 * tangential T. Where N > 0 (the wall pushes), T is replaced by Coulomb's
 * friction on the slip s = (u_i - u_w) tangential to the wall: with
 * s* = s + dt (acc_t - T), the slip at the step's end without the wall's
 * tangential force, the particle sticks (acc_t = -s / dt) while |s*| <=
 * mu_w N dt, else slides with acc_t - T - mu_w N s* / |s*|: the frictional
 * contact of Bardenhagen et al. (2000, MPM) at one particle, its normal load
 * whatever the discretisation carries it by. The walls are taken one after
 * another in their slot order. Where the wall pulls (N <= 0) nothing
 * changes, and so with dt = 0. The time-step bound keeps the flow rates'
 * |acc|. Lane `lane` of a
 * team of nlanes (hd.h); lane 0 writes. */
HD_INLINE void flow_contact_team(size_t i, particles_t *p, const grid_view *g, const flow_ctx *c, real dt, int lane,
                                 int nlanes)
{
    if (!(dt > 0)) return; /* no step to stop a slip in (and -s / dt undefined): acc as the flow rates made it */
    const sph_ctx *k = &c->k;
    real aw[3 * WALL_CONTACT_MAX];
    for (int q = 0; q < 3 * WALL_CONTACT_MAX; ++q) aw[q] = 0;
    const real si[6] = {p->sig[0][i], p->sig[1][i], p->sig[2][i], p->sig[3][i], p->sig[4][i], p->sig[5][i]};
    const real xi[3] = {p->x[0][i], p->x[1][i], p->x[2][i]}, ui[3] = {p->v[0][i], p->v[1][i], p->v[2][i]};
    real Bi[6] = {1, 1, 1, 0, 0, 0};
    if (c->kgc)
        for (int q = 0; q < 6; ++q) Bi[q] = p->B[q][i];
    const real av_coef = mom_av_coef(c->alpha_av, c->cs, k->h, c->rho, c->rho);
    NBR_BEGIN_T(g, p->x, i, j, lane, nlanes)
        if (p->kind[j] != KIND_DUMMY) continue;
        const int slot = wall_of(&c->w, p->wall[j])->contact;
        if (!slot) continue;
        real xij[3];
        const real r2 = grid_pair_xi(k->dim, xi, p->x, j, xij);
        if (r2 >= k->support2) continue;
        real uj[3], sj[6], volj;
        flow_load_j(p, j, uj, sj, &volj);
        const real f = kernel_f(sqrt_r(r2), k->h, k->alpha);
        const real gradW[3] = {f * xij[0], f * xij[1], f * xij[2]};
        const real uij[3] = {ui[0] - uj[0], ui[1] - uj[1], ui[2] - uj[2]};
        /* flow_rates_body's terms for a dummy neighbour (no bed damping: material pairs only) */
        real Pi = c->p_back;
        if (c->stab == STAB_MONAGHAN) {
            if (c->alpha_av > 0) Pi += mom_av_k(av_coef, k->h, uij, xij);
        } else if (c->stab == STAB_RIEMANN) {
            Pi += mom_riemann(c->eta_r, c->cs, c->rho, uij, xij, r2, 1);
        }
        real a[3] = {0, 0, 0};
        if (c->kgc) {
            real gi[3];
            linalg_sym_apply(Bi, gradW, gi);
            mom_accel_add_kgc(a, c->rho * volj, si, sj, c->rho, Pi, gradW, gi, gi);
        } else {
            mom_accel_add(a, c->rho * volj, si, c->rho, sj, c->rho, Pi, gradW);
        }
        if (c->nu > 0) mom_visc_add(a, volj, c->nu * c->visc_norm, f, uij);
        for (int w = 0; w < WALL_CONTACT_MAX; ++w) /* a fixed trip count: aw stays in registers */
            if (w == slot - 1)
                for (int d = 0; d < 3; ++d) aw[3 * w + d] += a[d];
    NBR_END
    team_sum(aw, 3 * WALL_CONTACT_MAX, nlanes);
    if (lane != 0) return;
    real acc[3] = {p->acc[0][i], p->acc[1][i], p->acc[2][i]};
    for (int q = 0; q < c->w.n; ++q) {
        const wall_prim *wp = &c->w.prim[q];
        if (!wp->contact) continue;
        real A[3] = {0, 0, 0}; /* its sums, picked by a fixed trip count (aw stays in registers) */
        for (int w = 0; w < WALL_CONTACT_MAX; ++w)
            if (w == wp->contact - 1)
                for (int d = 0; d < 3; ++d) A[d] = aw[3 * w + d];
        real n[3], uw[3];
        wall_prim_normal(wp, xi, n);
        wall_velocity_at(wp, xi, uw);
        const real N = A[0] * n[0] + A[1] * n[1] + A[2] * n[2];
        if (!(N > 0)) continue;
        real an = 0, sn = 0, s[3], at[3], T[3], ss = 0;
        for (int d = 0; d < 3; ++d) an += acc[d] * n[d], sn += (ui[d] - uw[d]) * n[d];
        for (int d = 0; d < 3; ++d) {
            s[d] = ui[d] - uw[d] - sn * n[d]; /* the slip */
            T[d] = A[d] - N * n[d];           /* the wall's tangential force */
            at[d] = acc[d] - an * n[d] - T[d]; /* the tangential acc without it */
        }
        real st[3];
        for (int d = 0; d < 3; ++d) st[d] = s[d] + dt * at[d], ss += st[d] * st[d];
        const real sm = sqrt_r(ss), cap = wp->mu_w * N;
        for (int d = 0; d < 3; ++d) {
            const real tn = sm <= cap * dt ? -s[d] / dt : at[d] - cap * st[d] / sm; /* sticks, or slides */
            acc[d] = an * n[d] + tn;
        }
    }
    for (int d = 0; d < 3; ++d) p->acc[d][i] = acc[d];
}

/* Material particle i, a in seconds: x = x_n + a u (in double, x + xr in
 * the single build: hd.h), u = u_n + a acc,
 * sigma = return_map(sigma_n + a dsig) onto the cone of Material:yield
 * (stress_yield_k: k_mu(mu) or mu) with mu(I) at the current shear rate, the
 * trial pressure and d_avg(C). The position uses the
 * velocity of the rate evaluation (read before u is overwritten). Returns
 * the return-mapping case (stress_return_map). */
HD_INLINE int flow_advance(size_t i, particles_t *p, real a, const flow_ctx *c)
{
    for (int d = 0; d < 3; ++d) { /* a fixed trip count: unrolled, the arrays indexed statically */
        if (d >= c->k.dim) break;
        const preal xd = p->x_n[d][i] + (preal)a * (preal)p->v[d][i]; /* in double: hd.h */
        p->x[d][i] = (real)xd;
        if (POS_REMAINDER) p->xr[d][i] = (real)(xd - (preal)p->x[d][i]);
        p->v[d][i] = p->v_n[d][i] + a * p->acc[d][i];
    }
    real s[6];
    for (int q = 0; q < 6; ++q) s[q] = p->sig_n[q][i] + a * p->dsig[q][i];
    real k = R(0.0); /* the Newtonian fluid: pressure only */
    if (!(c->nu > 0))
        k = stress_yield_k(c->yield, stress_mu(&c->m, p->gdot[i], stress_pressure(s), seg_davg(&c->sp, p->C[i])));
    int r = stress_return_map(s, k);
    for (int q = 0; q < 6; ++q) p->sig[q][i] = s[q];
    return r;
}

/* After flow_shepard over all particles: the filtered stress back into sig. */
HD_INLINE void flow_shepard_store(size_t i, const particles_t *p)
{
    if (p->kind[i] == KIND_MATERIAL)
        for (int q = 0; q < 6; ++q) p->sig[q][i] = p->dsig[q][i];
}

/* Flow:stress_filter mls: the first-order (moving-least-squares) form of the
 * filter (Colagrossi & Landrini 2003, their MLS density filter; Dilts 1999).
 * With xi = x_ji / h and P = (1, xi), the weights W_ij P_j^T b, A b = e_0,
 * A = sum_j W_ij P_j P_j^T, reproduce any linear field exactly: sum_j W P^T b
 * = 1 and sum_j W xi P^T b = 0. So sigma_i = b_0 sum W sigma_j + sum_a b_a
 * sum W xi_a sigma_j. In the bulk of a symmetric support b = (1/sum W, 0) and
 * this is (3.12); where the support is cut (a free surface, a wall) (3.12)
 * takes the deeper neighbours' stress (the top row of a layer about rho g h
 * too much), this does not. mo: sum W xi_a (a < 3), then sum W xi_a xi_b (xx,
 * yy, zz, xy, xz, yz); s1[6 a + q]: sum W xi_a sigma_j[q]. */
HD_INLINE void flow_mls_add(real mo[9], real s1[18], real W, const real xij[3], real inv_h, const real sj[6])
{
    const real xi[3] = {-xij[0] * inv_h, -xij[1] * inv_h, -xij[2] * inv_h};
    for (int a = 0; a < 3; ++a) {
        mo[a] += W * xi[a];
        for (int q = 0; q < 6; ++q) s1[6 * a + q] += W * xi[a] * sj[q];
    }
    mo[3] += W * xi[0] * xi[0], mo[4] += W * xi[1] * xi[1], mo[5] += W * xi[2] * xi[2];
    mo[6] += W * xi[0] * xi[1], mo[7] += W * xi[0] * xi[2], mo[8] += W * xi[1] * xi[2];
}

/* The filtered stress out[] from the sums of flow_shepard_team and
 * flow_mls_add (dim + 1 unknowns). Returns 1 where A is singular (too few
 * neighbours to fit a plane): the caller keeps (3.12). */
HD_INLINE int flow_mls_solve(int dim, real wsum, const real mo[9], const real acc[6], const real s1[18], real out[6])
{
    const int n = dim + 1;
    const int diag[3] = {3, 4, 5}, off[3][3] = {{3, 6, 7}, {6, 4, 8}, {7, 8, 5}};
    real A[16], b[4] = {1, 0, 0, 0};
    A[0] = wsum;
    for (int a = 0; a < dim; ++a) {
        A[a + 1] = A[(a + 1) * n] = mo[a];
        for (int e = 0; e < dim; ++e) A[(a + 1) * n + e + 1] = mo[a == e ? diag[a] : off[a][e]];
    }
    if (linalg_solve(n, A, b, 1, R(1e-6))) return 1;
    for (int q = 0; q < 6; ++q) {
        real s = b[0] * acc[q];
        for (int a = 0; a < dim; ++a) s += b[a + 1] * s1[6 * a + q];
        out[q] = s;
    }
    return 0;
}

/* Shepard filter (3.12) for material particle i, over its material
 * neighbours (self included), into dsig[] (the caller copies it back); with
 * Flow:stress_filter mls its first-order form (flow_mls_add). Lane `lane` of
 * a team of nlanes (hd.h); lane 0 writes. */
HD_INLINE void flow_shepard_team(size_t i, particles_t *p, const grid_view *g, const flow_ctx *c, int lane,
                                 int nlanes)
{
    const sph_ctx *k = &c->k;
    real acc[6] = {0, 0, 0, 0, 0, 0}, wsum = 0;
    real mo[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0}, s1[18] = {0};
    const int mls = c->filter_mls;
    const real inv_h = R(1.0) / k->h;
    NBR_BEGIN_T(g, p->x, i, j, lane, nlanes)
        if (p->kind[j] != KIND_MATERIAL) continue;
        real xij[3];
        real r2 = grid_pair(k->dim, p->x, i, j, xij);
        if (r2 >= k->support2) continue;
        real sj[6] = {p->sig[0][j], p->sig[1][j], p->sig[2][j], p->sig[3][j], p->sig[4][j], p->sig[5][j]};
        const real W = kernel_w(sqrt_r(r2), k->h, k->alpha);
        shepard_add(acc, &wsum, W, sj);
        if (mls) flow_mls_add(mo, s1, W, xij, inv_h, sj);
    NBR_END
    team_sum(acc, 6, nlanes);
    team_sum(&wsum, 1, nlanes);
    if (mls) {
        team_sum(mo, 9, nlanes);
        team_sum(s1, 18, nlanes);
    }
    if (lane != 0) return;
    real out[6];
    if (mls && !flow_mls_solve(k->dim, wsum, mo, acc, s1, out)) {
        for (int q = 0; q < 6; ++q) p->dsig[q][i] = out[q];
        return;
    }
    for (int q = 0; q < 6; ++q) p->dsig[q][i] = acc[q] / wsum; /* wsum >= W(0) > 0 */
}

HD_INLINE void flow_shepard(size_t i, particles_t *p, const grid_view *g, const flow_ctx *c)
{
    flow_shepard_team(i, p, g, c, 0, 1);
}

#endif
