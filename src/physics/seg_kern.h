/* seg_kern.h — the concentration rate dC_i/dt of one material particle, the
 * neighbour-loop body shared by the CPU (src/cpu/backend_cpu.c) and GPU drivers.
 * Gravity-aligned derivative: grad_g X = ghat . grad X (eq. E15). */
#ifndef SPHSEG_SEG_KERN_H
#define SPHSEG_SEG_KERN_H
#include <math.h>
#include "../core/particles.h"
#include "grid.h"
#include "linalg.h"
#include "options.h"
#include "seg.h"
#include "sph.h"
#include "stress.h"

typedef struct seg_ctx {
    sph_ctx k;
    seg_params sp;
    int scheme; /* enum seg_scheme (options.h) */
    int renorm; /* conservative scheme: symmetric renormalisation on/off */
    int limiter; /* conservative scheme: enum seg_limiter (options.h) */
} seg_ctx;

/* The context for seg_coeffs at a window's mean shear rate (gated as summed). */
HD_INLINE seg_ctx seg_ctx_mean(seg_ctx c)
{
    c.sp.gdot_yielded = 0;
    return c;
}

/* The three contributions to dC/dt, 1/s: segregation, diffusion, CSR source. */
typedef struct seg_rate {
    creal seg, diff, src;
} seg_rate;

/* Accumulators of the C1-consistent gradient system (App. E, E9–E14) for two
 * fields at once; unknowns ordered (X, dX/dx, dX/dy[, dX/dz]). */
typedef struct seg_c1 {
    real M[16]; /* (d+1) x (d+1) */
    real B[8];  /* (d+1) x 2 */
} seg_c1;

HD_INLINE void seg_c1_add(seg_c1 *s, int dim, real w, const real grad[3], const real xij[3],
                          real X0, real X1)
{
    int n = dim + 1;
    s->M[0] += w; /* C11 (E11) */
    s->B[0] += X0 * w;
    s->B[1] += X1 * w; /* B1 (E9) */
    for (int a = 0; a < dim; ++a) {
        s->M[a + 1] -= xij[a] * w;          /* C12 (E12) */
        s->M[(a + 1) * n] += grad[a];       /* C21 (E13) */
        for (int b = 0; b < dim; ++b) s->M[(a + 1) * n + b + 1] -= grad[a] * xij[b]; /* C22 (E14) */
        s->B[2 * (a + 1)] += X0 * grad[a];  /* B2 (E10) */
        s->B[2 * (a + 1) + 1] += X1 * grad[a];
    }
}

/* Solve (E2) and return ghat . grad X for both fields; 1 if singular. */
HD_INLINE int seg_c1_solve(seg_c1 *s, int dim, const real ghat[3], real out[2])
{
    if (linalg_solve(dim + 1, s->M, s->B, 2, R(1e-10))) return 1;
    for (int f = 0; f < 2; ++f) {
        out[f] = 0;
        for (int a = 0; a < dim; ++a) out[f] += ghat[a] * s->B[2 * (a + 1) + f];
    }
    return 0;
}

/* The shear rate gd of material particle i as eq. (2.7) takes it
 * (Segregation:shear_rate): gd itself (total), or gd where i's stress is on
 * or past the static yield cone and 0 strictly inside it (yielded: the bed,
 * which turns with the drum and deforms elastically, does not segregate;
 * docs/seg_refine.md measures the shear rate that SPH reads there). */
HD_INLINE real seg_drive_gdot(const seg_params *sp, const particles_t *p, size_t i, real gd)
{
    if (!sp->gdot_yielded) return gd;
    real s[6];
    for (int q = 0; q < 6; ++q) s[q] = p->sig[q][i];
    return stress_static_q(s, sp->k_static) >= R(1.0) ? gd : R(0.0);
}

/* Per-particle coefficients V, Q = V F and D, computed once per rate
 * evaluation so that pair loops only read them. With concentration windows
 * the caller's gdot is the window's mean, gated step by step as it was
 * summed (step_advance): the caller clears sp.gdot_yielded (seg_ctx_mean). */
HD_INLINE void seg_coeffs(size_t i, const particles_t *p, const seg_ctx *c)
{
    real C = p->C[i], gd = seg_drive_gdot(&c->sp, p, i, p->gdot[i]);
    p->segV[i] = seg_V(&c->sp, C, gd);
    p->segQ[i] = p->segV[i] * seg_F(&c->sp, C);
    p->segD[i] = seg_D(&c->sp, C, gd);
}

/* Fields whose gravity derivative the scheme needs: paper form (2.10) uses
 * C and V; the direct form (2.5) uses Q = V F (second slot unused). */
HD_INLINE void seg_fields(const seg_ctx *c, const particles_t *p, size_t j, real X[2])
{
    X[0] = c->scheme == 1 ? p->segQ[j] : p->C[j];
    X[1] = c->scheme == 1 ? R(0.0) : p->segV[j];
}

/* dC_i/dt by eq. (2.10) [scheme 0] or (2.5) [scheme 1] with the HCSR
 * treatment: standard difference gradients inside (3.13), C1 gradients at
 * boundary particles (App. E), diffusion with psi~ (4.13), CCSR source (4.9)
 * at walls, MCSR source (4.16) at the free surface. */
HD_INLINE seg_rate seg_rate_hcsr(size_t i, const particles_t *p, const grid_view *g, const seg_ctx *c,
                                 int lane, int nlanes)
{
    const sph_ctx *k = &c->k;
    const seg_params *sp = &c->sp;
    int cls = p->bclass[i];
    int bnd = cls != BC_INTERIOR;
    int ccsr = cls == BC_WALL_SURFACE || cls == BC_WALL_VICINITY;
    int mcsr = cls == BC_FREE_SURFACE || cls == BC_FREE_VICINITY;
    real Ci = p->C[i], Di = p->segD[i], Xi[2];
    seg_fields(c, p, i, Xi);
    real ni[3] = {p->nrm[0][i], p->nrm[1][i], p->nrm[2][i]};
    real gx[2] = {0, 0}, diff = 0, qs = 0;
    seg_c1 s1 = {{0}, {0}};
    NBR_BEGIN_T(g, p->x, i, j, lane, nlanes)
        real xij[3];
        real r2 = grid_pair(k->dim, p->x, i, j, xij);
        if (r2 >= k->support2) continue;
        real r = sqrt_r(r2);
        real f = kernel_f(r, k->h, k->alpha) * p->vol[j];
        real grad[3] = {f * xij[0], f * xij[1], f * xij[2]};
        if (p->kind[j] == KIND_DUMMY) {
            if (ccsr) { /* (4.9), f taken with the dummy's normal (see below) */
                real nj[3] = {p->nrm[0][j], p->nrm[1][j], p->nrm[2][j]};
                real s2 = (ni[0] + nj[0]) * grad[0] + (ni[1] + nj[1]) * grad[1] + (ni[2] + nj[2]) * grad[2];
                qs += seg_wall_flux(sp, Ci, p->gdot[i], nj) * s2;
            }
            else if (mcsr) /* (4.16), dummies fill the wall side */
                qs += ni[0] * grad[0] + ni[1] * grad[1] + ni[2] * grad[2];
            continue;
        }
        real Cj = p->C[j], Xj[2];
        seg_fields(c, p, j, Xj);
        if (bnd) seg_c1_add(&s1, k->dim, kernel_w(r, k->h, k->alpha) * p->vol[j], grad, xij, Xj[0], Xj[1]);
        if (j == i) continue;
        real gg = grad[0] * sp->ghat[0] + grad[1] * sp->ghat[1] + grad[2] * sp->ghat[2];
        gx[0] += (Xj[0] - Xi[0]) * gg;
        gx[1] += (Xj[1] - Xi[1]) * gg;
        diff += (p->psi[i] * Di + p->psi[j] * p->segD[j]) * (Ci - Cj) * f * r2 / (r2 + k->eta2);
        if (mcsr) qs += ni[0] * grad[0] + ni[1] * grad[1] + ni[2] * grad[2];
    NBR_END
    team_sum(gx, 2, nlanes);
    team_sum(&diff, 1, nlanes);
    team_sum(&qs, 1, nlanes);
    if (bnd) {
        team_sum(s1.M, 16, nlanes);
        team_sum(s1.B, 8, nlanes);
        real gc[2];
        if (!seg_c1_solve(&s1, k->dim, sp->ghat, gc)) gx[0] = gc[0], gx[1] = gc[1];
    }
    seg_rate out;
    if (c->scheme == 1)
        out.seg = -gx[0];
    else
        out.seg = -(Xi[1] * seg_dFdC(sp, Ci) * gx[0] + seg_F(sp, Ci) * gx[1]);
    out.diff = diff;
    /* CCSR: q_i = -sum_{j in Omega_s} f(C_i; n_j) (n_i + n_j).grad_i W_ij V_j. On
     * a flat wall n_j = n_i and this is (4.9); at a corner each wall adds the
     * flux through itself (none through a vertical wall), where f(C_i; n_i)
     * with the corner's diagonal n_i would inject flux through both. */
    real fc = seg_wall_flux(sp, Ci, p->gdot[i], ni);
    out.src = ccsr ? -qs : (mcsr ? R(2.0) * fc * qs : R(0.0));
    return out;
}

/* One pair's share of the renormalisation moment M_i (seg_renorm_team
 * below): w = -V_j w_ij. */
HD_INLINE void seg_renorm_add(real m[6], int dim, real w, const real xij[3])
{
    m[0] += w * xij[0] * xij[0];
    m[1] += w * xij[1] * xij[1];
    m[3] += w * xij[0] * xij[1];
    if (dim == 3) {
        m[2] += w * xij[2] * xij[2];
        m[4] += w * xij[0] * xij[2];
        m[5] += w * xij[1] * xij[2];
    }
}

/* The moment M_i = -sum_j V_j w_ij x_ij (x) x_ij (seg_renorm_add) of i over
 * its neighbours in support, the material only (material_only: the
 * conservative scheme's renormalisation, seg_renorm_team) or every one,
 * dummies too (the corrected kernel gradient, flow.h flow_kgc_team), added
 * to m (xx, yy, zz, xy, xz, yz; the caller zeroes it), summed over the team
 * of nlanes (hd.h). */
HD_INLINE void seg_moment_team(size_t i, const particles_t *p, const grid_view *g, const sph_ctx *k,
                               int material_only, int lane, int nlanes, real m[6])
{
    NBR_BEGIN_T(g, p->x, i, j, lane, nlanes)
        if (j == i || (material_only && p->kind[j] != KIND_MATERIAL)) continue;
        real xij[3];
        real r2 = grid_pair(k->dim, p->x, i, j, xij);
        if (r2 >= k->support2) continue;
        real w = -kernel_f(sqrt_r(r2), k->h, k->alpha) * p->vol[j];
        seg_renorm_add(m, k->dim, w, xij);
    NBR_END
    team_sum(m, 6, nlanes);
}

/* L_i = M_i^-1 (or I) from the summed moment m, into p->L. */
HD_INLINE void seg_renorm_store(size_t i, const particles_t *p, int dim, const real m[6])
{
    real l[6] = {1, 1, 1, 0, 0, 0};
    if (dim == 2) {
        real det = m[0] * m[1] - m[3] * m[3];
        if (det > R(1e-6) * (m[0] * m[0] + m[1] * m[1])) {
            l[0] = m[1] / det, l[1] = m[0] / det, l[3] = -m[3] / det;
        }
    } else {
        real A[9] = {m[0], m[3], m[4], m[3], m[1], m[5], m[4], m[5], m[2]};
        real B[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        if (!linalg_solve(3, A, B, 3, R(1e-6)))
            l[0] = B[0], l[1] = B[4], l[2] = B[8], l[3] = B[1], l[4] = B[2], l[5] = B[5];
    }
    for (int q = 0; q < 6; ++q) p->L[q][i] = l[q];
}

/* Renormalisation of the conservative scheme: L_i = M_i^-1 with the moment
 * M_i = -sum_{j in Omega} V_j w_ij x_ij (x) x_ij, w_ij = x_ij.grad_i W_ij / r^2
 * (M = I in the interior of a regular lattice, tests/test_kernel.c). Stored
 * as xx, yy, zz, xy, xz, yz (zz = 1, xz = yz = 0 in 2D). Where M is singular
 * L = I. Lane `lane` of a team of nlanes (hd.h); lane 0 writes. */
HD_INLINE void seg_renorm_team(size_t i, const particles_t *p, const grid_view *g, const seg_ctx *c, int lane,
                               int nlanes)
{
    real m[6] = {0, 0, 0, 0, 0, 0}; /* xx, yy, zz, xy, xz, yz */
    seg_moment_team(i, p, g, &c->k, 1, lane, nlanes, m);
    if (lane != 0) return;
    seg_renorm_store(i, p, c->k.dim, m);
}

HD_INLINE void seg_renorm(size_t i, const particles_t *p, const grid_view *g, const seg_ctx *c)
{
    seg_renorm_team(i, p, g, c, 0, 1);
}

/* (L_i + L_j)/2 applied to v (L_i, L_j as xx, yy, zz, xy, xz, yz). */
HD_INLINE void seg_Lbar(const real Li[6], const real Lj[6], const real v[3], real out[3])
{
    real l[6];
    for (int m = 0; m < 6; ++m) l[m] = R(0.5) * (Li[m] + Lj[m]);
    linalg_sym_apply(l, v, out);
}

/* What seg_rate_conservative reads of neighbour j besides its position
 * (cqdv[4], V of j, only with the donor limiter). */
HD_INLINE void seg_load_j(const particles_t *p, size_t j, int limiter, real Lj[6], real cqdv[5])
{
    for (int m = 0; m < 6; ++m) Lj[m] = p->L[m][j];
    cqdv[0] = p->C[j], cqdv[1] = p->segQ[j], cqdv[2] = p->segD[j], cqdv[3] = p->vol[j];
    cqdv[4] = limiter ? p->segV[j] : R(0.0);
}

/* The donor limiter of the conservative scheme's pair segregation flux: the
 * central flux Qsum = Q_u + Q_d capped at 2 A Vsum min(C_u, 1 - C_d), Vsum =
 * V_u + V_d, with u the particle the pair's flux takes small grains from
 * (the upper one along Lbar: ghat.Lbar x_ud < 0) and d the one it gives
 * them to; both C clamped to [0, 1], the result to >= 0. A particle without
 * small grains gives none and one full of them takes none. F(C) <= A min(C,
 * 1 - C) on [0, 1] for 0 <= kappa < 1 (2.8-2.9), so the cap leaves a pair of
 * equal C alone with a factor 2 to spare: it acts only across steep fronts
 * next to a bound. Each pair's outflow from u is at most 2 A Vsum C_u, so an
 * explicit step within the time-step bounds (step.h: wave speed >= A V)
 * keeps C in [0, 1] (docs/numerics.md, "Bounded C": the argument, its margin
 * and the measured factor 2). Symmetric in (i, j) once u and d are named, so
 * the pair flux stays antisymmetric. m/s. */
HD_INLINE real seg_flux_donor(real Qsum, real Vsum, real Cu, real Cd, real A)
{
    real a = Cu > 0 ? (Cu < 1 ? Cu : R(1.0)) : R(0.0);
    real b = Cd > 0 ? (Cd < 1 ? Cd : R(1.0)) : R(0.0);
    real room = a < R(1.0) - b ? a : R(1.0) - b;
    real cap = R(2.0) * A * Vsum * room;
    real q = Qsum < cap ? Qsum : cap;
    return q > 0 ? q : R(0.0);
}

/* dC_i/dt in conservative form: the divergence of J = Q ghat - D grad C by
 * pairwise antisymmetric two-point fluxes,
 *   dC_i/dt = sum_j V_j w_ij [ -(Q_i + Q_j) ghat.Lbar_ij x_ij
 *                              + (D_i + D_j) C_ij x_ij.Lbar_ij x_ij / r^2 ],
 *   w_ij = x_ij.grad_i W_ij / r^2   (cf. eq. 3.8),  Lbar_ij = (L_i + L_j)/2,
 * summed over material neighbours only. Lbar_ij is symmetric in (i, j), so
 * V_i dC_i/dt is antisymmetric: sum C_i V_i is conserved to round-off and the
 * no-flux condition holds at every boundary without dummy particles or
 * source terms; L restores first-order consistency where the support is cut
 * (side walls). Distinct particles never coincide, so the clipping eta of
 * (3.8), which lowers the Laplacian by ~1.5 % at h = 1.5 dr whatever dr, is
 * not needed. With renorm = 0, Lbar = I. With the donor limiter (limiter =
 * 1) Q_i + Q_j is the pair's seg_flux_donor, which keeps C in [0, 1]; the
 * diffusion term is bounded as it stands (its pair weights are >= 0: Lbar
 * is positive definite). */
HD_INLINE seg_rate seg_rate_conservative(size_t i, const particles_t *p, const grid_view *g, const seg_ctx *c,
                                         int lane, int nlanes)
{
    const sph_ctx *k = &c->k;
    const seg_params *sp = &c->sp;
    real Ci = p->C[i], Qi = p->segQ[i], Di = p->segD[i], Vi = c->limiter ? p->segV[i] : R(0.0);
    creal seg = 0, diff = 0; /* summed in double in both precisions (hd.h, creal) */
    /* i's own values read once; j's before or after the distance test by
     * SPH_EARLY_LOADS (hd.h) */
    const real xi[3] = {p->x[0][i], p->x[1][i], p->x[2][i]};
    real Li[6];
    for (int m = 0; m < 6; ++m) Li[m] = p->L[m][i];
    NBR_BEGIN_T(g, p->x, i, j, lane, nlanes)
        if (j == i || p->kind[j] != KIND_MATERIAL) continue;
        real Lj[6], cqdv[5]; /* C, Q, D, volume, V of j */
        if (SPH_EARLY_LOADS) seg_load_j(p, j, c->limiter, Lj, cqdv);
        real xij[3];
        real r2 = grid_pair_xi(k->dim, xi, p->x, j, xij);
        if (r2 >= k->support2) continue;
        if (!SPH_EARLY_LOADS) seg_load_j(p, j, c->limiter, Lj, cqdv);
        real Cj = cqdv[0], Qj = cqdv[1], Dj = cqdv[2], volj = cqdv[3];
        real r = sqrt_r(r2);
        real w = kernel_f(r, k->h, k->alpha) * volj;
        real lx[3] = {xij[0], xij[1], xij[2]};
        if (c->renorm) seg_Lbar(Li, Lj, xij, lx);
        real gx = sp->ghat[0] * lx[0] + sp->ghat[1] * lx[1] + sp->ghat[2] * lx[2];
        real xlx = (xij[0] * lx[0] + xij[1] * lx[1] + xij[2] * lx[2]) / r2;
        real q = Qi + Qj, vs = Vi + cqdv[4];
        if (c->limiter) /* gx < 0: the pair's flux takes small grains from i to j */
            q = gx < 0 ? seg_flux_donor(q, vs, Ci, Cj, sp->A) : seg_flux_donor(q, vs, Cj, Ci, sp->A);
        seg -= w * q * gx;
        diff += w * (Di + Dj) * (Ci - Cj) * xlx;
    NBR_END
    team_sum_c(&seg, 1, nlanes);
    team_sum_c(&diff, 1, nlanes);
    seg_rate out = {seg, diff, 0};
    return out;
}

/* rates(): dC_i/dt into p->dCdt (0 for dummies) by the scene's scheme.
 * Lane `lane` of a team of nlanes (hd.h; the rate bodies return the team's
 * sums to every lane); lane 0 writes. */
HD_INLINE void seg_dCdt_team(size_t i, const particles_t *p, const grid_view *g, const seg_ctx *c, int lane,
                             int nlanes)
{
    if (p->kind[i] != KIND_MATERIAL) {
        if (lane == 0) p->dCdt[i] = 0;
        return;
    }
    seg_rate r = c->scheme == 2 ? seg_rate_conservative(i, p, g, c, lane, nlanes)
                                : seg_rate_hcsr(i, p, g, c, lane, nlanes);
    if (lane == 0) p->dCdt[i] = r.seg + r.diff + r.src;
}

HD_INLINE void seg_dCdt(size_t i, const particles_t *p, const grid_view *g, const seg_ctx *c)
{
    seg_dCdt_team(i, p, g, c, 0, 1);
}

#endif
