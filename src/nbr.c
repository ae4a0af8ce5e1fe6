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

static void nbr_bounds(nbr_grid *g, const particles_t *p, real support)
{
    real lo[3] = {R(DBL_MAX), R(DBL_MAX), R(DBL_MAX)}, hi[3] = {-lo[0], -lo[1], -lo[2]};
    for (size_t i = 0; i < p->n; ++i)
        for (int d = 0; d < p->dim; ++d) {
            if (p->x[d][i] < lo[d]) lo[d] = p->x[d][i];
            if (p->x[d][i] > hi[d]) hi[d] = p->x[d][i];
        }
    g->ncell = grid_fit(&g->view, p->dim, p->n, lo, hi, support);
}

void nbr_build(nbr_grid *g, particles_t *p, real support)
{
    nbr_bounds(g, p, support);
    if (g->ncell > g->cap_cell) {
        g->start = nbr_grow(g->start, g->ncell, sizeof(size_t));
        g->end = nbr_grow(g->end, g->ncell, sizeof(size_t));
        g->count = nbr_grow(g->count, g->ncell + 1, sizeof(size_t));
        g->cap_cell = g->ncell;
    }
    if (p->n > g->cap_part) {
        g->key = nbr_grow(g->key, p->n, sizeof(size_t));
        g->perm = nbr_grow(g->perm, p->n, sizeof(size_t));
        g->cap_part = p->n;
    }
    for (size_t c = 0; c <= g->ncell; ++c) g->count[c] = 0;
    for (size_t i = 0; i < p->n; ++i) {
        int c[3];
        grid_cell_coords(&g->view, p->x[0], p->x[1], p->x[2], i, c);
        g->key[i] = grid_cell_index(&g->view, c[0], c[1], c[2]);
        g->count[g->key[i] + 1]++;
    }
    for (size_t c = 0; c < g->ncell; ++c) g->count[c + 1] += g->count[c];
    for (size_t c = 0; c < g->ncell; ++c) g->start[c] = g->end[c] = g->count[c];
    for (size_t i = 0; i < p->n; ++i) g->perm[g->end[g->key[i]]++] = i;
    part_permute(p, g->perm);
    g->view.start = g->start;
    g->view.end = g->end;
}

void nbr_free(nbr_grid *g)
{
    free(g->start);
    free(g->end);
    free(g->count);
    free(g->key);
    free(g->perm);
    *g = (nbr_grid){0};
}
