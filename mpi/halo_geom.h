/* halo_geom.h — who owns a lattice cell and whom a particle is a ghost of,
 * as HD_INLINE bodies over a plain view of the decomposition, so that
 * mpi/halo.c (the host exchange) and the GPU backend's device exchange
 * (gpu/gpu_exchange.cu) decide alike, bit for bit.
 *
 * A halo_geom is plain data: the numbers of halo_t that the decisions read,
 * and pointers to its arrays (slab bounds, METIS owners, the channels),
 * which point at host memory in halo.c and at device copies on the GPU.
 * The products a device could fuse into a multiply-add are taken on the
 * host once (inv_support, the periodic reach near_lo/near_hi) or rounded
 * apart (hg_mul_rn), so both sides round every operation alike.
 *
 * Includes only the physics' base (hd.h): the GPU unit includes it without
 * MPI. */
#ifndef SPHSEG_HALO_GEOM_H
#define SPHSEG_HALO_GEOM_H
#include <math.h>
#include <stddef.h>
#include "../src/core/hd.h"

enum { HG_NOSHIFT = 13, HG_NCODES = 27, HG_MAX_TARGETS = 256 };

typedef struct halo_geom {
    int rank, size, dim, axis;
    int metis;             /* 1: METIS coarse cells; 0: slabs */
    int depth, blk, cg_n[3];
    int per, nimg, img[HG_NCODES];
    real inv_support;      /* R(1) / support, as halo_column has always taken it */
    real origin[3];
    real near_lo[3], near_hi[3]; /* plo - depth 2h, plo + plen + depth 2h */
    real plo[3], plen[3];
    long pcol[2];          /* a periodic slab axis: the columns of plo and plo + plen */
    const long *bound;     /* slabs: size + 1 column bounds */
    const int *part;       /* METIS: the rank of each coarse cell */
    int nnb;
    const int *nb, *nbs;   /* the channels: neighbour rank and shift code */
} halo_geom;

/* a * b rounded to double once, also where the device would fuse it with a
 * following add (nvcc contracts by default; the host compiler here does not). */
HD_INLINE double hg_mul_rn(double a, double b)
{
#ifdef __CUDA_ARCH__
    return __dmul_rn(a, b);
#else
    return a * b;
#endif
}

HD_INLINE void hg_shift_of(int code, int s[3])
{
    s[0] = code % 3 - 1, s[1] = code / 3 % 3 - 1, s[2] = code / 9 - 1;
}

/* The lattice column of coordinate x along axis d (the expression
 * grid_cell_coords uses, so that both bin alike). */
HD_INLINE long hg_column(const halo_geom *g, int d, real x) { return (long)((x - g->origin[d]) * g->inv_support); }

HD_INLINE long hg_clamp(long v, long lo, long hi) { return v < lo ? lo : v > hi ? hi : v; }

HD_INLINE size_t hg_coarse_index(const halo_geom *g, const long c[3])
{
    size_t k = 0;
    for (int d = g->dim - 1; d >= 0; --d)
        k = k * (size_t)g->cg_n[d] + (size_t)hg_clamp(c[d] / g->blk, 0, g->cg_n[d] - 1);
    return k;
}

/* The rank owning lattice cell c. */
HD_INLINE int hg_owner(const halo_geom *g, const long c[3])
{
    if (g->metis) return g->part[hg_coarse_index(g, c)];
    if (c[g->axis] >= g->bound[g->rank] && c[g->axis] < g->bound[g->rank + 1]) return g->rank; /* most */
    int lo = 0, hi = g->size - 1; /* largest r with bound[r] <= c; bound[0] is open */
    while (lo < hi) {
        int mid = (lo + hi + 1) / 2;
        if (g->bound[mid] <= c[g->axis]) lo = mid;
        else hi = mid - 1;
    }
    return lo;
}

/* Add (rank r, shift code) to the targets out/codes[0..n) unless it is this
 * rank unshifted or already there; returns the new count. */
HD_INLINE int hg_add_target(const halo_geom *g, int r, int code, int *out, int *codes, int n)
{
    if (r == g->rank && code == HG_NOSHIFT) return n;
    for (int k = 0; k < n; ++k)
        if (out[k] == r && codes[k] == code) return n;
    if (n >= HG_MAX_TARGETS) return n; /* cannot happen: 2^dim coarse cells times 27 shifts */
    out[n] = r, codes[n] = code;
    return n + 1;
}

/* Targets of a particle in lattice cell c, its image moved by shift code
 * (HG_NOSHIFT: itself): the ranks other than this one (or this one, for an
 * image) owning a lattice cell within depth cells of c: the owners of the
 * 2 depth + 1 columns around c (slabs; along a periodic slab axis only the
 * columns of the period), or of the coarse cells that the box c +- depth
 * touches (at most 2^dim: blk >= depth). */
HD_INLINE int hg_targets(const halo_geom *g, const long c[3], int code, int *out, int *codes, int n)
{
    if (!g->metis) {
        long a = c[g->axis], lo = a - g->depth, hi = a + g->depth;
        if (code == HG_NOSHIFT && lo >= g->bound[g->rank] && hi < g->bound[g->rank + 1]) return n; /* inner */
        if (g->per >> g->axis & 1) lo = lo < g->pcol[0] ? g->pcol[0] : lo, hi = hi > g->pcol[1] ? g->pcol[1] : hi;
        long q[3] = {c[0], c[1], c[2]};
        for (long k = lo; k <= hi; ++k) {
            q[g->axis] = k;
            n = hg_add_target(g, hg_owner(g, q), code, out, codes, n);
        }
        return n;
    }
    long lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    for (int d = 0; d < g->dim; ++d) {
        lo[d] = hg_clamp((c[d] - g->depth) / g->blk, 0, g->cg_n[d] - 1);
        hi[d] = hg_clamp((c[d] + g->depth) / g->blk, 0, g->cg_n[d] - 1);
    }
    for (long z = lo[2]; z <= hi[2]; ++z)
        for (long y = lo[1]; y <= hi[1]; ++y)
            for (long x = lo[0]; x <= hi[0]; ++x)
                n = hg_add_target(g, g->part[((size_t)z * (size_t)g->cg_n[1] + (size_t)y) * (size_t)g->cg_n[0] + (size_t)x],
                                  code, out, codes, n);
    return n;
}

/* Every target of an owned particle at x: its own (hg_targets), and on
 * periodic axes those of each image whose position lies within depth cells
 * of the period (at most 3^dim - 1 images). */
HD_INLINE int hg_particle_targets(const halo_geom *g, const real x[3], int *out, int *codes)
{
    long c[3];
    for (int d = 0; d < 3; ++d) c[d] = d < g->dim ? hg_column(g, d, x[d]) : 0;
    int n = hg_targets(g, c, HG_NOSHIFT, out, codes, 0);
    for (int m = 0; m < g->nimg; ++m) {
        int s[3], code = g->img[m], near = 1;
        hg_shift_of(code, s);
        long q[3] = {c[0], c[1], c[2]};
        for (int d = 0; d < 3 && near; ++d) {
            if (!s[d]) continue;
            real y = x[d] + (real)s[d] * g->plen[d]; /* s = +-1: exact, fused or not */
            near = y > g->near_lo[d] && y < g->near_hi[d];
            q[d] = hg_column(g, d, y);
        }
        if (near) n = hg_targets(g, q, code, out, codes, n);
    }
    return n;
}

/* Channel of (rank r, shift code), or for code < 0 the first channel to r
 * (a migrating particle, already wrapped, may travel on any); -1 if none. */
HD_INLINE int hg_channel(int nnb, const int *nb, const int *nbs, int r, int code)
{
    for (int k = 0; k < nnb; ++k)
        if (nb[k] == r && (code < 0 || nbs[k] == code)) return k;
    return -1;
}

/* The shift, m, that brings position x (with the single build's remainder
 * xr) back into the period [lo, lo + len) along an axis; 0 inside. */
HD_INLINE double hg_wrap_shift(double x, double lo, double len)
{
    if (x >= lo && x < lo + len) return 0;
    return hg_mul_rn(-floor((x - lo) / len), len);
}

/* Move a particle by s along one axis: the position kept to double (x + xr
 * in the single build) and the start-of-step x_n alike, so that x = x_n +
 * a u still holds within the step. */
HD_INLINE void hg_move(real *x, real *xr, preal *xn, double s)
{
    double xd = (double)*x + (POS_REMAINDER ? (double)*xr : 0.0) + s;
    *x = (real)xd;
    if (POS_REMAINDER) *xr = (real)(xd - (double)*x);
    *xn += (preal)s;
}

#endif
