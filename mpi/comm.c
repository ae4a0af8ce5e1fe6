/* comm.c — see comm.h. */
#include "comm.h"
#include <mpi.h>
#include <stdlib.h>
#include "../src/core/error.h"
#include "../src/core/ksum.h"

int comm_rank(void)
{
    int r;
    MPICHECK(MPI_Comm_rank(MPI_COMM_WORLD, &r));
    return r;
}

int comm_size(void)
{
    int n;
    MPICHECK(MPI_Comm_size(MPI_COMM_WORLD, &n));
    return n;
}

static double comm_reduce(double x, MPI_Op op)
{
    double y;
    MPICHECK(MPI_Allreduce(&x, &y, 1, MPI_DOUBLE, op, MPI_COMM_WORLD));
    return y;
}

double comm_sum(double x) { return comm_reduce(x, MPI_SUM); }
double comm_sum_compensated(double hi, double lo)
{
    int n = comm_size();
    double mine[2] = {hi, lo}, *all = malloc(2 * (size_t)n * sizeof *all);
    if (!all) error_exit(1, "out of memory in comm_sum_compensated");
    MPICHECK(MPI_Allgather(mine, 2, MPI_DOUBLE, all, 2, MPI_DOUBLE, MPI_COMM_WORLD));
    ksum k = {0, 0};
    for (int r = 0; r < 2 * n; ++r) ksum_add(&k, all[r]);
    free(all);
    return ksum_value(k);
}
double comm_max(double x) { return comm_reduce(x, MPI_MAX); }

void comm_max_n(double *x, int n)
{
    if (comm_size() > 1) MPICHECK(MPI_Allreduce(MPI_IN_PLACE, x, n, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD));
}
double comm_min(double x) { return comm_reduce(x, MPI_MIN); }

long long comm_sum_ll(long long x)
{
    long long y;
    MPICHECK(MPI_Allreduce(&x, &y, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD));
    return y;
}

void comm_sum_rows_ordered(double *x, size_t n, int k)
{
    const int size = comm_size();
    if (size == 1) return;
    if (k < 1 || k > 8) error_exit(1, "comm_sum_rows_ordered: %d values a row (1 to 8)", k);
    const size_t w = (size_t)k + 1; /* a record: the row's index, then its values */
    size_t nz = 0;
    for (size_t i = 0; i < n; ++i)
        for (int q = 0; q < k; ++q)
            if (x[i * (size_t)k + (size_t)q] != 0) {
                ++nz;
                break;
            }
    double *mine = malloc((nz ? nz : 1) * w * sizeof(double));
    int *cnt = malloc((size_t)size * sizeof(int)), *dsp = malloc((size_t)size * sizeof(int));
    if (!mine || !cnt || !dsp) error_exit(1, "out of memory in comm_sum_rows_ordered");
    size_t m = 0;
    for (size_t i = 0; i < n; ++i) {
        const double *r = &x[i * (size_t)k];
        int any = 0;
        for (int q = 0; q < k; ++q) any |= r[q] != 0;
        if (!any) continue;
        mine[m * w] = (double)i; /* exact below 2^53 rows */
        for (int q = 0; q < k; ++q) mine[m * w + 1 + (size_t)q] = r[q];
        ++m;
    }
    if (nz * w > 0x7fffffff) error_exit(1, "comm_sum_rows_ordered: %zu rows over the int count of MPI", nz);
    int c = (int)(nz * w);
    MPICHECK(MPI_Allgather(&c, 1, MPI_INT, cnt, 1, MPI_INT, MPI_COMM_WORLD));
    long long tot = 0;
    for (int r = 0; r < size; ++r) dsp[r] = (int)tot, tot += cnt[r];
    if (tot > 0x7fffffff) error_exit(1, "comm_sum_rows_ordered: %lld values over the int count of MPI", tot);
    double *all = malloc((size_t)(tot ? tot : 1) * sizeof(double));
    unsigned char *seen = calloc(n ? n : 1, 1);
    if (!all || !seen) error_exit(1, "out of memory in comm_sum_rows_ordered");
    MPICHECK(MPI_Allgatherv(mine, c, MPI_DOUBLE, all, cnt, dsp, MPI_DOUBLE, MPI_COMM_WORLD));
    for (size_t i = 0; i < n * (size_t)k; ++i) x[i] = 0;
    for (long long e = 0; e < tot; e += (long long)w) { /* rank order, then row order */
        const double *rec = &all[e];
        const size_t i = (size_t)rec[0];
        double *r = &x[i * (size_t)k];
        for (int q = 0; q < k; ++q) r[q] = seen[i] ? r[q] + rec[1 + q] : rec[1 + q];
        seen[i] = 1;
    }
    free(mine), free(cnt), free(dsp), free(all), free(seen);
}

char *comm_exchange_bytes(const char *send, const size_t *soff, size_t *roff)
{
    const int size = comm_size();
    int *sc = malloc(4 * (size_t)size * sizeof(int));
    if (!sc) error_exit(1, "out of memory in comm_exchange_bytes");
    int *sd = sc + size, *rc = sc + 2 * size, *rd = sc + 3 * size;
    for (int r = 0; r < size; ++r) {
        if (soff[r + 1] - soff[0] > 0x7fffffff)
            error_exit(1, "comm_exchange_bytes: %zu bytes for one rank, over the int count of MPI", soff[r + 1]);
        sc[r] = (int)(soff[r + 1] - soff[r]), sd[r] = (int)(soff[r] - soff[0]);
    }
    MPICHECK(MPI_Alltoall(sc, 1, MPI_INT, rc, 1, MPI_INT, MPI_COMM_WORLD));
    size_t tot = 0;
    roff[0] = 0;
    for (int r = 0; r < size; ++r) {
        if (tot > 0x7fffffff) error_exit(1, "comm_exchange_bytes: %zu bytes received, over the int count of MPI", tot);
        rd[r] = (int)tot, tot += (size_t)rc[r], roff[r + 1] = tot;
    }
    char *recv = malloc(tot ? tot : 1);
    if (!recv) error_exit(1, "out of memory in comm_exchange_bytes (%zu bytes)", tot);
    MPICHECK(MPI_Alltoallv(send + soff[0], sc, sd, MPI_BYTE, recv, rc, rd, MPI_BYTE, MPI_COMM_WORLD));
    free(sc);
    return recv;
}

void comm_exchange_known(const char *send, const size_t *soff, char *recv, const size_t *roff)
{
    const int size = comm_size();
    int *sc = malloc(4 * (size_t)size * sizeof(int));
    if (!sc) error_exit(1, "out of memory in comm_exchange_known");
    int *sd = sc + size, *rc = sc + 2 * size, *rd = sc + 3 * size;
    for (int r = 0; r < size; ++r) {
        if (soff[r + 1] - soff[0] > 0x7fffffff || roff[r + 1] - roff[0] > 0x7fffffff)
            error_exit(1, "comm_exchange_known: over the int count of MPI");
        sc[r] = (int)(soff[r + 1] - soff[r]), sd[r] = (int)(soff[r] - soff[0]);
        rc[r] = (int)(roff[r + 1] - roff[r]), rd[r] = (int)(roff[r] - roff[0]);
    }
    MPICHECK(MPI_Alltoallv(send + soff[0], sc, sd, MPI_BYTE, recv + roff[0], rc, rd, MPI_BYTE, MPI_COMM_WORLD));
    free(sc);
}

int comm_local_rank(void)
{
    MPI_Comm node;
    int r;
    MPICHECK(MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node));
    MPICHECK(MPI_Comm_rank(node, &r));
    MPICHECK(MPI_Comm_free(&node));
    return r;
}

/* This node's communicator (free it with MPI_Comm_free). */
static MPI_Comm comm_node(void)
{
    MPI_Comm node;
    MPICHECK(MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node));
    return node;
}

int comm_local_size(void)
{
    MPI_Comm node = comm_node();
    int n;
    MPICHECK(MPI_Comm_size(node, &n));
    MPICHECK(MPI_Comm_free(&node));
    return n;
}

long long comm_node_sum_ll(long long x)
{
    MPI_Comm node = comm_node();
    long long y;
    MPICHECK(MPI_Allreduce(&x, &y, 1, MPI_LONG_LONG, MPI_SUM, node));
    MPICHECK(MPI_Comm_free(&node));
    return y;
}

void comm_node_bor(unsigned char *bytes, int n)
{
    MPI_Comm node = comm_node();
    MPICHECK(MPI_Allreduce(MPI_IN_PLACE, bytes, n, MPI_BYTE, MPI_BOR, node));
    MPICHECK(MPI_Comm_free(&node));
}
