/* nlist.c — the CPU backend's Verlet neighbour list (nlist.h): its build
 * from the cell scan, the skin test, and the rows following each sort. */
#include "nlist.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "core/error.h"
#include "core/omp_shim.h"
#include "core/tuning.h"
#include "physics/flow.h"

/* Rows per dynamic chunk of a build (a 3D particle scans about 730 candidates). */
#define NLIST_CHUNK 64

static size_t nlist_row_bytes(unsigned cap) { return 2 * ((size_t)cap + 1) * sizeof(unsigned); }

/* Bytes a particle of rows of cap entries: the rows, counts, build
 * positions (each twice: the sort moves them into their spares) and the
 * inverse permutation. */
static size_t nlist_part_bytes(unsigned cap) { return nlist_row_bytes(cap) + 6 * sizeof(real) + sizeof(unsigned) + 2; }

size_t nlist_bytes(const nlist *L) { return L->on ? nlist_part_bytes(L->cap) : 0; }

/* Free memory of this machine now, bytes (the physical memory where the
 * system does not say). */
static double nlist_free_memory(void)
{
#ifdef _SC_AVPHYS_PAGES
    long pages = sysconf(_SC_AVPHYS_PAGES);
#else
    long pages = sysconf(_SC_PHYS_PAGES);
#endif
    return (double)pages * (double)sysconf(_SC_PAGESIZE);
}

void nlist_init(nlist *L, const particles_t *p, double h, double dr, double skin_h)
{
    *L = (nlist){0};
    L->skin = skin_h * h;
    const double sup = 2 * h + L->skin;
    L->list2 = sup * sup;
    const unsigned est = grid_list_est(p->dim, (1 + 0.5 * skin_h) * h / dr); /* the fit test's width */
    L->cap = 0; /* the first build counts and sizes the rows (nlist_build), as the GPU's list */
    const int want = tuning_get()->cpu_nbr; /* 0 list (the default), 2 cells */
    if (want < 0) error_exit(2, "SPHSEG_CPU_NBR=%s: expected list or cells", tuning_get()->cpu_nbr_text);
    L->on = want == 0;
    const double need = (double)(p->n + p->ng) * (double)nlist_part_bytes(est), have = nlist_free_memory();
    const char *why = want ? "SPHSEG_CPU_NBR=cells" : "";
    if (L->on && need > 0.5 * have) L->on = 0, why = "the list would not fit in half the free memory";
    if (L->on && 2.0 * (double)(p->n + p->ng) >= 4294967295.0) L->on = 0, why = "4-byte entries: too many particles";
    if (L->on)
        message("cpu: neighbour pass: Verlet list within 2h + %.3g h (%s), about %u entries a particle "
                "(sized at the first build), %.1f MiB", skin_h,
                skin_h == NLIST_SKIN_FRESH ? "built at every prepare: a halo's, no skin" : "Run:list_skin", est,
                need / 1048576.0);
    else
        message("cpu: neighbour pass: the cells (%s; the list would take %.1f MiB, %.1f MiB free)", why,
                need / 1048576.0, have / 1048576.0);
}

static void *nlist_grow(void *ptr, size_t n, size_t size)
{
    void *q = realloc(ptr, (n ? n : 1) * size);
    if (!q) error_exit(1, "out of memory in the neighbour list (%zu bytes; SPHSEG_CPU_NBR=cells scans the cells)",
                       n * size);
    return q;
}

/* Room for n particles (a little more: the ghosts of several ranks vary);
 * rows: the rows of L->cap entries too. Contents are lost where they grow. */
static void nlist_reserve(nlist *L, size_t n, int rows)
{
    if (n > L->cap_part) {
        const size_t m = L->cap_part = n + n / 8;
        L->cnt = nlist_grow(L->cnt, m, sizeof(unsigned));
        L->cnt2 = nlist_grow(L->cnt2, m, sizeof(unsigned));
        L->inv = nlist_grow(L->inv, m, sizeof(unsigned));
        L->wact = nlist_grow(L->wact, m, 1);
        L->wact2 = nlist_grow(L->wact2, m, 1);
        for (int d = 0; d < 3; ++d) {
            L->xb[d] = nlist_grow(L->xb[d], m, sizeof(real));
            L->xb2[d] = nlist_grow(L->xb2[d], m, sizeof(real));
        }
        rows = 1;
    }
    if (rows) {
        L->nl = nlist_grow(L->nl, L->cap_part * L->cap, sizeof(unsigned));
        L->nl2 = nlist_grow(L->nl2, L->cap_part * L->cap, sizeof(unsigned));
    }
}

/* v as the rows of L (GRID_NBR_ROWS, nlist.h). */
static void nlist_view(const nlist *L, grid_view *v)
{
    v->form = GRID_NBR_ROWS;
    v->nl = L->nl, v->ncnt = L->cnt;
    v->nl_stride = L->cap, v->nl_cap = L->cap;
}

/* Every row from the cells of g (grid_list_fill_reach), at the positions
 * now; a row too short for the densest particle grows the rows to its
 * count + 1/16, rounded up to 8 (the GPU's rule, gpu_list), and the build
 * runs again: the first build, with rows of 0, counts and sizes them. */
static void nlist_build(nlist *L, const nbr_grid *g, particles_t *p)
{
    const size_t nt = p->n + p->ng;
    const grid_view *vc = &g->view;
    const real l2 = (real)L->list2, reach = (real)sqrt(L->list2);
    nlist_reserve(L, nt, L->nl == NULL);
    for (;;) {
        unsigned most = 0, *nl = L->nl, *cnt = L->cnt;
        const size_t cap = L->cap;
#pragma omp parallel for schedule(dynamic, NLIST_CHUNK) reduction(max : most)
        for (long i = 0; i < (long)nt; ++i) {
            cnt[i] = grid_list_fill_reach(vc, p->x, (size_t)i, reach, l2, nl + (size_t)i * cap, (unsigned)cap);
            most = cnt[i] > most ? cnt[i] : most;
        }
        if (most <= L->cap) break;
        L->cap = grid_list_width(most);
        nlist_reserve(L, nt, 1);
    }
    grid_view rv = *vc; /* the dummies whose wall loop is due until the next build (the skin) */
    nlist_view(L, &rv);
    unsigned char *wa = L->wact;
#pragma omp parallel for schedule(dynamic, NLIST_CHUNK)
    for (long i = 0; i < (long)nt; ++i) wa[i] = p->kind[i] == KIND_DUMMY && flow_wall_reached((size_t)i, p, &rv);
    for (int d = 0; d < p->dim; ++d) memcpy(L->xb[d], p->x[d], nt * sizeof(real));
    L->n = nt;
    L->valid = 1;
    L->builds++;
}

/* Has one of particles [0, n) moved skin/2 since the build? perm: the
 * sort's (the old index now at k; xb by old index), or NULL before a sort
 * (xb by the index now). */
static int nlist_moved(const nlist *L, const particles_t *p, const size_t *perm, size_t n)
{
    const double lim = 0.25 * (1 - 1e-6) * L->skin * L->skin; /* a hair inside skin/2: rounding */
    const long nt = (long)n;
    const int dim = p->dim;
    int moved = 0;
#pragma omp parallel for schedule(static) reduction(max : moved)
    for (long k = 0; k < nt; ++k) {
        const size_t o = perm ? perm[k] : (size_t)k;
        double d2 = 0;
        for (int d = 0; d < dim; ++d) {
            const double dx = (double)p->x[d][k] - (double)L->xb[d][o];
            d2 += dx * dx;
        }
        if (d2 > lim) moved = 1;
    }
    return moved;
}

/* Does j (old index, of the sort g made) come after i in the cell scan of
 * a store whose owned and ghost particles share cells: by cell, then by
 * the rank within it (nbr.c: periodic image last, global ID). */
static int nlist_after(const nbr_grid *g, unsigned j, unsigned i)
{
    return g->key[j] != g->key[i] ? g->key[j] > g->key[i] : g->rank[j] > g->rank[i];
}

/* The rows follow the sort: row k is the old row of perm[k], its entries
 * renamed to the new indices and put in ascending order (the cell scan's
 * order where there are no ghosts: nlist.h), by an insertion sort (a sort
 * moves few particles past each other). With ghosts kept (n_owned < L->n),
 * a row's owned entries and its ghost entries, each ascending, are then
 * merged by cell and rank (nlist_after): a particle that moved across a
 * slab bound since the exchange shares its cell with particles of the
 * other kind, and the one-rank run meets that cell's particles by rank. */
static void nlist_follow(nlist *L, const nbr_grid *g, int dim, size_t n_owned)
{
    const size_t *perm = g->perm;
    const long nt = (long)L->n;
    const size_t cap = L->cap;
    unsigned *inv = L->inv, *src = L->nl, *dst = L->nl2, *cnt = L->cnt, *cnt2 = L->cnt2;
#pragma omp parallel
    {
#pragma omp for schedule(static)
        for (long k = 0; k < nt; ++k) inv[perm[k]] = (unsigned)k;
#pragma omp for schedule(static)
        for (long k = 0; k < nt; ++k) {
            const size_t o = perm[k];
            const unsigned c = cnt[o];
            cnt2[k] = c;
            L->wact2[k] = L->wact[o]; /* the row's particles, renamed: the same kinds */
            for (int d = 0; d < dim; ++d) L->xb2[d][k] = L->xb[d][o];
            if (c > cap) continue; /* overflowed: this particle scans the cells */
            const unsigned *a = src + o * cap;
            unsigned *b = dst + (size_t)k * cap;
            unsigned down = 0; /* entries below the one before them (a gather loop, then the sort if any) */
            for (unsigned e = 0; e < c; ++e) b[e] = inv[a[e]];
            for (unsigned e = 1; e < c; ++e) down |= b[e] < b[e - 1];
            if (down)
                for (unsigned e = 1; e < c; ++e) {
                    const unsigned v = b[e];
                    unsigned m = e;
                    for (; m > 0 && b[m - 1] > v; --m) b[m] = b[m - 1];
                    b[m] = v;
                }
            unsigned s = 0; /* the first ghost entry */
            while (s < c && b[s] < n_owned) ++s;
            if (s == 0 || s == c || !nlist_after(g, (unsigned)perm[b[s - 1]], (unsigned)perm[b[s]])) continue;
            /* a ghost before the last owned entry: merge the two runs into the old row (read above), back */
            unsigned *t = (unsigned *)a, u = 0, v = s, e = 0; /* (row o is read by this k alone) */
            while (u < s || v < c)
                t[e++] = v >= c || (u < s && !nlist_after(g, (unsigned)perm[b[u]], (unsigned)perm[b[v]])) ? b[u++] : b[v++];
            memcpy(b, t, c * sizeof(unsigned));
        }
    }
    L->nl = dst, L->nl2 = src, L->cnt = cnt2, L->cnt2 = cnt;
    unsigned char *w = L->wact;
    L->wact = L->wact2, L->wact2 = w;
    for (int d = 0; d < 3; ++d) {
        real *t = L->xb[d];
        L->xb[d] = L->xb2[d], L->xb2[d] = t;
    }
    L->follows++;
}

int nlist_stale(const nlist *L, const particles_t *p)
{
    return !L->on || !L->valid || p->n + p->ng != L->n || nlist_moved(L, p, NULL, p->n);
}

void nlist_update(nlist *L, nbr_grid *g, particles_t *p, int mode)
{
    grid_view *v = &g->view;
    v->form = GRID_NBR_LIST, v->nl = v->ncnt = NULL;
    if (!L->on) return;
    const size_t nt = p->n + p->ng;
    int build = mode == NLIST_BUILD;
    if (mode == NLIST_AUTO) build = p->ng || !L->valid || nt != L->n || nlist_moved(L, p, g->perm, L->n);
    if (mode == NLIST_FOLLOW && (!L->valid || nt != L->n))
        error_exit(1, "nlist_update: asked to follow a list of %zu particles that does not match the store (%zu)",
                   L->n, nt);
    if (build) nlist_build(L, g, p);
    else nlist_follow(L, g, p->dim, p->n);
    nlist_view(L, v);
}

void nlist_forget(nlist *L) { L->valid = 0; }

void nlist_free(nlist *L)
{
    free(L->nl), free(L->nl2), free(L->cnt), free(L->cnt2), free(L->inv), free(L->wact), free(L->wact2);
    for (int d = 0; d < 3; ++d) free(L->xb[d]), free(L->xb2[d]);
    *L = (nlist){0};
}
