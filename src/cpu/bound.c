/* bound.c — the two-stage boundary-particle search of paper §4.2.2 on the
 * CPU: stage 1 types the cells of edge 2h by their material content (outer:
 * a neighbour cell is empty; second: next to an outer cell; inner: the rest);
 * stage 2 runs the umbrella test (4.19) only in outer cells and the vicinity
 * test (4.20) only in outer and second cells. Loop bodies: physics/bound_kern.h. */
#include "bound.h"
#include "core/error.h"
#include <stdlib.h>

/* Particles per dynamic chunk of the two sweeps: their cost depends on the
 * cell type (only outer cells run the umbrella test), so static slices of
 * the cell-sorted store would not balance. */
#define BOUND_CHUNK 32

static void *bound_grow(void *ptr, size_t n, size_t size)
{
    void *q = realloc(ptr, (n ? n : 1) * size);
    if (!q) error_exit(1, "out of memory in the boundary search");
    return q;
}

/* Stage 1, each sweep parallel over cells (pass 1 reads only CELL_OUTER,
 * which it never writes: bound_cell_type). */
static void bound_cell_types(bound_work *w, const particles_t *p, const nbr_grid *g)
{
    const grid_view *v = &g->view;
    const long nc = (long)g->ncell;
#pragma omp parallel
    {
#pragma omp for schedule(static)
        for (long c = 0; c < nc; ++c) w->cell_mat[c] = bound_cell_material(v, p, (size_t)c);
        for (int pass = 0; pass < 2; ++pass) {
#pragma omp for schedule(static)
            for (long c = 0; c < nc; ++c)
                w->cell_type[c] = bound_cell_type(v, w->cell_type, w->cell_mat, (size_t)c, pass);
        }
    }
}

static void bound_reserve(bound_work *w, const particles_t *p, const nbr_grid *g)
{
    if (g->ncell > w->cap_cell) {
        w->cell_type = bound_grow(w->cell_type, g->ncell, 1);
        w->cell_mat = bound_grow(w->cell_mat, g->ncell, sizeof(size_t));
        w->cap_cell = g->ncell;
    }
    if (p->n + p->ng > w->cap_part) {
        w->sums = bound_grow(w->sums, p->n + p->ng, sizeof(bound_sums));
        w->cls = bound_grow(w->cls, p->n + p->ng, 1);
        w->cap_part = p->n + p->ng;
    }
}

void bound_classify(bound_work *w, particles_t *p, const nbr_grid *g, const sph_ctx *k)
{
    bound_reserve(w, p, g);
    bound_cell_types(w, p, g);
    const long n = (long)(p->n + p->ng), no = (long)p->n; /* ghosts too: owned particles read their classes */
    size_t count[6] = {0};
#pragma omp parallel
    {
#pragma omp for schedule(dynamic, BOUND_CHUNK)
        for (long i = 0; i < n; ++i)
            p->bclass[i] = (uint8_t)bound_class_first((size_t)i, p, &g->view, k, w->cell_type, &w->sums[i]);
#pragma omp for schedule(dynamic, BOUND_CHUNK)
        for (long i = 0; i < n; ++i) /* p->bclass is still read by neighbours */
            w->cls[i] = (uint8_t)bound_class_second((size_t)i, p, &g->view, k, w->cell_type, &w->sums[i]);
#pragma omp for schedule(static) reduction(+ : count[:6])
        for (long i = 0; i < n; ++i) {
            p->bclass[i] = w->cls[i];
            if (i < no) count[w->cls[i]]++;
        }
    }
    for (int c = 0; c < 6; ++c) w->count[c] = count[c];
}

void bound_free(bound_work *w)
{
    free(w->cell_type);
    free(w->cell_mat);
    free(w->sums);
    free(w->cls);
    *w = (bound_work){0};
}
