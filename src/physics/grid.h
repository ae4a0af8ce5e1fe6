/* grid.h — the cell-linked list with sorting (paper §3.4, Green 2010), as a
 * plain view usable from host and device code: particles are sorted by cell,
 * so each cell is the index range [start[c], end[c]). Cell edge >= 2h. */
#ifndef SPHSEG_GRID_H
#define SPHSEG_GRID_H
#include <stddef.h>
#include "hd.h"

typedef struct grid_view {
    int dim;
    real lo[3];     /* lower corner of the grid, m */
    real inv_cell;  /* 1 / cell edge, 1/m */
    int nc[3];      /* cells per axis (nc[2] = 1 in 2D) */
    const size_t *start, *end;
} grid_view;

/* Cell coordinates of position x, clamped into the grid. */
HD_INLINE void grid_cell_coords(const grid_view *g, const real *x0, const real *x1,
                                const real *x2, size_t i, int c[3])
{
    real x[3] = {x0[i], x1[i], g->dim == 3 ? x2[i] : g->lo[2]};
    for (int d = 0; d < 3; ++d) {
        int k = (int)((x[d] - g->lo[d]) * g->inv_cell);
        c[d] = k < 0 ? 0 : (k >= g->nc[d] ? g->nc[d] - 1 : k);
    }
}

HD_INLINE size_t grid_cell_index(const grid_view *g, int cx, int cy, int cz)
{
    return ((size_t)cz * (size_t)g->nc[1] + (size_t)cy) * (size_t)g->nc[0] + (size_t)cx;
}

/* Loop over every particle j in the 3^d cells around particle i (j == i
 * included; callers skip it where the formula excludes self). */
#define NBR_BEGIN(g, x, i, j)                                                          \
    {                                                                                  \
        int c0_[3];                                                                    \
        grid_cell_coords((g), (x)[0], (x)[1], (x)[2], (i), c0_);                       \
        int zr_ = (g)->dim == 3 ? 1 : 0;                                               \
        for (int dz_ = -zr_; dz_ <= zr_; ++dz_)                                        \
            for (int dy_ = -1; dy_ <= 1; ++dy_)                                        \
                for (int dx_ = -1; dx_ <= 1; ++dx_) {                                  \
                    int cx_ = c0_[0] + dx_, cy_ = c0_[1] + dy_, cz_ = c0_[2] + dz_;    \
                    if (cx_ < 0 || cy_ < 0 || cz_ < 0 || cx_ >= (g)->nc[0] ||          \
                        cy_ >= (g)->nc[1] || cz_ >= (g)->nc[2])                        \
                        continue;                                                      \
                    size_t cell_ = grid_cell_index((g), cx_, cy_, cz_);                \
                    for (size_t j = (g)->start[cell_]; j < (g)->end[cell_]; ++j) {

#define NBR_END                                                                        \
                    }                                                                  \
                }                                                                      \
    }

/* Pair geometry: x_ij = x_i - x_j and r^2. */
HD_INLINE real grid_pair(int dim, real *const *x, size_t i, size_t j, real xij[3])
{
    xij[0] = x[0][i] - x[0][j];
    xij[1] = x[1][i] - x[1][j];
    xij[2] = dim == 3 ? x[2][i] - x[2][j] : R(0.0);
    return xij[0] * xij[0] + xij[1] * xij[1] + xij[2] * xij[2];
}

#endif
