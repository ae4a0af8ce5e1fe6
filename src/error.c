/* error.c — see error.h. */
#include "error.h"
#include <mpi.h>
#include <stdarg.h>
#include <stdlib.h>

static int error_rank(void)
{
    int init = 0, rank = 0;
    MPI_Initialized(&init);
    if (init) MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    return rank;
}

void message(const char *fmt, ...)
{
    if (error_rank() != 0) return;
    va_list ap;
    va_start(ap, fmt);
    vfprintf(stdout, fmt, ap);
    va_end(ap);
    fputc('\n', stdout);
    fflush(stdout);
}

void warning(const char *fmt, ...)
{
    if (error_rank() != 0) return;
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "sphseg: warning: ");
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    fflush(stderr);
}

static void finish(int code)
{
    int init = 0, fin = 0, size = 1;
    MPI_Initialized(&init);
    MPI_Finalized(&fin);
    if (init && !fin) {
        MPI_Comm_size(MPI_COMM_WORLD, &size);
        if (size > 1) MPI_Abort(MPI_COMM_WORLD, code);
        MPI_Finalize();
    }
    exit(code);
}

void error_exit(int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "sphseg: error: ");
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    fflush(stderr);
    finish(code);
    exit(code);
}

void input_error(const char *fmt, ...)
{
    if (error_rank() == 0) {
        va_list ap;
        va_start(ap, fmt);
        fprintf(stderr, "sphseg: error: ");
        vfprintf(stderr, fmt, ap);
        va_end(ap);
        fputc('\n', stderr);
        fflush(stderr);
    }
    int init = 0, fin = 0;
    MPI_Initialized(&init);
    MPI_Finalized(&fin);
    if (init && !fin) MPI_Finalize();
    exit(EXIT_BAD_INPUT);
}
