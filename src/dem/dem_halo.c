/* dem_halo.c — the DEM grains divided among the ranks as the fluid is
 * (dem.h, "split"): ownership by the fluid's halo lattice, migration with
 * the whole state, ghosts near each rank's domain, their refresh at each
 * DEM step, the grains' sums over the fluid brought home, and the whole
 * store for output. Messages go through comm_exchange_bytes (mpi/comm.h).
 *
 * The reach. A rank needs, besides its own grains: every grain within 2h
 * of its fluid particles, owned and ghosts (the fraction at each, eq. 15,
 * and the source), which lie within the halo's depth cells of 2h of its
 * domain (and, on the GPU between list builds, their skin beyond); and
 * every grain within d of its own (contacts). A ghost therefore goes to
 * every rank owning a lattice cell within depth + 2 + ceil(d / 2h) cells
 * of the grain (hg_particle_targets at that depth, periodic images
 * included): a cell for the kernel, a cell of room for what moves between
 * two exchanges (a grain over one fluid step, a GPU ghost within its
 * skin). Exchanges run at each coupling, so ownership follows the grains
 * at the fluid's step.
 *
 * Order. The owned grains are kept in ID order; the ghosts in their
 * owners' rank order, each owner's in its ID order. Every choice is made
 * from positions and IDs, so a run is the same bits run to run; between
 * rank counts the sums over a cell's grains run in another order (round-
 * off: tests/validate_mpi.py). */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "core/error.h"
#include "dem.h"
#include "mpi/comm.h"
#include "mpi/halo.h"

/* ---- the per-grain arrays ------------------------------------------------------ */

typedef struct dem_arr {
    void **a;     /* the array's pointer in dem_t */
    size_t bytes; /* bytes a grain */
} dem_arr;

enum { DEM_NARR = 28 };

/* Every per-grain array of d; the first DEM_NMIG travel with a migrating
 * grain (the rest are scratch a step rewrites). */
enum { DEM_NMIG = 24 };
static void dem_arrays(dem_t *d, dem_arr t[DEM_NARR])
{
    int k = 0;
    double **vec[6] = {d->x, d->v, d->w, d->fint, d->fd, d->uf};
    for (int q = 0; q < 6; ++q)
        for (int a = 0; a < 3; ++a) t[k++] = (dem_arr){(void **)&vec[q][a], sizeof(double)};
    t[k++] = (dem_arr){(void **)&d->eps, sizeof(double)};
    t[k++] = (dem_arr){(void **)&d->snorm, sizeof(double)};
    t[k++] = (dem_arr){(void **)&d->id, sizeof(int64_t)};
    t[k++] = (dem_arr){(void **)&d->ncon, sizeof(int)};
    t[k++] = (dem_arr){(void **)&d->cid, DEM_CMAX * sizeof(int64_t)};
    t[k++] = (dem_arr){(void **)&d->cxi, 3 * DEM_CMAX * sizeof(double)};
    t[k++] = (dem_arr){(void **)&d->ncon2, sizeof(int)};    /* 24: scratch from here */
    t[k++] = (dem_arr){(void **)&d->cid2, DEM_CMAX * sizeof(int64_t)};
    t[k++] = (dem_arr){(void **)&d->cxi2, 3 * DEM_CMAX * sizeof(double)};
    t[k] = (dem_arr){(void **)&d->gsum, 5 * sizeof(double)}; /* k = DEM_NARR - 1 */
}

void dem_reserve(dem_t *d, size_t m)
{
    if (m <= d->cap) return;
    size_t cap = d->cap + d->cap / 2;
    if (cap < m) cap = m;
    dem_arr t[DEM_NARR];
    dem_arrays(d, t);
    for (int k = 0; k < DEM_NARR; ++k) {
        void *q = realloc(*t[k].a, cap * t[k].bytes);
        if (!q) error_exit(EXIT_SYSTEM, "out of memory for %zu DEM grains", cap);
        *t[k].a = q;
    }
    d->cap = cap;
}

/* Bytes of a migrating grain's record. */
static size_t dem_rec_bytes(dem_t *d)
{
    dem_arr t[DEM_NARR];
    dem_arrays(d, t);
    size_t b = 0;
    for (int k = 0; k < DEM_NMIG; ++k) b += t[k].bytes;
    return b;
}

static void dem_pack(dem_t *d, size_t i, char *buf)
{
    dem_arr t[DEM_NARR];
    dem_arrays(d, t);
    for (int k = 0; k < DEM_NMIG; ++k) {
        memcpy(buf, (char *)*t[k].a + i * t[k].bytes, t[k].bytes);
        buf += t[k].bytes;
    }
}

static void dem_unpack(dem_t *d, size_t i, const char *buf)
{
    dem_arr t[DEM_NARR];
    dem_arrays(d, t);
    for (int k = 0; k < DEM_NMIG; ++k) {
        memcpy((char *)*t[k].a + i * t[k].bytes, buf, t[k].bytes);
        buf += t[k].bytes;
    }
}

/* Grain j's record to slot i (same store). */
static void dem_move_grain(dem_t *d, size_t j, size_t i)
{
    if (i == j) return;
    dem_arr t[DEM_NARR];
    dem_arrays(d, t);
    for (int k = 0; k < DEM_NMIG; ++k)
        memcpy((char *)*t[k].a + i * t[k].bytes, (char *)*t[k].a + j * t[k].bytes, t[k].bytes);
}

static void *dem_xmalloc(size_t n)
{
    void *q = malloc(n ? n : 1);
    if (!q) error_exit(EXIT_SYSTEM, "out of memory exchanging DEM grains (%zu bytes)", n);
    return q;
}

/* Two arrays of size + 1 offsets (send, receive), zeroed: free the first. */
static size_t *dem_offs(int size, size_t **roff)
{
    size_t *o = calloc(2 * ((size_t)size + 1), sizeof(size_t));
    if (!o) error_exit(EXIT_SYSTEM, "out of memory");
    *roff = o + size + 1;
    return o;
}

/* ---- ownership ------------------------------------------------------------------- */

/* The halo's decisions at the grains' reach (the file's comment). */
static void dem_geom(const dem_t *d, const halo_t *h, halo_geom *g)
{
    halo_geom_of(h, g);
    const int reach = h->depth + 2 + (int)ceil((double)d->c.d / (double)h->support);
    g->depth = reach;
    for (int a = 0; a < 3; ++a) {
        g->near_lo[a] = h->plo[a] - (real)reach * h->support;
        g->near_hi[a] = h->plo[a] + h->plen[a] + (real)reach * h->support;
    }
}

static void dem_cols(const halo_geom *g, const dem_t *d, size_t i, long c[3], real x[3])
{
    for (int a = 0; a < 3; ++a) {
        x[a] = (real)d->x[a][i];
        c[a] = a < g->dim ? hg_column(g, a, x[a]) : 0;
    }
}

static int dem_owner(const halo_geom *g, const dem_t *d, size_t i)
{
    long c[3];
    real x[3];
    dem_cols(g, d, i, c, x);
    return hg_owner(g, c);
}

static int dem_cmp_id(const void *a, const void *b)
{
    const int64_t x = ((const int64_t *)a)[0], y = ((const int64_t *)b)[0];
    return (x > y) - (x < y);
}

/* The owned grains [0, no) into ID order. */
static void dem_sort_owned(dem_t *d)
{
    const size_t no = d->no, rb = dem_rec_bytes(d);
    int sorted = 1;
    for (size_t i = 1; i < no && sorted; ++i) sorted = d->id[i - 1] < d->id[i];
    if (sorted) return;
    int64_t *key = dem_xmalloc(2 * no * sizeof(int64_t)); /* (id, index) pairs */
    for (size_t i = 0; i < no; ++i) key[2 * i] = d->id[i], key[2 * i + 1] = (int64_t)i;
    qsort(key, no, 2 * sizeof(int64_t), dem_cmp_id);
    char *buf = dem_xmalloc(no * rb);
    for (size_t i = 0; i < no; ++i) dem_pack(d, (size_t)key[2 * i + 1], buf + i * rb);
    for (size_t i = 0; i < no; ++i) dem_unpack(d, i, buf + i * rb);
    free(buf), free(key);
}

/* The first division: this rank keeps its own grains of the replicated
 * store, in ID order. */
static void dem_divide(dem_t *d, const halo_geom *g)
{
    size_t m = 0;
    for (size_t i = 0; i < d->n; ++i)
        if (dem_owner(g, d, i) == g->rank) dem_move_grain(d, i, m++);
    d->n = d->no = m;
    d->split = 1, d->nrank = g->size;
    d->soff = calloc((size_t)g->size + 1, sizeof(size_t));
    d->goff = calloc((size_t)g->size + 1, sizeof(size_t));
    if (!d->soff || !d->goff) error_exit(EXIT_SYSTEM, "out of memory");
}

/* Owned grains that left the domain to their new owners, with their state. */
static void dem_migrate(dem_t *d, const halo_geom *g)
{
    const int size = g->size;
    const size_t rb = dem_rec_bytes(d), no = d->no;
    int *to = dem_xmalloc(no * sizeof(int));
    size_t *off = calloc((size_t)size + 1, sizeof(size_t)), *fill = calloc((size_t)size, sizeof(size_t));
    if (!off || !fill) error_exit(EXIT_SYSTEM, "out of memory");
    for (size_t i = 0; i < no; ++i) {
        to[i] = dem_owner(g, d, i);
        if (to[i] != g->rank) off[to[i] + 1]++;
    }
    for (int r = 0; r < size; ++r) off[r + 1] += off[r];
    char *send = dem_xmalloc(off[size] * rb);
    size_t keep = 0;
    for (size_t i = 0; i < no; ++i)
        if (to[i] != g->rank) dem_pack(d, i, send + (off[to[i]] + fill[to[i]]++) * rb);
        else dem_move_grain(d, i, keep++);
    size_t *roff, *o2 = dem_offs(size, &roff);
    for (int r = 0; r <= size; ++r) off[r] *= rb;
    char *recv = comm_exchange_bytes(send, off, roff);
    const size_t got = roff[size] / rb;
    dem_reserve(d, keep + got);
    for (size_t k = 0; k < got; ++k) dem_unpack(d, keep + k, recv + k * rb);
    d->n = d->no = keep + got;
    d->migrated += (long long)(no - keep);
    free(recv), free(send), free(off), free(fill), free(to), free(o2);
    dem_sort_owned(d);
}

/* Ghost records: ID, centre, velocity, spin. */
enum { DEM_GHOST_DOUBLES = 10 };

static void dem_ghosts(dem_t *d, const halo_geom *g)
{
    const int size = g->size;
    const size_t no = d->no;
    int out[HG_MAX_TARGETS], codes[HG_MAX_TARGETS];
    /* count, then list: each owned grain once for each other rank that wants it */
    memset(d->soff, 0, ((size_t)size + 1) * sizeof(size_t));
    for (int pass = 0; pass < 2; ++pass) {
        size_t *fill = calloc((size_t)size, sizeof(size_t));
        if (!fill) error_exit(EXIT_SYSTEM, "out of memory");
        for (size_t i = 0; i < no; ++i) {
            long c[3];
            real x[3];
            dem_cols(g, d, i, c, x);
            (void)c;
            int nt = hg_particle_targets(g, x, out, codes);
            for (int k = 0; k < nt; ++k) {
                int r = out[k], dup = r == g->rank; /* the grain itself is here: minimum images */
                for (int q = 0; q < k && !dup; ++q) dup = out[q] == r;
                if (dup) continue;
                if (pass == 0) d->soff[r + 1]++;
                else d->slist[d->soff[r] + fill[r]++] = i;
            }
        }
        free(fill);
        if (pass == 1) break;
        for (int r = 0; r < size; ++r) d->soff[r + 1] += d->soff[r];
        if (d->soff[size] > d->scap || !d->slist) {
            free(d->slist);
            d->slist = dem_xmalloc(d->soff[size] * sizeof(size_t));
            d->scap = d->soff[size];
        }
    }
    const size_t rb = DEM_GHOST_DOUBLES * sizeof(double);
    double *send = dem_xmalloc(d->soff[size] * rb);
    for (size_t k = 0; k < d->soff[size]; ++k) {
        const size_t i = d->slist[k];
        double *r = &send[k * DEM_GHOST_DOUBLES];
        r[0] = (double)d->id[i]; /* exact below 2^53 grains */
        for (int a = 0; a < 3; ++a) r[1 + a] = d->x[a][i], r[4 + a] = d->v[a][i], r[7 + a] = d->w[a][i];
    }
    size_t *roff, *off = dem_offs(size, &roff);
    for (int r = 0; r <= size; ++r) off[r] = d->soff[r] * rb;
    double *recv = (double *)comm_exchange_bytes((const char *)send, off, roff);
    const size_t got = roff[size] / rb;
    dem_reserve(d, no + got);
    for (int r = 0; r <= size; ++r) d->goff[r] = roff[r] / rb;
    for (size_t k = 0; k < got; ++k) {
        const double *r = &recv[k * DEM_GHOST_DOUBLES];
        const size_t j = no + k;
        d->id[j] = (int64_t)r[0];
        for (int a = 0; a < 3; ++a) {
            d->x[a][j] = r[1 + a], d->v[a][j] = r[4 + a], d->w[a][j] = r[7 + a];
            d->fint[a][j] = d->fd[a][j] = d->uf[a][j] = 0;
        }
        d->eps[j] = 1, d->snorm[j] = 0, d->ncon[j] = 0, d->ncon2[j] = 0;
    }
    d->n = no + got;
    free(recv), free(send), free(off);
}

void dem_exchange(dem_t *d, const halo_t *h)
{
    if (!h || h->size < 2) return;
    halo_geom g;
    dem_geom(d, h, &g);
    if (!d->split) dem_divide(d, &g);
    else d->n = d->no, dem_migrate(d, &g);
    dem_ghosts(d, &g);
}

/* ---- refreshes and sums ------------------------------------------------------------ */

void dem_refresh(dem_t *d, int what)
{
    if (!d->split) return;
    const int size = d->nrank, k = what == DEM_SEND_MOTION ? 9 : 11;
    double *const *vec[3] = {d->x, d->v, d->w}, *const *cpl[3] = {d->fint, d->fd, d->uf};
    double *send = dem_xmalloc(d->soff[size] * (size_t)k * sizeof(double));
    for (size_t m = 0; m < d->soff[size]; ++m) {
        const size_t i = d->slist[m];
        double *r = &send[m * (size_t)k];
        for (int q = 0; q < 3; ++q)
            for (int a = 0; a < 3; ++a) r[3 * q + a] = what == DEM_SEND_MOTION ? vec[q][a][i] : cpl[q][a][i];
        if (what != DEM_SEND_MOTION) r[9] = d->eps[i], r[10] = d->snorm[i];
    }
    size_t *roff, *off = dem_offs(size, &roff);
    for (int r = 0; r <= size; ++r) off[r] = d->soff[r] * (size_t)k * sizeof(double);
    double *recv = (double *)comm_exchange_bytes((const char *)send, off, roff);
    if (roff[size] != (d->n - d->no) * (size_t)k * sizeof(double))
        error_exit(1, "dem_refresh: %zu bytes for %zu ghost grains", roff[size], d->n - d->no);
    for (size_t m = 0; m < d->n - d->no; ++m) {
        const size_t j = d->no + m;
        const double *r = &recv[m * (size_t)k];
        for (int q = 0; q < 3; ++q)
            for (int a = 0; a < 3; ++a) (what == DEM_SEND_MOTION ? vec : cpl)[q][a][j] = r[3 * q + a];
        if (what != DEM_SEND_MOTION) d->eps[j] = r[9], d->snorm[j] = r[10];
    }
    free(recv), free(send), free(off);
}

void dem_sums_home(dem_t *d)
{
    if (!d->split) return;
    const int size = d->nrank, me = comm_rank();
    const size_t rb = 5 * sizeof(double), no = d->no;
    /* the ghosts' rows to their owners: ghosts from rank r are r's slist to this rank, in order */
    size_t *roff, *off = dem_offs(size, &roff);
    for (int r = 0; r <= size; ++r) off[r] = d->goff[r] * rb;
    double *recv = (double *)comm_exchange_bytes((const char *)&d->gsum[5 * no], off, roff);
    double *own = dem_xmalloc(no * rb);
    memcpy(own, d->gsum, no * rb);
    memset(d->gsum, 0, no * rb);
    for (int r = 0; r < size; ++r) { /* rank order: each owned grain's total the same on any timing */
        if (r == me) {
            for (size_t i = 0; i < 5 * no; ++i) d->gsum[i] += own[i];
            continue;
        }
        const size_t m0 = roff[r] / rb, m1 = roff[r + 1] / rb;
        if (m1 - m0 != d->soff[r + 1] - d->soff[r]) error_exit(1, "dem_sums_home: rank %d sent %zu rows", r, m1 - m0);
        for (size_t m = m0; m < m1; ++m) {
            const size_t i = d->slist[d->soff[r] + (m - m0)];
            for (int q = 0; q < 5; ++q) d->gsum[5 * i + (size_t)q] += recv[5 * m + (size_t)q];
        }
    }
    free(own), free(recv), free(off);
}

void dem_sum_ranks(const dem_t *d, double *x, int k)
{
    if (!d->split) return;
    double row[16] = {0};
    if (k > 16) error_exit(1, "dem_sum_ranks: %d values", k);
    const int rows = (k + 7) / 8;
    for (int q = 0; q < k; ++q) row[q] = x[q];
    comm_sum_rows_ordered(row, (size_t)rows, 8);
    for (int q = 0; q < k; ++q) x[q] = row[q];
}

void dem_totals(const dem_t *d, double *ke, double exch[3])
{
    double x[1] = {dem_kinetic_energy(d)};
    dem_sum_ranks(d, x, 1);
    *ke = x[0];
    for (int q = 0; q < 3; ++q) exch[q] = d->exch[q]; /* every rank's: summed over the ranks at each DEM step */
}

/* ---- the whole store --------------------------------------------------------------- */

dem_t *dem_whole(dem_t *d)
{
    if (!d || !d->split) return d;
    const int size = d->nrank;
    const size_t rb = dem_rec_bytes(d);
    char *one = dem_xmalloc(d->no * rb);
    for (size_t i = 0; i < d->no; ++i) dem_pack(d, i, one + i * rb);
    /* every rank's owned records to every rank */
    char *send = dem_xmalloc((size_t)size * d->no * rb);
    size_t *roff, *off = dem_offs(size, &roff);
    for (int r = 0; r < size; ++r) memcpy(send + (size_t)r * d->no * rb, one, d->no * rb), off[r] = (size_t)r * d->no * rb;
    off[size] = (size_t)size * d->no * rb;
    char *recv = comm_exchange_bytes(send, off, roff);
    const size_t got = roff[size];
    free(send), free(one), free(off);
    if (got != d->ntot * rb) error_exit(1, "dem_whole: %zu grains on the ranks, %zu in the run", got / rb, d->ntot);
    dem_t *w = dem_alloc(d->ntot);
    w->c = d->c, w->coupling = d->coupling, w->motion = d->motion;
    w->V = d->V, w->m = d->m, w->I = d->I, w->dt = d->dt, w->steps = d->steps;
    w->rho_f = d->rho_f, w->nu = d->nu, w->K = d->K, w->h = d->h, w->t_damp = d->t_damp, w->per = d->per;
    for (int a = 0; a < 3; ++a) w->g[a] = d->g[a], w->plen[a] = d->plen[a], w->exch[a] = d->exch[a];
    for (size_t k = 0; k < d->ntot; ++k) { /* each record into its ID's slot */
        int64_t id;
        memcpy(&id, recv + k * rb + 20 * sizeof(double), sizeof id); /* after 18 vector components, eps, snorm */
        if (id < 0 || (size_t)id >= d->ntot) error_exit(1, "dem_whole: grain ID %lld", (long long)id);
        dem_unpack(w, (size_t)id, recv + k * rb);
    }
    free(recv);
    return w;
}

void dem_whole_free(const dem_t *d, dem_t *whole)
{
    if (whole && whole != d) dem_free(whole);
}
