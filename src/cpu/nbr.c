/* nbr.c — cell-linked list with sorting: a counting sort by cell index
 * (stable, O(N + cells)), then each cell's run in a canonical order, periodic
 * images last, each part by global particle ID (an insertion sort of runs
 * that the last build left nearly in order; nbr.h says why). Every pass runs
 * on all threads: a
 * min/max reduction for the bounding box, per-thread histograms of
 * contiguous index chunks for the sort (chunk t's particles of a cell go
 * after chunk t-1's, so the order is the serial stable sort's whatever the
 * thread count), and part_permute over particles. */
#include "nbr.h"
#include "core/error.h"
#include <float.h>
#include <stdlib.h>
#include <string.h>
#include "core/omp_shim.h"

/* Below this many particles a build runs on one thread (the fork costs
 * more than the work); the result is the same. */
#define NBR_PAR_MIN 4096

static void *nbr_grow(void *ptr, size_t n, size_t size)
{
    void *q = realloc(ptr, (n ? n : 1) * size);
    if (!q) error_exit(1, "out of memory in the neighbour grid (%zu bytes)", n * size);
    return q;
}

static void nbr_bounds(nbr_grid *g, const particles_t *p, real support, const real *origin)
{
    real lo[3] = {R(DBL_MAX), R(DBL_MAX), R(DBL_MAX)}, hi[3] = {-lo[0], -lo[1], -lo[2]};
    const long n = (long)(p->n + p->ng);
    const int dim = p->dim;
    /* min and max are exact: any split gives the serial box */
#pragma omp parallel for schedule(static) reduction(min : lo[:3]) reduction(max : hi[:3]) if (n >= NBR_PAR_MIN)
    for (long i = 0; i < n; ++i)
        for (int d = 0; d < dim; ++d) {
            if (p->x[d][i] < lo[d]) lo[d] = p->x[d][i];
            if (p->x[d][i] > hi[d]) hi[d] = p->x[d][i];
        }
    g->ncell = origin ? grid_fit_lattice(&g->view, p->dim, (size_t)n, origin, lo, hi, support)
                      : grid_fit(&g->view, p->dim, (size_t)n, lo, hi, support);
}

static void nbr_reserve(nbr_grid *g, size_t n)
{
    if (g->ncell > g->cap_cell) {
        g->start = nbr_grow(g->start, g->ncell, sizeof(size_t));
        g->end = nbr_grow(g->end, g->ncell, sizeof(size_t));
        g->gstart = nbr_grow(g->gstart, g->ncell, sizeof(size_t));
        g->gend = nbr_grow(g->gend, g->ncell, sizeof(size_t));
        g->cap_cell = g->ncell;
    }
    size_t nt = (size_t)omp_get_max_threads(), nh = nt * g->ncell;
    if (nh > g->cap_hist) {
        g->hist = nbr_grow(g->hist, nh, sizeof(size_t));
        g->cap_hist = nh;
    }
    g->nthread = (int)nt;
    if (n > g->cap_part) {
        g->key = nbr_grow(g->key, n, sizeof(size_t));
        g->rank = nbr_grow(g->rank, n, sizeof(uint64_t));
        g->perm = nbr_grow(g->perm, n, sizeof(size_t));
        g->cap_part = n;
    }
}

/* Counting sort of particles [a, b) by cell into perm[a, b) (stable);
 * start/end of each cell, offset by a. Called by every thread of the
 * enclosing parallel region: thread t counts, then places, the chunk
 * [a + (b-a)t/T, a + (b-a)(t+1)/T) with its own row of g->hist. */
static void nbr_sort_range(nbr_grid *g, size_t a, size_t b, size_t *start, size_t *end)
{
    const size_t T = (size_t)omp_get_num_threads(), t = (size_t)omp_get_thread_num(), nc = g->ncell;
    const size_t i0 = a + (b - a) * t / T, i1 = a + (b - a) * (t + 1) / T;
    size_t *h = g->hist + t * nc;
    memset(h, 0, nc * sizeof *h);
    for (size_t i = i0; i < i1; ++i) h[g->key[i]]++;
#pragma omp barrier
    /* cell sizes, then their offsets (one thread: O(cells)), then each
     * thread's place in each cell: chunk order within the cell */
#pragma omp for schedule(static)
    for (size_t c = 0; c < nc; ++c) {
        size_t m = 0;
        for (size_t u = 0; u < T; ++u) m += g->hist[u * nc + c];
        end[c] = m;
    }
#pragma omp single
    for (size_t c = 0, at = a; c < nc; ++c) start[c] = at, at += end[c];
#pragma omp for schedule(static)
    for (size_t c = 0; c < nc; ++c) {
        size_t at = start[c];
        for (size_t u = 0; u < T; ++u) {
            size_t m = g->hist[u * nc + c];
            g->hist[u * nc + c] = at;
            at += m;
        }
        end[c] = at;
    }
    for (size_t i = i0; i < i1; ++i) g->perm[h[g->key[i]]++] = i;
#pragma omp barrier
    /* each cell's run by its rank in the cell (nbr_rank); an insertion sort: the
     * runs are short and, the store sorted at the last build, nearly in order */
    const uint64_t *rk = g->rank;
#pragma omp for schedule(static)
    for (size_t c = 0; c < nc; ++c)
        for (size_t k = start[c] + 1; k < end[c]; ++k) {
            const size_t v = g->perm[k];
            const uint64_t r = rk[v];
            size_t m = k;
            for (; m > start[c] && rk[g->perm[m - 1]] > r; --m) g->perm[m] = g->perm[m - 1];
            g->perm[m] = v;
        }
}

/* The rank of particle i in its cell: its global ID, with bit 62 set for a
 * periodic image (a position outside the period along a periodic axis:
 * owned particles are wrapped into it, images lie beyond it). */
static uint64_t nbr_rank(const nbr_grid *g, const particles_t *p, size_t i)
{
    uint64_t img = 0;
    for (int d = 0; d < p->dim; ++d)
        if (g->per >> d & 1) {
            const double x = (double)p->x[d][i];
            img |= x < g->plo[d] || x >= g->plo[d] + g->plen[d];
        }
    return (uint64_t)p->id[i] | img << 62;
}

void nbr_set_period(nbr_grid *g, int mask, const real lo[3], const real len[3])
{
    g->per = mask;
    for (int d = 0; d < 3; ++d) g->plo[d] = (double)lo[d], g->plen[d] = (double)len[d];
}

void nbr_build(nbr_grid *g, particles_t *p, real support, const real *origin)
{
    size_t n = p->n + p->ng;
    nbr_bounds(g, p, support, origin);
    nbr_reserve(g, n);
    const long nl = (long)n;
#pragma omp parallel num_threads(g->nthread) if (n >= NBR_PAR_MIN)
    {
#pragma omp for schedule(static)
        for (long i = 0; i < nl; ++i) {
            int c[3];
            grid_cell_coords(&g->view, p->x[0], p->x[1], p->x[2], (size_t)i, c);
            g->key[i] = grid_cell_index(&g->view, c[0], c[1], c[2]);
            g->rank[i] = nbr_rank(g, p, (size_t)i);
        }
        nbr_sort_range(g, 0, p->n, g->start, g->end);
        if (p->ng) nbr_sort_range(g, p->n, n, g->gstart, g->gend);
    }
    part_permute(p, g->perm);
    g->view.start = g->start;
    g->view.end = g->end;
    g->view.gstart = p->ng ? g->gstart : NULL;
    g->view.gend = p->ng ? g->gend : NULL;
}

void nbr_free(nbr_grid *g)
{
    free(g->start);
    free(g->end);
    free(g->gstart);
    free(g->gend);
    free(g->hist);
    free(g->key);
    free(g->rank);
    free(g->perm);
    *g = (nbr_grid){0};
}
