/* bound_kern.h — HCSR boundary-particle search and normals (paper §4.2.2):
 * stage 1 cell types, stage 2 umbrella test (4.19) and vicinity (4.20–4.21),
 * normals (4.10, 4.17) and the smoothed degenerate function (4.14, 4.18).
 * Every normal points into the material. Neighbour-loop bodies shared by the
 * CPU driver (src/cpu/bound.c) and the GPU driver. */
#ifndef SPHSEG_BOUND_KERN_H
#define SPHSEG_BOUND_KERN_H
#include <math.h>
#include "../core/particles.h"
#include "grid.h"
#include "sph.h"

enum cell_type { CELL_EMPTY = 0, CELL_OUTER = 1, CELL_SECOND = 2, CELL_INNER = 3 };

/* Per-particle sums over the support, gathered once per classification. */
typedef struct bound_sums {
    real gm[3];   /* sum_{j in Omega} grad_i W_ij V_j (material) */
    real gd[3];   /* sum_{j in Omega_s} grad_i W_ij V_j (dummies) */
    real wm, wd;  /* sum W_ij V_j over material / dummies, self included */
    int ndummy;   /* dummies within the support */
} bound_sums;

HD_INLINE bound_sums bound_gather(size_t i, const particles_t *p, const grid_view *g,
                                  const sph_ctx *k)
{
    bound_sums s = {{0, 0, 0}, {0, 0, 0}, 0, 0, 0};
    NBR_BEGIN(g, p->x, i, j)
        real xij[3];
        real r2 = grid_pair(k->dim, p->x, i, j, xij);
        if (r2 >= k->support2) continue;
        real r = sqrt_r(r2);
        real w = kernel_w(r, k->h, k->alpha) * p->vol[j];
        real f = kernel_f(r, k->h, k->alpha) * p->vol[j];
        int dum = p->kind[j] == KIND_DUMMY;
        real *gv = dum ? s.gd : s.gm;
        for (int d = 0; d < 3; ++d) gv[d] += f * xij[d];
        if (dum) { s.wd += w; s.ndummy++; } else s.wm += w;
    NBR_END
    return s;
}

/* Umbrella test (4.19) after Marrone et al. (2010): i is a surface particle
 * if no neighbour lies in the umbrella around the outward axis a = -gsum/|gsum|
 * (T = x_i + h a). Neighbours are material particles, or all particles when
 * with_dummies (then walls count as filled space). */
HD_INLINE int bound_is_surface(size_t i, const particles_t *p, const grid_view *g,
                               const sph_ctx *k, const real gsum[3], int with_dummies)
{
    real a[3] = {-gsum[0], -gsum[1], -gsum[2]};
    sph_unit(a, R(1.0) / k->h);
    if (sph_norm(a) == 0) return 0; /* symmetric support: interior */
    const real sq2 = R(1.4142135623730951);
    int surface = 1;
    NBR_BEGIN(g, p->x, i, j)
        if (j == i || (!with_dummies && p->kind[j] != KIND_MATERIAL) || !surface) continue;
        real xji[3];
        real r2 = grid_pair(k->dim, p->x, j, i, xji);
        if (r2 >= k->support2) continue;
        real r = sqrt_r(r2);
        if (r >= sq2 * k->h) {
            real t[3] = {xji[0] - k->h * a[0], xji[1] - k->h * a[1], xji[2] - k->h * a[2]};
            if (sph_norm(t) < k->h * k->h) surface = 0;
        } else if (xji[0] * a[0] + xji[1] * a[1] + xji[2] * a[2] > R(0.5) * sq2 * r) {
            surface = 0;
        }
    NBR_END
    return surface;
}

/* Surface class of a particle in an outer cell: not a surface particle
 * (interior), a wall surface particle Omega_W (surface of the material alone,
 * but covered once dummies count), or a free-surface particle Omega_F (still
 * a surface with the dummies counted: this keeps particles where a free
 * surface meets a wall on the free surface). */
HD_INLINE int bound_surface_class(size_t i, const particles_t *p, const grid_view *g,
                                  const sph_ctx *k, const bound_sums *s)
{
    if (!bound_is_surface(i, p, g, k, s->gm, 0)) return BC_INTERIOR;
    if (s->ndummy == 0) return BC_FREE_SURFACE;
    real all[3] = {s->gm[0] + s->gd[0], s->gm[1] + s->gd[1], s->gm[2] + s->gd[2]};
    return bound_is_surface(i, p, g, k, all, 1) ? BC_FREE_SURFACE : BC_WALL_SURFACE;
}

/* Vicinity test (4.20) and the direction to the nearby surface: returns 1 if a
 * free-surface particle lies closer than 2h - dr; nf = -sum_{j in Omega_F}
 * grad_i W_ij V_j (the sign makes it point into the material, eq. 4.17). */
HD_INLINE int bound_near_free(size_t i, const particles_t *p, const grid_view *g,
                              const sph_ctx *k, real nf[3])
{
    real lim = R(2.0) * k->h - k->dr;
    int near = 0;
    nf[0] = nf[1] = nf[2] = 0;
    NBR_BEGIN(g, p->x, i, j)
        if (j == i || p->bclass[j] != BC_FREE_SURFACE) continue;
        real xij[3];
        real r2 = grid_pair(k->dim, p->x, i, j, xij);
        if (r2 >= k->support2) continue;
        real r = sqrt_r(r2);
        if (r < lim) near = 1;
        real f = kernel_f(r, k->h, k->alpha) * p->vol[j];
        for (int d = 0; d < 3; ++d) nf[d] -= f * xij[d];
    NBR_END
    return near;
}

/* Normal and psi~ of a classified particle (4.10, 4.14, 4.17, 4.18). */
HD_INLINE void bound_normal_psi(int bclass, const bound_sums *s, const real nf[3],
                                const sph_ctx *k, real n[3], real *psi)
{
    n[0] = n[1] = n[2] = 0;
    *psi = 1;
    switch (bclass) {
    case BC_FREE_SURFACE: /* (4.17), dummies counted so walls do not tilt n */
        for (int d = 0; d < 3; ++d) n[d] = s->gm[d] + s->gd[d];
        *psi = R(2.0) * (s->wm + s->wd) - R(1.0); /* (4.18) */
        break;
    case BC_FREE_VICINITY:
        for (int d = 0; d < 3; ++d) n[d] = nf[d];
        *psi = R(2.0) * (s->wm + s->wd) - R(1.0);
        break;
    case BC_WALL_SURFACE:
    case BC_WALL_VICINITY: /* colour function c = 0 material, 1 dummy (4.10) */
        for (int d = 0; d < 3; ++d) n[d] = -s->gd[d];
        *psi = (s->wm - s->wd) / (s->wm + s->wd);
        break;
    case BC_DUMMY: /* (4.10) with c_i = 1: sum over material neighbours */
        for (int d = 0; d < 3; ++d) n[d] = s->gm[d];
        *psi = -1;
        break;
    default:
        break;
    }
    sph_unit(n, R(1.0) / k->h);
}

/* Does any of the 3^d cells around (cx,cy,cz) satisfy the test? want_outer:
 * a cell typed CELL_OUTER; otherwise: a cell with no material (cells outside
 * the grid count as empty). */
HD_INLINE int bound_any_neighbour(const grid_view *v, const unsigned char *type, const size_t *mat,
                                  int cx, int cy, int cz, int want_outer)
{
    int zr = v->dim == 3 ? 1 : 0;
    for (int dz = -zr; dz <= zr; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                int x = cx + dx, y = cy + dy, z = cz + dz;
                int out = x < 0 || y < 0 || z < 0 || x >= v->nc[0] || y >= v->nc[1] || z >= v->nc[2];
                if (want_outer) {
                    if (!out && type[grid_cell_index(v, x, y, z)] == CELL_OUTER) return 1;
                } else if (out || mat[grid_cell_index(v, x, y, z)] == 0) {
                    return 1;
                }
            }
    return 0;
}

/* Stage 1 of the search for cell c, two passes (each parallel over cells):
 * pass 0 from the material counts alone (empty, outer: next to an empty
 * cell, inner); pass 1 turns inner cells next to an outer cell into second
 * cells (it reads only CELL_OUTER, which pass 1 never writes). */
HD_INLINE unsigned char bound_cell_type(const grid_view *v, const unsigned char *type, const size_t *mat,
                                        size_t c, int pass)
{
    int x = (int)(c % (size_t)v->nc[0]), y = (int)(c / (size_t)v->nc[0] % (size_t)v->nc[1]);
    int z = (int)(c / ((size_t)v->nc[0] * (size_t)v->nc[1]));
    if (pass == 0)
        return mat[c] == 0 ? CELL_EMPTY : bound_any_neighbour(v, type, mat, x, y, z, 0) ? CELL_OUTER : CELL_INNER;
    return type[c] == CELL_INNER && bound_any_neighbour(v, type, mat, x, y, z, 1) ? CELL_SECOND : type[c];
}

/* Material particles in cell c (the input of bound_cell_type). */
HD_INLINE size_t bound_cell_material(const grid_view *v, const particles_t *p, size_t c)
{
    size_t m = 0;
    for (size_t i = v->start[c]; i < v->end[c]; ++i) m += p->kind[i] == KIND_MATERIAL;
    if (v->gstart)
        for (size_t i = v->gstart[c]; i < v->gend[c]; ++i) m += p->kind[i] == KIND_MATERIAL;
    return m;
}

/* The stage-1 type of the cell holding particle i. */
HD_INLINE unsigned char bound_cell_of(const grid_view *v, const unsigned char *type, const particles_t *p,
                                      size_t i)
{
    int c[3];
    grid_cell_coords(v, p->x[0], p->x[1], p->x[2], i, c);
    return type[grid_cell_index(v, c[0], c[1], c[2])];
}

/* Stage 2, first sweep for particle i: its support sums and its class as a
 * surface particle (dummy, interior, free or wall surface). */
HD_INLINE int bound_class_first(size_t i, const particles_t *p, const grid_view *g, const sph_ctx *k,
                                const unsigned char *type, bound_sums *s)
{
    *s = bound_gather(i, p, g, k);
    if (p->kind[i] == KIND_DUMMY) return BC_DUMMY;
    return bound_cell_of(g, type, p, i) == CELL_OUTER ? bound_surface_class(i, p, g, k, s) : BC_INTERIOR;
}

/* Stage 2, second sweep (after every particle has its first class): the
 * vicinity classes (4.20–4.21), the normal and psi~ of particle i. Returns
 * the final class (the caller stores it after the sweep, since neighbours
 * still read bclass). */
HD_INLINE int bound_class_second(size_t i, particles_t *p, const grid_view *g, const sph_ctx *k,
                                 const unsigned char *type, const bound_sums *s)
{
    real nf[3] = {0, 0, 0};
    int cls = p->bclass[i];
    if (cls == BC_INTERIOR) {
        int near = bound_cell_of(g, type, p, i) != CELL_INNER && bound_near_free(i, p, g, k, nf);
        cls = near ? BC_FREE_VICINITY : (s->ndummy > 0 ? BC_WALL_VICINITY : BC_INTERIOR);
    }
    real n3[3], psi;
    bound_normal_psi(cls, s, nf, k, n3, &psi);
    for (int d = 0; d < 3; ++d) p->nrm[d][i] = n3[d];
    p->psi[i] = psi;
    return cls;
}

#endif
