/* halo_bandwidth.c — the cost of one halo message, measured the way
 * mpi/halo.c sends it: every rank MPI_Sendrecv's m bytes to its upper
 * neighbour while receiving from its lower one (a ring, so every rank is
 * busy as in a slab run). Prints "bytes,seconds_per_exchange" rows, the
 * latency (the 8-byte exchange) and the bandwidth (the largest one), for the
 * scaling model in docs/parallel.md.
 *   mpicc -O2 tools/bench/halo_bandwidth.c -o halo_bandwidth
 *   mpirun -np 2 ./halo_bandwidth [max_bytes] */
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>

int main(int argc, char **argv)
{
    MPI_Init(&argc, &argv);
    int rank, size;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    long max = argc > 1 ? atol(argv[1]) : 64L << 20;
    char *s = malloc((size_t)max), *r = malloc((size_t)max);
    for (long k = 0; k < max; ++k) s[k] = (char)k;
    int up = (rank + 1) % size, down = (rank + size - 1) % size;
    double lat = 0, bw = 0;
    if (rank == 0) printf("bytes,seconds_per_exchange\n");
    for (long m = 8; m <= max; m *= 4) {
        int reps = m < (1 << 16) ? 2000 : m < (1 << 22) ? 200 : 20;
        for (int w = 0; w < 2; ++w) /* warm-up */
            MPI_Sendrecv(s, (int)m, MPI_BYTE, up, 0, r, (int)m, MPI_BYTE, down, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        MPI_Barrier(MPI_COMM_WORLD);
        double t0 = MPI_Wtime();
        for (int k = 0; k < reps; ++k)
            MPI_Sendrecv(s, (int)m, MPI_BYTE, up, 0, r, (int)m, MPI_BYTE, down, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        double t = (MPI_Wtime() - t0) / reps, tmax;
        MPI_Reduce(&t, &tmax, 1, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD);
        if (rank == 0) {
            printf("%ld,%.6e\n", m, tmax);
            if (m == 8) lat = tmax;
            bw = (double)m / tmax;
        }
    }
    if (rank == 0) {
        printf("# %d ranks: latency %.3g s (8 bytes), bandwidth %.4g GB/s per direction (largest message)\n", size,
               lat, 1e-9 * bw);
    }
    free(s), free(r);
    MPI_Finalize();
    return 0;
}
