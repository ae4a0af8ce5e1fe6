/* decomp.h — setting up a run's domain decomposition (DESIGN.md "Parallel
 * model"): the halo of a multi-rank run, or of one rank with periodic axes,
 * made from plain settings (the caller reads them from the scene, the stage
 * table and the backend), cut afresh or taken over from a checkpoint, and
 * reported in one log line. */
#ifndef SPHSEG_DECOMP_H
#define SPHSEG_DECOMP_H
#include "halo.h"

/* What the decomposition is made from. */
typedef struct decomp_config {
    int dim;
    real support;       /* lattice cell edge 2h, m */
    int method, axis;   /* HALO_SLABS | HALO_METIS; slab axis 0, 1, 2 or -1 (the longest) */
    int depth;          /* ghost depth in lattice cells (the backend's) */
    const int *arr;     /* the arrays a ghost carries */
    int narr;
    int periodic;       /* bit d: axis d periodic, with the period [0, period[d]) */
    real period[3];
    const char *backend; /* its name, for the log */
} decomp_config;

/* A checkpoint's decomposition (its rank count is this run's). */
typedef struct decomp_saved {
    int method, axis, blk, cg[3];
    const long *bound;
    const int *part;
} decomp_saved;

/* Collective. A halo for c over the particles p, which every rank holds an
 * even share of (or, restarting on the checkpoint's rank count, its own
 * block): saved (may be NULL) is taken over when its method is c's and,
 * for METIS, its coarse cells are as wide as c's ghost depth needs (else
 * the domain is cut again: the run continues to round-off, not bit for
 * bit, and the log says so); otherwise halo_decompose cuts it and sends
 * every particle to its owner. The decomposition is logged. Returns the
 * halo (malloc'd; halo_free then free). */
halo_t *decomp_start(const decomp_config *c, const decomp_saved *saved, particles_t *p);

#endif
