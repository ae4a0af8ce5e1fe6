/* grid.h — the cell-linked list with sorting (paper §3.4, Green 2010), as a
 * plain view usable from host and device code: particles are sorted by cell,
 * so each cell is the index range [start[c], end[c]). Cell edge >= 2h. */
#ifndef SPHSEG_GRID_H
#define SPHSEG_GRID_H
#include <stddef.h>
#include "../core/hd.h"

typedef struct grid_view {
    int dim;
    real lo[3];     /* lower corner of the grid, m */
    real inv_cell;  /* 1 / cell edge, 1/m */
    int nc[3];      /* cells per axis (nc[2] = 1 in 2D) */
    int off[3];     /* lattice offset: cell k of this grid is lattice cell k + off (the
                     * lattice of edge 1/inv_cell from lo); 0 but on a multi-rank run */
    const size_t *start, *end;
    /* Ghost particles (mpi/halo.h) are sorted apart, after the owned ones:
     * cell c holds [start[c], end[c]) and [gstart[c], gend[c]). NULL: none. */
    const size_t *gstart, *gend;
    /* Optional neighbour list (NULL: the cell scan): the particles within
     * the support of i, in the order the cell scan meets them, ncnt[i] of
     * them; entry q at nl[q * nl_stride + i] (the GPU's columns), or at
     * nl[i * nl_stride + q] in the form GRID_NBR_ROWS (the CPU's rows,
     * src/cpu/nlist.h). A particle with more than nl_cap falls back to the
     * cell scan. */
    const unsigned *nl, *ncnt;
    size_t nl_stride;
    unsigned nl_cap;
    /* The GPU's other forms of the pass (SPHSEG_GPU_NBR, core/tuning.h;
     * docs/gpu.md, "Neighbour pass"), each meeting the list's
     * particles in the list's order, lane by lane (test_nbr.c):
     * GRID_NBR_LIST16, the list in 16-bit entries nl16 (grid_enc16);
     * GRID_NBR_CELLS, no list: the cell scan of the build, owned and ghost
     * runs merged by rk, the particles within sqrt(list2) at the build's
     * positions xb. Both take i's cell from xb (the cell it was sorted
     * into). GRID_NBR_LIST (0): the list nl, or the plain cell scan.
     * GRID_NBR_ROWS: the CPU's list nl in rows (above); its fallback is
     * the plain cell scan, as GRID_NBR_LIST's. */
    int form;
    const unsigned short *nl16;
    real *xb[3];
    const unsigned *rk;
    real list2;
    /* GRID_NBR_LIST16 with a tile (the GPU's staged pass, gpu/gpu_pairs.cu):
     * the neighbours of the particles of one cell staged in tp at the slots
     * of tile (grid_tile); NULL: read from the store. Bodies that read j
     * through NBR_BEGIN_TJ's jp and jj take them from the tile. A view with
     * a tile serves only the particles of its cell whose list it holds
     * (ncnt[i] <= nl_cap). */
    int tiled; /* 1: tile and tp are set (a flag, not a pointer test: the compiler folds it) */
    const struct grid_tile *tile;
    const struct particles *tp;
} grid_view;

enum { GRID_NBR_LIST = 0, GRID_NBR_LIST16 = 1, GRID_NBR_CELLS = 2, GRID_NBR_ROWS = 3 };

/* A 16-bit entry: the slot s of the neighbour's cell among i's 3^d cells
 * (the scan's order, dz, dy, dx ascending; bits 11-15) and its offset in
 * that cell's owned run followed by its ghost run (bits 0-10). */
#define GRID_ENC16_OFF 2047u
#define GRID_ENC16_OVER 0xffffffffu /* a build's count: an offset past GRID_ENC16_OFF */
HD_INLINE unsigned grid_enc16(int s, size_t off) { return (unsigned)s << 11 | (unsigned)off; }

/* A tile: the 3^d cells around one cell c0 in the order of the 16-bit
 * entries' slots, each cell's owned run followed by its ghost run, staged
 * one after the other (the GPU's staged flow pass, gpu/gpu_pairs.cu, in a
 * block's shared memory): slot s's cell holds the store's [a[s], a[s] +
 * na[s]) and [ga[s], ga[s] + ng) at the tile's base[s], ...; base[3^d] is
 * the tile's size. Entry e of a particle of c0 is then at base[s] + offset,
 * the store's particle grid_tile_j. */
typedef struct grid_tile {
    size_t a[27], ga[27];
    unsigned na[27], base[28];
} grid_tile;

HD_INLINE size_t grid_tile_j(const grid_tile *t, unsigned e)
{
    const unsigned s = e >> 11, o = e & GRID_ENC16_OFF;
    return o < t->na[s] ? t->a[s] + o : t->ga[s] + (o - t->na[s]);
}

/* Fit the grid to the bounding box [lo, hi] of n particles with cells of
 * edge `support` (2h); returns the number of cells. Shared by the CPU and
 * GPU neighbour builds, so that both bin (and so order) particles alike. */
HD_INLINE size_t grid_fit(grid_view *g, int dim, size_t n, const real lo[3], const real hi[3], real support)
{
    g->dim = dim;
    g->inv_cell = R(1.0) / support;
    g->gstart = g->gend = NULL;
    for (int d = 0; d < 3; ++d) {
        g->off[d] = 0;
        if (d >= dim || n == 0) {
            g->lo[d] = 0;
            g->nc[d] = 1;
            continue;
        }
        g->lo[d] = lo[d] - R(1e-6) * support;
        g->nc[d] = (int)((hi[d] - g->lo[d]) / support) + 1;
    }
    return (size_t)g->nc[0] * (size_t)g->nc[1] * (size_t)g->nc[2];
}

/* The grid over the box [lmin, lmax] of a rank's particles cut from the
 * global lattice whose cells start at origin (the global grid_fit lo), so
 * that every rank bins a position into the same lattice cell as one rank
 * holding all particles would; returns the number of cells. */
HD_INLINE size_t grid_fit_lattice(grid_view *g, int dim, size_t n, const real origin[3], const real lmin[3],
                                  const real lmax[3], real support)
{
    g->dim = dim;
    g->inv_cell = R(1.0) / support;
    g->gstart = g->gend = NULL;
    for (int d = 0; d < 3; ++d) {
        g->lo[d] = d < dim ? origin[d] : 0;
        g->off[d] = 0;
        g->nc[d] = 1;
        if (d >= dim || n == 0) continue;
        g->off[d] = (int)((lmin[d] - g->lo[d]) * g->inv_cell);
        g->nc[d] = (int)((lmax[d] - g->lo[d]) * g->inv_cell) - g->off[d] + 1;
    }
    return (size_t)g->nc[0] * (size_t)g->nc[1] * (size_t)g->nc[2];
}

/* Cell coordinates of position x, clamped into the grid. */
HD_INLINE void grid_cell_coords(const grid_view *g, const real *x0, const real *x1,
                                const real *x2, size_t i, int c[3])
{
    real x[3] = {x0[i], x1[i], g->dim == 3 ? x2[i] : g->lo[2]};
    for (int d = 0; d < 3; ++d) {
        int k = (int)((x[d] - g->lo[d]) * g->inv_cell) - g->off[d];
        c[d] = k < 0 ? 0 : (k >= g->nc[d] ? g->nc[d] - 1 : k);
    }
}

HD_INLINE size_t grid_cell_index(const grid_view *g, int cx, int cy, int cz)
{
    return ((size_t)cz * (size_t)g->nc[1] + (size_t)cy) * (size_t)g->nc[0] + (size_t)cx;
}

/* Loop over every particle j in the 3^d cells around particle i (j == i
 * included; callers skip it where the formula excludes self), cell by cell
 * (dz, dy, dx ascending; each cell in store order, its owned particles then
 * its ghosts); or, where the view has a neighbour list, over the list, which
 * holds the same particles within the support in the same order, so that
 * sums come out alike. Bodies test the distance themselves and may
 * `continue`. The store order of a cell is canonical (nbr_build: periodic
 * images last, each part in global ID order) and the lattice global
 * (grid_fit_lattice), so a particle's neighbours come in the one-rank order
 * on any rank count, and every sum has the one-rank bits. */
#define NBR_BEGIN(g, x, i, j) NBR_BEGIN_T(g, x, i, j, 0, 1)

/* The same loop for lane `lane` of a team of `nlanes` (hd.h): entries
 * lane, lane + nlanes, ... of each segment (the list, or each cell), so that
 * the lanes of a team meet every neighbour exactly once between them. The
 * list's other forms (form, above) hand each lane the entries the list
 * would: GRID_NBR_LIST16 decodes them (grid_dec16), GRID_NBR_CELLS counts
 * the particles within the list's radius across its cells (grid_ex_next). */
#define NBR_BEGIN_T(g, x, i, j, lane, nlanes)                                          \
    NBR_BEGIN_X(g, x, i, j, nbr_jj_, nbr_jp_, (const struct particles *)0, lane, nlanes) \
    (void)nbr_jj_, (void)nbr_jp_;

/* The same loop for a body that reads neighbour j's fields through jp at
 * index jj: the store p at j, or, for a particle whose list is read from a
 * tile (grid_view tile), the tile's staged copy. */
#define NBR_BEGIN_TJ(g, p, i, j, jj, jp, lane, nlanes) NBR_BEGIN_X(g, (p)->x, i, j, jj, jp, (p), lane, nlanes)

#define NBR_BEGIN_X(g, x, i, j, jj, jp, psrc, lane, nlanes)                            \
    {                                                                                  \
        const int frm_ = (g)->form;                                                    \
        int c0_[3];                                                                    \
        const int row_ = frm_ == GRID_NBR_ROWS;                                        \
        if (frm_ == GRID_NBR_LIST || row_) grid_cell_coords((g), (x)[0], (x)[1], (x)[2], (i), c0_); \
        else grid_cell_coords((g), (g)->xb[0], (g)->xb[1], (g)->xb[2], (i), c0_);      \
        const int zr_ = (g)->dim == 3 ? 1 : 0;                                         \
        const int l16_ = (g)->nl16 != NULL && (g)->ncnt[i] <= (g)->nl_cap;             \
        const int lst_ = l16_ || ((g)->nl != NULL && (g)->ncnt[i] <= (g)->nl_cap);     \
        const int tld_ = (g)->tiled;                                                   \
        const grid_tile *const tl_ = (g)->tile;                                        \
        const struct particles *const jp = tld_ ? (g)->tp : (psrc);                    \
        const int ex_ = frm_ == GRID_NBR_CELLS;                                        \
        const int nsub_ = (g)->gstart != NULL && !ex_ ? 2 : 1;                         \
        const int nseg_ = lst_ ? 1 : (zr_ ? 27 : 9) * nsub_;                           \
        grid_dec dc_ = {-1, 0, 0, 0};                                                  \
        grid_ex xs_ = {(size_t)(i), 0, 0, 0, 0, 0};                                    \
        for (int s_ = 0; s_ < nseg_; ++s_) {                                           \
            size_t a_ = 0, b_ = 0;                                                     \
            if (lst_) {                                                                \
                b_ = (g)->ncnt[i];                                                     \
            } else {                                                                   \
                const int k_ = s_ / nsub_;                                             \
                int cx_ = c0_[0] + k_ % 3 - 1, cy_ = c0_[1] + (k_ / 3) % 3 - 1;        \
                int cz_ = c0_[2] + (zr_ ? k_ / 9 - 1 : 0);                             \
                if (cx_ < 0 || cy_ < 0 || cz_ < 0 || cx_ >= (g)->nc[0] ||              \
                    cy_ >= (g)->nc[1] || cz_ >= (g)->nc[2])                            \
                    continue;                                                          \
                size_t cell_ = grid_cell_index((g), cx_, cy_, cz_);                    \
                if (ex_) grid_ex_cell(&xs_, (g), cell_), b_ = GRID_EX_END;             \
                else if (s_ % nsub_ == 0) a_ = (g)->start[cell_], b_ = (g)->end[cell_]; \
                else a_ = (g)->gstart[cell_], b_ = (g)->gend[cell_];                   \
            }                                                                          \
            for (size_t q_ = ex_ ? grid_ex_next(&xs_, (g), (lane), (nlanes)) : a_ + (size_t)(lane); \
                 q_ < b_; q_ = ex_ ? grid_ex_next(&xs_, (g), (lane), (nlanes)) : q_ + (size_t)(nlanes)) { \
                const unsigned e16_ = l16_ ? (g)->nl16[q_ * (g)->nl_stride + (i)] : 0u;  \
                const size_t j = !lst_ ? q_                                            \
                                 : tld_ ? grid_tile_j(tl_, e16_)                       \
                                 : l16_ ? grid_dec16((g), &dc_, c0_, e16_)             \
                                 : row_ ? (size_t)(g)->nl[(i) * (g)->nl_stride + q_]   \
                                        : (size_t)(g)->nl[q_ * (g)->nl_stride + (i)];  \
                const size_t jj = tld_ ? (size_t)tl_->base[e16_ >> 11] + (e16_ & GRID_ENC16_OFF) : j;

#define NBR_END                                                                        \
            }                                                                          \
        }                                                                              \
    }

/* Pair geometry: x_ij = x_i - x_j and r^2, with x_i already at hand (read
 * once outside a neighbour loop). */
HD_INLINE real grid_pair_xi(int dim, const real xi[3], real *const *x, size_t j, real xij[3])
{
    xij[0] = xi[0] - x[0][j];
    xij[1] = xi[1] - x[1][j];
    xij[2] = dim == 3 ? xi[2] - x[2][j] : R(0.0);
    return xij[0] * xij[0] + xij[1] * xij[1] + xij[2] * xij[2];
}

/* Pair geometry: x_ij = x_i - x_j and r^2 (the same arithmetic as
 * grid_pair_xi, reading x_i at each call). */
HD_INLINE real grid_pair(int dim, real *const *x, size_t i, size_t j, real xij[3])
{
    xij[0] = x[0][i] - x[0][j];
    xij[1] = x[1][i] - x[1][j];
    xij[2] = dim == 3 ? x[2][i] - x[2][j] : R(0.0);
    return xij[0] * xij[0] + xij[1] * xij[1] + xij[2] * xij[2];
}

/* GRID_NBR_LIST16: the particle of 16-bit entry e of the particle in cell
 * c0 (at its build), the slot's cell ranges cached in d (a lane's entries
 * come slot by slot, in ascending order). */
typedef struct grid_dec {
    int s;
    size_t a, na, ga;
} grid_dec;

HD_INLINE size_t grid_dec16(const grid_view *g, grid_dec *d, const int c0[3], unsigned e)
{
    const int s = (int)(e >> 11);
    const size_t o = e & GRID_ENC16_OFF;
    if (s != d->s) {
        const size_t c = grid_cell_index(g, c0[0] + s % 3 - 1, c0[1] + (s / 3) % 3 - 1,
                                         c0[2] + (g->dim == 3 ? s / 9 - 1 : 0));
        d->s = s, d->a = g->start[c], d->na = g->end[c] - g->start[c];
        d->ga = g->gstart ? g->gstart[c] : 0;
    }
    return o < d->na ? d->a + o : d->ga + (o - d->na);
}

/* Slot s of the tile around cell c0: its cell's runs into t (na[s] = 0
 * outside the grid); returns the ghost run's length. */
HD_INLINE unsigned grid_tile_slot(const grid_view *g, const int c0[3], int s, grid_tile *t)
{
    const int cx = c0[0] + s % 3 - 1, cy = c0[1] + (s / 3) % 3 - 1, cz = c0[2] + (g->dim == 3 ? s / 9 - 1 : 0);
    t->a[s] = t->ga[s] = 0, t->na[s] = 0;
    if (cx < 0 || cy < 0 || cz < 0 || cx >= g->nc[0] || cy >= g->nc[1] || cz >= g->nc[2]) return 0;
    const size_t c = grid_cell_index(g, cx, cy, cz);
    t->a[s] = g->start[c], t->na[s] = (unsigned)(g->end[c] - g->start[c]);
    if (!g->gstart) return 0;
    t->ga[s] = g->gstart[c];
    return (unsigned)(g->gend[c] - g->gstart[c]);
}

/* The tile's bases from the slots' run lengths (ng: the ghost runs). */
HD_INLINE void grid_tile_bases(grid_tile *t, const unsigned *ng, int dim)
{
    const int ns = dim == 3 ? 27 : 9;
    t->base[0] = 0;
    for (int s = 0; s < ns; ++s) t->base[s + 1] = t->base[s] + t->na[s] + ng[s];
    for (int s = ns; s < 27; ++s) t->base[s + 1] = t->base[ns];
}

/* The store index of the tile's k-th particle (k < base[3^d]). */
HD_INLINE size_t grid_tile_at(const grid_tile *t, unsigned k, int dim)
{
    int lo = 0, hi = dim == 3 ? 27 : 9; /* the slot s with base[s] <= k < base[s + 1] */
    while (hi - lo > 1) {
        const int m = (lo + hi) / 2;
        if (t->base[m] <= k) lo = m;
        else hi = m;
    }
    const unsigned o = k - t->base[lo];
    return o < t->na[lo] ? t->a[lo] + o : t->ga[lo] + (o - t->na[lo]);
}

/* GRID_NBR_CELLS: a lane's walk over i's cells, each cell's owned run
 * [a, b) and ghost run [r, e) merged by rk (grid_list_fill_ranked's
 * order), m the particles within the list's radius met so far. */
typedef struct grid_ex {
    size_t i, a, b, r, e, m;
} grid_ex;
#define GRID_EX_END ((size_t)-1)

HD_INLINE void grid_ex_cell(grid_ex *w, const grid_view *g, size_t cell)
{
    w->a = g->start[cell], w->b = g->end[cell], w->r = w->e = 0;
    if (g->gstart) w->r = g->gstart[cell], w->e = g->gend[cell];
}

/* The lane's next particle in the cell (GRID_EX_END: none): the m-th within
 * the radius, m = lane mod nlanes, as the list's entry m would be. */
HD_INLINE size_t grid_ex_next(grid_ex *w, const grid_view *g, int lane, int nlanes)
{
    for (;;) {
        size_t j;
        if (w->a < w->b && (w->r >= w->e || g->rk[w->a] < g->rk[w->r])) j = w->a++;
        else if (w->r < w->e) j = w->r++;
        else return GRID_EX_END;
        real xij[3];
        if (grid_pair(g->dim, g->xb, w->i, j, xij) >= g->list2) continue;
        if (w->m++ % (size_t)nlanes == (size_t)lane) return j;
    }
}

/* Periodic images (mpi/halo.h) are ghosts whose positions are their
 * owners' moved by a period: the position arrays a refresh sets (NULL where
 * it does not set that array), and the move of ghost i by s (m per axis).
 * The CPU's halo and the GPU's refresh both call it. */
typedef struct grid_image {
    real *x[3];
    preal *xn[3];
    double s[3];
} grid_image;

HD_INLINE void grid_image_move(const grid_image *q, size_t i)
{
    for (int d = 0; d < 3; ++d) {
        if (q->s[d] == 0) continue;
        if (q->x[d]) q->x[d][i] = (real)((double)q->x[d][i] + q->s[d]);
        if (q->xn[d]) q->xn[d][i] += (preal)q->s[d];
    }
}

/* Neighbour list of particle i from the cell scan of g (g->nl NULL): the
 * particles within sqrt(support2), at most cap of them stored, at
 * nl[q * stride + i]. Returns how many there are (stored or not). */
HD_INLINE unsigned grid_list_fill(const grid_view *g, real *const *x, size_t i, real support2, unsigned *nl,
                                  size_t stride, unsigned cap)
{
    unsigned c = 0;
    NBR_BEGIN(g, x, i, j)
        real xij[3];
        if (grid_pair(g->dim, x, i, j, xij) >= support2) continue;
        if (c < cap) nl[(size_t)c * stride + i] = (unsigned)j;
        ++c;
    NBR_END
    return c;
}

/* The CPU's Verlet row of particle i (GRID_NBR_ROWS; src/cpu/nlist.h): the
 * particles within `reach` (reach^2 = list2, past the support by the skin),
 * at most cap of them stored in row. The cells of edge 2h that the ball of
 * radius reach about i touches (its 3^d cells, and where the ball passes
 * their faces, the next ones out: a neighbour within reach may lie two
 * cells away), in ascending cell index, each cell's owned run then its
 * ghost run: the cell scan's order for the particles both meet. Returns
 * how many there are (stored or not). */
HD_INLINE unsigned grid_list_fill_reach(const grid_view *g, real *const *x, size_t i, real reach, real list2,
                                        unsigned *row, unsigned cap)
{
    int c0[3], a[3] = {0, 0, 0}, b[3] = {0, 0, 0};
    grid_cell_coords(g, x[0], x[1], x[2], i, c0);
    const real rm = reach * R(1.000001); /* past the rounding of the cells' bounds */
    for (int d = 0; d < g->dim; ++d) {
        const real xi = x[d][i];
        int lo = (int)floor((double)((xi - rm - g->lo[d]) * g->inv_cell)) - g->off[d];
        int hi = (int)floor((double)((xi + rm - g->lo[d]) * g->inv_cell)) - g->off[d];
        lo = lo > c0[d] - 1 ? c0[d] - 1 : lo, hi = hi < c0[d] + 1 ? c0[d] + 1 : hi;
        a[d] = lo < 0 ? 0 : lo, b[d] = hi >= g->nc[d] ? g->nc[d] - 1 : hi;
    }
    unsigned c = 0;
    for (int cz = a[2]; cz <= b[2]; ++cz)
        for (int cy = a[1]; cy <= b[1]; ++cy)
            for (int cx = a[0]; cx <= b[0]; ++cx) {
                const size_t cell = grid_cell_index(g, cx, cy, cz);
                for (int part = 0; part < (g->gstart ? 2 : 1); ++part) {
                    const size_t s = part ? g->gstart[cell] : g->start[cell], e = part ? g->gend[cell] : g->end[cell];
                    for (size_t j = s; j < e; ++j) {
                        real xij[3];
                        if (grid_pair(g->dim, x, i, j, xij) >= list2) continue;
                        if (c < cap) row[c] = (unsigned)j;
                        ++c;
                    }
                }
            }
    return c;
}

/* grid_list_fill_ranked (below), either form of entry. */
HD_INLINE unsigned grid_list_fill_form(const grid_view *g, real *const *x, size_t i, real support2, unsigned *nl,
                                       unsigned short *nl16, size_t stride, unsigned cap, const unsigned *rk)
{
    int c0[3];
    grid_cell_coords(g, x[0], x[1], x[2], i, c0);
    const int zr = g->dim == 3 ? 1 : 0;
    unsigned c = 0, over = 0;
    for (int s = 0; s < (zr ? 27 : 9); ++s) {
        int cx = c0[0] + s % 3 - 1, cy = c0[1] + (s / 3) % 3 - 1, cz = c0[2] + (zr ? s / 9 - 1 : 0);
        if (cx < 0 || cy < 0 || cz < 0 || cx >= g->nc[0] || cy >= g->nc[1] || cz >= g->nc[2]) continue;
        const size_t cell = grid_cell_index(g, cx, cy, cz);
        const size_t a0 = g->start[cell], na = g->end[cell] - a0;
        size_t a = a0, b = g->end[cell], r = 0, e = 0, r0 = 0;
        if (g->gstart) r0 = r = g->gstart[cell], e = g->gend[cell];
        while (a < b || r < e) {
            const size_t j = r >= e || (a < b && rk[a] < rk[r]) ? a++ : r++;
            real xij[3];
            if (grid_pair(g->dim, x, i, j, xij) >= support2) continue;
            if (c < cap && nl) nl[(size_t)c * stride + i] = (unsigned)j;
            if (c < cap && !nl) {
                const size_t off = j >= a0 && j < a0 + na ? j - a0 : na + (j - r0);
                over |= off > GRID_ENC16_OFF;
                nl16[(size_t)c * stride + i] = (unsigned short)grid_enc16(s, off & GRID_ENC16_OFF);
            }
            ++c;
        }
    }
    return over ? GRID_ENC16_OVER : c;
}

/* grid_list_fill where a cell may hold owned particles and ghosts that
 * must be met in one order (the GPU's lists over cells of 2h + skin, whose
 * lines are not the slabs'; periodic images): each cell's owned run and
 * ghost run, each sorted by rk (the build's key: images last, then the
 * global ID), taken merged by rk, so that the list holds a particle's
 * neighbours in the order of one rank's store whatever the ranks. Entries
 * go to nl, or where nl is NULL to nl16 as grid_enc16 (the same particles;
 * returns GRID_ENC16_OVER where an offset exceeds GRID_ENC16_OFF). */
HD_INLINE unsigned grid_list_fill_ranked(const grid_view *g, real *const *x, size_t i, real support2, unsigned *nl,
                                         size_t stride, unsigned cap, const unsigned *rk)
{
    return grid_list_fill_form(g, x, i, support2, nl, NULL, stride, cap, rk);
}

/* The lattice count in the support for smoothing length h = h_dr * dr:
 * pi (2 h_dr)^2 in 2D, 4/3 pi (2 h_dr)^3 in 3D. */
HD_INLINE double grid_lattice_count(int dim, double h_dr)
{
    double r = 2 * h_dr;
    return dim == 3 ? 4.0 / 3.0 * M_PI * r * r * r : M_PI * r * r;
}

/* A list capacity with 30 % room for compression, rounded up to 8 (48 in 2D,
 * 160 in 3D at h = 1.5 dr): the tests' (tests/test_nbr.c). */
HD_INLINE unsigned grid_list_cap(int dim, double h_dr)
{
    unsigned c = (unsigned)(1.3 * grid_lattice_count(dim, h_dr) + 8);
    return (c + 7) / 8 * 8;
}

/* The list's width to expect (the GPU's form choice, gpu_form_fits; the
 * CPU's fit test, nlist_init): the lattice count with 15 % room, rounded up
 * to 8. The width a build sets is grid_list_width (below): 144 for a lattice
 * count of 131 on the 3D drum, 1.1 of it (one H200, 2026-11-29,
 * tools/bench/drum_rates.sh; docs/gpu.md "Neighbour pass"). */
HD_INLINE unsigned grid_list_est(int dim, double h_dr)
{
    unsigned c = (unsigned)(1.15 * grid_lattice_count(dim, h_dr) + 0.999);
    return (c + 7) / 8 * 8;
}

/* The width a list takes when a build finds `most` entries in its longest
 * row: most + 1/16, rounded up to 8 (the GPU's gpu_list and the CPU's
 * nlist_build; it grows, never shrinks). */
HD_INLINE unsigned grid_list_width(unsigned most) { return (most + most / 16 + 7) / 8 * 8; }

#endif
