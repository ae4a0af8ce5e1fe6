/* core/error.h — rank-aware messages and located errors (DESIGN.md "Errors").
 * Exit status 1: system failure (out of memory, a failed MPI or HDF5 call).
 * Exit status 2: bad input (before any step, nothing written).
 * Exit status 3: numerical failure (names step, time, particle).
 * Exit status 4: an output file could not be written (disk full, quota, I/O
 *                error): the last complete snapshot and checkpoint stay. */
#ifndef SPHSEG_ERROR_H
#define SPHSEG_ERROR_H
#include <stdio.h>

enum { EXIT_SYSTEM = 1, EXIT_BAD_INPUT = 2, EXIT_NUMERICAL = 3, EXIT_WRITE = 4 };

/* Printed on rank 0 only: messages, and warnings (every warning is about
 * state all ranks share: the scene, global sums). */
void message(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
void warning(const char *fmt, ...) __attribute__((format(printf, 1, 2)));
/* Print "sphseg: error: ..." once and end every rank with status code. */
void error_exit(int code, const char *fmt, ...) __attribute__((format(printf, 2, 3), noreturn));
/* Input errors found identically on all ranks: rank 0 prints, all ranks
 * exit with EXIT_BAD_INPUT. A rank whose peers do not all call it within
 * ERROR_AGREE_S seconds (an error only it found) prints the line itself
 * with its rank and aborts the job (status 2): never a hang. */
void input_error(const char *fmt, ...) __attribute__((format(printf, 1, 2), noreturn));
/* Collective: every rank passes NULL (no problem here) or the line it would
 * print; if any rank has one, rank 0 prints the lowest such rank's line
 * ("rank r: ..." when r > 0) and every rank exits with EXIT_BAD_INPUT. */
void input_error_agree(const char *why);
/* Collective, for failures a rank may meet alone in a collective operation
 * (a parallel write to a full disk): every rank passes NULL or its line; if
 * any rank has one, rank 0 prints the lowest such rank's line once, the
 * error_on_exit hook runs on every rank (collectively), and every rank
 * finalizes and exits with code. Called by all ranks before the next
 * collective call, it never leaves one rank waiting for another. */
void error_agree(int code, const char *why);
/* A function error_exit runs (once) before it ends the process, e.g. to
 * close an open HDF5 file and remove a half-written temporary (src/output/io.c);
 * it returns nonzero when MPI_Finalize must be skipped (a file HDF5 could
 * not close, which HDF5's shutdown inside MPI_Finalize would crash on). */
void error_on_exit(int (*fn)(void));
enum { ERROR_AGREE_S = 10 };

/* Check an HDF5 call (negative = failure). hdf5.h defines an H5CHECK of
 * its own (a version check inside the H5F_ACC_* flags) and #undefs any
 * earlier one: a file using both includes <hdf5.h> first, reads the flags it
 * needs before this header (see src/output/io.c), and this definition wins. */
#undef H5CHECK
#define H5CHECK(call)                                                              \
    do {                                                                           \
        if ((call) < 0) error_exit(1, "HDF5 call failed at %s:%d: %s", __FILE__, __LINE__, #call); \
    } while (0)
/* Check an MPI call. */
#define MPICHECK(call)                                                             \
    do {                                                                           \
        int mpi_rc_ = (call);                                                      \
        if (mpi_rc_ != MPI_SUCCESS) error_exit(1, "MPI call failed at %s:%d: %s", __FILE__, __LINE__, #call); \
    } while (0)

#endif
