/* bound.c — the two-stage boundary-particle search of paper §4.2.2 on the
 * CPU: stage 1 types the cells of edge 2h by their material content (outer:
 * a neighbour cell is empty; second: next to an outer cell; inner: the rest);
 * stage 2 runs the umbrella test (4.19) only in outer cells and the vicinity
 * test (4.20) only in outer and second cells. Loop bodies: physics/bound_kern.h. */
#include "bound.h"
#include "error.h"
#include <stdlib.h>

static void *bound_grow(void *ptr, size_t n, size_t size)
{
    void *q = realloc(ptr, (n ? n : 1) * size);
    if (!q) error_exit(1, "out of memory in the boundary search");
    return q;
}

/* Does any of the 3^d cells around (cx,cy,cz) satisfy pred? Cells outside
 * the grid count as empty. */
static int bound_any_neighbour(const grid_view *v, const unsigned char *type,
                               const size_t *mat, int cx, int cy, int cz, int want_outer)
{
    int zr = v->dim == 3 ? 1 : 0;
    for (int dz = -zr; dz <= zr; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                int x = cx + dx, y = cy + dy, z = cz + dz;
                int out = x < 0 || y < 0 || z < 0 || x >= v->nc[0] || y >= v->nc[1] || z >= v->nc[2];
                if (want_outer) {
                    if (!out && type[grid_cell_index(v, x, y, z)] == CELL_OUTER) return 1;
                } else if (out || mat[grid_cell_index(v, x, y, z)] == 0) {
                    return 1;
                }
            }
    return 0;
}

static void bound_cell_types(bound_work *w, const particles_t *p, const nbr_grid *g)
{
    const grid_view *v = &g->view;
    for (size_t c = 0; c < g->ncell; ++c) {
        w->cell_mat[c] = 0;
        for (size_t i = g->start[c]; i < g->end[c]; ++i) w->cell_mat[c] += p->kind[i] == KIND_MATERIAL;
    }
    for (int pass = 0; pass < 2; ++pass)
        for (int z = 0; z < v->nc[2]; ++z)
            for (int y = 0; y < v->nc[1]; ++y)
                for (int x = 0; x < v->nc[0]; ++x) {
                    size_t c = grid_cell_index(v, x, y, z);
                    if (pass == 0)
                        w->cell_type[c] = w->cell_mat[c] == 0 ? CELL_EMPTY
                                          : bound_any_neighbour(v, w->cell_type, w->cell_mat, x, y, z, 0)
                                              ? CELL_OUTER : CELL_INNER;
                    else if (w->cell_type[c] == CELL_INNER &&
                             bound_any_neighbour(v, w->cell_type, w->cell_mat, x, y, z, 1))
                        w->cell_type[c] = CELL_SECOND;
                }
}

static void bound_reserve(bound_work *w, const particles_t *p, const nbr_grid *g)
{
    if (g->ncell > w->cap_cell) {
        w->cell_type = bound_grow(w->cell_type, g->ncell, 1);
        w->cell_mat = bound_grow(w->cell_mat, g->ncell, sizeof(size_t));
        w->cap_cell = g->ncell;
    }
    if (p->n > w->cap_part) {
        w->sums = bound_grow(w->sums, p->n, sizeof(bound_sums));
        w->cls = bound_grow(w->cls, p->n, 1);
        w->cap_part = p->n;
    }
}

static unsigned char bound_cell_of(const bound_work *w, const particles_t *p, const nbr_grid *g, size_t i)
{
    int c[3];
    grid_cell_coords(&g->view, p->x[0], p->x[1], p->x[2], i, c);
    return w->cell_type[grid_cell_index(&g->view, c[0], c[1], c[2])];
}

void bound_classify(bound_work *w, particles_t *p, const nbr_grid *g, const sph_ctx *k)
{
    bound_reserve(w, p, g);
    bound_cell_types(w, p, g);
    const long n = (long)p->n;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) {
        w->sums[i] = bound_gather((size_t)i, p, &g->view, k);
        unsigned char ct = bound_cell_of(w, p, g, (size_t)i);
        int cls = BC_INTERIOR;
        if (p->kind[i] == KIND_DUMMY)
            cls = BC_DUMMY;
        else if (ct == CELL_OUTER)
            cls = bound_surface_class((size_t)i, p, &g->view, k, &w->sums[i]);
        p->bclass[i] = (uint8_t)cls;
    }
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) {
        real nf[3] = {0, 0, 0};
        int cls = p->bclass[i];
        if (cls == BC_INTERIOR) {
            unsigned char ct = bound_cell_of(w, p, g, (size_t)i);
            int near = ct != CELL_INNER && bound_near_free((size_t)i, p, &g->view, k, nf);
            cls = near ? BC_FREE_VICINITY : (w->sums[i].ndummy > 0 ? BC_WALL_VICINITY : BC_INTERIOR);
        }
        real n3[3], psi;
        bound_normal_psi(cls, &w->sums[i], nf, k, n3, &psi);
        for (int d = 0; d < 3; ++d) p->nrm[d][i] = n3[d];
        p->psi[i] = psi;
        w->cls[i] = (uint8_t)cls; /* p->bclass is still read by neighbours */
    }
    for (int c = 0; c < 6; ++c) w->count[c] = 0;
    for (long i = 0; i < n; ++i) {
        p->bclass[i] = w->cls[i];
        w->count[w->cls[i]]++;
    }
}

void bound_free(bound_work *w)
{
    free(w->cell_type);
    free(w->cell_mat);
    free(w->sums);
    free(w->cls);
    *w = (bound_work){0};
}
