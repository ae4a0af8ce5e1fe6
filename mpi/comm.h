/* comm.h — global reductions over all ranks (MPI_COMM_WORLD). The slab
 * decomposition and halo exchange of later issues live beside this file. */
#ifndef SPHSEG_COMM_H
#define SPHSEG_COMM_H
#include <stddef.h>

int comm_rank(void);
int comm_size(void);
/* Rank among the ranks of this node (picks the GPU). */
int comm_local_rank(void);
/* The ranks of this node, and over them: the sum of x, and the bitwise OR
 * of bytes[0..n-1] in place (collective over all ranks). */
int comm_local_size(void);
long long comm_node_sum_ll(long long x);
void comm_node_bor(unsigned char *bytes, int n);
double comm_sum(double x);
/* The sum over ranks of a compensated per-rank sum (hi, lo), itself summed
 * compensated in rank order: the same on every rank and, to round-off of the
 * total, independent of how the particles are split and ordered. */
double comm_sum_compensated(double hi, double lo);
double comm_max(double x);
/* x[0..n) replaced by its maxima over ranks, in one reduction (a no-op on one rank). */
void comm_max_n(double *x, int n);
double comm_min(double x);
long long comm_sum_ll(long long x);
/* Collective. x: n rows of k doubles (k <= 8), this rank's partial sums;
 * replaced by their sums over the ranks taken in rank order (a row's first
 * nonzero partial, then each later rank's added), so every rank gets the
 * same bits whatever the timing; on one rank x is left as it is. Rows all
 * zero on a rank are not sent: an MPI_Allgatherv of (row, values) records,
 * 8 (k + 1) bytes each, every rank receiving every rank's nonzero rows
 * (the DEM grains' sums over the fluid, src/dem/dem.c). */
void comm_sum_rows_ordered(double *x, size_t n, int k);
/* Collective. Personalised exchange of bytes: send + soff[r] .. send +
 * soff[r + 1] go to rank r (soff: size + 1 offsets, soff[size] the total);
 * returns a malloc'd buffer (free it) holding what each rank sent this one,
 * rank after rank, from offset roff[r] (roff: size + 1 entries, filled in).
 * On one rank: a copy of send. Counts over 2^31 bytes a rank stop the run
 * (exit 1). The DEM grains' migration, ghosts and sums (src/dem/dem_halo.c). */
char *comm_exchange_bytes(const char *send, const size_t *soff, size_t *roff);
/* The same when both ends know the sizes: recv + roff[r] .. roff[r + 1]
 * from rank r (one MPI_Alltoallv; the DEM ghosts' refreshes). */
void comm_exchange_known(const char *send, const size_t *soff, char *recv, const size_t *roff);

#endif
