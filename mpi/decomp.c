/* decomp.c — setting up a run's domain decomposition (see decomp.h). */
#include "decomp.h"
#include <mpi.h>
#include <stdlib.h>
#include "../src/core/error.h"

/* One log line: the cut, the particles per rank, the ghosts, the periods. */
static void decomp_report(const halo_t *h, const particles_t *p)
{
    long long nmin = (long long)p->n, nmax = nmin;
    int nbmax = h->nnb;
    MPICHECK(MPI_Allreduce(MPI_IN_PLACE, &nmin, 1, MPI_LONG_LONG, MPI_MIN, MPI_COMM_WORLD));
    MPICHECK(MPI_Allreduce(MPI_IN_PLACE, &nmax, 1, MPI_LONG_LONG, MPI_MAX, MPI_COMM_WORLD));
    MPICHECK(MPI_Allreduce(MPI_IN_PLACE, &nbmax, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD));
    if (h->method == HALO_METIS)
        message("METIS decomposition over %d ranks (coarse cells of %d x 2h): %lld to %lld particles per rank, up "
                "to %d neighbours, ghosts %d cells of 2h deep", h->size, h->blk, nmin, nmax, nbmax, h->depth);
    else if (h->size > 1)
        message("slab decomposition along %c over %d ranks: %lld to %lld particles per rank, ghosts %d cells "
                "of 2h deep", "xyz"[h->axis], h->size, nmin, nmax, h->depth);
    if (h->per)
        message("periodic along %s%s%s: images %d cells of 2h deep across each period boundary, %d channel(s) on "
                "the busiest rank", h->per & 1 ? "x" : "", h->per & 2 ? "y" : "", h->per & 4 ? "z" : "", h->depth,
                nbmax);
}

halo_t *decomp_start(const decomp_config *c, const decomp_saved *saved, particles_t *p)
{
    halo_t *h = malloc(sizeof *h);
    if (!h) error_exit(1, "out of memory");
    halo_init(h, c->dim, c->support, c->method, c->axis, c->arr, c->narr);
    halo_set_depth(h, c->depth);
    if (c->periodic) { /* the periods are the container's, whole dr (setup_contexts) */
        const real lo[3] = {0, 0, 0};
        halo_set_periodic(h, c->periodic, lo, c->period);
    }
    /* METIS parts are coarse cells as wide as the ghost depth: a cut saved
     * with other coarse cells (a backend with another depth) is re-made, and
     * the run continues to round-off rather than bit for bit */
    int take = saved && saved->method == c->method;
    if (take && c->method == HALO_METIS && saved->blk != h->blk) {
        message("restart: the saved METIS parts are of coarse cells %d lattice cells wide, backend %s needs %d "
                "(its ghost depth): partitioning again", saved->blk, c->backend, h->blk);
        take = 0;
    }
    if (take)
        halo_restore(h, c->method, saved->axis, saved->bound, saved->cg, saved->part);
    else
        halo_decompose(h, p);
    decomp_report(h, p);
    return h;
}
