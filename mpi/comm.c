/* comm.c — see comm.h. */
#include "comm.h"
#include <mpi.h>
#include "../src/core/error.h"

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
double comm_max(double x) { return comm_reduce(x, MPI_MAX); }
double comm_min(double x) { return comm_reduce(x, MPI_MIN); }

long long comm_sum_ll(long long x)
{
    long long y;
    MPICHECK(MPI_Allreduce(&x, &y, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD));
    return y;
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
