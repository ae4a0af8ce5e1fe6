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
#include "dem_body.h"
#include "mpi/comm.h"
#include "mpi/halo.h"

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

/* The halo's decisions at the grains' reach (the file's comment), or
 * (contact) at their contact reach: a cell of room and the grains' d. */
static void dem_geom(const dem_t *d, const halo_t *h, halo_geom *g, int contact)
{
    halo_geom_of(h, g);
    const int reach = (contact ? 1 : h->depth + 2) + (int)ceil((double)d->c.d / (double)h->support);
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
    d->scnt = calloc((size_t)g->size, sizeof(size_t));
    d->gcnt = calloc((size_t)g->size, sizeof(size_t));
    if (!d->soff || !d->goff || !d->scnt || !d->gcnt) error_exit(EXIT_SYSTEM, "out of memory");
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

/* Ghost records: ID, centre, velocity, spin, the contact tier's flag. */
enum { DEM_GHOST_DOUBLES = 11 };

/* The ranks other than this one that own a lattice cell within g->depth
 * cells of owned grain i (a periodic image's owner too), each once. */
static int dem_targets(const halo_geom *g, const dem_t *d, size_t i, int *out)
{
    int codes[HG_MAX_TARGETS], all[HG_MAX_TARGETS], m = 0;
    long c[3];
    real x[3];
    dem_cols(g, d, i, c, x);
    const int nt = hg_particle_targets(g, x, all, codes);
    for (int k = 0; k < nt; ++k) {
        int r = all[k], dup = r == g->rank; /* the grain itself is here: minimum images */
        for (int q = 0; q < m && !dup; ++q) dup = out[q] == r;
        if (!dup) out[m++] = r;
    }
    return m;
}

/* Slabs: a grain's targets depend on its lattice column along the slab
 * axis alone (hg_targets reads only that column; an image across another
 * periodic axis reaches the same ranks, and this one, which dem_targets
 * drops), so they are worked out once a column, at its first grain in ID
 * order. Only the near test of an image across a periodic slab axis reads
 * the coordinate itself: a grain in the same column on the other side of
 * that test is still within the reach's cell of room. METIS: per grain. */
typedef struct dem_memo {
    long c0, nc; /* the columns held: c0 .. c0 + nc - 1 */
    int w;       /* room a column */
    int *n, *r;  /* each column's count (-1: not yet) and ranks */
} dem_memo;

static void dem_memo_init(dem_memo *m, const halo_geom *g, const dem_t *d)
{
    memset(m, 0, sizeof *m);
    if (g->metis || !d->no) return;
    long lo = 0, hi = 0;
    for (size_t i = 0; i < d->no; ++i) {
        const long c = hg_column(g, g->axis, (real)d->x[g->axis][i]);
        if (i == 0 || c < lo) lo = c;
        if (i == 0 || c > hi) hi = c;
    }
    m->c0 = lo, m->nc = hi - lo + 1, m->w = 2 * (2 * g->depth + 1) + 2;
    if (m->nc > 1 << 24) return; /* a grain flung far away: per grain */
    m->n = malloc((size_t)m->nc * sizeof(int));
    m->r = malloc((size_t)m->nc * (size_t)m->w * sizeof(int));
    if (!m->n || !m->r) error_exit(EXIT_SYSTEM, "out of memory");
    for (long k = 0; k < m->nc; ++k) m->n[k] = -1;
}

static int dem_targets(const halo_geom *g, const dem_t *d, size_t i, int *out);

static int dem_targets_memo(dem_memo *m, const halo_geom *g, const dem_t *d, size_t i, int *out)
{
    if (!m->n) return dem_targets(g, d, i, out);
    const long k = hg_column(g, g->axis, (real)d->x[g->axis][i]) - m->c0;
    if (m->n[k] < 0) {
        const int nt = dem_targets(g, d, i, out);
        if (nt > m->w) return nt; /* cannot happen: 2 depth + 1 columns, and as many across the period */
        memcpy(&m->r[k * m->w], out, (size_t)nt * sizeof(int));
        m->n[k] = nt;
        return nt;
    }
    memcpy(out, &m->r[k * m->w], (size_t)m->n[k] * sizeof(int));
    return m->n[k];
}

/* The ghosts: for each other rank, the owned grains within the reach g of
 * its domain, those within the contact reach gc first (the tier a DEM
 * step refreshes: they can touch that rank's grains before the next
 * exchange), each tier in ID order; sent with their centres, velocities
 * and spins. */
static void dem_ghosts(dem_t *d, const halo_geom *g, const halo_geom *gc)
{
    const int size = g->size;
    const size_t no = d->no;
    int out[HG_MAX_TARGETS], cout[HG_MAX_TARGETS];
    size_t *fill = calloc(2 * (size_t)size, sizeof(size_t)), *cfill = fill + size;
    if (!fill) error_exit(EXIT_SYSTEM, "out of memory");
    memset(d->soff, 0, ((size_t)size + 1) * sizeof(size_t));
    memset(d->scnt, 0, (size_t)size * sizeof(size_t));
    dem_memo mg, mc;
    dem_memo_init(&mg, g, d), dem_memo_init(&mc, gc, d);
    for (int pass = 0; pass < 2; ++pass) {
        for (size_t i = 0; i < no; ++i) {
            const int nt = dem_targets_memo(&mg, g, d, i, out), nc = dem_targets_memo(&mc, gc, d, i, cout);
            for (int k = 0; k < nt; ++k) {
                const int r = out[k];
                int near = 0;
                for (int q = 0; q < nc && !near; ++q) near = cout[q] == r;
                if (pass == 0) d->soff[r + 1]++, d->scnt[r] += (size_t)near;
                else if (near) d->slist[d->soff[r] + cfill[r]++] = i;
                else d->slist[d->soff[r] + d->scnt[r] + fill[r]++] = i;
            }
        }
        if (pass == 1) break;
        for (int r = 0; r < size; ++r) d->soff[r + 1] += d->soff[r];
        if (d->soff[size] > d->scap || !d->slist) {
            free(d->slist);
            d->slist = dem_xmalloc(d->soff[size] * sizeof(size_t));
            d->scap = d->soff[size];
        }
    }
    free(fill), free(mg.n), free(mg.r), free(mc.n), free(mc.r);
    const size_t rb = DEM_GHOST_DOUBLES * sizeof(double);
    double *send = dem_xmalloc(d->soff[size] * rb);
    for (int q = 0; q < size; ++q)
        for (size_t k = d->soff[q]; k < d->soff[q + 1]; ++k) {
            const size_t i = d->slist[k];
            double *r = &send[k * DEM_GHOST_DOUBLES];
            r[0] = (double)d->id[i]; /* exact below 2^53 grains */
            for (int a = 0; a < 3; ++a) r[1 + a] = d->x[a][i], r[4 + a] = d->v[a][i], r[7 + a] = d->w[a][i];
            r[10] = k - d->soff[q] < d->scnt[q];
        }
    size_t *roff, *off = dem_offs(size, &roff);
    for (int r = 0; r <= size; ++r) off[r] = d->soff[r] * rb;
    double *recv = (double *)comm_exchange_bytes((const char *)send, off, roff);
    const size_t got = roff[size] / rb;
    dem_reserve(d, no + got);
    for (int r = 0; r <= size; ++r) d->goff[r] = roff[r] / rb;
    for (int q = 0; q < size; ++q) {
        d->gcnt[q] = 0;
        for (size_t k = d->goff[q]; k < d->goff[q + 1]; ++k) d->gcnt[q] += recv[k * DEM_GHOST_DOUBLES + 10] != 0;
    }
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

static void dem_exchanged(dem_t *d, const halo_t *h);

size_t dem_migrating(const dem_t *d, const halo_t *h)
{
    if (!d->split || !h) return 0;
    halo_geom g;
    dem_geom(d, h, &g, 0);
    size_t m = 0;
    for (size_t i = 0; i < d->no; ++i) m += dem_owner(&g, d, i) != g.rank;
    return m;
}

void dem_exchange(dem_t *d, const halo_t *h)
{
    if (!h || h->size < 2) return;
    halo_geom g, gc;
    dem_geom(d, h, &g, 0);
    dem_geom(d, h, &gc, 1);
    if (!d->split) dem_divide(d, &g);
    else d->n = d->no, dem_migrate(d, &g);
    dem_ghosts(d, &g, &gc);
    dem_exchanged(d, h);
}

/* ---- refreshes and sums ------------------------------------------------------------ */

int dem_exchange_due(dem_t *d, const halo_t *h, double maxdisp)
{
    if (!d->split) return 1;
    int due = d->due || h->method == HALO_METIS || maxdisp >= 0.5 * d->h || !d->bound0;
    for (int r = 0; r <= h->size && !due; ++r) due = h->bound[r] != d->bound0[r];
    for (int a = 0; a < 3 && !due; ++a) due = h->origin[a] != d->origin0[a];
    return comm_max((double)due) > 0;
}

double dem_max_shift(const dem_t *d)
{
    if (d->x0cap < d->no) return 0; /* no exchange yet: dem_exchange_due asks for one */
    const dem_view v = dem_view_of((dem_t *)d);
    const double *const x0[3] = {d->x0[0], d->x0[1], d->x0[2]};
    double m = 0;
    for (size_t i = 0; i < d->no; ++i) m = fmax(m, dem_shift2(&v, i, x0));
    return sqrt(m);
}

/* What this exchange was made for (dem_exchange_due). */
static void dem_exchanged(dem_t *d, const halo_t *h)
{
    if (!d->bound0) d->bound0 = dem_xmalloc(((size_t)h->size + 1) * sizeof(long));
    memcpy(d->bound0, h->bound, ((size_t)h->size + 1) * sizeof(long));
    for (int a = 0; a < 3; ++a) d->origin0[a] = h->origin[a];
    if (d->no > d->x0cap) {
        for (int a = 0; a < 3; ++a) {
            free(d->x0[a]);
            d->x0[a] = dem_xmalloc(d->cap * sizeof(double));
        }
        d->x0cap = d->cap;
    }
    for (int a = 0; a < 3; ++a) memcpy(d->x0[a], d->x[a], d->no * sizeof(double));
    d->due = 0;
    d->exchanges++;
}

size_t dem_refresh_lists(const dem_t *d, int what, size_t *sidx, size_t *ridx, size_t *nrecv)
{
    const int size = d->nrank, all = what != DEM_SEND_MOTION;
    size_t ns = 0, nr = 0;
    for (int r = 0; r < size; ++r) {
        const size_t s1 = all ? d->soff[r + 1] : d->soff[r] + d->scnt[r];
        const size_t g1 = all ? d->goff[r + 1] : d->goff[r] + d->gcnt[r];
        for (size_t k = d->soff[r]; k < s1; ++k) sidx[ns++] = d->slist[k];
        for (size_t k = d->goff[r]; k < g1; ++k) ridx[nr++] = d->no + k;
    }
    *nrecv = nr;
    return ns;
}

void dem_refresh_swap(const dem_t *d, int what, int k, const double *send, double *recv)
{
    const int size = d->nrank, all = what != DEM_SEND_MOTION;
    const size_t rb = (size_t)k * sizeof(double);
    size_t *roff, *off = dem_offs(size, &roff);
    for (int r = 0; r < size; ++r) { /* both ends know the counts: the lists of the last exchange */
        off[r + 1] = off[r] + (all ? d->soff[r + 1] - d->soff[r] : d->scnt[r]) * rb;
        roff[r + 1] = roff[r] + (all ? d->goff[r + 1] - d->goff[r] : d->gcnt[r]) * rb;
    }
    comm_exchange_known((const char *)send, off, (char *)recv, roff);
    free(off);
}

void dem_refresh(dem_t *d, int what)
{
    if (!d->split) return;
    const int k = what == DEM_SEND_COUPLING ? 11 : 9;
    d->refreshes += what == DEM_SEND_GHOSTS;
    size_t *sidx = dem_xmalloc((d->soff[d->nrank] + d->n - d->no) * sizeof(size_t)), *ridx = sidx + d->soff[d->nrank], nr;
    const size_t ns = dem_refresh_lists(d, what, sidx, ridx, &nr);
    double *const *vec[3] = {d->x, d->v, d->w}, *const *cpl[3] = {d->fint, d->fd, d->uf};
    double *const *const *src = what == DEM_SEND_COUPLING ? cpl : vec;
    double *send = dem_xmalloc((ns + nr) * (size_t)k * sizeof(double)), *recv = send + ns * (size_t)k;
    for (size_t m = 0; m < ns; ++m) {
        const size_t i = sidx[m];
        double *r = &send[m * (size_t)k];
        for (int q = 0; q < 3; ++q)
            for (int a = 0; a < 3; ++a) r[3 * q + a] = src[q][a][i];
        if (k == 11) r[9] = d->eps[i], r[10] = d->snorm[i];
    }
    dem_refresh_swap(d, what, k, send, recv);
    for (size_t m = 0; m < nr; ++m) {
        const size_t j = ridx[m];
        const double *r = &recv[m * (size_t)k];
        for (int q = 0; q < 3; ++q)
            for (int a = 0; a < 3; ++a) src[q][a][j] = r[3 * q + a];
        if (k == 11) d->eps[j] = r[9], d->snorm[j] = r[10];
    }
    free(send), free(sidx);
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

void dem_exch_steps(dem_t *d, double *ex, long m)
{
    if (!d->split) return;
    comm_sum_rows_ordered(ex, (size_t)m, 3);
    for (long k = 0; k < m; ++k)
        for (int q = 0; q < 3; ++q) d->exch[q] += ex[3 * k + q];
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
