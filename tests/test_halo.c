/* test_halo.c — the slab decomposition against brute force (mpi/halo.h).
 * Run under mpirun with 1 to 4 ranks (tests/run.sh uses 3). Every rank
 * builds the same random particle cloud, keeps a share, and then:
 *  - decomposition: every ID owned exactly once, each in its slab;
 *  - ghosts: for every owned particle, the IDs the cell list finds within
 *    the support (owned and ghosts) equal the IDs an all-pairs search over
 *    the whole cloud finds (brute force, SPH-EXA/SWIFT-style check);
 *  - migration: five rounds of random moves (< h each) keep every ID
 *    exactly once, owned by the slab its position falls in, and keep the
 *    neighbour sets exact;
 *  - refresh: a field set on the owners arrives in every ghost;
 *  - depth: ghosts d cells of 2h deep hold every particle within 2h d
 *    (less a hair) of an owned one (d = 2, the CPU; d = 3, the GPU, whose
 *    Verlet lists reach 2h + skin and whose ghosts must hold their own
 *    support too: 4h + 2 skin < 6h);
 *  - byte segments (halo_post_bytes / halo_wait_bytes, the GPU refresh):
 *    the IDs of every send list, packed field-major with an 8-aligned
 *    1-byte field, arrive in the ghost slots of the receiving rank;
 *  - balance: when a rank reports three times the cost of the others, the
 *    re-cut equalises the predicted cost (each particle weighs its rank's
 *    cost per particle) to within 25 % of the mean, and no ID is lost;
 * for slabs and for METIS parts of the coarse-cell graph alike; and with
 * periodic axes (slabs and METIS; 2D: x and y, 3D: x and z, so that one is
 * the slab axis and one is not), where the brute force takes the nearest image, the
 * moves wrap, the refresh must bring every image's position shifted by its
 * period, and (check_lattice) a lattice that fills the periods gives every
 * particle of a row the same kernel sum, before and after the whole lattice
 * moves across the period boundary.
 * Failures are counted on every rank and summed, so that all ranks take
 * part in every collective and the program ends nonzero on any failure. */
#include <math.h>
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "mpi/halo.h"
#include "cpu/nbr.h"
#include "core/particles.h"

static int fails;
#define CHECK(cond, ...)                                                                                     \
    do {                                                                                                     \
        if (!(cond)) {                                                                                       \
            if (fails++ < 10) fprintf(stderr, "FAIL %s:%d: ", __FILE__, __LINE__), fprintf(stderr, __VA_ARGS__), \
                fputc('\n', stderr);                                                                         \
        }                                                                                                    \
    } while (0)

enum { N = 3000 };
#define TOL (sizeof(real) == 4 ? 1e-5 : 1e-12) /* round-off of a position moved by a period */
static const double H = 0.0125, L[3] = {1.0, 0.3, 0.2}; /* support 2h = 0.025: 40 columns along x */

static double urand(unsigned *s)
{
    *s = *s * 1103515245u + 12345u;
    return ((*s >> 8) & 0xffffff) / (double)0x1000000;
}

/* The global cloud: positions g[d][id]; every rank holds the same copy. */
static real *g[3];
static int per; /* periodic axes of this run (bit d), period L[d] from 0 */

/* The separation of a and b along axis d: the nearest image on a periodic axis. */
static double sep(int d, double a, double b)
{
    double x = a - b;
    if (per >> d & 1) x -= L[d] * floor(x / L[d] + 0.5);
    return x;
}

static void cloud_init(particles_t *p, int dim, int rank, int size)
{
    unsigned s = 7;
    for (int d = 0; d < 3; ++d) g[d] = malloc(N * sizeof(real));
    for (int i = 0; i < N; ++i)
        for (int d = 0; d < 3; ++d) g[d][i] = d < dim ? (real)(urand(&s) * L[d]) : 0;
    size_t a = (size_t)N * (size_t)rank / (size_t)size, b = (size_t)N * (size_t)(rank + 1) / (size_t)size;
    part_alloc(p, dim, b - a);
    for (size_t i = a; i < b; ++i, ++p->n) {
        for (int d = 0; d < 3; ++d) p->x[d][p->n] = p->X0[d][p->n] = g[d][i];
        p->id[p->n] = (int64_t)i;
        p->vol[p->n] = 1;
    }
}

/* Move every particle of the cloud by a random step shorter than h (the
 * same on all ranks: the step is a function of the ID and the round). */
static void cloud_move(particles_t *p, int dim, int round)
{
    for (int i = 0; i < N; ++i) {
        unsigned s = (unsigned)(i * 7919 + round * 104729 + 1);
        for (int d = 0; d < dim; ++d) {
            real x = g[d][i] + (real)((urand(&s) - 0.5) * 1.4 * H);
            if (per >> d & 1) x = x < 0 ? x + (real)L[d] : x >= (real)L[d] ? x - (real)L[d] : x;
            else x = x < 0 ? -x : x > L[d] ? 2 * (real)L[d] - x : x;
            g[d][i] = x;
        }
    }
    for (size_t k = 0; k < p->n; ++k)
        for (int d = 0; d < dim; ++d) p->x[d][k] = g[d][p->id[k]];
}

static int cmp_i64(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

/* Every ID 0..N-1 owned by exactly one rank, inside that rank's slab. */
static void check_owned(const halo_t *h, const particles_t *p)
{
    int n = (int)p->n, *cnt = malloc((size_t)h->size * sizeof(int)), *dis = malloc((size_t)h->size * sizeof(int));
    MPI_Allgather(&n, 1, MPI_INT, cnt, 1, MPI_INT, MPI_COMM_WORLD);
    int tot = 0;
    for (int r = 0; r < h->size; ++r) dis[r] = tot, tot += cnt[r];
    CHECK(tot == N, "%d particles owned, expected %d", tot, N);
    int64_t *all = malloc((size_t)(tot > 0 ? tot : 1) * sizeof(int64_t));
    MPI_Allgatherv(p->id, n, MPI_INT64_T, all, cnt, dis, MPI_INT64_T, MPI_COMM_WORLD);
    qsort(all, (size_t)tot, sizeof(int64_t), cmp_i64);
    for (int k = 0; k < tot && k < N; ++k) CHECK(all[k] == k, "ID %d missing or duplicated", k);
    for (size_t i = 0; i < p->n; ++i) {
        long c[3];
        for (int d = 0; d < 3; ++d) c[d] = d < p->dim ? halo_column(h, d, p->x[d][i]) : 0;
        CHECK(halo_owner(h, c) == h->rank, "particle %lld outside its domain", (long long)p->id[i]);
    }
    free(all), free(cnt), free(dis);
}

/* Neighbour IDs of every owned particle (cell list over owned + ghosts)
 * against all pairs of the global cloud. */
static void check_neighbours(const nbr_grid *gr, const particles_t *p, real support)
{
    int64_t *mine = malloc(N * sizeof(int64_t)), *ref = malloc(N * sizeof(int64_t));
    real s2 = support * support;
    for (size_t i = 0; i < p->n; ++i) {
        size_t a = 0, b = 0;
        NBR_BEGIN(&gr->view, p->x, i, j)
            real xij[3];
            if (grid_pair(p->dim, p->x, i, j, xij) < s2) mine[a++] = p->id[j];
        NBR_END
        int64_t id = p->id[i];
        for (int j = 0; j < N; ++j) {
            real r2 = 0;
            for (int d = 0; d < p->dim; ++d) r2 += (real)(sep(d, g[d][id], g[d][j]) * sep(d, g[d][id], g[d][j]));
            if (r2 < s2) ref[b++] = j;
        }
        qsort(mine, a, sizeof(int64_t), cmp_i64);
        int same = a == b;
        for (size_t k = 0; same && k < a; ++k) same = mine[k] == ref[k];
        CHECK(same, "particle %lld: %zu neighbours found, %zu by brute force", (long long)id, a, b);
    }
    free(mine), free(ref);
}

static void check_refresh(halo_t *h, particles_t *p, int round)
{
    for (size_t i = 0; i < p->n + p->ng; ++i) p->C[i] = i < p->n ? (real)(2 * p->id[i] + round) : -1;
    int arr[1] = {part_array_find(p, p->C)};
    halo_refresh(h, p, arr, 1);
    for (size_t i = p->n; i < p->n + p->ng; ++i)
        CHECK(p->C[i] == (real)(2 * p->id[i] + round), "ghost %lld not refreshed", (long long)p->id[i]);
    /* positions: a ghost's is its owner's, an image's moved by a period */
    real *was[3];
    int ax[3];
    for (int d = 0; d < p->dim; ++d) {
        was[d] = malloc((p->ng + 1) * sizeof(real));
        memcpy(was[d], p->x[d] + p->n, p->ng * sizeof(real));
        for (size_t i = p->n; i < p->n + p->ng; ++i) p->x[d][i] = -99;
        ax[d] = part_array_find(p, p->x[d]);
    }
    halo_refresh(h, p, ax, p->dim);
    int bad = 0;
    for (int d = 0; d < p->dim; ++d) {
        for (size_t i = 0; i < p->ng; ++i) {
            double x = p->x[d][p->n + i], own = g[d][p->id[p->n + i]], off = x - own;
            bad += x != was[d][i] || fabs(off - L[d] * floor(off / L[d] + 0.5)) > TOL ||
                   (!(per >> d & 1) && off != 0);
        }
        free(was[d]);
    }
    CHECK(bad == 0, "%d ghost positions not their owners' (or an image's) after a refresh", bad);
}

static int cmp_ll(const void *a, const void *b)
{
    long long x = *(const long long *)a, y = *(const long long *)b;
    return (x > y) - (x < y);
}

/* Every particle of the cloud within radius of an owned one is held here
 * (owned or ghost): brute force over the global cloud. */
static void check_present(const particles_t *p, int dim, double radius)
{
    size_t m = p->n + p->ng;
    long long *ids = malloc((m + 1) * sizeof(long long));
    for (size_t k = 0; k < m; ++k) ids[k] = p->id[k];
    qsort(ids, m, sizeof *ids, cmp_ll);
    int missing = 0;
    for (size_t i = 0; i < p->n; ++i)
        for (long long j = 0; j < N; ++j) {
            double r2 = 0;
            for (int d = 0; d < dim; ++d) r2 += sep(d, p->x[d][i], g[d][j]) * sep(d, p->x[d][i], g[d][j]);
            if (r2 < radius * radius && !bsearch(&j, ids, m, sizeof *ids, cmp_ll)) missing++;
        }
    CHECK(missing == 0, "%d particles within %.4g of an owned particle are not held (depth too thin)", missing, radius);
    free(ids);
}

/* The GPU refresh's message layout, on the host: for each neighbour, the
 * IDs (8 bytes) then a 1-byte field, each block 8-aligned. */
static void check_bytes(halo_t *h, const particles_t *p)
{
    int m = h->nnb;
    size_t *sb = calloc((size_t)m + 1, sizeof(size_t)), *rb = calloc((size_t)m + 1, sizeof(size_t));
    for (int k = 0; k < m; ++k) {
        sb[k + 1] = sb[k] + 8 * h->nsend[k] + (h->nsend[k] + 7) / 8 * 8;
        rb[k + 1] = rb[k] + 8 * h->nrecv[k] + (h->nrecv[k] + 7) / 8 * 8;
    }
    char *sbuf = calloc(sb[m] + 8, 1), *rbuf = calloc(rb[m] + 8, 1);
    for (int k = 0; k < m; ++k)
        for (size_t q = 0; q < h->nsend[k]; ++q) {
            int64_t id = p->id[h->send[k][q]];
            memcpy(sbuf + sb[k] + 8 * q, &id, 8);
            sbuf[sb[k] + 8 * h->nsend[k] + q] = (char)(id % 97);
        }
    halo_post_bytes(h, sbuf, sb, rbuf, rb);
    halo_wait_bytes(h);
    size_t r = 0;
    int bad = 0;
    for (int k = 0; k < m; ++k)
        for (size_t q = 0; q < h->nrecv[k]; ++q, ++r) {
            int64_t id;
            memcpy(&id, rbuf + rb[k] + 8 * q, 8);
            size_t slot = h->recv[r];
            bad += slot < p->n || slot >= p->n + p->ng || id != p->id[slot] ||
                   rbuf[rb[k] + 8 * h->nrecv[k] + q] != (char)(id % 97);
        }
    CHECK(bad == 0, "%d ghost records arrived wrong through halo_post_bytes", bad);
    free(sb), free(rb), free(sbuf), free(rbuf);
}

/* A lattice of spacing a that fills the periods (x; in 3D also z; y is
 * not periodic, so the rows near its ends have cut supports): every
 * particle of a row (same y) has the same sum of a smooth function of the
 * distance over its support, whatever its place relative to the period
 * boundary or to the slabs; and after the whole lattice moved by 0.63 a
 * along the periodic axes (a column crossing the boundary, wrapped by the
 * exchange) the sums are the same again. */
static void check_lattice(int dim, int rank, int size, int depth)
{
    per = dim == 3 ? 5 : 1;
    const real support = (real)(2 * H), a = support / (dim == 3 ? 2 : 3), s2 = support * support;
    long n[3] = {lround(L[0] / (double)a), lround(L[1] / (double)a), dim == 3 ? lround(L[2] / (double)a) : 1};
    size_t tot = (size_t)(n[0] * n[1] * n[2]), lo = tot * (size_t)rank / (size_t)size, hi = tot * (size_t)(rank + 1) / (size_t)size;
    particles_t p;
    part_alloc(&p, dim, hi - lo);
    for (size_t k = lo; k < hi; ++k, ++p.n) {
        long i = (long)(k % (size_t)n[0]), j = (long)(k / (size_t)n[0] % (size_t)n[1]), q = (long)(k / (size_t)(n[0] * n[1]));
        p.x[0][p.n] = (real)((i + 0.5) * a), p.x[1][p.n] = (real)((j + 0.5) * a);
        p.x[2][p.n] = dim == 3 ? (real)((q + 0.5) * a) : 0;
        p.id[p.n] = (int64_t)k, p.vol[p.n] = 1;
    }
    int arr[8], na = 0;
    for (int d = 0; d < 3; ++d) arr[na++] = part_array_find(&p, p.x[d]);
    arr[na++] = part_array_find(&p, p.id), arr[na++] = part_array_find(&p, p.vol);
    halo_t h;
    halo_init(&h, dim, support, HALO_SLABS, -1, arr, na);
    halo_set_depth(&h, depth);
    const real plo[3] = {0, 0, 0}, plen[3] = {(real)(n[0] * a), (real)(n[1] * a), (real)(n[2] * a)};
    halo_set_periodic(&h, per, plo, plen);
    halo_decompose(&h, &p);
    nbr_grid gr = {0};
    double *rlo = malloc((size_t)n[1] * sizeof(double)), *rhi = malloc((size_t)n[1] * sizeof(double));
    double *ref = malloc((size_t)n[1] * sizeof(double));
    for (int pass = 0; pass < 2; ++pass) {
        if (pass == 1)
            for (size_t i = 0; i < p.n; ++i) {
                p.x[0][i] += (real)(0.63 * a);
                if (dim == 3) p.x[2][i] += (real)(0.63 * a);
            }
        halo_exchange(&h, &p);
        nbr_build(&gr, &p, support, h.origin);
        halo_sorted(&h, gr.perm, p.n + p.ng);
        for (long r = 0; r < n[1]; ++r) rlo[r] = 1e300, rhi[r] = -1e300;
        long crossed = 0;
        for (size_t i = 0; i < p.n; ++i) {
            double sum = 0;
            NBR_BEGIN(&gr.view, p.x, i, j)
                real xij[3], r2 = grid_pair(dim, p.x, i, j, xij);
                if (r2 < s2) sum += (1 - (double)r2 / (double)s2) * (1 - (double)r2 / (double)s2);
            NBR_END
            long r = lround((double)p.x[1][i] / (double)a - 0.5);
            rlo[r] = sum < rlo[r] ? sum : rlo[r], rhi[r] = sum > rhi[r] ? sum : rhi[r];
            crossed += pass == 1 && p.id[i] % n[0] == n[0] - 1 && p.x[0][i] < a;
        }
        MPI_Allreduce(MPI_IN_PLACE, rlo, (int)n[1], MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
        MPI_Allreduce(MPI_IN_PLACE, rhi, (int)n[1], MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
        MPI_Allreduce(MPI_IN_PLACE, &crossed, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
        int bad = 0;
        for (long r = 0; r < n[1]; ++r) {
            bad += rhi[r] - rlo[r] > TOL * rhi[r];
            if (pass == 0) ref[r] = rhi[r];
            else bad += fabs(rhi[r] - ref[r]) > TOL * ref[r];
        }
        CHECK(bad == 0, "%dD lattice, pass %d: %d rows whose kernel sums differ along the period", dim, pass, bad);
        if (pass == 1)
            CHECK(crossed == n[1] * n[2], "%ld particles of the last column wrapped to the start, expected %ld", crossed,
                  n[1] * n[2]);
    }
    if (rank == 0) printf("%dD lattice across the period, depth %d: row sums equal, also after crossing\n", dim, depth);
    free(rlo), free(rhi), free(ref);
    halo_free(&h);
    nbr_free(&gr);
    part_free(&p);
}

static void run_dim(int dim, int method, int rank, int size, int depth, int periodic)
{
    per = periodic;
    particles_t p;
    nbr_grid gr = {0};
    cloud_init(&p, dim, rank, size);
    int arr[8], na = 0;
    for (int d = 0; d < 3; ++d) arr[na++] = part_array_find(&p, p.x[d]);
    arr[na++] = part_array_find(&p, p.id), arr[na++] = part_array_find(&p, p.vol);
    halo_t h;
    real support = (real)(2 * H);
    halo_init(&h, dim, support, method, -1, arr, na);
    halo_set_depth(&h, depth);
    if (per) {
        const real lo[3] = {0, 0, 0}, len[3] = {(real)L[0], (real)L[1], (real)L[2]};
        halo_set_periodic(&h, per, lo, len);
    }
    halo_decompose(&h, &p);
    CHECK(method == HALO_METIS || h.axis == 0, "slab axis %d, expected the longest (x)", h.axis);
    check_owned(&h, &p);
    for (int round = 0; round < 6; ++round) {
        if (round > 0) cloud_move(&p, dim, round);
        halo_exchange(&h, &p);
        check_owned(&h, &p);
        nbr_build(&gr, &p, support, size > 1 || per ? h.origin : NULL);
        halo_sorted(&h, gr.perm, p.n + p.ng);
        check_neighbours(&gr, &p, support);
        check_refresh(&h, &p, round);
        check_present(&p, dim, 0.999 * support * depth);
        check_bytes(&h, &p);
    }
    long long moved = h.migrated;
    MPI_Allreduce(MPI_IN_PLACE, &moved, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD);
    CHECK(size == 1 || moved > 0, "no particle migrated in five rounds");
    /* rank 0 reports 3 s, the others 1 s: each particle carries its share of
     * its rank's cost (in C, which travels with it); after the re-cut the
     * costs so predicted must be near equal */
    double cost = rank == 0 ? 3.0 : 1.0;
    for (size_t i = 0; i < p.n; ++i) p.C[i] = (real)(cost / (double)p.n);
    int changed = halo_balance(&h, &p, cost, 0.1);
    double mine = 0, cmax = 0, csum = 0;
    for (size_t i = 0; i < p.n; ++i) mine += (double)p.C[i];
    MPI_Allreduce(&mine, &cmax, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
    MPI_Allreduce(&mine, &csum, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    if (size > 1) {
        CHECK(changed, "a 3x cost imbalance did not re-cut the domains");
        CHECK(cmax / (csum / size) < 1.25, "predicted cost after balance: max %.3f of the mean (was %.3f)",
              cmax / (csum / size), 3.0 / ((3.0 + size - 1) / size));
    }
    check_owned(&h, &p);
    halo_exchange(&h, &p);
    nbr_build(&gr, &p, support, size > 1 || per ? h.origin : NULL);
    check_neighbours(&gr, &p, support);
    int nbmax = h.nnb;
    MPI_Allreduce(MPI_IN_PLACE, &nbmax, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    if (rank == 0)
        printf("%dD %s, depth %d%s: %lld migrations, up to %d channels, balance %s\n", dim,
               method == HALO_METIS ? "metis" : "slabs", depth, per ? ", periodic" : "", moved, nbmax,
               changed ? "moved bounds" : "no move");
    halo_free(&h);
    nbr_free(&gr);
    part_free(&p);
    for (int d = 0; d < 3; ++d) free(g[d]);
}

int main(int argc, char **argv)
{
    MPI_Init(&argc, &argv);
    int rank, size;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    for (int depth = HALO_DEPTH; depth <= 3; ++depth) {
        for (int m = HALO_SLABS; m <= HALO_METIS; ++m) {
            run_dim(2, m, rank, size, depth, 0);
            run_dim(3, m, rank, size, depth, 0);
        }
        for (int m = HALO_SLABS; m <= HALO_METIS; ++m) {
            run_dim(2, m, rank, size, depth, 3);
            run_dim(3, m, rank, size, depth, 5);
        }
        check_lattice(2, rank, size, depth);
        check_lattice(3, rank, size, depth);
    }
    int total = 0;
    MPI_Allreduce(&fails, &total, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
    if (rank == 0) printf("test_halo on %d ranks: %s (%d failed checks)\n", size, total ? "FAIL" : "ok", total);
    MPI_Finalize();
    return total ? 1 : 0;
}
