/* halo.c — domain decomposition (slabs or METIS), migration, ghosts and
 * load balance (see halo.h). Messages are records of the chosen arrays
 * (part_pack), counted in records through a contiguous MPI type so that
 * counts stay small, exchanged with each neighbour in ascending rank order
 * (deterministic). */
#include "halo.h"
#include <limits.h>
#include <math.h>
#include <metis.h>
#include <mpi.h>
#if defined(OPEN_MPI) && OPEN_MPI
#include <mpi-ext.h>
#endif
#include <stdlib.h>
#include <string.h>
#include "../src/core/error.h"
#include "../src/core/tuning.h"
#include "../src/physics/grid.h"

#define HALO_MPI_REAL (sizeof(real) == sizeof(double) ? MPI_DOUBLE : MPI_FLOAT)

static void *halo_grow(void *ptr, size_t *cap, size_t n, size_t size)
{
    if (n <= *cap && ptr) return ptr;
    size_t c = n + n / 4 + 16;
    void *q = realloc(ptr, c * size);
    if (!q) error_exit(1, "out of memory in the halo exchange (%zu bytes)", c * size);
    *cap = c;
    return q;
}

static void *halo_calloc(size_t n, size_t size)
{
    void *q = calloc(n ? n : 1, size);
    if (!q) error_exit(1, "out of memory in the domain decomposition (%zu bytes)", n * size);
    return q;
}

void halo_init(halo_t *h, int dim, real support, int method, int axis, const int *arr, int narr)
{
    memset(h, 0, sizeof *h);
    MPICHECK(MPI_Comm_rank(MPI_COMM_WORLD, &h->rank));
    MPICHECK(MPI_Comm_size(MPI_COMM_WORLD, &h->size));
    h->dim = dim;
    h->axis = axis;
    h->method = method;
    h->depth = HALO_DEPTH;
    h->blk = HALO_DEPTH; /* coarse cells of 4h: ghosts reach only the coarse cells around */
    h->support = support;
    if (narr > HALO_MAX_ARRAYS) error_exit(1, "halo_init: %d arrays > %d", narr, HALO_MAX_ARRAYS);
    memcpy(h->arr, arr, (size_t)narr * sizeof *arr);
    h->narr = narr;
    h->bound = halo_calloc((size_t)h->size + 1, sizeof(long));
}

void halo_set_depth(halo_t *h, int depth)
{
    if (depth < 1) error_exit(1, "halo_set_depth: depth %d < 1", depth);
    h->depth = depth;
    h->blk = depth;
}

/* ---- periodic axes ------------------------------------------------------------- */

void halo_set_periodic(halo_t *h, int mask, const real lo[3], const real len[3])
{
    h->per = mask & ((1 << h->dim) - 1);
    h->nimg = 0;
    for (int code = 0; code < HALO_NCODES; ++code) { /* the shifts along periodic axes only */
        int sh[3], ok = code != HALO_NOSHIFT;
        halo_shift_of(code, sh);
        for (int d = 0; d < 3; ++d) ok &= !sh[d] || (d < h->dim && (h->per >> d & 1));
        if (ok) h->img[h->nimg++] = code;
    }
    for (int d = 0; d < 3; ++d) {
        h->plo[d] = lo[d], h->plen[d] = len[d];
        if (h->per >> d & 1) h->origin[d] = lo[d] - (real)(h->depth + 1) * h->support;
    }
}

void halo_shift_of(int code, int s[3]) { hg_shift_of(code, s); }

void halo_image_shift(const halo_t *h, int k, double s[3])
{
    int q[3];
    halo_shift_of(HALO_NCODES - 1 - h->nbs[k], q); /* the sender moved them by its channel's shift */
    for (int d = 0; d < 3; ++d) s[d] = q[d] * (double)h->plen[d];
}

void halo_wrap(const halo_t *h, particles_t *p)
{
    for (int d = 0; d < h->dim; ++d) {
        if (!(h->per >> d & 1)) continue;
        double lo = h->plo[d], len = h->plen[d];
        for (size_t i = 0; i < p->n; ++i) {
            double s = hg_wrap_shift((double)p->x[d][i] + (POS_REMAINDER ? (double)p->xr[d][i] : 0.0), lo, len);
            if (s != 0) hg_move(&p->x[d][i], &p->xr[d][i], &p->x_n[d][i], s);
        }
    }
}

/* The images' shifts on the positions among arrays arr of the ghosts
 * received (halo_exchange, halo_refresh): store indices h->recv in
 * channel order. */
static void halo_shift_images(const halo_t *h, particles_t *p, const int *arr, int narr)
{
    if (!h->per) return;
    grid_image im = {{NULL, NULL, NULL}, {NULL, NULL, NULL}, {0, 0, 0}};
    for (int d = 0; d < h->dim; ++d) {
        int ix = part_array_find(p, p->x[d]), in = part_array_find(p, p->x_n[d]);
        for (int a = 0; a < narr; ++a) {
            if (arr[a] == ix) im.x[d] = p->x[d];
            if (arr[a] == in) im.xn[d] = p->x_n[d];
        }
    }
    size_t q = 0;
    for (int k = 0; k < h->nnb; ++k) {
        halo_image_shift(h, k, im.s);
        for (size_t e = 0; e < h->nrecv[k]; ++e, ++q) grid_image_move(&im, h->recv[q]);
    }
}

static void halo_free_lists(halo_t *h)
{
    for (int k = 0; k < h->nnb; ++k) free(h->send[k]);
    free(h->send), free(h->nsend), free(h->cap_send), free(h->nrecv), free(h->nb), free(h->nbs);
    h->send = NULL, h->nsend = h->cap_send = h->nrecv = NULL, h->nb = h->nbs = NULL, h->nnb = 0;
}

void halo_free(halo_t *h)
{
    halo_free_lists(h);
    free(h->bound), free(h->part), free(h->recv), free(h->inv);
    free(h->buf[0]), free(h->buf[1]), free(h->req);
    memset(h, 0, sizeof *h);
}

/* ---- who owns what ----------------------------------------------------------- */

void halo_geom_of(const halo_t *h, halo_geom *g)
{
    memset(g, 0, sizeof *g);
    g->rank = h->rank, g->size = h->size, g->dim = h->dim, g->axis = h->axis;
    g->metis = h->method == HALO_METIS;
    g->depth = h->depth, g->blk = h->blk;
    g->per = h->per, g->nimg = h->nimg;
    g->inv_support = R(1.0) / h->support;
    for (int d = 0; d < 3; ++d) {
        g->cg_n[d] = h->cg_n[d];
        g->origin[d] = h->origin[d], g->plo[d] = h->plo[d], g->plen[d] = h->plen[d];
        g->near_lo[d] = h->plo[d] - (real)h->depth * h->support;
        g->near_hi[d] = h->plo[d] + h->plen[d] + (real)h->depth * h->support;
    }
    for (int m = 0; m < h->nimg; ++m) g->img[m] = h->img[m];
    if (h->axis >= 0 && (h->per >> h->axis & 1)) {
        g->pcol[0] = hg_column(g, h->axis, h->plo[h->axis]);
        g->pcol[1] = hg_column(g, h->axis, h->plo[h->axis] + h->plen[h->axis]);
    }
    g->bound = h->bound, g->part = h->part;
    g->nnb = h->nnb, g->nb = h->nb, g->nbs = h->nbs;
}

long halo_column(const halo_t *h, int d, real x)
{
    halo_geom g;
    halo_geom_of(h, &g);
    return hg_column(&g, d, x);
}

static void halo_cell_of(const halo_geom *g, const particles_t *p, size_t i, long c[3])
{
    for (int d = 0; d < 3; ++d) c[d] = d < g->dim ? hg_column(g, d, p->x[d][i]) : 0;
}

int halo_owner(const halo_t *h, const long c[3])
{
    halo_geom g;
    halo_geom_of(h, &g);
    return hg_owner(&g, c);
}

/* Every target of owned particle i (hg_particle_targets). */
static int halo_particle_targets(const halo_geom *g, const particles_t *p, size_t i, int *out, int *codes)
{
    real x[3];
    for (int d = 0; d < 3; ++d) x[d] = p->x[d][i];
    return hg_particle_targets(g, x, out, codes);
}

/* ---- neighbours ----------------------------------------------------------------- */

/* The channels: is_nb[r * HALO_NCODES + code] for rank r and shift code. */
static void halo_set_neighbours(halo_t *h, const int *is_nb)
{
    halo_free_lists(h);
    h->gen++; /* on every rank at once: every caller is collective */
    h->nb = halo_calloc((size_t)h->size * HALO_NCODES, sizeof(int));
    h->nbs = halo_calloc((size_t)h->size * HALO_NCODES, sizeof(int));
    for (int r = 0; r < h->size; ++r)
        for (int code = 0; code < HALO_NCODES; ++code)
            if (is_nb[r * HALO_NCODES + code] && !(r == h->rank && code == HALO_NOSHIFT))
                h->nb[h->nnb] = r, h->nbs[h->nnb++] = code;
    size_t m = (size_t)(h->nnb ? h->nnb : 1);
    h->send = halo_calloc(m, sizeof(size_t *));
    h->nsend = halo_calloc(m, sizeof(size_t));
    h->cap_send = halo_calloc(m, sizeof(size_t));
    h->nrecv = halo_calloc(m, sizeof(size_t));
}

/* The box, m, of every rank's domain (lo[3 r + d], hi[3 r + d]), along a
 * periodic axis cut to the period: slabs, their extent along the axis (open
 * ends and the other axes unbounded); METIS, the box of the coarse cells a
 * rank owns (empty, lo > hi, for a rank without any). One pass for all
 * ranks, so that both sides of a pair see the same numbers. */
static void halo_boxes(const halo_t *h, double *lo, double *hi)
{
    for (int k = 0; k < 3 * h->size; ++k) lo[k] = -1e300, hi[k] = 1e300;
    if (h->method != HALO_METIS) {
        int d = h->axis;
        for (int r = 0; r < h->size; ++r) {
            if (h->bound[r] != LONG_MIN) lo[3 * r + d] = (double)h->origin[d] + (double)h->bound[r] * (double)h->support;
            if (h->bound[r + 1] != LONG_MAX)
                hi[3 * r + d] = (double)h->origin[d] + (double)h->bound[r + 1] * (double)h->support;
        }
    } else {
        for (int k = 0; k < 3 * h->size; ++k) lo[k] = 1e300, hi[k] = -1e300;
        int n[3] = {h->cg_n[0], h->cg_n[1], h->dim == 3 ? h->cg_n[2] : 1};
        for (int z = 0; z < n[2]; ++z)
            for (int y = 0; y < n[1]; ++y)
                for (int x = 0; x < n[0]; ++x) {
                    int r = h->part[((size_t)z * n[1] + y) * n[0] + x], c[3] = {x, y, z};
                    for (int d = 0; d < h->dim; ++d) {
                        double a = (double)h->origin[d] + (double)c[d] * h->blk * (double)h->support;
                        lo[3 * r + d] = fmin(lo[3 * r + d], a);
                        hi[3 * r + d] = fmax(hi[3 * r + d], a + h->blk * (double)h->support);
                    }
                }
    }
    for (int r = 0; r < h->size; ++r)
        for (int d = 0; d < h->dim; ++d)
            if (h->per >> d & 1) {
                lo[3 * r + d] = fmax(lo[3 * r + d], (double)h->plo[d]);
                hi[3 * r + d] = fmin(hi[3 * r + d], (double)h->plo[d] + (double)h->plen[d]);
            }
}

/* Does rank ra's box, moved by shift code, come within the ghost reach of
 * rank rb's (depth + 1 cells, and one more for rounding) on every axis?
 * Evaluated alike on both ranks (the pair in one canonical order), so that
 * a channel always has its partner: (rb, code) on ra and (ra, 26 - code) on
 * rb. A box encloses a domain: a channel may carry nothing, never miss an
 * image. */
static int halo_near(const halo_t *h, const double *lo, const double *hi, int ra, int rb, int code)
{
    if (ra > rb || (ra == rb && code > HALO_NOSHIFT)) {
        int t = ra;
        ra = rb, rb = t, code = HALO_NCODES - 1 - code;
    }
    int sh[3];
    halo_shift_of(code, sh);
    const double reach = (double)(h->depth + 2) * (double)h->support;
    for (int d = 0; d < h->dim; ++d) {
        const double *al = lo + 3 * ra, *ah = hi + 3 * ra, *bl = lo + 3 * rb, *bh = hi + 3 * rb;
        if (al[d] > ah[d] || bl[d] > bh[d]) return 0; /* a rank without a domain */
        double sig = sh[d] * (double)h->plen[d];
        if (fmax(bl[d] - (ah[d] + sig), (al[d] + sig) - bh[d]) >= reach) return 0;
    }
    return 1;
}

/* Periodic axes: the channels to every (rank, shift) whose domain the shift
 * brings within reach of this rank's, into is (halo_set_neighbours). */
static void halo_image_neighbours(const halo_t *h, int *is)
{
    if (!h->per) return;
    double *lo = halo_calloc((size_t)(6 * h->size), sizeof(double)), *hi = lo + 3 * h->size;
    halo_boxes(h, lo, hi);
    for (int r = 0; r < h->size; ++r)
        for (int m = 0; m < h->nimg; ++m) is[r * HALO_NCODES + h->img[m]] = halo_near(h, lo, hi, h->rank, r, h->img[m]);
    free(lo);
}

/* Slabs: the ranks whose columns overlap [lo - depth, hi + depth); with
 * periodic axes also the images' channels. */
static void halo_slab_neighbours(halo_t *h)
{
    int *is = halo_calloc((size_t)h->size * HALO_NCODES, sizeof(int));
    long lo = h->bound[h->rank], hi = h->bound[h->rank + 1];
    for (int r = 0; r < h->size; ++r) {
        long a = h->bound[r], b = h->bound[r + 1];
        int below = lo != LONG_MIN && b != LONG_MAX && b <= lo - h->depth;
        int above = hi != LONG_MAX && a != LONG_MIN && a >= hi + h->depth;
        is[r * HALO_NCODES + HALO_NOSHIFT] = !below && !above;
    }
    halo_image_neighbours(h, is);
    halo_set_neighbours(h, is);
    free(is);
}

/* METIS: the owners of the coarse cells around this rank's coarse cells (the
 * coarse edge blk >= depth, so ghosts reach no farther). Symmetric. With
 * periodic axes also the images' channels. */
static void halo_metis_neighbours(halo_t *h)
{
    int *is = halo_calloc((size_t)h->size * HALO_NCODES, sizeof(int)), n[3] = {h->cg_n[0], h->cg_n[1], h->dim == 3 ? h->cg_n[2] : 1};
    for (int z = 0; z < n[2]; ++z)
        for (int y = 0; y < n[1]; ++y)
            for (int x = 0; x < n[0]; ++x) {
                if (h->part[((size_t)z * n[1] + y) * n[0] + x] != h->rank) continue;
                for (int dz = -(h->dim == 3); dz <= (h->dim == 3); ++dz)
                    for (int dy = -1; dy <= 1; ++dy)
                        for (int dx = -1; dx <= 1; ++dx) {
                            int X = x + dx, Y = y + dy, Z = z + dz;
                            if (X < 0 || Y < 0 || Z < 0 || X >= n[0] || Y >= n[1] || Z >= n[2]) continue;
                            is[h->part[((size_t)Z * n[1] + Y) * n[0] + X] * HALO_NCODES + HALO_NOSHIFT] = 1;
                        }
            }
    halo_image_neighbours(h, is);
    halo_set_neighbours(h, is);
    free(is);
}

/* ---- point-to-point exchange ------------------------------------------------------ */

/* The tag of a message of kind `base` on channel k: a send carries its
 * channel's shift code, a receive expects its partner's, the opposite
 * (two channels between the same two ranks differ in shift). */
static int halo_tag(const halo_t *h, int k, int base, int recv)
{
    return base * 32 + (recv ? HALO_NCODES - 1 - h->nbs[k] : h->nbs[k]);
}

static MPI_Datatype halo_record_type(size_t bytes)
{
    MPI_Datatype t;
    MPICHECK(MPI_Type_contiguous((int)bytes, MPI_BYTE, &t));
    MPICHECK(MPI_Type_commit(&t));
    return t;
}

/* Send the records list[k][0..n[k]) of arrays arr to neighbour k, for every
 * k, and receive every neighbour's into h->buf[1] in neighbour order;
 * got[k] records from neighbour k. Returns the total received. */
void halo_swap_counts(halo_t *h, const size_t *n, size_t *got)
{
    int m = h->nnb;
    MPI_Request *rq = halo_calloc((size_t)(2 * m + 1), sizeof(MPI_Request));
    long long *cs = halo_calloc((size_t)(2 * m + 1), sizeof(long long)), *cr = cs + m;
    for (int k = 0; k < m; ++k) {
        cs[k] = (long long)n[k];
        MPICHECK(MPI_Irecv(&cr[k], 1, MPI_LONG_LONG, h->nb[k], halo_tag(h, k, 21, 1), MPI_COMM_WORLD, &rq[k]));
        MPICHECK(MPI_Isend(&cs[k], 1, MPI_LONG_LONG, h->nb[k], halo_tag(h, k, 21, 0), MPI_COMM_WORLD, &rq[m + k]));
        h->bytes += (long long)sizeof(long long), h->messages += 1;
    }
    double t0 = MPI_Wtime();
    MPICHECK(MPI_Waitall(2 * m, rq, MPI_STATUSES_IGNORE));
    h->wall_wait += MPI_Wtime() - t0;
    for (int k = 0; k < m; ++k) got[k] = (size_t)cr[k];
    free(rq), free(cs);
}

/* Send the records list[k][0..n[k]) of arrays arr to neighbour k, for every
 * k, and receive every neighbour's into h->buf[1] in neighbour order;
 * got[k] records from neighbour k. Returns the total received. */
static size_t halo_swap(halo_t *h, const particles_t *p, size_t *const *list, const size_t *n, const int *arr,
                        int narr, size_t *got)
{
    size_t rec = part_record_bytes(arr, narr), ns = 0, nr = 0;
    int m = h->nnb;
    halo_swap_counts(h, n, got);
    for (int k = 0; k < m; ++k) ns += n[k], nr += got[k];
    MPI_Request *rq = halo_calloc((size_t)(2 * m + 1), sizeof(MPI_Request));
    h->buf[0] = halo_grow(h->buf[0], &h->cap_buf[0], ns * rec + 1, 1);
    h->buf[1] = halo_grow(h->buf[1], &h->cap_buf[1], nr * rec + 1, 1);
    MPI_Datatype t = halo_record_type(rec);
    size_t os = 0, orr = 0;
    for (int k = 0; k < m; ++k) {
        part_pack(p, list[k], n[k], arr, narr, h->buf[0] + os * rec);
        MPICHECK(MPI_Irecv(h->buf[1] + orr * rec, (int)got[k], t, h->nb[k], halo_tag(h, k, 22, 1), MPI_COMM_WORLD, &rq[k]));
        MPICHECK(MPI_Isend(h->buf[0] + os * rec, (int)n[k], t, h->nb[k], halo_tag(h, k, 22, 0), MPI_COMM_WORLD, &rq[m + k]));
        os += n[k], orr += got[k];
        h->bytes += (long long)(n[k] * rec), h->messages += 1;
    }
    double t0 = MPI_Wtime();
    MPICHECK(MPI_Waitall(2 * m, rq, MPI_STATUSES_IGNORE));
    h->wall_wait += MPI_Wtime() - t0;
    MPICHECK(MPI_Type_free(&t));
    free(rq);
    return nr;
}

/* Channel k of (rank r, shift code), or for code < 0 the first channel to
 * r (a migrating particle, already wrapped, may travel on any). */
static int halo_channel(const halo_t *h, int r, int code) { return hg_channel(h->nnb, h->nb, h->nbs, r, code); }

static void halo_list_add(halo_t *h, int r, int code, size_t i, const char *what)
{
    int k = halo_channel(h, r, code);
    if (k < 0)
        error_exit(EXIT_NUMERICAL, "%s: rank %d is not a neighbour of rank %d (a particle crossed more than "
                   "one domain in a step: the flow is unstable)", what, r, h->rank);
    h->send[k] = halo_grow(h->send[k], &h->cap_send[k], h->nsend[k] + 1, sizeof(size_t));
    h->send[k][h->nsend[k]++] = i;
}

/* ---- migration and ghosts -------------------------------------------------------- */

/* Lattice origin: the particles' lower corner over all ranks, less 1e-6 of
 * a cell, exactly as grid_fit computes it on one rank; also the upper
 * corner when hi is given. */
static void halo_corner(halo_t *h, const particles_t *p, real *hi)
{
    real lo[3] = {R(1e30), R(1e30), R(1e30)}, up[3] = {R(-1e30), R(-1e30), R(-1e30)};
    for (size_t i = 0; i < p->n; ++i)
        for (int d = 0; d < h->dim; ++d) {
            if (p->x[d][i] < lo[d]) lo[d] = p->x[d][i];
            if (p->x[d][i] > up[d]) up[d] = p->x[d][i];
        }
    if (hi) {
        double t0 = MPI_Wtime();
        MPICHECK(MPI_Allreduce(up, hi, 3, HALO_MPI_REAL, MPI_MAX, MPI_COMM_WORLD));
        h->wall_wait += MPI_Wtime() - t0;
        for (int d = 0; d < 3; ++d)
            if (h->per >> d & 1) hi[d] = h->plo[d] + h->plen[d]; /* the period's end */
    }
    halo_set_origin(h, lo);
}

void halo_reorigin(halo_t *h, const particles_t *p) { halo_corner(h, p, NULL); }

void halo_set_origin(halo_t *h, const real lo_local[3])
{
    real lo[3] = {lo_local[0], lo_local[1], lo_local[2]};
    double t0 = MPI_Wtime();
    MPICHECK(MPI_Allreduce(MPI_IN_PLACE, lo, 3, HALO_MPI_REAL, MPI_MIN, MPI_COMM_WORLD));
    h->wall_wait += MPI_Wtime() - t0;
    for (int d = 0; d < 3; ++d) {
        h->corner[d] = d < h->dim ? lo[d] : 0;
        if (h->per >> d & 1) continue; /* fixed (halo_set_periodic) */
        h->origin[d] = d < h->dim ? lo[d] - R(1e-6) * h->support : 0;
    }
}

/* Every array the store holds (a field the run does not allocate is NULL
 * and not sent: part_alloc_fields). */
static void halo_all_arrays(const particles_t *p, int *arr, int *narr)
{
    if ((int)part_narrays() > HALO_MAX_ARRAYS + 8)
        error_exit(1, "halo: %zu particle arrays, room for %d", part_narrays(), HALO_MAX_ARRAYS + 8);
    *narr = 0;
    for (size_t k = 0; k < part_narrays(); ++k)
        if (part_array_get(p, k)) arr[(*narr)++] = (int)k;
}

/* Particles whose cell another rank owns go to it, whole (every array);
 * arrivals are appended. */
static void halo_migrate(halo_t *h, particles_t *p)
{
    int all[HALO_MAX_ARRAYS + 8], nall;
    halo_all_arrays(p, all, &nall);
    halo_wrap(h, p);
    size_t nkeep = 0;
    h->inv = halo_grow(h->inv, &h->cap_inv, p->n, sizeof(size_t)); /* keep list */
    for (int k = 0; k < h->nnb; ++k) h->nsend[k] = 0;
    halo_geom g;
    halo_geom_of(h, &g);
    for (size_t i = 0; i < p->n; ++i) {
        long c[3];
        halo_cell_of(&g, p, i, c);
        int r = hg_owner(&g, c);
        if (r == h->rank) h->inv[nkeep++] = i;
        else halo_list_add(h, r, -1, i, "migration"), h->migrated++;
    }
    size_t *got = halo_calloc((size_t)h->nnb + 1, sizeof(size_t));
    size_t nin = halo_swap(h, p, h->send, h->nsend, all, nall, got);
    if (nkeep < p->n) part_compact(p, h->inv, nkeep); /* most prepares: nobody left */
    part_reserve(p, nkeep + nin);
    part_unpack(p, NULL, p->n, nin, all, nall, h->buf[1]);
    p->n += nin;
    free(got);
}

/* Ghosts: every owned particle within depth cells of another rank's cell
 * is sent to that rank, carrying h->arr; arrivals at [n, n + ng). */
static void halo_make_ghosts(halo_t *h, particles_t *p)
{
    int tg[256], tc[256];
    for (int k = 0; k < h->nnb; ++k) h->nsend[k] = 0;
    halo_geom g;
    halo_geom_of(h, &g);
    for (size_t i = 0; i < p->n; ++i) {
        int nt = halo_particle_targets(&g, p, i, tg, tc);
        for (int t = 0; t < nt; ++t) halo_list_add(h, tg[t], tc[t], i, "ghosts");
    }
    size_t ng = halo_swap(h, p, h->send, h->nsend, h->arr, h->narr, h->nrecv);
    part_reserve(p, p->n + ng);
    part_unpack(p, NULL, p->n, ng, h->arr, h->narr, h->buf[1]);
    p->ng = ng;
    h->recv = halo_grow(h->recv, &h->cap_recv, ng, sizeof(size_t));
    for (size_t k = 0; k < ng; ++k) h->recv[k] = p->n + k;
    halo_shift_images(h, p, h->arr, h->narr);
}

void halo_exchange(halo_t *h, particles_t *p)
{
    double t0 = MPI_Wtime();
    p->ng = 0;
    halo_corner(h, p, NULL);
    halo_migrate(h, p);
    halo_make_ghosts(h, p);
    h->wall_comm += MPI_Wtime() - t0;
}

void halo_sorted(halo_t *h, const size_t *perm, size_t n)
{
    h->inv = halo_grow(h->inv, &h->cap_inv, n, sizeof(size_t));
    for (size_t k = 0; k < n; ++k) h->inv[perm[k]] = k;
    size_t nr = 0;
    for (int k = 0; k < h->nnb; ++k) {
        for (size_t q = 0; q < h->nsend[k]; ++q) h->send[k][q] = h->inv[h->send[k][q]];
        nr += h->nrecv[k];
    }
    for (size_t k = 0; k < nr; ++k) h->recv[k] = h->inv[h->recv[k]];
}

void halo_refresh(halo_t *h, particles_t *p, const int *arr, int narr)
{
    double t0 = MPI_Wtime();
    size_t *got = halo_calloc((size_t)h->nnb + 1, sizeof(size_t)), total = 0;
    halo_swap(h, p, h->send, h->nsend, arr, narr, got);
    for (int k = 0; k < h->nnb; ++k) {
        if (got[k] != h->nrecv[k])
            error_exit(1, "halo_refresh: %zu records from rank %d, expected %zu", got[k], h->nb[k], h->nrecv[k]);
        total += got[k];
    }
    part_unpack(p, h->recv, 0, total, arr, narr, h->buf[1]);
    halo_shift_images(h, p, arr, narr);
    free(got);
    h->wall_comm += MPI_Wtime() - t0;
}

/* ---- decomposition and balance ----------------------------------------------------- */

/* Slabs: bounds that split the columns' weights w[0..ncol-1] into equal
 * shares, every slab at least depth columns wide. */
static void halo_cut_slabs(halo_t *h, const double *w, long ncol)
{
    if (ncol < (long)h->size * h->depth)
        input_error("Parallel: %d ranks need at least %d cells of 2h = %.4g m along the slab axis (%c); the "
                    "domain has %ld: run with at most %ld ranks", h->size, h->size * h->depth,
                    (double)h->support, "xyz"[h->axis], ncol, ncol / h->depth);
    double total = 0, cum = 0;
    for (long c = 0; c < ncol; ++c) total += w[c];
    h->bound[0] = LONG_MIN;
    h->bound[h->size] = LONG_MAX;
    long c = 0;
    for (int r = 1; r < h->size; ++r) {
        double target = total * r / h->size;
        while (c < ncol && cum + 0.5 * w[c] < target) cum += w[c++];
        long lo = (r == 1 ? 0 : h->bound[r - 1]) + h->depth, hi = ncol - (long)(h->size - r) * h->depth;
        long b = c < lo ? lo : c > hi ? hi : c;
        for (; c < b; ++c) cum += w[c];
        for (; c > b; --c) cum -= w[c - 1];
        h->bound[r] = b;
    }
}

/* METIS: k-way partition of the coarse-cell graph (vertex weights w, in
 * units of the smallest positive weight, at least 1 so that empty cells
 * get an owner too), on rank 0, broadcast. */
static void halo_cut_metis(halo_t *h, const double *w, size_t nv)
{
    h->part = realloc(h->part, nv * sizeof(int));
    if (!h->part) error_exit(1, "out of memory: %zu coarse cells", nv);
    if (h->size == 1) { /* METIS_PartGraphKway divides by zero for one part */
        memset(h->part, 0, nv * sizeof(int));
    } else if (h->rank == 0) {
        idx_t n = (idx_t)nv, ncon = 1, np = (idx_t)h->size, cut = 0, opt[METIS_NOPTIONS];
        idx_t *xadj = halo_calloc(nv + 1, sizeof(idx_t)), *adj = halo_calloc(nv * 26, sizeof(idx_t));
        idx_t *vw = halo_calloc(nv, sizeof(idx_t)), *part = halo_calloc(nv, sizeof(idx_t));
        double wmin = 0;
        for (size_t v = 0; v < nv; ++v)
            if (w[v] > 0 && (wmin == 0 || w[v] < wmin)) wmin = w[v];
        int N[3] = {h->cg_n[0], h->cg_n[1], h->dim == 3 ? h->cg_n[2] : 1}, zr = h->dim == 3;
        for (size_t v = 0; v < nv; ++v) {
            int x = (int)(v % (size_t)N[0]), y = (int)(v / (size_t)N[0] % (size_t)N[1]), z = (int)(v / ((size_t)N[0] * N[1]));
            vw[v] = 1 + (idx_t)(wmin > 0 ? w[v] / wmin * 10 : 0);
            xadj[v + 1] = xadj[v];
            for (int dz = -zr; dz <= zr; ++dz)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        int X = x + dx, Y = y + dy, Z = z + dz;
                        if ((!dx && !dy && !dz) || X < 0 || Y < 0 || Z < 0 || X >= N[0] || Y >= N[1] || Z >= N[2])
                            continue;
                        adj[xadj[v + 1]++] = (idx_t)(((size_t)Z * N[1] + Y) * N[0] + X);
                    }
        }
        METIS_SetDefaultOptions(opt);
        opt[METIS_OPTION_SEED] = 1;
        opt[METIS_OPTION_CONTIG] = 1;
        int rc = METIS_PartGraphKway(&n, &ncon, xadj, adj, vw, NULL, NULL, &np, NULL, NULL, opt, &cut, part);
        if (rc != METIS_OK) error_exit(1, "METIS_PartGraphKway failed (%d) on %zu coarse cells", rc, nv);
        for (size_t v = 0; v < nv; ++v) h->part[v] = (int)part[v];
        free(xadj), free(adj), free(vw), free(part);
    }
    MPICHECK(MPI_Bcast(h->part, (int)nv, MPI_INT, 0, MPI_COMM_WORLD));
}

/* Send every particle (whole) to the rank owning its cell: all-to-all of the
 * movers alone. Those that stay keep their order and are not copied (a re-cut
 * moves a few per cent: packing them all cost 4-5 us a particle at 1.1e7 a
 * rank); arrivals are appended in the senders' rank order. Ghosts are dropped. */
static void halo_route(halo_t *h, particles_t *p)
{
    int all[HALO_MAX_ARRAYS + 8], nall, P = h->size;
    halo_all_arrays(p, all, &nall);
    size_t rec = part_record_bytes(all, nall), nkeep = 0, nout = 0;
    int *cnt = halo_calloc((size_t)4 * P, sizeof(int)), *rcnt = cnt + P, *sdis = cnt + 2 * P, *rdis = cnt + 3 * P;
    size_t *order = halo_calloc(p->n + 1, sizeof(size_t)), *keep = halo_calloc(p->n + 1, sizeof(size_t));
    int *dest = halo_calloc(p->n + 1, sizeof(int));
    halo_geom g;
    halo_geom_of(h, &g);
    for (size_t i = 0; i < p->n; ++i) {
        long c[3];
        halo_cell_of(&g, p, i, c);
        dest[i] = hg_owner(&g, c);
        if (dest[i] == h->rank) keep[nkeep++] = i;
        else cnt[dest[i]]++, nout++;
    }
    for (int r = 1; r < P; ++r) sdis[r] = sdis[r - 1] + cnt[r - 1];
    for (size_t i = 0; i < p->n; ++i)
        if (dest[i] != h->rank) order[sdis[dest[i]]++] = i; /* stable by destination */
    for (int r = 0; r < P; ++r) sdis[r] -= cnt[r];
    MPICHECK(MPI_Alltoall(cnt, 1, MPI_INT, rcnt, 1, MPI_INT, MPI_COMM_WORLD));
    size_t nin = 0;
    for (int r = 0; r < P; ++r) rdis[r] = (int)nin, nin += (size_t)rcnt[r];
    char *sb = halo_calloc(nout * rec + 1, 1), *rb = halo_calloc(nin * rec + 1, 1);
    part_pack(p, order, nout, all, nall, sb);
    MPI_Datatype t = halo_record_type(rec);
    MPICHECK(MPI_Alltoallv(sb, cnt, sdis, t, rb, rcnt, rdis, t, MPI_COMM_WORLD));
    MPICHECK(MPI_Type_free(&t));
    if (nkeep < p->n) part_compact(p, keep, nkeep);
    p->ng = 0;
    part_reserve(p, nkeep + nin);
    part_unpack(p, NULL, nkeep, nin, all, nall, rb);
    p->n = nkeep + nin;
    free(sb), free(rb), free(order), free(keep), free(dest), free(cnt);
}

/* The lattice extent (cells per axis) of all particles; picks the slab axis
 * if it is to be the longest; sizes the METIS coarse grid. Returns the
 * number of weight bins: columns along the axis, or coarse cells. */
static size_t halo_grid(halo_t *h, const particles_t *p)
{
    real hi[3];
    halo_corner(h, p, hi);
    long n[3] = {1, 1, 1};
    for (int d = 0; d < h->dim; ++d) n[d] = halo_column(h, d, hi[d]) + 1;
    if (h->axis < 0) { /* the longest extent */
        h->axis = 0;
        for (int d = 1; d < h->dim; ++d)
            if (n[d] > n[h->axis]) h->axis = d;
    }
    if (h->method != HALO_METIS) return (size_t)n[h->axis];
    size_t nv = 1;
    for (int d = 0; d < 3; ++d) h->cg_n[d] = d < h->dim ? (int)((n[d] + h->blk - 1) / h->blk) : 1, nv *= (size_t)h->cg_n[d];
    if (nv < (size_t)h->size)
        input_error("Parallel: %d ranks need at least as many coarse cells (4h) as ranks; the domain has %zu",
                    h->size, nv);
    return nv;
}

/* Weight per bin (column or coarse cell), summed over ranks: each local
 * particle counts `each`. */
static double *halo_weights(halo_t *h, const particles_t *p, size_t nbin, double each)
{
    double *w = halo_calloc(nbin, sizeof(double));
    halo_geom g;
    halo_geom_of(h, &g);
    for (size_t i = 0; i < p->n; ++i) {
        long c[3];
        halo_cell_of(&g, p, i, c);
        size_t b = h->method == HALO_METIS ? hg_coarse_index(&g, c) : (size_t)hg_clamp(c[h->axis], 0, (long)nbin - 1);
        w[b] += each;
    }
    MPICHECK(MPI_Allreduce(MPI_IN_PLACE, w, (int)nbin, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD));
    return w;
}

/* The cut only: the neighbours and their ghost lists stay as they are
 * until halo_neighbours (a cut that halo_recut drops must not clear them). */
static void halo_cut(halo_t *h, const double *w, size_t nbin)
{
    if (h->method == HALO_METIS) halo_cut_metis(h, w, nbin);
    else halo_cut_slabs(h, w, (long)nbin);
}

/* The neighbour ranks of the cut in force; the ghost lists start empty. */
static void halo_neighbours(halo_t *h)
{
    if (h->method == HALO_METIS) halo_metis_neighbours(h);
    else halo_slab_neighbours(h);
}

void halo_decompose(halo_t *h, particles_t *p)
{
    double t0 = MPI_Wtime();
    p->ng = 0;
    halo_wrap(h, p);
    size_t nbin = halo_grid(h, p);
    double *w = halo_weights(h, p, nbin, 1.0);
    halo_cut(h, w, nbin);
    free(w);
    halo_neighbours(h);
    halo_route(h, p);
    h->wall_comm += MPI_Wtime() - t0;
}

void halo_restore(halo_t *h, int method, int axis, const long *bound, const int cg[3], const int *part)
{
    h->method = method;
    h->axis = axis;
    memcpy(h->bound, bound, ((size_t)h->size + 1) * sizeof(long));
    if (method != HALO_METIS) {
        halo_slab_neighbours(h);
        return;
    }
    size_t nv = (size_t)cg[0] * (size_t)cg[1] * (size_t)cg[2];
    for (int d = 0; d < 3; ++d) h->cg_n[d] = cg[d];
    h->part = realloc(h->part, (nv ? nv : 1) * sizeof(int));
    if (!h->part) error_exit(1, "out of memory: %zu coarse cells", nv);
    memcpy(h->part, part, nv * sizeof(int));
    halo_metis_neighbours(h);
}

/* Particles each rank would own under the present cut (for the log). */
static long long halo_owned_after(halo_t *h, const particles_t *p)
{
    long long m = 0;
    halo_geom g;
    halo_geom_of(h, &g);
    for (size_t i = 0; i < p->n; ++i) {
        long c[3];
        halo_cell_of(&g, p, i, c);
        m += hg_owner(&g, c) == h->rank;
    }
    return m;
}

double halo_imbalance(halo_t *h, double cost)
{
    double sum = 0, max = 0;
    MPICHECK(MPI_Allreduce(&cost, &sum, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD));
    MPICHECK(MPI_Allreduce(&cost, &max, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD));
    double mean = sum / h->size;
    return mean > 0 ? max / mean - 1 : 0;
}

int halo_balance(halo_t *h, particles_t *p, double cost, double threshold)
{
    return halo_recut(h, p, cost, halo_imbalance(h, cost), threshold);
}

int halo_recut(halo_t *h, particles_t *p, double cost, double imb, double threshold)
{
    if (imb <= threshold) return 0;
    double t0 = MPI_Wtime();
    /* the cut in force, kept when the new one would move no particle: the
     * decision rests on timings, and a cut that changed only ghost sets
     * would make the run differ from a repeat for nothing */
    size_t nold = h->method == HALO_METIS ? (size_t)h->cg_n[0] * (size_t)h->cg_n[1] * (size_t)h->cg_n[2] : 0;
    long *ob = halo_calloc((size_t)h->size + 1, sizeof(long));
    int *op = halo_calloc(nold + 1, sizeof(int)), ocg[3] = {h->cg_n[0], h->cg_n[1], h->cg_n[2]};
    memcpy(ob, h->bound, ((size_t)h->size + 1) * sizeof(long));
    if (nold) memcpy(op, h->part, nold * sizeof(int));
    halo_wrap(h, p);
    size_t nbin = halo_grid(h, p);
    double *w = halo_weights(h, p, nbin, p->n ? cost / (double)p->n : 0);
    halo_cut(h, w, nbin);
    free(w);
    int moved = halo_owned_after(h, p) != (long long)p->n, any = 0;
    MPICHECK(MPI_Allreduce(&moved, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD));
    if (!any) { /* the old cut, and its neighbours and ghost lists, which were never cleared */
        memcpy(h->bound, ob, ((size_t)h->size + 1) * sizeof(long));
        if (h->method == HALO_METIS) {
            memcpy(h->cg_n, ocg, sizeof ocg);
            free(h->part);
            h->part = op, op = NULL;
        }
    }
    free(ob), free(op);
    if (any) {
        message("load balance: the slowest rank took %.0f %% more than the mean (threshold %.0f %%): domains "
                "re-cut", 100 * imb, 100 * threshold);
        halo_neighbours(h);
        halo_route(h, p);
    }
    h->wall_comm += MPI_Wtime() - t0;
    return any;
}

/* ---- byte segments (device refreshes) -------------------------------------------- */

void halo_post_bytes(halo_t *h, const char *send, const size_t *soff, char *recv, const size_t *roff)
{
    double t0 = MPI_Wtime();
    int m = h->nnb;
    if (h->nreq) error_exit(1, "halo_post_bytes: an exchange is already posted");
    h->req = halo_grow(h->req, &h->cap_req, (size_t)(2 * m + 2), sizeof(MPI_Request)); /* channels may outnumber ranks */
    MPI_Request *rq = h->req;
    MPI_Datatype t8; /* 8-byte words: segments up to 16 GiB in an int count */
    MPICHECK(MPI_Type_contiguous(8, MPI_BYTE, &t8));
    MPICHECK(MPI_Type_commit(&t8));
    for (int k = 0; k < m; ++k) {
        size_t ns = soff[k + 1] - soff[k], nr = roff[k + 1] - roff[k];
        if (ns % 8 || nr % 8 || ns / 8 > INT_MAX || nr / 8 > INT_MAX)
            error_exit(1, "halo_post_bytes: segment of %zu / %zu bytes (multiples of 8 up to 16 GiB)", ns, nr);
        MPICHECK(MPI_Irecv(recv + roff[k], (int)(nr / 8), t8, h->nb[k], halo_tag(h, k, 23, 1), MPI_COMM_WORLD, &rq[k]));
        MPICHECK(MPI_Isend(send + soff[k], (int)(ns / 8), t8, h->nb[k], halo_tag(h, k, 23, 0), MPI_COMM_WORLD, &rq[m + k]));
        h->bytes += (long long)ns, h->messages += 1;
    }
    MPICHECK(MPI_Type_free(&t8));
    h->nreq = 2 * m;
    h->wall_comm += MPI_Wtime() - t0;
}

void halo_wait_bytes(halo_t *h)
{
    double t0 = MPI_Wtime();
    MPICHECK(MPI_Waitall(h->nreq, (MPI_Request *)h->req, MPI_STATUSES_IGNORE));
    h->nreq = 0;
    double dt = MPI_Wtime() - t0;
    h->wall_wait += dt, h->wall_comm += dt;
}

void halo_swap_small(halo_t *h, const void *send, void *recv, size_t bytes, const int *on)
{
    int m = h->nnb;
    MPI_Request *rq = halo_calloc((size_t)(2 * m + 1), sizeof(MPI_Request));
    for (int k = 0; k < m; ++k) rq[k] = rq[m + k] = MPI_REQUEST_NULL;
    for (int k = 0; k < m; ++k) {
        if (on && !on[k]) continue;
        MPICHECK(MPI_Irecv((char *)recv + k * bytes, (int)bytes, MPI_BYTE, h->nb[k], halo_tag(h, k, 24, 1),
                           MPI_COMM_WORLD, &rq[k]));
        MPICHECK(MPI_Isend((const char *)send + k * bytes, (int)bytes, MPI_BYTE, h->nb[k], halo_tag(h, k, 24, 0),
                           MPI_COMM_WORLD, &rq[m + k]));
        h->bytes += (long long)bytes, h->messages += 1;
    }
    double t0 = MPI_Wtime();
    MPICHECK(MPI_Waitall(2 * m, rq, MPI_STATUSES_IGNORE));
    h->wall_wait += MPI_Wtime() - t0;
    free(rq);
}

int halo_cuda_aware(void)
{
    if (!tuning_get()->cuda_aware) return 0;
#if defined(MPIX_CUDA_AWARE_SUPPORT) && MPIX_CUDA_AWARE_SUPPORT
    return MPIX_Query_cuda_support() ? 1 : 0;
#else
    return 0;
#endif
}
