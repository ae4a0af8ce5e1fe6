/* hd.h — the one precision switch and the host/device inline marker.
 * Every per-particle or per-pair formula lives in src/physics/ as HD_INLINE so
 * that the CPU (OpenMP) and GPU (CUDA) drivers call the same code. */
#ifndef SPHSEG_HD_H
#define SPHSEG_HD_H
#include <math.h>

#ifdef __CUDACC__
#define HD_INLINE __host__ __device__ static inline
#else
#define HD_INLINE static inline
#endif

#ifdef SPHSEG_SINGLE
typedef float real;
#define REAL_EPS 1.1920929e-7f
#define R(x) ((real)(x))
#else
typedef double real;
#define REAL_EPS 2.220446049250313e-16
#define R(x) ((real)(x))
#endif

/* The concentration, its start-of-step copy and its rate are double in both
 * precisions (creal): a float C rounds at every update, and Σ C_i V_i then
 * drifts by ~1e-5 in 2e4 steps (docs/gpu.md "Mixed precision"); with C,
 * its rate and the pair sums of the conservative scheme in double the
 * single build conserves it as the double build does. */
typedef double creal;

/* Positions are held to double precision in both builds: the start-of-step
 * position x_n is double (preal), and the single build keeps beside each
 * float x its rounding remainder xr (particles.h), so that x + xr is the
 * integrated position. A float position alone rounds every step's
 * displacement to its ulp, 3.7e-9 to 7.5e-9 m at 0.05 to 0.1 m from the
 * origin, and so leaves a particle slower than ulp / (2 dt), 0.07 to 0.15
 * mm/s at dt = 2.5e-5 s, where it is: the slow axial drift of a 3D drum
 * (docs/gpu.md, "Mixed precision"). The neighbour loops read x alone. */
typedef double preal;
#ifdef SPHSEG_SINGLE
#define POS_REMAINDER 1
#else
#define POS_REMAINDER 0 /* x is the double position itself; xr stays 0 */
#endif

/* The square root of a real, correctly rounded in either precision: sqrtf in
 * the single build (IEEE on the CPU, and in CUDA, which compiles it
 * correctly rounded unless -use_fast_math or -prec-sqrt=false: the Makefile
 * sets the latter for gpu/gpu_pairs.cu alone in the single build,
 * NVFLAGS_PAIRS, where it is within 2 ulp), sqrt in the double one. It gives the bits of
 * (float)sqrt((double)x): a double-rounded square root is exact when the
 * wide format has at least 2p + 2 bits (53 >= 2 * 24 + 2; Figueroa 1995,
 * "When is double rounding innocuous?"), so writing it either way changes
 * no result. On the GPU the single form spares a pair two conversions (16 a
 * clock per SM on sm_90, against 128 fp32 operations) and a double square
 * root. */
#ifdef SPHSEG_SINGLE
HD_INLINE real sqrt_r(real x) { return sqrtf(x); }
#else
HD_INLINE real sqrt_r(real x) { return sqrt(x); }
#endif

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define DIM_MAX 3

/* Neighbour loops read all of a neighbour's values before the distance test
 * on the GPU (its loads then go out together: +13 % on the 3D drum,
 * docs/gpu.md) and only within the support on the CPU (whose cell scan
 * meets six times more candidates than the support holds). Either way the
 * same values enter the same arithmetic. */
#ifdef __CUDA_ARCH__
#define SPH_EARLY_LOADS 1
#else
#define SPH_EARLY_LOADS 0
#endif

/* Teams: the neighbour-loop bodies take (lane, nlanes) and sum over every
 * nlanes-th entry of the particle's neighbours from entry lane on
 * (NBR_BEGIN_T, grid.h); team_sum then adds the partial sums of the team.
 * On the GPU a team is nlanes consecutive threads of one warp (a power of
 * two up to 32), summed by a butterfly in a fixed order, so that every lane
 * holds the same bits and runs stay bit-identical; on the host nlanes is 1
 * and team_sum does nothing. */
/* One body for both element types: team_sum (real) and team_sum_c (creal,
 * the concentration rates, double in the single build too). */
#ifdef __CUDA_ARCH__
#define TEAM_SUM_DEF(name, type)                                                                           \
    HD_INLINE void name(type *v, int n, int nlanes)                                                        \
    {                                                                                                      \
        if (nlanes <= 1) return;                                                                           \
        const unsigned lane = threadIdx.x & 31u, base = lane & ~(unsigned)(nlanes - 1);                     \
        const unsigned mask = nlanes == 32 ? 0xffffffffu : ((1u << nlanes) - 1u) << base;                  \
        for (int k = 0; k < n; ++k)                                                                        \
            for (int o = nlanes >> 1; o > 0; o >>= 1) v[k] += __shfl_xor_sync(mask, v[k], o, nlanes);       \
    }
#else
#define TEAM_SUM_DEF(name, type)                                                                           \
    HD_INLINE void name(type *v, int n, int nlanes) { (void)v, (void)n, (void)nlanes; }
#endif
TEAM_SUM_DEF(team_sum, real)
TEAM_SUM_DEF(team_sum_c, creal)
#undef TEAM_SUM_DEF

#endif
