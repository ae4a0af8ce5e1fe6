/* halo.c — slab decomposition, migration, ghosts and load balance (see
 * halo.h). Messages are records of the chosen arrays (part_pack), counted
 * in records through a contiguous MPI type so that counts stay small. */
#include "halo.h"
#include <limits.h>
#include <math.h>
#include <mpi.h>
#include <stdlib.h>
#include <string.h>
#include "../src/error.h"

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

void halo_init(halo_t *h, int dim, real support, int axis, const int *arr, int narr)
{
    memset(h, 0, sizeof *h);
    MPICHECK(MPI_Comm_rank(MPI_COMM_WORLD, &h->rank));
    MPICHECK(MPI_Comm_size(MPI_COMM_WORLD, &h->size));
    h->dim = dim;
    h->axis = axis;
    h->depth = HALO_DEPTH;
    h->support = support;
    if (narr > HALO_MAX_ARRAYS) error_exit(1, "halo_init: %d arrays > %d", narr, HALO_MAX_ARRAYS);
    memcpy(h->arr, arr, (size_t)narr * sizeof *arr);
    h->narr = narr;
    h->bound = calloc((size_t)h->size + 1, sizeof(long));
    if (!h->bound) error_exit(1, "out of memory in halo_init");
}

void halo_free(halo_t *h)
{
    free(h->bound);
    free(h->send[0]);
    free(h->send[1]);
    free(h->recv);
    free(h->inv);
    free(h->buf[0]);
    free(h->buf[1]);
    memset(h, 0, sizeof *h);
}

long halo_column(const halo_t *h, real x)
{
    /* the expression grid_cell_coords uses, so both bin alike */
    return (long)((x - h->origin[h->axis]) * (R(1.0) / h->support));
}

static int halo_owner(const halo_t *h, long c)
{
    int lo = 0, hi = h->size - 1; /* largest r with bound[r] <= c; bound[0] is open */
    while (lo < hi) {
        int mid = (lo + hi + 1) / 2;
        if (h->bound[mid] <= c) lo = mid;
        else hi = mid - 1;
    }
    return lo;
}

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
    MPICHECK(MPI_Allreduce(MPI_IN_PLACE, lo, 3, HALO_MPI_REAL, MPI_MIN, MPI_COMM_WORLD));
    if (hi) MPICHECK(MPI_Allreduce(up, hi, 3, HALO_MPI_REAL, MPI_MAX, MPI_COMM_WORLD));
    for (int d = 0; d < 3; ++d) h->origin[d] = d < h->dim ? lo[d] - R(1e-6) * h->support : 0;
}

static MPI_Datatype halo_record_type(size_t bytes)
{
    MPI_Datatype t;
    MPICHECK(MPI_Type_contiguous((int)bytes, MPI_BYTE, &t));
    MPICHECK(MPI_Type_commit(&t));
    return t;
}

/* Send m records from sbuf to rank `to` while receiving from rank `from`
 * (either may be MPI_PROC_NULL) into h->buf[1]; returns the count received. */
static size_t halo_shift(halo_t *h, const char *sbuf, size_t m, int to, int from, size_t rec)
{
    long long ms = (long long)m, mr = 0;
    MPICHECK(MPI_Sendrecv(&ms, 1, MPI_LONG_LONG, to, 11, &mr, 1, MPI_LONG_LONG, from, 11, MPI_COMM_WORLD,
                          MPI_STATUS_IGNORE));
    h->buf[1] = halo_grow(h->buf[1], &h->cap_buf[1], (size_t)mr * rec, 1);
    MPI_Datatype t = halo_record_type(rec);
    MPICHECK(MPI_Sendrecv(sbuf, (int)m, t, to, 12, h->buf[1], (int)mr, t, from, 12, MPI_COMM_WORLD,
                          MPI_STATUS_IGNORE));
    MPICHECK(MPI_Type_free(&t));
    if (to != MPI_PROC_NULL) h->bytes += (long long)(m * rec + sizeof ms), h->messages += 2;
    return (size_t)mr;
}

static int halo_neighbour(const halo_t *h, int side)
{
    int r = h->rank + (side ? 1 : -1);
    return r < 0 || r >= h->size ? MPI_PROC_NULL : r;
}

/* ---- migration ------------------------------------------------------------- */

static void halo_all_arrays(int *arr, int *narr)
{
    *narr = (int)part_narrays();
    for (int k = 0; k < *narr; ++k) arr[k] = k;
}

/* Particles outside [bound[rank], bound[rank+1]) go to the neighbour on
 * that side, whole (every array); arrivals are appended. A particle that
 * would need to cross more than one slab is an error: particles move less
 * than h per step and slabs are at least two cells of 2h wide. */
static void halo_migrate(halo_t *h, particles_t *p)
{
    int all[HALO_MAX_ARRAYS + 8], nall;
    halo_all_arrays(all, &nall);
    size_t rec = part_record_bytes(all, nall), nkeep = 0;
    h->inv = halo_grow(h->inv, &h->cap_inv, p->n, sizeof(size_t)); /* keep list */
    for (int s = 0; s < 2; ++s) h->nsend[s] = 0;
    for (size_t i = 0; i < p->n; ++i) {
        long c = halo_column(h, p->x[h->axis][i]);
        int side = c < h->bound[h->rank] ? 0 : c >= h->bound[h->rank + 1] ? 1 : -1;
        if (side < 0) {
            h->inv[nkeep++] = i;
            continue;
        }
        h->send[side] = halo_grow(h->send[side], &h->cap_send[side], h->nsend[side] + 1, sizeof(size_t));
        h->send[side][h->nsend[side]++] = i;
    }
    size_t got[2];
    char *in[2] = {NULL, NULL};
    for (int s = 0; s < 2; ++s) { /* s = 0: to the lower rank, from the upper */
        h->buf[0] = halo_grow(h->buf[0], &h->cap_buf[0], h->nsend[s] * rec, 1);
        part_pack(p, h->send[s], h->nsend[s], all, nall, h->buf[0]);
        h->migrated += (long long)h->nsend[s];
        got[s] = halo_shift(h, h->buf[0], h->nsend[s], halo_neighbour(h, s), halo_neighbour(h, !s), rec);
        in[s] = malloc(got[s] * rec + 1);
        if (!in[s]) error_exit(1, "out of memory migrating %zu particles", got[s]);
        memcpy(in[s], h->buf[1], got[s] * rec);
    }
    part_compact(p, h->inv, nkeep);
    part_reserve(p, nkeep + got[0] + got[1]);
    for (int s = 0; s < 2; ++s) {
        part_unpack(p, NULL, p->n, got[s], all, nall, in[s]);
        p->n += got[s];
        free(in[s]);
    }
    for (size_t i = nkeep; i < p->n; ++i) {
        long c = halo_column(h, p->x[h->axis][i]);
        if (c < h->bound[h->rank] || c >= h->bound[h->rank + 1])
            error_exit(EXIT_NUMERICAL, "particle %lld crossed more than one slab in a step (column %ld, slab "
                       "[%ld, %ld)): the flow is unstable", (long long)p->id[i], c, h->bound[h->rank],
                       h->bound[h->rank + 1]);
    }
}

/* ---- ghosts ---------------------------------------------------------------- */

static void halo_make_ghosts(halo_t *h, particles_t *p)
{
    size_t rec = part_record_bytes(h->arr, h->narr);
    long lo = h->bound[h->rank], hi = h->bound[h->rank + 1];
    for (int s = 0; s < 2; ++s) h->nsend[s] = 0;
    for (size_t i = 0; i < p->n; ++i) {
        long c = halo_column(h, p->x[h->axis][i]);
        for (int s = 0; s < 2; ++s)
            if (halo_neighbour(h, s) != MPI_PROC_NULL && (s == 0 ? c < lo + h->depth : c >= hi - h->depth)) {
                h->send[s] = halo_grow(h->send[s], &h->cap_send[s], h->nsend[s] + 1, sizeof(size_t));
                h->send[s][h->nsend[s]++] = i;
            }
    }
    p->ng = 0;
    for (int s = 1; s >= 0; --s) { /* first from the lower rank (to the upper), then from the upper */
        h->buf[0] = halo_grow(h->buf[0], &h->cap_buf[0], h->nsend[s] * rec, 1);
        part_pack(p, h->send[s], h->nsend[s], h->arr, h->narr, h->buf[0]);
        size_t got = halo_shift(h, h->buf[0], h->nsend[s], halo_neighbour(h, s), halo_neighbour(h, !s), rec);
        part_reserve(p, p->n + p->ng + got);
        part_unpack(p, NULL, p->n + p->ng, got, h->arr, h->narr, h->buf[1]);
        h->nrecv[1 - s] = got;
        p->ng += got;
    }
    h->recv = halo_grow(h->recv, &h->cap_recv, p->ng, sizeof(size_t));
    for (size_t k = 0; k < p->ng; ++k) h->recv[k] = p->n + k;
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
    for (int s = 0; s < 2; ++s)
        for (size_t k = 0; k < h->nsend[s]; ++k) h->send[s][k] = h->inv[h->send[s][k]];
    for (size_t k = 0; k < h->nrecv[0] + h->nrecv[1]; ++k) h->recv[k] = h->inv[h->recv[k]];
}

void halo_refresh(halo_t *h, particles_t *p, const int *arr, int narr)
{
    double t0 = MPI_Wtime();
    size_t rec = part_record_bytes(arr, narr);
    for (int s = 1; s >= 0; --s) { /* the order of halo_make_ghosts */
        h->buf[0] = halo_grow(h->buf[0], &h->cap_buf[0], h->nsend[s] * rec, 1);
        part_pack(p, h->send[s], h->nsend[s], arr, narr, h->buf[0]);
        size_t got = halo_shift(h, h->buf[0], h->nsend[s], halo_neighbour(h, s), halo_neighbour(h, !s), rec);
        if (got != h->nrecv[1 - s])
            error_exit(1, "halo_refresh: %zu records from rank %d, expected %zu", got, halo_neighbour(h, !s),
                       h->nrecv[1 - s]);
        part_unpack(p, h->recv + (s == 1 ? 0 : h->nrecv[0]), 0, got, arr, narr, h->buf[1]);
    }
    h->wall_comm += MPI_Wtime() - t0;
}

/* ---- decomposition and balance --------------------------------------------- */

/* Bounds that split the columns' weights w[0..ncol-1] into equal shares,
 * every slab at least depth columns wide. */
static void halo_cut(halo_t *h, const double *w, long ncol)
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

/* Send every particle (whole) to the rank owning its column: all-to-all. */
static void halo_route(halo_t *h, particles_t *p)
{
    int all[HALO_MAX_ARRAYS + 8], nall, P = h->size;
    halo_all_arrays(all, &nall);
    size_t rec = part_record_bytes(all, nall);
    int *cnt = calloc((size_t)4 * P, sizeof(int)), *rcnt = cnt + P, *sdis = cnt + 2 * P, *rdis = cnt + 3 * P;
    size_t *order = malloc((p->n + 1) * sizeof(size_t));
    int *dest = malloc((p->n + 1) * sizeof(int));
    if (!cnt || !order || !dest) error_exit(1, "out of memory routing %zu particles", p->n);
    for (size_t i = 0; i < p->n; ++i) cnt[dest[i] = halo_owner(h, halo_column(h, p->x[h->axis][i]))]++;
    for (int r = 1; r < P; ++r) sdis[r] = sdis[r - 1] + cnt[r - 1];
    for (size_t i = 0; i < p->n; ++i) order[sdis[dest[i]]++] = i; /* stable by destination */
    for (int r = 0; r < P; ++r) sdis[r] -= cnt[r];
    MPICHECK(MPI_Alltoall(cnt, 1, MPI_INT, rcnt, 1, MPI_INT, MPI_COMM_WORLD));
    size_t nin = 0;
    for (int r = 0; r < P; ++r) rdis[r] = (int)nin, nin += (size_t)rcnt[r];
    char *sb = malloc(p->n * rec + 1), *rb = malloc(nin * rec + 1);
    if (!sb || !rb) error_exit(1, "out of memory routing %zu particles", p->n);
    part_pack(p, order, p->n, all, nall, sb);
    MPI_Datatype t = halo_record_type(rec);
    MPICHECK(MPI_Alltoallv(sb, cnt, sdis, t, rb, rcnt, rdis, t, MPI_COMM_WORLD));
    MPICHECK(MPI_Type_free(&t));
    p->n = p->ng = 0;
    part_reserve(p, nin);
    part_unpack(p, NULL, 0, nin, all, nall, rb);
    p->n = nin;
    free(sb), free(rb), free(order), free(dest), free(cnt);
}

/* Weight of each lattice column along the axis, summed over ranks: each
 * local particle counts `each`. */
static double *halo_column_weights(halo_t *h, const particles_t *p, long ncol, double each)
{
    double *w = calloc((size_t)ncol, sizeof(double));
    if (!w) error_exit(1, "out of memory: %ld lattice columns", ncol);
    for (size_t i = 0; i < p->n; ++i) {
        long c = halo_column(h, p->x[h->axis][i]);
        w[c < 0 ? 0 : c >= ncol ? ncol - 1 : c] += each;
    }
    MPICHECK(MPI_Allreduce(MPI_IN_PLACE, w, (int)ncol, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD));
    return w;
}

static long halo_ncol(halo_t *h, const particles_t *p)
{
    real hi[3];
    halo_corner(h, p, hi);
    if (h->axis < 0) { /* the longest extent */
        h->axis = 0;
        for (int d = 1; d < h->dim; ++d)
            if (hi[d] - h->origin[d] > hi[h->axis] - h->origin[h->axis]) h->axis = d;
    }
    return halo_column(h, hi[h->axis]) + 1;
}

void halo_decompose(halo_t *h, particles_t *p)
{
    double t0 = MPI_Wtime();
    p->ng = 0;
    long ncol = halo_ncol(h, p);
    double *w = halo_column_weights(h, p, ncol, 1.0);
    halo_cut(h, w, ncol);
    free(w);
    halo_route(h, p);
    h->wall_comm += MPI_Wtime() - t0;
}

int halo_balance(halo_t *h, particles_t *p, double cost, double threshold)
{
    double sum = 0, max = 0;
    MPICHECK(MPI_Allreduce(&cost, &sum, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD));
    MPICHECK(MPI_Allreduce(&cost, &max, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD));
    double mean = sum / h->size, imb = mean > 0 ? max / mean - 1 : 0;
    if (imb <= threshold) return 0;
    double t0 = MPI_Wtime();
    long ncol = halo_ncol(h, p);
    double *w = halo_column_weights(h, p, ncol, p->n ? cost / (double)p->n : 0);
    long *old = malloc(((size_t)h->size + 1) * sizeof(long));
    if (!old) error_exit(1, "out of memory in halo_balance");
    memcpy(old, h->bound, ((size_t)h->size + 1) * sizeof(long));
    halo_cut(h, w, ncol);
    int moved = memcmp(old, h->bound, ((size_t)h->size + 1) * sizeof(long)) != 0;
    if (moved)
        message("load balance: the slowest rank took %.0f %% more than the mean (threshold %.0f %%): slab "
                "bounds moved", 100 * imb, 100 * threshold);
    free(old);
    free(w);
    if (moved) halo_route(h, p);
    h->wall_comm += MPI_Wtime() - t0;
    return moved;
}
