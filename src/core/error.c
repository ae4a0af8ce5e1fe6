/* core/error.c — see error.h. */
#include "error.h"
#include <mpi.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static int (*error_cleanup)(void);

void error_on_exit(int (*fn)(void)) { error_cleanup = fn; }

/* MPI is running: initialised and not yet finalised. */
static int error_mpi_live(void)
{
    int init = 0, fin = 0;
    MPI_Initialized(&init);
    MPI_Finalized(&fin);
    return init && !fin;
}

static int error_rank(void)
{
    int rank = 0;
    if (error_mpi_live()) MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    return rank;
}

static int error_size(void)
{
    int size = 1;
    if (error_mpi_live()) MPI_Comm_size(MPI_COMM_WORLD, &size);
    return size;
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

/* The cleanup hook runs first (an open HDF5 file closed before MPI_Finalize,
 * whose HDF5 shutdown would otherwise flush it and crash); several ranks
 * abort together, one rank finalizes. */
static void finish(int code) __attribute__((noreturn));
static void finish(int code)
{
    int (*fn)(void) = error_cleanup, skip = 0;
    error_cleanup = NULL;
    if (fn) skip = fn();
    int init = 0, fin = 0;
    MPI_Initialized(&init);
    MPI_Finalized(&fin);
    if (init && !fin && !skip) {
        if (error_size() > 1) MPI_Abort(MPI_COMM_WORLD, code);
        MPI_Finalize();
    }
    exit(code);
}

/* The line in one write(2): when several ranks fail at once (a collective
 * write to a full disk) their lines do not interleave mid-line, as
 * separate fprintf calls on unbuffered stderr did (test_fulldisk.sh on 2
 * ranks read "sphseg: error: sphseg: error: cannot write ..."). Atomic for
 * lines up to PIPE_BUF (4096 bytes); a longer one is cut. */
static void error_vprint(const char *prefix, const char *fmt, va_list ap)
{
    char buf[4096];
    int o = snprintf(buf, sizeof buf - 1, "sphseg: error: %s", prefix);
    if (o < 0) o = 0;
    if (o < (int)sizeof buf - 1) {
        int k = vsnprintf(buf + o, sizeof buf - 1 - (size_t)o, fmt, ap);
        o += k < 0 ? 0 : k;
    }
    if (o > (int)sizeof buf - 2) o = (int)sizeof buf - 2;
    buf[o++] = '\n';
    fflush(stderr);
    ssize_t w = write(STDERR_FILENO, buf, (size_t)o);
    (void)w;
}

void error_exit(int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    error_vprint("", fmt, ap);
    va_end(ap);
    finish(code);
}

/* Every rank reached the barrier within ERROR_AGREE_S seconds. */
static int error_all_here(void)
{
    MPI_Request req;
    int done = 0;
    if (MPI_Ibarrier(MPI_COMM_WORLD, &req) != MPI_SUCCESS) return 0;
    struct timespec nap = {0, 2000000};
    for (int k = 0; k < ERROR_AGREE_S * 500 && !done; ++k) {
        MPI_Test(&req, &done, MPI_STATUS_IGNORE);
        if (!done) nanosleep(&nap, NULL);
    }
    return done;
}

void input_error(const char *fmt, ...)
{
    int init = 0, fin = 0, rank = error_rank();
    MPI_Initialized(&init);
    MPI_Finalized(&fin);
    int live = init && !fin, alone = !live || error_size() == 1;
    int all = alone || error_all_here(); /* every rank found it: rank 0 speaks for all */
    if (rank == 0 || !all) {
        char pre[32] = "";
        if (rank > 0) snprintf(pre, sizeof pre, "rank %d: ", rank);
        va_list ap;
        va_start(ap, fmt);
        error_vprint(pre, fmt, ap);
        va_end(ap);
    }
    if (!all) MPI_Abort(MPI_COMM_WORLD, EXIT_BAD_INPUT);
    if (live) MPI_Finalize();
    exit(EXIT_BAD_INPUT);
}

/* Collective: the lowest rank whose why is not NULL, its line copied to
 * every rank; -1 when no rank has one. */
static int error_agree_line(const char *why, char *line, size_t n)
{
    int rank = error_rank(), first = why ? rank : 1 << 30;
    if (error_size() > 1) MPI_Allreduce(MPI_IN_PLACE, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    if (first == 1 << 30) return -1;
    line[0] = 0;
    if (rank == first) snprintf(line, n, "%s", why);
    if (error_size() > 1) MPI_Bcast(line, (int)n, MPI_CHAR, first, MPI_COMM_WORLD);
    return first;
}

static void error_print(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
static void error_print(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    error_vprint("", fmt, ap);
    va_end(ap);
}

/* Every rank is here: rank 0 prints, the cleanup hook runs on every rank
 * (it may be collective: closing a parallel HDF5 file), every rank
 * finalizes and exits with code; no MPI_Abort, so no rank is left waiting. */
void error_agree(int code, const char *why)
{
    char line[4800];
    if (error_agree_line(why, line, sizeof line) < 0) return;
    if (error_rank() == 0) error_print("%s", line);
    int (*fn)(void) = error_cleanup, skip = 0, init = 0, fin = 0;
    error_cleanup = NULL;
    if (fn) skip = fn();
    if (skip) { /* a file HDF5 could not close: its exit handlers would try again, collectively */
        fflush(stdout);
        _exit(code);
    }
    MPI_Initialized(&init);
    MPI_Finalized(&fin);
    if (init && !fin) MPI_Finalize();
    exit(code);
}

void input_error_agree(const char *why)
{
    char line[1200];
    int first = error_agree_line(why, line, sizeof line);
    if (first < 0) return;
    if (first > 0) {
        char tmp[1200];
        snprintf(tmp, sizeof tmp, "%s", line);
        snprintf(line, sizeof line, "rank %d: %.1150s", first, tmp);
    }
    input_error("%s", line);
}
