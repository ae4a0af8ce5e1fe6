/* shift.h — particle shifting (Flow:shifting fickian), the regularisation of
 * Lind, Xu, Stansby & Rogers (2012, J. Comput. Phys. 231, 1499): a Fickian
 * shift dr_s = -D grad C down the gradient of the particle concentration,
 * with D = A h |u_i| dt and the anti-clumping term of Monaghan (2000):
 *
 *   dr_i = -A h |u_i| dt sum_j V_j (1 + R (W_ij / W(dr))^n) grad_i W_ij,
 *
 * R = 0.2, n = 4 (their values, Monaghan's), A = Flow:shift_coeff (Lind et
 * al. take 2, the default). The sum runs over material
 * and dummies, so a particle crowding a wall is pushed off it; dummies are
 * never shifted. At a free surface the particle concentration has a jump
 * the shift would follow outwards: a particle whose divergence of position
 * div r_i = -sum_j V_j x_ij . grad_i W_ij is below d - s (s =
 * Flow:shift_surface, 1/2 by default: 1.5 in 2D, Lind et al.'s threshold; d
 * in a full support) is not shifted. The drums' surface speed depends on s
 * (docs/drum3d.md: the periodic 3D drum's slab -12.5 % from s 1/2 to 3/4).
 * With Flow:shift_surface_rule tangential such a particle keeps the part of
 * its shift along the surface: dr - (dr . n) n / |n|^2, n = sum_j V_j grad
 * W_ij (unweighted: the shift's own sum without the anti-clumping weight;
 * the free-surface treatment of Lind et al. 2012 and of Sun et al. 2017's
 * delta+-SPH, whose normal is this sum's). A particle of a flat surface
 * row moved along it by 0.2 dr is shifted back by about half of what an
 * interior one is, its normal part under a fifth of that (tests/test_shift.c).
 * With Flow:shift_surface_rule fade there is no threshold: every particle
 * keeps its tangential part and a share w = 2 div r / d - 1, clamped to
 * [0, 1], of its normal part, dr - (1 - w) (dr . n) n / |n|^2; w is 0 where a
 * flat surface cuts the support in half (div r = d/2 in the continuum, in 2D
 * and 3D alike) and 1 in a whole support (div r = d): the normal part fades
 * in over the kernel's reach below the surface instead of at a step.
 *
 * The shifted particle carries its velocity and stress to its new place by
 * the first-order Taylor step phi' = phi + dr . grad phi (as Lind et al. do,
 * with grad phi_i = sum_j V_j (phi_j - phi_i) grad_i W_ij over material and
 * dummies; for u that is the flow rates' velocity gradient L of the same
 * pairs, mom_velgrad_add, which the fused pass hands over rather than
 * summing it twice); C is not corrected: shifting moves a particle with its C and V
 * unchanged, so sum C_i V_i stays conserved to round-off (a Taylor step of
 * C would not conserve it). Gather style, one material particle per call;
 * it runs in the save hook (ST_SHIFT, src/sim/stages.c), after step_save, and
 * writes only i's start-of-step copies x_n, v_n, sig_n, which no neighbour
 * reads: the predictor and corrector then start from the shifted state. */
#ifndef SPHSEG_SHIFT_H
#define SPHSEG_SHIFT_H
#include <math.h>
#include "../core/particles.h"
#include "grid.h"
#include "kernel.h"
#include "momentum.h"
#include "options.h"
#include "sph.h"


typedef struct shift_ctx {
    sph_ctx k;
    int kind;   /* enum shift_kind (Flow:shifting) */
    real A;     /* Flow:shift_coeff, - */
    real R;     /* anti-clumping weight, 0.2 (Monaghan 2000; Lind et al. 2012) */
    real w_dr;  /* W(dr), the kernel at the initial spacing */
    real div_free; /* div r below which a particle is at a free surface: d - s (Flow:shift_surface) */
    int rule;      /* enum shift_surface_rule (Flow:shift_surface_rule) */
} shift_ctx;

HD_INLINE shift_ctx shift_make(const sph_ctx *k, int kind, real A, real s, int rule)
{
    shift_ctx c;
    c.k = *k;
    c.kind = kind;
    c.A = A;
    c.R = R(0.2);
    c.w_dr = kernel_w(k->dr, k->h, k->alpha);
    c.div_free = (real)k->dim - s;
    c.rule = rule;
    return c;
}

/* The sums of a shift (shift_team): grad C (with the anti-clumping
 * weight), div r, and the gradient of sigma, over i's neighbours (that of
 * u is the velocity gradient L, summed by the caller: shift_finish). */
typedef struct shift_sums {
    real gc[3], div, gs[18], gk[3]; /* gk: sum_j V_j grad W_ij, the surface normal's (rule tangential only) */
} shift_sums;

HD_INLINE void shift_sums_zero(shift_sums *a)
{
    for (int b = 0; b < 3; ++b) a->gc[b] = 0;
    a->div = 0;
    for (int q = 0; q < 18; ++q) a->gs[q] = 0;
    for (int b = 0; b < 3; ++b) a->gk[b] = 0;
}

/* Neighbour j's share (r, r2, f = kernel_f(r), V = V_j, x_ij, sigma_j;
 * si: i's). Called from shift_team and, fused, from the flow pass
 * (flow_rates_body): the same arithmetic in both. */
HD_INLINE void shift_pair_add(shift_sums *a, const shift_ctx *c, real r, real r2, real f, real V, const real xij[3],
                              const real sj[6], const real si[6])
{
    const sph_ctx *k = &c->k;
    const real t = kernel_w(r, k->h, k->alpha) * (R(1.0) / c->w_dr), t2 = t * t; /* 1/w_dr hoisted */
    const real cw = V * (R(1.0) + c->R * t2 * t2) * f, vf = V * f;
    a->div -= vf * r2;
    if (c->rule != SHIFT_SURFACE_NONE)
        for (int b = 0; b < 3; ++b) a->gk[b] += vf * xij[b];
    for (int b = 0; b < 3; ++b) {
        a->gc[b] += cw * xij[b];
        for (int q = 0; q < 6; ++q) a->gs[3 * q + b] += vf * (sj[q] - si[q]) * xij[b];
    }
}

/* The team's sums added up; lane 0 applies the shift dr_i to x_n and its
 * Taylor steps to v_n and sig_n (step length dt; ui: i's velocity; gu: the
 * velocity gradient L of mom_velgrad_add over the same pairs, row-major,
 * without the gradient correction, already summed over the team). */
HD_INLINE void shift_finish(size_t i, particles_t *p, const shift_ctx *c, real dt, shift_sums *a, const real gu[9],
                            const real ui[3], int lane, int nlanes)
{
    const sph_ctx *k = &c->k;
    team_sum(a->gc, 3, nlanes);
    team_sum(&a->div, 1, nlanes);
    team_sum(a->gs, 18, nlanes);
    if (c->rule != SHIFT_SURFACE_NONE) team_sum(a->gk, 3, nlanes);
    if (lane != 0) return;
    const real speed = sqrt_r(ui[0] * ui[0] + ui[1] * ui[1] + ui[2] * ui[2]);
    const real D = c->A * k->h * speed * dt;
    real dr[3] = {-D * a->gc[0], -D * a->gc[1], -D * a->gc[2]};
    const int fade = c->rule == SHIFT_SURFACE_FADE;
    if (fade || a->div < c->div_free) { /* at a free surface, or fading: the part along the normal cut */
        if (c->rule == SHIFT_SURFACE_NONE) return; /* not shifted */
        real keep = 0; /* the share of the normal part kept: tangential none; fade 2 div r / d - 1 in [0, 1] */
        if (fade) {
            keep = R(2.0) * a->div / (real)k->dim - R(1.0);
            keep = keep < 0 ? 0 : (keep > 1 ? R(1.0) : keep);
        }
        const real *n = a->gk; /* the normal, inwards: sum_j V_j grad W_ij */
        const real n2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
        if (n2 > 0) {
            const real dn = (R(1.0) - keep) * (dr[0] * n[0] + dr[1] * n[1] + dr[2] * n[2]) / n2;
            for (int d = 0; d < 3; ++d) dr[d] -= dn * n[d];
        }
    }
    for (int d = 0; d < 3; ++d) { /* a fixed trip count: the pointer table indexed statically (a runtime
                                   * bound put the fused flow pass's particles_t on the stack) */
        if (d >= k->dim) break;
        p->x_n[d][i] += (preal)dr[d];
    }
    for (int d = 0; d < 3; ++d)
        p->v_n[d][i] += gu[3 * d] * dr[0] + gu[3 * d + 1] * dr[1] + gu[3 * d + 2] * dr[2];
    for (int q = 0; q < 6; ++q)
        p->sig_n[q][i] += a->gs[3 * q] * dr[0] + a->gs[3 * q + 1] * dr[1] + a->gs[3 * q + 2] * dr[2];
}

/* Material particle i at the start of a step of length dt: the shift
 * dr_i into x_n and the Taylor steps into v_n and sig_n (after step_save).
 * Lane `lane` of a team of nlanes (hd.h); lane 0 writes. */
HD_INLINE void shift_team(size_t i, particles_t *p, const grid_view *g, const shift_ctx *c, real dt, int lane,
                          int nlanes)
{
    const sph_ctx *k = &c->k;
    shift_sums a;
    shift_sums_zero(&a);
    real gu[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    const real xi[3] = {p->x[0][i], p->x[1][i], p->x[2][i]}, ui[3] = {p->v[0][i], p->v[1][i], p->v[2][i]};
    real si[6];
    for (int q = 0; q < 6; ++q) si[q] = p->sig[q][i];
    NBR_BEGIN_T(g, p->x, i, j, lane, nlanes)
        if (j == i) continue;
        real xij[3];
        real r2 = grid_pair_xi(k->dim, xi, p->x, j, xij);
        if (r2 >= k->support2) continue;
        const real r = sqrt_r(r2), f = kernel_f(r, k->h, k->alpha);
        const real uij[3] = {ui[0] - p->v[0][j], ui[1] - p->v[1][j], ui[2] - p->v[2][j]};
        const real gradW[3] = {f * xij[0], f * xij[1], f * xij[2]};
        const real sj[6] = {p->sig[0][j], p->sig[1][j], p->sig[2][j], p->sig[3][j], p->sig[4][j], p->sig[5][j]};
        shift_pair_add(&a, c, r, r2, f, p->vol[j], xij, sj, si);
        mom_velgrad_add(gu, p->vol[j], uij, gradW); /* the flow rates' L (flow_rates_body) */
    NBR_END
    team_sum(gu, 9, nlanes);
    shift_finish(i, p, c, dt, &a, gu, ui, lane, nlanes);
}

#endif
