/* core/omp_shim.h — the OpenMP runtime calls the host code uses, as one-thread
 * stand-ins when the build has no OpenMP (OPENMP=0), so that a threaded loop
 * is written once. */
#ifndef SPHSEG_OMP_SHIM_H
#define SPHSEG_OMP_SHIM_H
#ifdef _OPENMP
#include <omp.h>
#else
static inline int omp_get_max_threads(void) { return 1; }
static inline int omp_get_num_threads(void) { return 1; }
static inline int omp_get_thread_num(void) { return 0; }
#endif
#endif
