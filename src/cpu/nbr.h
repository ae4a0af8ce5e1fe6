/* nbr.h — building the cell-linked list with sorting (paper §3.4) on the
 * host: bin particles into cells of edge >= 2h, sort the store by cell. */
#ifndef SPHSEG_NBR_H
#define SPHSEG_NBR_H
#include "core/particles.h"
#include "physics/grid.h"

typedef struct nbr_grid {
    grid_view view;
    size_t *start, *end;   /* ncell each: owned particles of each cell */
    size_t *gstart, *gend; /* ncell each: ghosts of each cell (p->ng > 0) */
    size_t ncell, cap_cell;
    size_t *key, *perm;    /* scratch: n each */
    uint64_t *rank;        /* scratch: n, each particle's rank in its cell (nbr.c nbr_rank) */
    int per;               /* periodic axes (bit d; nbr_set_period), 0: none */
    double plo[3], plen[3]; /* the period along them: [plo, plo + plen) */
    size_t *hist;          /* scratch: a row of ncell per thread (the parallel counting sort) */
    size_t cap_part, cap_hist;
    int nthread;           /* threads the last build sized hist for */
} nbr_grid;

/* Bin all particles of p into cells of edge `support` (2h) covering their
 * bounding box, and permute p so that each cell's particles are contiguous:
 * the owned particles [0, n) and the ghosts [n, n + ng) each sorted by cell
 * in their own range, and each cell's particles in a canonical order:
 * periodic images last (nbr_set_period), each part in global ID order. A
 * cell is owned by one rank whole (slab bounds and METIS coarse cells are
 * lattice lines), so it holds owned particles or ghosts alone, but a cell
 * cut by a period's end, which holds owned particles (inside the period)
 * and images (beyond it): the cell's store order, owned then ghosts, is
 * then the canonical order on any rank count, and a particle's neighbours
 * are summed in the one-rank order (issue 55). origin NULL: the grid starts at the particles' lower
 * corner (one rank); otherwise the grid is cut from the global lattice that
 * starts at origin (grid_fit_lattice; mpi/halo.h gives it). g->perm[k] is
 * then the old index of the particle now at k. */
void nbr_build(nbr_grid *g, particles_t *p, real support, const real *origin);
void nbr_free(nbr_grid *g);
/* The periodic axes (bit d of mask) and their periods [lo, lo + len) that
 * tell images from the rest (mpi/halo.h); 0 (the default): none. */
void nbr_set_period(nbr_grid *g, int mask, const real lo[3], const real len[3]);

#endif
