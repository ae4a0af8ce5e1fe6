/* nbr.c — cell-linked list with sorting: a counting sort by cell index
 * (stable, O(N + cells)); see nbr.h. */
#include "nbr.h"
#include "error.h"
#include <float.h>
#include <stdlib.h>

static void *nbr_grow(void *ptr, size_t n, size_t size)
{
    void *q = realloc(ptr, (n ? n : 1) * size);
    if (!q) error_exit(1, "out of memory in the neighbour grid (%zu bytes)", n * size);
    return q;
}

static void nbr_bounds(nbr_grid *g, const particles_t *p, real support, const real *origin)
{
    real lo[3] = {R(DBL_MAX), R(DBL_MAX), R(DBL_MAX)}, hi[3] = {-lo[0], -lo[1], -lo[2]};
    size_t n = p->n + p->ng;
    for (size_t i = 0; i < n; ++i)
        for (int d = 0; d < p->dim; ++d) {
            if (p->x[d][i] < lo[d]) lo[d] = p->x[d][i];
            if (p->x[d][i] > hi[d]) hi[d] = p->x[d][i];
        }
    g->ncell = origin ? grid_fit_lattice(&g->view, p->dim, n, origin, lo, hi, support)
                      : grid_fit(&g->view, p->dim, n, lo, hi, support);
}

static void nbr_reserve(nbr_grid *g, size_t n)
{
    if (g->ncell > g->cap_cell) {
        g->start = nbr_grow(g->start, g->ncell, sizeof(size_t));
        g->end = nbr_grow(g->end, g->ncell, sizeof(size_t));
        g->gstart = nbr_grow(g->gstart, g->ncell, sizeof(size_t));
        g->gend = nbr_grow(g->gend, g->ncell, sizeof(size_t));
        g->count = nbr_grow(g->count, g->ncell + 1, sizeof(size_t));
        g->cap_cell = g->ncell;
    }
    if (n > g->cap_part) {
        g->key = nbr_grow(g->key, n, sizeof(size_t));
        g->perm = nbr_grow(g->perm, n, sizeof(size_t));
        g->cap_part = n;
    }
}

/* Counting sort of particles [a, b) by cell into perm[a, b) (stable);
 * start/end of each cell, offset by a. */
static void nbr_sort_range(nbr_grid *g, size_t a, size_t b, size_t *start, size_t *end)
{
    for (size_t c = 0; c <= g->ncell; ++c) g->count[c] = 0;
    for (size_t i = a; i < b; ++i) g->count[g->key[i] + 1]++;
    g->count[0] = a;
    for (size_t c = 0; c < g->ncell; ++c) g->count[c + 1] += g->count[c];
    for (size_t c = 0; c < g->ncell; ++c) start[c] = end[c] = g->count[c];
    for (size_t i = a; i < b; ++i) g->perm[end[g->key[i]]++] = i;
}

void nbr_build(nbr_grid *g, particles_t *p, real support, const real *origin)
{
    size_t n = p->n + p->ng;
    nbr_bounds(g, p, support, origin);
    nbr_reserve(g, n);
    for (size_t i = 0; i < n; ++i) {
        int c[3];
        grid_cell_coords(&g->view, p->x[0], p->x[1], p->x[2], i, c);
        g->key[i] = grid_cell_index(&g->view, c[0], c[1], c[2]);
    }
    nbr_sort_range(g, 0, p->n, g->start, g->end);
    if (p->ng) nbr_sort_range(g, p->n, n, g->gstart, g->gend);
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
    free(g->count);
    free(g->key);
    free(g->perm);
    *g = (nbr_grid){0};
}
