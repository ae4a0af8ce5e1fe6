/* backend_gpu.cu — the CUDA backend (struct backend, src/sim.h).
 *
 * The particle arrays live on the device for the whole run; the host copy
 * s->p is refreshed only by to_host (snapshots, diagnostics, error reports).
 * Every kernel calls the same HD_INLINE bodies of src/physics/ as the CPU
 * backend, gather style: a particle's thread sums over its neighbours and
 * writes only its own entries, so results do not depend on thread
 * scheduling and runs are bit-identical run to run. The neighbour loops of
 * small stores run a team of 2-16 threads per particle (k_team; each lane
 * takes every T-th neighbour and team_sum adds the lanes in a fixed order).
 * Reductions (bounding box, time-step bounds, blow-up guard) are max and min
 * with CUB, exact in any order; the check takes them all in one pass, the
 * step's one host synchronisation. save_start and advance are held back and
 * run in the next prepare's motion kernel (gpu_step_kernel).
 *
 * The neighbour build mirrors src/nbr.c: the same grid (grid_fit on the same
 * bounding box), cell keys sorted by a stable CUB radix sort (the order of a
 * stable counting sort: CPU and GPU hold particles in the same order), cell
 * start/end from key changes, then every array gathered into a spare set of
 * buffers and the two sets swapped; then a neighbour list per particle
 * (grid_list_fill, in the cell scan's order) that every neighbour loop reads.
 *
 * Verlet skin: the list holds the particles within 2h + skin (skin =
 * GPU_SKIN h) and is kept, with the store's order and cells, for as long as
 * no particle can have moved skin/2 since the build: gpu_check measures the
 * largest displacement since the build (D) and in the last step (d) and
 * marks the list stale when D + 2 d > skin / 2, or for every stage when
 * d > skin / 4, and for prescribed kinematics (the shear box moves up to h
 * a step: it rebuilds every stage). A build for the HCSR classification (the paper scheme, every step;
 * snapshots) uses no skin and cells of edge 2h, as the CPU does, so that the
 * classes are the CPU's; the next stage rebuilds. Between builds the order
 * of the store differs from the CPU's (which sorts every stage), so sums are
 * taken in another order: CPU and GPU agree to round-off, not bitwise.
 *
 * Several ranks (mpi/halo.h; one GPU per rank, or several ranks sharing
 * one): the device store holds the owned particles at [0, n) and ghosts at
 * [n, n + ng), each range sorted by cell (the sort key carries a ghost bit;
 * the view's gstart/gend are the ghost half of start/end), as on the CPU.
 * Ghosts are HALO 3 lattice cells deep (ghost_depth), so that a set made at
 * a list build still covers the 2h + 2 skin that a Verlet list needs while
 * particles move. At a build (rare in a flowing scene: the list is kept)
 * the owned arrays come to the host, mpi/halo.c migrates particles and
 * makes fresh ghosts, and everything goes back; the send and receive lists
 * follow the device sort (halo_sorted). Between builds a stage's refresh
 * packs only the fields it needs for the send lists on the device, stages
 * them through pinned host memory (or hands device buffers to a CUDA-aware
 * MPI), and unpacks them into the ghost slots on the device. The exchange
 * overlaps interior work: each particle gets a level at the build (0 ghost,
 * 1 a ghost in its list, 2 a level-1 particle in its list, 3 else), and
 * while positions, velocities, stresses and C are in flight the GPU runs
 * the dummy walls and L of levels >= 2 and the flow rates of level 3 (their
 * lists read no ghost and nothing computed from one), then the rest after
 * the ghosts arrive; likewise the shear-rate refresh overlaps the
 * concentration rates of levels >= 2. Each particle is computed by the same
 * body whatever the pass, so results do not depend on the overlap. */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <cuda_runtime.h>
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_reduce.cuh>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/iterator/transform_iterator.h>
extern "C" {
#include "error.h"
#include "mpi/comm.h"
#include "sim.h"
}

#define CK(call)                                                                                     \
    do {                                                                                             \
        cudaError_t e_ = (call);                                                                     \
        if (e_ != cudaSuccess)                                                                       \
            error_exit(1, "CUDA error at %s:%d: %s (%s)", __FILE__, __LINE__, cudaGetErrorString(e_), \
                       #call);                                                                       \
    } while (0)

enum { PERM_MAX = 64, BLOCK = 128 };
#define GPU_SKIN 0.1 /* Verlet skin, in units of h */
#define GPU_TEAM_MAX_2D 4 /* threads per particle in the neighbour loops (gpu_team_size) */
#define GPU_TEAM_MAX_3D 8
#define GPU_TEAM_THREADS 2097152.0

/* Source and destination of every per-particle array (the permutation). */
struct perm_tab {
    int n;
    unsigned char es[PERM_MAX];
    void *src[PERM_MAX], *dst[PERM_MAX];
};

struct box {
    real lo[3], hi[3];
};

/* Fields of a ghost refresh: device array and element size. */
enum { FT_MAX = 16 };
struct ftab {
    int n;
    unsigned char es[FT_MAX];
    void *p[FT_MAX];
};

/* Which particles a kernel pass runs on: all (lvl NULL), or those whose
 * halo level (0 ghost, 1..3 owned, see the top) lies in [lo, hi]. */
struct sel {
    const uint8_t *lvl;
    uint8_t lo, hi;
};
__device__ __forceinline__ bool sel_on(const sel &s, size_t i)
{
    return !s.lvl || (s.lvl[i] >= s.lo && s.lvl[i] <= s.hi);
}

/* Halo state of a multi-rank run on the device. */
enum { HX_EV = 64 };
struct dhalo {
    unsigned *sidx, *ridx;       /* send lists (neighbour order), ghost slots of the received */
    size_t cap_s, cap_r;
    size_t *soff, *roff;         /* entry offsets per neighbour (host, nnb + 1) */
    size_t *sb, *rb;             /* byte offsets of the current refresh (host, nnb + 1) */
    int cap_nb;
    char *dsend, *drecv, *hsend, *hrecv; /* device and pinned host buffers */
    size_t cap_dsend, cap_drecv, cap_hsend, cap_hrecv;
    int cuda_aware;
    int overlap;                 /* SPHSEG_GPU_OVERLAP=0 turns the overlap off (for measuring it) */
    int pending;                 /* a refresh is in flight (gpu_settle completes it) */
    int pend_walls, pend_renorm; /* boundary passes to run when it lands */
    ftab pend;
    cudaEvent_t ev[HX_EV];       /* pairs (start, end) of GPU time spent on the halo */
    int nev;
    long full, refresh;          /* exchanges at builds; refreshes */
    double full_s;               /* host seconds in the exchanges at builds */
};

typedef struct gpu {
    int dev;
    cudaStream_t st;
    particles_t d, alt; /* device arrays: current and the permutation's spare set */
    size_t n, ng, cap;  /* owned particles, ghosts (at [n, n + ng)), allocated */
    uint8_t *lvl;       /* halo level of each particle (several ranks), else NULL */
    uint8_t *wact;      /* a dummy with material in its list (gpu_build); NULL: every dummy
                         * runs its loop (SPHSEG_GPU_WALLSKIP=0, for measuring the skip) */
    int wskip;
    struct dhalo *hx;   /* several ranks, else NULL */
    grid_view view;     /* start/end point to device memory */
    size_t *start, *end, ncell, cap_cell;
    unsigned *key, *key2, *idx, *idx2;
    unsigned char *cell_type, *cls;
    size_t *cell_mat;
    bound_sums *sums;
    unsigned *nl, *ncnt, nl_cap; /* neighbour list (grid_view), rebuilt with the cells */
    real *xb[3];        /* positions at the last build */
    real skin;          /* m */
    int built, stale, every; /* the list: exists; must be rebuilt; rebuild every stage */
    long builds;
    real *amag;         /* |acc| of the last flow rate evaluation */
    int acc_pending;    /* amag not yet reduced into dres[STEP_ACC] (gpu_acc_reduce, gpu_check) */
    int pend_save, pend_adv; /* save_start and advance held back for the next kernel (gpu_step_kernel) */
    real pend_a, pend_w;
    flow_ctx pend_fc;
    int team;           /* threads per particle in the neighbour loops: 1, 2, 4, 8 or 16 */
    void *tmp;          /* CUB scratch */
    size_t tmp_bytes;
    struct box *dbox;   /* device results */
    double *dres;       /* [STEP_NBOUNDS]: D, wave, speed, acc */
    long long *dfirst;  /* also the list-length maximum */
    struct chkb *dchk, *hchk;
    int bnd_fresh;      /* hres[0..2] hold the bounds of the current store (gpu_check) */
    struct box *hbox;   /* pinned host copies */
    double *hres;
    long long *hfirst;
} gpu_t;

static int g_local_rank;

/* Stage timing (SPHSEG_GPU_PROFILE=1 in the environment): events around each
 * stage with a synchronisation after it, so the stages do not overlap and
 * the total runs slower than without; a table at the end of the run. */
enum { P_MOTION, P_BBOX, P_SORT, P_PERMUTE, P_LIST, P_CLASSIFY, P_WALLS, P_FLOW, P_SEG, P_FILTER, P_BOUNDS_CHECK,
       P_NPROF };
static const char *prof_name[P_NPROF] = {"save start, advance, motion", "bounding box (+sync)",
                                          "cell keys, radix sort, start/end", "permute arrays", "neighbour list",
                                          "HCSR classification", "dummy walls, renormalisation L",
                                          "flow rates (+seg. coefficients)", "concentration rates", "Shepard filter",
                                          "dt bounds, blow-up check (+sync)"};
static struct {
    int on;
    cudaEvent_t a, b;
    double ms[P_NPROF];
    long calls[P_NPROF];
} prof;

static void prof_begin(cudaStream_t st)
{
    if (prof.on) CK(cudaEventRecord(prof.a, st));
}
static void prof_end(cudaStream_t st, int k)
{
    if (!prof.on) return;
    CK(cudaEventRecord(prof.b, st));
    CK(cudaEventSynchronize(prof.b));
    float ms;
    CK(cudaEventElapsedTime(&ms, prof.a, prof.b));
    prof.ms[k] += ms;
    prof.calls[k]++;
}

/* ---- launching ----------------------------------------------------------- */

template <class F> __global__ void k_each(size_t n, F f)
{
    size_t i = (size_t)blockIdx.x * blockDim.x + threadIdx.x;
    if (i < n) f(i);
}

template <class F> static void each(const gpu_t *g, size_t n, F f)
{
    if (n == 0) return;
    k_each<<<(unsigned)((n + BLOCK - 1) / BLOCK), BLOCK, 0, g->st>>>(n, f);
    CK(cudaGetLastError());
}

/* At least SPHSEG_TEAM_MINB blocks of BLOCK threads per SM: at most 128
 * registers a thread on sm_90 (65536 / (128 * 4)). The flow rates want 144
 * and spill a little at 128, yet the fourth block's warps hide more of the
 * neighbour-gather latency: 1.20x on the 3D drum at 1.1e7 particles with the
 * fused L, neutral on the 2D drums (docs/gpu.md, H100). 0 lets nvcc choose. */
#ifndef SPHSEG_TEAM_MINB
#define SPHSEG_TEAM_MINB 4
#endif
#if SPHSEG_TEAM_MINB > 0
#define TEAM_LB __launch_bounds__(BLOCK, SPHSEG_TEAM_MINB)
#else
#define TEAM_LB
#endif
/* Teams (src/physics/hd.h): T consecutive threads per particle, f(i, lane,
 * T), T a power of two dividing the warp, so that a team never straddles a
 * warp and a team past n is out as a whole. */
template <int T, class F> __global__ void TEAM_LB k_team(size_t n, F f)
{
    size_t t = (size_t)blockIdx.x * blockDim.x + threadIdx.x, i = t / T;
    if (i < n) f(i, (int)(t % T), T);
}

template <int T, class F> static void team_launch(const gpu_t *g, size_t n, F f)
{
    size_t nt = n * T;
    k_team<T><<<(unsigned)((nt + BLOCK - 1) / BLOCK), BLOCK, 0, g->st>>>(n, f);
    CK(cudaGetLastError());
}

/* The neighbour-loop kernels, g->team threads per particle. */
template <class F> static void team(const gpu_t *g, size_t n, F f)
{
    if (n == 0) return;
    switch (g->team) {
    case 1: team_launch<1>(g, n, f); break;
    case 2: team_launch<2>(g, n, f); break;
    case 4: team_launch<4>(g, n, f); break;
    case 8: team_launch<8>(g, n, f); break;
    default: team_launch<16>(g, n, f); break;
    }
}

__global__ void k_permute(perm_tab t, const unsigned *perm, size_t n)
{
    size_t k = (size_t)blockIdx.x * blockDim.x + threadIdx.x;
    if (k >= n) return;
    int a = blockIdx.y;
    size_t s = perm[k];
    switch (t.es[a]) {
    case 8: ((uint64_t *)t.dst[a])[k] = ((const uint64_t *)t.src[a])[s]; break;
    case 4: ((uint32_t *)t.dst[a])[k] = ((const uint32_t *)t.src[a])[s]; break;
    default: ((uint8_t *)t.dst[a])[k] = ((const uint8_t *)t.src[a])[s]; break;
    }
}

static void *dev_alloc(size_t bytes)
{
    void *p = NULL;
    cudaError_t e = cudaMalloc(&p, bytes ? bytes : 1);
    if (e != cudaSuccess)
        error_exit(1, "GPU out of memory: %zu bytes (%s); use fewer particles per GPU (a larger Geometry:dr "
                   "or more ranks)", bytes, cudaGetErrorString(e));
    return p;
}

/* Grow the CUB scratch to at least bytes. */
static void *scratch(gpu_t *g, size_t bytes)
{
    if (bytes > g->tmp_bytes) {
        if (g->tmp) CK(cudaFree(g->tmp));
        g->tmp = dev_alloc(bytes);
        g->tmp_bytes = bytes;
    }
    return g->tmp;
}

/* ---- reductions (functors for CUB) -------------------------------------- */

struct box_of {
    particles_t p;
    __device__ box operator()(size_t i) const
    {
        box b;
        for (int d = 0; d < 3; ++d) b.lo[d] = b.hi[d] = p.x[d][i];
        return b;
    }
};
struct box_merge {
    __device__ box operator()(const box &a, const box &b) const
    {
        box c;
        for (int d = 0; d < 3; ++d) {
            c.lo[d] = b.lo[d] < a.lo[d] ? b.lo[d] : a.lo[d];
            c.hi[d] = b.hi[d] > a.hi[d] ? b.hi[d] : a.hi[d];
        }
        return c;
    }
};

struct bnd3 {
    double v[3];
};
struct bnd_of {
    particles_t p;
    step_ctx c;
    __device__ bnd3 operator()(size_t i) const
    {
        bnd3 b = {{0, 0, 0}};
        if (p.kind[i] == KIND_MATERIAL) step_bounds_of(i, &p, &c, b.v);
        return b;
    }
};
struct bnd_max {
    __device__ bnd3 operator()(const bnd3 &a, const bnd3 &b) const
    {
        bnd3 c;
        for (int k = 0; k < 3; ++k) c.v[k] = a.v[k] > b.v[k] ? a.v[k] : b.v[k];
        return c;
    }
};

/* The blow-up guard (lowest bad index) and the displacements of the Verlet
 * test, squared: since the list build (xb) and in the last step (x_n). */
struct chk {
    long long first;
    real build2, step2;
};
struct chk_of {
    particles_t p;
    step_ctx c;
    double t;
    const real *xb0, *xb1, *xb2;
    __device__ chk operator()(size_t i) const
    {
        chk r;
        r.first = p.kind[i] == KIND_MATERIAL && step_guard(i, &p, &c, t) ? (long long)i : (long long)p.n;
        real b0 = p.x[0][i] - xb0[i], b1 = p.x[1][i] - xb1[i], b2 = p.x[2][i] - xb2[i];
        real s0 = p.x[0][i] - p.x_n[0][i], s1 = p.x[1][i] - p.x_n[1][i], s2 = p.x[2][i] - p.x_n[2][i];
        r.build2 = b0 * b0 + b1 * b1 + b2 * b2;
        r.step2 = s0 * s0 + s1 * s1 + s2 * s2;
        if (!(r.build2 < R(1e30))) r.build2 = R(1e30); /* non-finite: the guard reports it */
        if (!(r.step2 < R(1e30))) r.step2 = R(1e30);
        return r;
    }
};
struct chk_merge {
    __device__ chk operator()(const chk &a, const chk &b) const
    {
        chk r;
        r.first = b.first < a.first ? b.first : a.first;
        r.build2 = b.build2 > a.build2 ? b.build2 : a.build2;
        r.step2 = b.step2 > a.step2 ? b.step2 : a.step2;
        return r;
    }
};
/* The check and the next step's time-step bounds in one pass (gpu_check):
 * nothing changes the store between them, and a host synchronisation per
 * step is saved. */
struct chkb {
    chk c;
    bnd3 b;
    real amax; /* the largest |acc| (amag, when given) */
};
struct chkb_of {
    chk_of c;
    bnd_of b;
    const real *amag;
    __device__ chkb operator()(size_t i) const { return chkb{c(i), b(i), amag ? amag[i] : R(0.0)}; }
};
struct chkb_merge {
    __device__ chkb operator()(const chkb &a, const chkb &b) const
    {
        return chkb{chk_merge()(a.c, b.c), bnd_max()(a.b, b.b), b.amax > a.amax ? b.amax : a.amax};
    }
};
struct max_real {
    __device__ real operator()(real a, real b) const { return b > a ? b : a; }
};

template <class It, class T, class Op> static void reduce(gpu_t *g, It in, T *out, size_t n, Op op, T init)
{
    size_t bytes = 0;
    CK(cub::DeviceReduce::Reduce(NULL, bytes, in, out, (int64_t)n, op, init, g->st));
    CK(cub::DeviceReduce::Reduce(scratch(g, bytes), bytes, in, out, (int64_t)n, op, init, g->st));
}

/* ---- set-up -------------------------------------------------------------- */

extern "C" int gpu_devices(void)
{
    int n = 0;
    if (cudaGetDeviceCount(&n) != cudaSuccess) {
        (void)cudaGetLastError();
        return 0;
    }
    return n;
}

/* Per-particle device arrays for at least need particles (contents are not
 * kept: callers upload after). */
static void gpu_reserve(gpu_t *g, size_t need)
{
    if (need <= g->cap && g->key) return;
    size_t cap = g->key ? need + need / 8 + 1024 : need; /* one rank: exactly n, as before */
    if (cap >= 0xffffffffu) error_exit(1, "backend_gpu: %zu particles on one rank: more than 2^32 - 1", cap);
    size_t na = part_narrays();
    if (g->key) {
        for (size_t k = 0; k < na; ++k) {
            CK(cudaFree(part_array_get(&g->d, k)));
            CK(cudaFree(part_array_get(&g->alt, k)));
        }
        void *bufs[] = {g->key, g->key2, g->idx, g->idx2, g->cls, g->sums, g->nl, g->ncnt, g->amag,
                        g->xb[0], g->xb[1], g->xb[2], g->lvl, g->wact};
        for (size_t k = 0; k < sizeof bufs / sizeof bufs[0]; ++k)
            if (bufs[k]) CK(cudaFree(bufs[k]));
    }
    for (size_t k = 0; k < na; ++k) {
        size_t bytes = cap * part_array_esize(k);
        part_array_set(&g->d, k, dev_alloc(bytes));
        part_array_set(&g->alt, k, dev_alloc(bytes));
    }
    g->key = (unsigned *)dev_alloc(cap * sizeof(unsigned));
    g->key2 = (unsigned *)dev_alloc(cap * sizeof(unsigned));
    g->idx = (unsigned *)dev_alloc(cap * sizeof(unsigned));
    g->idx2 = (unsigned *)dev_alloc(cap * sizeof(unsigned));
    g->cls = (unsigned char *)dev_alloc(cap);
    g->sums = (bound_sums *)dev_alloc(cap * sizeof(bound_sums));
    for (int d = 0; d < 3; ++d) {
        g->xb[d] = (real *)dev_alloc(cap * sizeof(real));
        CK(cudaMemset(g->xb[d], 0, cap * sizeof(real)));
    }
    g->nl = (unsigned *)dev_alloc(cap * g->nl_cap * sizeof(unsigned));
    g->ncnt = (unsigned *)dev_alloc(cap * sizeof(unsigned));
    g->amag = (real *)dev_alloc(cap * sizeof(real));
    CK(cudaMemset(g->amag, 0, cap * sizeof(real)));
    g->lvl = g->hx ? (uint8_t *)dev_alloc(cap) : NULL;
    g->wact = g->wskip ? (uint8_t *)dev_alloc(cap) : NULL;
    g->cap = cap;
    g->built = 0;
}

/* Host arrays [a, b) of every particle array to the device. */
static void gpu_upload(gpu_t *g, const particles_t *h, size_t a, size_t b)
{
    for (size_t k = 0; k < part_narrays(); ++k) {
        size_t es = part_array_esize(k);
        CK(cudaMemcpyAsync((char *)part_array_get(&g->d, k) + a * es, (const char *)part_array_get(h, k) + a * es,
                           (b - a) * es, cudaMemcpyHostToDevice, g->st));
    }
    CK(cudaStreamSynchronize(g->st));
}

/* The counts in the device structs (kernels read p.n, p.ng). */
static void gpu_counts(gpu_t *g, size_t n, size_t ng)
{
    g->n = n, g->ng = ng;
    g->d.n = g->alt.n = n;
    g->d.ng = g->alt.ng = ng;
    g->d.cap = g->alt.cap = g->cap;
}

/* Threads per particle in the neighbour loops: SPHSEG_GPU_TEAM (1, 2, 4, 8
 * or 16), else GPU_TEAM_MAX of the dimension (by the length of the list:
 * 4 in 2D, about 30 neighbours; 8 in 3D, about 140), halved while n T
 * exceeds GPU_TEAM_THREADS: a small store runs more threads per particle
 * (latency), a large one fills the device with one (the rule is measured in
 * docs/gpu.md, "Teams"). */
static int gpu_team_size(int dim, size_t n)
{
    const char *e = getenv("SPHSEG_GPU_TEAM");
    if (e && *e) {
        char *end;
        long t = strtol(e, &end, 10);
        if (*end || (t != 1 && t != 2 && t != 4 && t != 8 && t != 16))
            error_exit(2, "SPHSEG_GPU_TEAM=%s: expected 1, 2, 4, 8 or 16 threads per particle", e);
        return (int)t;
    }
    int t = dim == 3 ? GPU_TEAM_MAX_3D : GPU_TEAM_MAX_2D;
    while (t > 1 && (double)n * t > GPU_TEAM_THREADS) t /= 2;
    return t;
}

static gpu_t *gpu_get(sim_t *s)
{
    if (s->be_data) return (gpu_t *)s->be_data;
    gpu_t *g = (gpu_t *)calloc(1, sizeof *g);
    if (!g) error_exit(1, "out of memory");
    int ndev = gpu_devices();
    g->dev = g_local_rank % (ndev > 0 ? ndev : 1);
    CK(cudaSetDevice(g->dev));
    CK(cudaStreamCreateWithFlags(&g->st, cudaStreamNonBlocking));
    const char *pe = getenv("SPHSEG_GPU_PROFILE");
    prof.on = pe && *pe && strcmp(pe, "0") != 0;
    const char *ws = getenv("SPHSEG_GPU_WALLSKIP");
    g->wskip = !(ws && strcmp(ws, "0") == 0);
    if (prof.on) {
        CK(cudaEventCreate(&prof.a));
        CK(cudaEventCreate(&prof.b));
    }
    cudaDeviceProp prop;
    CK(cudaGetDeviceProperties(&prop, g->dev));
    const particles_t *h = &s->p;
    size_t n = h->n, na = part_narrays();
    if (na > PERM_MAX) error_exit(1, "backend_gpu: %zu particle arrays > PERM_MAX", na);
    g->nl_cap = grid_list_cap(h->dim, (1 + 0.5 * GPU_SKIN) * (double)(s->seg.k.h / s->seg.k.dr));
    if (s->halo) {
        g->hx = (dhalo *)calloc(1, sizeof *g->hx);
        if (!g->hx) error_exit(1, "out of memory");
        g->hx->cuda_aware = halo_cuda_aware();
        const char *ov = getenv("SPHSEG_GPU_OVERLAP");
        g->hx->overlap = !(ov && !strcmp(ov, "0"));
        s->halo->exposed_measured = 1;
        for (int k = 0; k < HX_EV; ++k) CK(cudaEventCreate(&g->hx->ev[k]));
    }
    g->team = gpu_team_size(h->dim, n);
    message("gpu: device %d of %d, %s, %.1f GiB; %zu MiB of particle arrays (two sets), %zu MiB of neighbour "
            "list (%u per particle), %d threads per particle in neighbour loops%s", g->dev, ndev, prop.name,
            (double)prop.totalGlobalMem / (1u << 30), 2 * n * part_bytes_per_particle() >> 20,
            (n * g->nl_cap * sizeof(unsigned)) >> 20, g->nl_cap, g->team,
            !g->hx ? "" : g->hx->cuda_aware ? "; halo: CUDA-aware MPI on device buffers"
                                            : "; halo: packed on the device, staged through pinned host memory");
    g->d = *h;
    g->alt = *h;
    gpu_reserve(g, n);
    gpu_counts(g, n, 0);
    gpu_upload(g, h, 0, n);
    g->skin = (real)(GPU_SKIN * s->seg.k.h);
    g->every = !s->flow_on; /* prescribed motion moves up to h a stage: from the first step on */
    g->dbox = (box *)dev_alloc(sizeof(box));
    g->dres = (double *)dev_alloc(STEP_NBOUNDS * sizeof(double));
    CK(cudaMemset(g->dres, 0, STEP_NBOUNDS * sizeof(double)));
    g->dfirst = (long long *)dev_alloc(sizeof(long long));
    g->dchk = (chkb *)dev_alloc(sizeof(chkb));
    CK(cudaMallocHost((void **)&g->hchk, sizeof(chkb)));
    CK(cudaMallocHost((void **)&g->hbox, sizeof(box)));
    CK(cudaMallocHost((void **)&g->hres, STEP_NBOUNDS * sizeof(double)));
    CK(cudaMallocHost((void **)&g->hfirst, sizeof(long long)));
    s->be_data = g;
    return g;
}

static void gpu_step_kernel(sim_t *s, gpu_t *g, int place, double t);

/* gpu_get for a hook: the held-back save and advance run first; for a hook
 * that changes the store (mut), the bounds taken by the last check no
 * longer hold. */
static gpu_t *gpu_hook(sim_t *s, int mut)
{
    gpu_t *g = gpu_get(s);
    gpu_step_kernel(s, g, 0, 0.0);
    if (mut) g->bnd_fresh = 0;
    return g;
}

/* ---- the neighbour build ------------------------------------------------- */

struct max_uint {
    __device__ unsigned operator()(unsigned a, unsigned b) const { return b > a ? b : a; }
};

/* Cells of edge `support` over owned particles and ghosts, each range
 * sorted apart (a ghost bit above the cell index), on the global lattice
 * when origin is given (multi-rank exact builds: HCSR cell types as on one
 * rank); the list of the particles within sqrt(list2). With ghosts, the
 * permutation goes back to the halo lists (halo_sorted). */
static void gpu_build(gpu_t *g, halo_t *hl, int dim, real support, real list2, const real *origin)
{
    g->builds++;
    const size_t n = g->n + g->ng, nown = g->n;
    particles_t p = g->d;
    box init;
    for (int d = 0; d < 3; ++d) init.lo[d] = R(INFINITY), init.hi[d] = -R(INFINITY);
    prof_begin(g->st);
    auto bx = thrust::make_transform_iterator(thrust::counting_iterator<size_t>(0), box_of{p});
    reduce(g, bx, g->dbox, n, box_merge(), init);
    CK(cudaMemcpyAsync(g->hbox, g->dbox, sizeof(box), cudaMemcpyDeviceToHost, g->st));
    CK(cudaStreamSynchronize(g->st));
    prof_end(g->st, P_BBOX);
    g->ncell = origin ? grid_fit_lattice(&g->view, dim, n, origin, g->hbox->lo, g->hbox->hi, support)
                      : grid_fit(&g->view, dim, n, g->hbox->lo, g->hbox->hi, support);
    if (2 * g->ncell >= 0xffffffffu)
        error_exit(EXIT_NUMERICAL, "the particles spread over %zu cells of edge 2h (more than 2^31): a particle "
                   "flew far from the rest", g->ncell);
    if (g->ncell > g->cap_cell) {
        if (g->start) {
            CK(cudaFree(g->start));
            CK(cudaFree(g->end));
            CK(cudaFree(g->cell_mat));
            CK(cudaFree(g->cell_type));
        }
        g->cap_cell = g->ncell + g->ncell / 4;
        g->start = (size_t *)dev_alloc(2 * g->cap_cell * sizeof(size_t)); /* owned, then ghost cells */
        g->end = (size_t *)dev_alloc(2 * g->cap_cell * sizeof(size_t));
        g->cell_mat = (size_t *)dev_alloc(g->cap_cell * sizeof(size_t));
        g->cell_type = (unsigned char *)dev_alloc(g->cap_cell);
    }
    grid_view v = g->view;
    unsigned *key = g->key, *idx = g->idx;
    const unsigned gbit = (unsigned)g->ncell;
    prof_begin(g->st);
    each(g, n, [=] __device__(size_t i) {
        int c[3];
        grid_cell_coords(&v, p.x[0], p.x[1], p.x[2], i, c);
        key[i] = (unsigned)grid_cell_index(&v, c[0], c[1], c[2]) + (i >= nown ? gbit : 0u);
        idx[i] = (unsigned)i;
    });
    const size_t nkey = g->ng ? 2 * g->ncell : g->ncell;
    int bits = 1;
    while (bits < 32 && ((size_t)1 << bits) < nkey) ++bits;
    cub::DoubleBuffer<unsigned> kb(g->key, g->key2), vb(g->idx, g->idx2);
    size_t bytes = 0;
    CK(cub::DeviceRadixSort::SortPairs(NULL, bytes, kb, vb, (int64_t)n, 0, bits, g->st));
    CK(cub::DeviceRadixSort::SortPairs(scratch(g, bytes), bytes, kb, vb, (int64_t)n, 0, bits, g->st));
    const unsigned *sk = kb.Current(), *perm = vb.Current();
    size_t *start = g->start, *end = g->end;
    CK(cudaMemsetAsync(start, 0, nkey * sizeof(size_t), g->st));
    CK(cudaMemsetAsync(end, 0, nkey * sizeof(size_t), g->st));
    each(g, n, [=] __device__(size_t k) {
        unsigned c = sk[k];
        if (k == 0 || sk[k - 1] != c) start[c] = k;
        if (k == n - 1 || sk[k + 1] != c) end[c] = k + 1;
    });
    prof_end(g->st, P_SORT);
    if (hl) { /* the halo lists follow the particles through the sort */
        unsigned *hp = (unsigned *)malloc((n ? n : 1) * sizeof(unsigned));
        size_t *pz = (size_t *)malloc((n ? n : 1) * sizeof(size_t));
        if (!hp || !pz) error_exit(1, "out of memory (%zu particles)", n);
        CK(cudaMemcpyAsync(hp, perm, n * sizeof(unsigned), cudaMemcpyDeviceToHost, g->st));
        CK(cudaStreamSynchronize(g->st));
        for (size_t k = 0; k < n; ++k) pz[k] = hp[k];
        halo_sorted(hl, pz, n);
        free(hp), free(pz);
    }
    prof_begin(g->st);
    perm_tab t;
    t.n = (int)part_narrays();
    for (int a = 0; a < t.n; ++a) {
        t.es[a] = (unsigned char)part_array_esize((size_t)a);
        t.src[a] = part_array_get(&g->d, (size_t)a);
        t.dst[a] = part_array_get(&g->alt, (size_t)a);
    }
    dim3 grid((unsigned)((n + 255) / 256), (unsigned)t.n);
    if (n) k_permute<<<grid, 256, 0, g->st>>>(t, perm, n);
    CK(cudaGetLastError());
    prof_end(g->st, P_PERMUTE);
    particles_t tmp = g->d;
    g->d = g->alt;
    g->alt = tmp;
    g->view.start = g->start;
    g->view.end = g->end;
    g->view.gstart = g->ng ? g->start + g->ncell : NULL;
    g->view.gend = g->ng ? g->end + g->ncell : NULL;
    /* the neighbour list, from the cell scan in its order (grid_list_fill) */
    grid_view vc = g->view;
    vc.nl = vc.ncnt = NULL;
    particles_t q = g->d;
    unsigned *cnt = g->ncnt;
    prof_begin(g->st);
    for (;;) { /* a list too short for the densest particle grows, once in a while */
        unsigned *nl = g->nl, cap = g->nl_cap;
        each(g, n, [=] __device__(size_t i) { cnt[i] = grid_list_fill(&vc, q.x, i, list2, nl, n, cap); });
        reduce(g, cnt, (unsigned *)g->dfirst, n, max_uint(), 0u);
        CK(cudaMemcpyAsync(g->hfirst, g->dfirst, sizeof(long long), cudaMemcpyDeviceToHost, g->st));
        CK(cudaStreamSynchronize(g->st));
        unsigned most;
        memcpy(&most, g->hfirst, sizeof most);
        if (most <= cap) break;
        CK(cudaFree(g->nl));
        g->nl_cap = (most + most / 4 + 7) / 8 * 8;
        g->nl = (unsigned *)dev_alloc(g->cap * g->nl_cap * sizeof(unsigned));
    }
    for (int d = 0; d < dim; ++d)
        CK(cudaMemcpyAsync(g->xb[d], q.x[d], n * sizeof(real), cudaMemcpyDeviceToDevice, g->st));
    unsigned *nl = g->nl, cap = g->nl_cap;
    prof_end(g->st, P_LIST);
    g->view.nl = nl;
    g->view.ncnt = cnt;
    g->view.nl_stride = n;
    g->view.nl_cap = cap;
    if (g->wact) { /* dummies that no material reaches until the next build (the list's skin) */
        uint8_t *wa = g->wact;
        grid_view vw = g->view;
        each(g, n, [=] __device__(size_t i) {
            int r = q.kind[i] == KIND_DUMMY && cnt[i] > cap; /* a cell scan at use: keep the loop */
            if (q.kind[i] == KIND_DUMMY && !r) {
                NBR_BEGIN(&vw, q.x, i, j)
                    r |= q.kind[j] == KIND_MATERIAL;
                NBR_END
            }
            wa[i] = (uint8_t)r;
        });
    }
    if (g->lvl) { /* halo levels (see the top) from the new list */
        uint8_t *lvl = g->lvl;
        grid_view vl = g->view;
        each(g, n, [=] __device__(size_t i) { lvl[i] = i >= nown ? 0 : 3; });
        each(g, nown, [=] __device__(size_t i) {
            int ghost = 0;
            NBR_BEGIN(&vl, q.x, i, j)
                ghost |= j >= nown;
            NBR_END
            if (ghost) lvl[i] = 1;
        });
        each(g, nown, [=] __device__(size_t i) {
            if (lvl[i] != 3) return;
            int near = 0;
            NBR_BEGIN(&vl, q.x, i, j)
                near |= lvl[j] == 1;
            NBR_END
            if (near) lvl[i] = 2;
        });
    }
}

/* HCSR classification (bound.c on the CPU): cell types, then the two sweeps,
 * over owned particles and ghosts. */
static void gpu_classify(gpu_t *g, const sph_ctx *kc)
{
    particles_t p = g->d;
    grid_view v = g->view;
    sph_ctx k = *kc;
    size_t *mat = g->cell_mat, n = g->n + g->ng;
    unsigned char *type = g->cell_type, *cls = g->cls;
    bound_sums *sums = g->sums;
    prof_begin(g->st);
    each(g, g->ncell, [=] __device__(size_t c) {
        mat[c] = bound_cell_material(&v, &p, c);
    });
    for (int pass = 0; pass < 2; ++pass)
        each(g, g->ncell, [=] __device__(size_t c) { type[c] = bound_cell_type(&v, type, mat, c, pass); });
    each(g, n, [=] __device__(size_t i) {
        p.bclass[i] = (uint8_t)bound_class_first(i, &p, &v, &k, type, &sums[i]);
    });
    each(g, n, [=] __device__(size_t i) {
        particles_t q = p;
        cls[i] = (unsigned char)bound_class_second(i, &q, &v, &k, type, &sums[i]);
    });
    CK(cudaMemcpyAsync(p.bclass, cls, n, cudaMemcpyDeviceToDevice, g->st));
    prof_end(g->st, P_CLASSIFY);
}

/* Pass selections: everything (one rank, or right after a build), the
 * particles whose support reads no ghost data (level >= lo), the rest. */
static sel sel_all(void) { return sel{NULL, 0, 0}; }
static sel sel_in(const gpu_t *g, int lo) { return g->lvl ? sel{g->lvl, (uint8_t)lo, 3} : sel_all(); }
static sel sel_bd(const gpu_t *g, int lo) { return sel{g->lvl, 0, (uint8_t)(lo - 1)}; }

/* Over owned particles and ghosts in sl: the dummy walls (paper §4.1;
 * walls) and the conservative scheme's L of the material (renorm). Neither
 * reads what the other writes: a small store (several threads per
 * particle, latency-bound) runs them as one kernel, a large one as two (the
 * merged kernel would run both at the larger register count: 2 % slower on
 * the 3D drum, docs/gpu.md). */
/* Dummy i's wall state: its loop when material may be in reach (wa[i]),
 * else flow_wall_none, the same result without the loop (the list holds no
 * material, so the loop's sums would be zero): about half the dummies of a
 * drum lie above the bed or deep in an end wall. */
__device__ __forceinline__ void wall_one(size_t i, particles_t *q, const grid_view *v, const flow_ctx *c,
                                         const uint8_t *wa, int lane, int T)
{
    if (!wa || wa[i]) flow_wall_team(i, q, v, c, lane, T);
    else if (lane == 0) flow_wall_none(i, q, c);
}

static void gpu_walls_renorm(sim_t *s, gpu_t *g, int walls, int renorm, sel sl)
{
    particles_t p = g->d;
    grid_view v = g->view;
    flow_ctx c = s->flow;
    seg_ctx sc = s->seg;
    const size_t n = g->n + g->ng;
    const size_t rlo = s->renorm_due ? g->n : 0; /* the owned L due in the flow rates: the ghosts' here */
    const uint8_t *wa = g->wact;
    if (rlo >= n) renorm = 0;
    if (!walls && !renorm) return;
    prof_begin(g->st);
    if (walls && renorm && g->team > 1) {
        team(g, n, [=] __device__(size_t i, int lane, int T) {
            if (!sel_on(sl, i)) return;
            particles_t q = p;
            if (q.kind[i] == KIND_DUMMY) wall_one(i, &q, &v, &c, wa, lane, T);
            else if (q.kind[i] == KIND_MATERIAL && i >= rlo) seg_renorm_team(i, &q, &v, &sc, lane, T);
        });
    } else {
        if (walls)
            team(g, n, [=] __device__(size_t i, int lane, int T) {
                particles_t q = p;
                if (q.kind[i] == KIND_DUMMY && sel_on(sl, i)) wall_one(i, &q, &v, &c, wa, lane, T);
            });
        if (renorm) /* particles rlo.. only: with the owned L due later, just the ghosts */
            team(g, n - rlo, [=] __device__(size_t k, int lane, int T) {
                const size_t i = rlo + k;
                if (p.kind[i] == KIND_MATERIAL && sel_on(sl, i)) seg_renorm_team(i, &p, &v, &sc, lane, T);
            });
    }
    prof_end(g->st, P_WALLS);
}

/* ---- ghost refreshes (several ranks) ------------------------------------------ */

static size_t r8(size_t b) { return (b + 7) / 8 * 8; }

/* Bytes of cnt records of t: field-major, each field's block 8-aligned. */
static size_t ft_bytes(const ftab &t, size_t cnt)
{
    size_t b = 0;
    for (int f = 0; f < t.n; ++f) b += r8(cnt * t.es[f]);
    return b;
}

template <int UNPACK> __global__ void k_pack(ftab t, const unsigned *idx, size_t cnt, char *buf)
{
    size_t e = (size_t)blockIdx.x * blockDim.x + threadIdx.x;
    if (e >= cnt) return;
    size_t i = idx[e], off = 0;
    for (int f = 0; f < t.n; ++f) {
        char *b = buf + off;
        switch (t.es[f]) {
        case 8:
            if (UNPACK) ((uint64_t *)t.p[f])[i] = ((const uint64_t *)b)[e];
            else ((uint64_t *)b)[e] = ((const uint64_t *)t.p[f])[i];
            break;
        case 4:
            if (UNPACK) ((uint32_t *)t.p[f])[i] = ((const uint32_t *)b)[e];
            else ((uint32_t *)b)[e] = ((const uint32_t *)t.p[f])[i];
            break;
        default:
            if (UNPACK) ((uint8_t *)t.p[f])[i] = ((const uint8_t *)b)[e];
            else ((uint8_t *)b)[e] = ((const uint8_t *)t.p[f])[i];
        }
        off += (cnt * t.es[f] + 7) / 8 * 8;
    }
}

static void ft_add(ftab *t, void *p, size_t es)
{
    if (t->n >= FT_MAX) error_exit(1, "backend_gpu: more than %d refresh fields", FT_MAX);
    t->p[t->n] = p, t->es[t->n] = (unsigned char)es, t->n++;
}

static void *grow_dev(void *p, size_t *cap, size_t need)
{
    if (need <= *cap && p) return p;
    if (p) CK(cudaFree(p));
    *cap = need + need / 4 + 64;
    return dev_alloc(*cap);
}

static void *grow_pinned(void *p, size_t *cap, size_t need)
{
    if (need <= *cap && p) return p;
    if (p) CK(cudaFreeHost(p));
    *cap = need + need / 4 + 64;
    void *q = NULL;
    CK(cudaMallocHost(&q, *cap));
    return q;
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* GPU time spent on the halo: an event pair around each piece of halo work
 * on the stream (pack and copy out; wait, copy in and unpack), summed into
 * halo_t.wall_exposed once both have completed (at the next check, or when
 * the ring is full). */
static void hx_resolve(gpu_t *g, halo_t *h)
{
    dhalo *x = g->hx;
    if (!x) return;
    for (int k = 0; k + 1 < x->nev; k += 2) {
        float ms = 0;
        CK(cudaEventSynchronize(x->ev[k + 1]));
        CK(cudaEventElapsedTime(&ms, x->ev[k], x->ev[k + 1]));
        h->wall_exposed += 1e-3 * ms;
    }
    x->nev = 0;
}
static void hx_mark(gpu_t *g, halo_t *h, int end)
{
    dhalo *x = g->hx;
    if (!end && x->nev + 2 > HX_EV) hx_resolve(g, h); /* pairs are recorded whole */
    CK(cudaEventRecord(x->ev[x->nev++], g->st));
}

/* Start a refresh of fields t of the ghosts: pack the send lists on the
 * device, stage (or hand the device buffer to a CUDA-aware MPI), post. */
static void gpu_refresh_start(sim_t *s, gpu_t *g, const ftab &t)
{
    halo_t *h = s->halo;
    dhalo *x = g->hx;
    int m = h->nnb;
    if (x->pending) error_exit(1, "backend_gpu: a refresh is already in flight");
    double t0 = now();
    x->sb[0] = x->rb[0] = 0;
    for (int k = 0; k < m; ++k) {
        x->sb[k + 1] = x->sb[k] + ft_bytes(t, x->soff[k + 1] - x->soff[k]);
        x->rb[k + 1] = x->rb[k] + ft_bytes(t, x->roff[k + 1] - x->roff[k]);
    }
    x->dsend = (char *)grow_dev(x->dsend, &x->cap_dsend, x->sb[m]);
    x->drecv = (char *)grow_dev(x->drecv, &x->cap_drecv, x->rb[m]);
    hx_mark(g, h, 0);
    for (int k = 0; k < m; ++k) {
        size_t cnt = x->soff[k + 1] - x->soff[k];
        if (cnt)
            k_pack<0><<<(unsigned)((cnt + BLOCK - 1) / BLOCK), BLOCK, 0, g->st>>>(t, x->sidx + x->soff[k], cnt,
                                                                                   x->dsend + x->sb[k]);
    }
    CK(cudaGetLastError());
    char *sbuf = x->dsend, *rbuf = x->drecv;
    if (!x->cuda_aware) {
        x->hsend = (char *)grow_pinned(x->hsend, &x->cap_hsend, x->sb[m]);
        x->hrecv = (char *)grow_pinned(x->hrecv, &x->cap_hrecv, x->rb[m]);
        CK(cudaMemcpyAsync(x->hsend, x->dsend, x->sb[m], cudaMemcpyDeviceToHost, g->st));
        sbuf = x->hsend, rbuf = x->hrecv;
    }
    hx_mark(g, h, 1);
    CK(cudaStreamSynchronize(g->st));
    h->wall_comm += now() - t0;
    halo_post_bytes(h, sbuf, x->sb, rbuf, x->rb);
    x->pend = t;
    x->pending = 1;
    x->refresh++;
}

/* Complete the refresh in flight: wait for the messages, unpack into the
 * ghost slots. The GPU's wait for them (idle) plus the copy and unpack
 * count as exposed halo time. */
static void gpu_refresh_finish(sim_t *s, gpu_t *g)
{
    halo_t *h = s->halo;
    dhalo *x = g->hx;
    if (!x || !x->pending) return;
    int m = h->nnb;
    hx_mark(g, h, 0);
    halo_wait_bytes(h);
    double t0 = now();
    if (!x->cuda_aware) CK(cudaMemcpyAsync(x->drecv, x->hrecv, x->rb[m], cudaMemcpyHostToDevice, g->st));
    for (int k = 0; k < m; ++k) {
        size_t cnt = x->roff[k + 1] - x->roff[k];
        if (cnt)
            k_pack<1><<<(unsigned)((cnt + BLOCK - 1) / BLOCK), BLOCK, 0, g->st>>>(x->pend, x->ridx + x->roff[k], cnt,
                                                                                   x->drecv + x->rb[k]);
    }
    CK(cudaGetLastError());
    hx_mark(g, h, 1);
    x->pending = 0;
    h->wall_comm += now() - t0;
}

/* Refresh fields t of the ghosts now (no overlap). */
static void gpu_refresh(sim_t *s, gpu_t *g, const ftab &t)
{
    gpu_refresh_start(s, g, t);
    gpu_refresh_finish(s, g);
}

/* The refresh in flight lands; then the boundary passes it held back. */
static void gpu_settle(sim_t *s, gpu_t *g)
{
    dhalo *x = g->hx;
    if (!x || !x->pending) return;
    gpu_refresh_finish(s, g);
    gpu_walls_renorm(s, g, x->pend_walls, x->pend_renorm, sel_bd(g, 2));
    x->pend_renorm = x->pend_walls = 0;
}

/* Every array of the owned particles into the host copy s->p (its ghosts
 * are not kept there). */
static void gpu_download(sim_t *s, gpu_t *g)
{
    CK(cudaStreamSynchronize(g->st));
    for (size_t k = 0; k < part_narrays(); ++k)
        CK(cudaMemcpy(part_array_get(&s->p, k), part_array_get(&g->d, k), g->n * part_array_esize(k),
                      cudaMemcpyDeviceToHost));
    s->p.n = g->n, s->p.ng = 0;
}

/* At a list build on several ranks: the owned particles to the host, where
 * mpi/halo.c migrates them and makes fresh ghosts; everything back. */
static void gpu_full_exchange(sim_t *s, gpu_t *g)
{
    double t0 = now();
    particles_t *hp = &s->p;
    gpu_download(s, g);
    halo_exchange(s->halo, hp);
    gpu_reserve(g, hp->n + hp->ng);
    gpu_counts(g, hp->n, hp->ng);
    gpu_upload(g, hp, 0, hp->n + hp->ng);
    double dt = now() - t0;
    g->hx->full++, g->hx->full_s += dt;
    s->halo->wall_exposed += dt;
}

/* After the build's sort: the send lists and ghost slots to the device. */
static void gpu_halo_lists(sim_t *s, gpu_t *g)
{
    halo_t *h = s->halo;
    dhalo *x = g->hx;
    int m = h->nnb;
    if (m + 1 > x->cap_nb) {
        free(x->soff), free(x->roff), free(x->sb), free(x->rb);
        x->cap_nb = m + 1;
        x->soff = (size_t *)calloc((size_t)x->cap_nb, sizeof(size_t));
        x->roff = (size_t *)calloc((size_t)x->cap_nb, sizeof(size_t));
        x->sb = (size_t *)calloc((size_t)x->cap_nb, sizeof(size_t));
        x->rb = (size_t *)calloc((size_t)x->cap_nb, sizeof(size_t));
        if (!x->soff || !x->roff || !x->sb || !x->rb) error_exit(1, "out of memory");
    }
    x->soff[0] = x->roff[0] = 0;
    for (int k = 0; k < m; ++k) {
        x->soff[k + 1] = x->soff[k] + h->nsend[k];
        x->roff[k + 1] = x->roff[k] + h->nrecv[k];
    }
    size_t ns = x->soff[m], nr = x->roff[m];
    unsigned *hs = (unsigned *)malloc((ns + nr + 1) * sizeof(unsigned));
    if (!hs) error_exit(1, "out of memory");
    for (int k = 0; k < m; ++k)
        for (size_t q = 0; q < h->nsend[k]; ++q) hs[x->soff[k] + q] = (unsigned)h->send[k][q];
    for (size_t q = 0; q < nr; ++q) hs[ns + q] = (unsigned)h->recv[q];
    x->sidx = (unsigned *)grow_dev(x->sidx, &x->cap_s, ns * sizeof(unsigned));
    x->ridx = (unsigned *)grow_dev(x->ridx, &x->cap_r, nr * sizeof(unsigned));
    CK(cudaMemcpyAsync(x->sidx, hs, ns * sizeof(unsigned), cudaMemcpyHostToDevice, g->st));
    CK(cudaMemcpyAsync(x->ridx, hs + ns, nr * sizeof(unsigned), cudaMemcpyHostToDevice, g->st));
    CK(cudaStreamSynchronize(g->st)); /* hs is pageable and freed next */
    free(hs);
}

/* What neighbours read of a ghost that moves between builds: positions,
 * and with computed flow velocity and stress (prescribed motion: velocity
 * and shear rate; it rebuilds every stage, so this is a fallback), and C. */
static ftab moving_fields(const sim_t *s, const gpu_t *g)
{
    ftab t;
    t.n = 0;
    const particles_t &p = g->d;
    int dim = s->p.dim;
    for (int d = 0; d < dim; ++d) ft_add(&t, p.x[d], sizeof(real));
    for (int d = 0; d < dim; ++d) ft_add(&t, p.v[d], sizeof(real));
    if (s->flow_on)
        for (int q = 0; q < (dim == 3 ? 6 : 4); ++q) ft_add(&t, p.sig[q], sizeof(real));
    else
        ft_add(&t, p.gdot, sizeof(real));
    if (s->seg_on && !s->win.on) ft_add(&t, p.C, sizeof(creal)); /* windows: refreshed by conc_step */
    return t;
}

/* ---- the hooks ----------------------------------------------------------- */

/* The largest |acc| of the last flow-rate evaluation into dres[STEP_ACC] (a
 * real, widened on read), if not reduced yet: the check folds it into its
 * own pass; a build or a load balance, which reorder the store, take it
 * first. */
static void gpu_acc_reduce(gpu_t *g)
{
    if (!g->acc_pending) return;
    reduce(g, g->amag, (real *)(g->dres + STEP_ACC), g->n, max_real(), R(0.0));
    g->acc_pending = 0;
}

static void gpu_prepare(sim_t *s, double t, int classify)
{
    gpu_t *g = gpu_get(s);
    g->bnd_fresh = 0;
    gpu_settle(s, g);
    gpu_step_kernel(s, g, 1, t); /* with the held-back save and advance */
    int exact = classify == 2 || (s->hcsr && classify);
    int renorm = s->seg_on && classify && s->seg.scheme == SEG_SCHEME_CONSERVATIVE && s->seg.renorm;
    if (renorm) s->renorm_due = s->flow_on; /* the owned L: with the next flow rates (sim.h) */
    int build = !g->built || g->stale || g->every || exact;
    if (s->halo) build = comm_max((double)build) > 0; /* a build exchanges: every rank or none */
    if (build) {
        gpu_acc_reduce(g); /* before the store is re-sorted */
        if (s->halo) gpu_full_exchange(s, g);
        real skin = exact ? R(0.0) : g->skin, sup = R(2.0) * s->seg.k.h + skin;
        gpu_build(g, s->halo, s->p.dim, sup, exact ? s->seg.k.support2 : sup * sup,
                  s->halo && exact ? s->halo->origin : NULL);
        if (s->halo) gpu_halo_lists(s, g);
        g->built = 1;
        g->stale = exact; /* a list without skin is stale as soon as anything moves */
        if (exact) {
            gpu_classify(g, &s->seg.k);
            if (s->halo) { /* deep ghosts lack part of their support: the owners' classes */
                ftab c;
                c.n = 0;
                ft_add(&c, g->d.bclass, 1);
                for (int d = 0; d < 3; ++d) ft_add(&c, g->d.nrm[d], sizeof(real));
                ft_add(&c, g->d.psi, sizeof(real));
                gpu_refresh(s, g, c);
            }
        }
        gpu_walls_renorm(s, g, s->flow_on, renorm, sel_all());
        return;
    }
    if (s->halo && !g->hx->overlap) gpu_refresh(s, g, moving_fields(s, g));
    if (s->halo && g->hx->overlap) { /* ghosts moved: refresh them while the interior goes on */
        gpu_refresh_start(s, g, moving_fields(s, g));
        g->hx->pend_renorm = renorm;
        g->hx->pend_walls = s->flow_on;
        gpu_walls_renorm(s, g, s->flow_on, renorm, sel_in(g, 2));
        return;
    }
    gpu_walls_renorm(s, g, s->flow_on, renorm, sel_all());
}

/* The flow rates of the owned particles in sl, and with segregation their
 * concentration coefficients (seg_coeffs reads only i's C and the shear
 * rate just computed). */
template <int RENORM> static void gpu_flow_pass(sim_t *s, gpu_t *g, sel sl)
{
    particles_t p = g->d;
    grid_view v = g->view;
    flow_ctx c = s->flow;
    seg_ctx sc = s->seg;
    const int seg = s->seg_on && !s->win.on; /* in windows: the coefficients at their close */
    real *amag = g->amag;
    team(g, g->n, [=] __device__(size_t i, int lane, int T) {
        if (!sel_on(sl, i)) return;
        particles_t q = p;
        const int mat = q.kind[i] == KIND_MATERIAL;
        real a = mat ? flow_rates_team(i, &q, &v, &c, lane, T, RENORM) : R(0.0);
        if (lane != 0) return;
        amag[i] = a;
        if (seg && mat) seg_coeffs(i, &q, &sc);
    });
}

/* (and the owned particles' L when prepare left them due: a kernel of its
 * own, so that the other passes keep the smaller register count) */
static void gpu_flow_rates(sim_t *s, gpu_t *g, sel sl)
{
    prof_begin(g->st);
    if (s->renorm_due) gpu_flow_pass<1>(s, g, sl);
    else gpu_flow_pass<0>(s, g, sl);
    g->acc_pending = 1;
    prof_end(g->st, P_FLOW);
}

/* (p: g->d, or g->d reading the window's mean shear rate as gdot) */
static void gpu_seg_coeffs(sim_t *s, gpu_t *g, particles_t p, size_t a, size_t b)
{
    seg_ctx c = s->seg;
    each(g, b - a, [=] __device__(size_t k) {
        size_t i = a + k;
        if (p.kind[i] == KIND_MATERIAL) seg_coeffs(i, &p, &c);
    });
}

static void gpu_dcdt(sim_t *s, gpu_t *g, particles_t p, sel sl)
{
    grid_view v = g->view;
    seg_ctx c = s->seg;
    team(g, g->n, [=] __device__(size_t i, int lane, int T) {
        if (sel_on(sl, i)) seg_dCdt_team(i, &p, &v, &c, lane, T);
    });
}

static void gpu_rates(sim_t *s)
{
    gpu_t *g = gpu_hook(s, 1);
    const int overlap = g->hx && g->hx->pending;
    if (s->flow_on) {
        if (overlap) { /* level 3 reads nothing the refresh in flight brings */
            gpu_flow_rates(s, g, sel_in(g, 3));
            gpu_settle(s, g);
            gpu_flow_rates(s, g, sel_bd(g, 3));
        } else {
            gpu_settle(s, g);
            gpu_flow_rates(s, g, sel_all());
        }
        s->renorm_due = 0;
    }
    gpu_settle(s, g);
    if (s->seg_on && !s->win.on) {
        prof_begin(g->st);
        if (s->halo && s->flow_on && !g->hx->overlap) {
            ftab t;
            t.n = 0;
            ft_add(&t, g->d.gdot, sizeof(real));
            gpu_refresh(s, g, t);
            gpu_seg_coeffs(s, g, g->d, g->n, g->n + g->ng); /* the owned: with the flow rates */
            gpu_dcdt(s, g, g->d, sel_all());
        } else if (s->halo && s->flow_on) { /* the ghosts' shear rate, while the interior goes on */
            ftab t;
            t.n = 0;
            ft_add(&t, g->d.gdot, sizeof(real));
            gpu_refresh_start(s, g, t);
            gpu_dcdt(s, g, g->d, sel_in(g, 2));
            gpu_refresh_finish(s, g);
            gpu_seg_coeffs(s, g, g->d, g->n, g->n + g->ng);
            gpu_dcdt(s, g, g->d, sel_bd(g, 2));
        } else {
            if (!s->flow_on) gpu_seg_coeffs(s, g, g->d, 0, g->n + g->ng);
            gpu_dcdt(s, g, g->d, sel_all());
        }
        prof_end(g->st, P_SEG);
    }
}

/* save_start and advance only note what to do: the per-particle updates
 * run in one kernel with the next prepare's wall or kinematic motion
 * (integrate_step calls save_start, advance, prepare in a row), or alone
 * when another hook comes first (gpu_hook). Each particle's updates are its
 * own, so running them together changes nothing. */
static void gpu_step_kernel(sim_t *s, gpu_t *g, int place, double t)
{
    const int sv = g->pend_save, ad = g->pend_adv;
    if (!sv && !ad && !place) return;
    g->pend_save = g->pend_adv = 0;
    particles_t p = g->d;
    flow_ctx c = g->pend_fc;
    const int flow = s->flow_on, seg = s->seg_on && !s->win.on;
    const real a = g->pend_a, w8 = g->pend_w;
    wall_geom w = s->flow.w;
    kin_params kin = s->kin;
    prof_begin(g->st);
    each(g, g->n, [=] __device__(size_t i) {
        particles_t q = p;
        if (sv) step_save(i, &q, flow);
        if (ad) step_advance(i, &q, a, &c, flow, seg, w8);
        if (place) step_place(i, &q, flow, &w, &kin, t);
    });
    prof_end(g->st, P_MOTION);
}

static void gpu_save_start(sim_t *s)
{
    gpu_t *g = gpu_hook(s, 1);
    g->pend_save = 1;
}

static void gpu_advance(sim_t *s, double a, double w)
{
    gpu_t *g = gpu_get(s); /* a save_start just before stays held */
    if (g->pend_adv) gpu_step_kernel(s, g, 0, 0.0);
    g->bnd_fresh = 0;
    g->pend_adv = 1;
    g->pend_a = (real)a;
    g->pend_w = (real)w;
    g->pend_fc = s->flow;
}

/* Concentration windows (sim.h): the mean shear rate over the window, here
 * and in the ghosts; L of every material particle at the window's end; the
 * bounds at that rate (into dres[0..2]: the next gpu_bounds takes its own). */
static void gpu_conc_begin(sim_t *s, double T, double out[STEP_NBOUNDS])
{
    gpu_t *g = gpu_hook(s, 1);
    gpu_settle(s, g);
    particles_t p = g->d;
    const real inv = (real)(1.0 / T);
    prof_begin(g->st);
    each(g, g->n, [=] __device__(size_t i) {
        particles_t q = p;
        step_shear_mean(i, &q, inv);
    });
    if (s->halo) {
        ftab t;
        t.n = 0;
        ft_add(&t, p.gsum, sizeof(real));
        gpu_refresh(s, g, t);
    }
    if (s->seg.scheme == SEG_SCHEME_CONSERVATIVE && s->seg.renorm) {
        grid_view v = g->view;
        seg_ctx sc = s->seg;
        team(g, g->n + g->ng, [=] __device__(size_t i, int lane, int T) {
            if (p.kind[i] == KIND_MATERIAL) seg_renorm_team(i, &p, &v, &sc, lane, T);
        });
    }
    particles_t q = p;
    q.gdot = p.gsum;
    bnd3 init = {{0, 0, 0}};
    auto it = thrust::make_transform_iterator(thrust::counting_iterator<size_t>(0), bnd_of{q, s->step_c});
    reduce(g, it, (bnd3 *)g->dres, g->n, bnd_max(), init);
    CK(cudaMemcpyAsync(g->hres, g->dres, 3 * sizeof(double), cudaMemcpyDeviceToHost, g->st));
    CK(cudaStreamSynchronize(g->st));
    prof_end(g->st, P_SEG);
    out[STEP_D] = g->hres[0], out[STEP_WAVE] = g->hres[1], out[STEP_SPEED] = 0, out[STEP_ACC] = 0;
}

/* One midpoint step of C alone (length a) at the window's mean shear rate;
 * the ghosts' C refreshed after each stage. */
static void gpu_conc_step(sim_t *s, double a, int last)
{
    gpu_t *g = gpu_hook(s, 1);
    gpu_settle(s, g);
    particles_t p = g->d, q = g->d;
    q.gdot = p.gsum;
    ftab c;
    c.n = 0;
    ft_add(&c, p.C, sizeof(creal));
    prof_begin(g->st);
    for (int stage = 0; stage < 2; ++stage) {
        gpu_seg_coeffs(s, g, q, 0, g->n + g->ng);
        gpu_dcdt(s, g, q, sel_all());
        const real as = (real)(stage ? a : 0.5 * a);
        each(g, g->n, [=] __device__(size_t i) {
            particles_t r = p;
            step_conc_advance(i, &r, as, stage);
        });
        if (s->halo) gpu_refresh(s, g, c);
    }
    if (last) CK(cudaMemsetAsync(p.gsum, 0, (g->n + g->ng) * sizeof(real), g->st));
    prof_end(g->st, P_SEG);
}

static void gpu_filter(sim_t *s)
{
    gpu_t *g = gpu_hook(s, 1);
    gpu_settle(s, g);
    particles_t p = g->d;
    grid_view v = g->view;
    flow_ctx c = s->flow;
    prof_begin(g->st);
    team(g, g->n, [=] __device__(size_t i, int lane, int T) {
        particles_t q = p;
        if (q.kind[i] == KIND_MATERIAL) flow_shepard_team(i, &q, &v, &c, lane, T);
    });
    each(g, g->n, [=] __device__(size_t i) { flow_shepard_store(i, &p); });
    prof_end(g->st, P_FILTER);
    if (s->halo) {
        ftab t;
        t.n = 0;
        for (int q = 0; q < (s->p.dim == 3 ? 6 : 4); ++q) ft_add(&t, g->d.sig[q], sizeof(real));
        gpu_refresh(s, g, t);
    }
    gpu_walls_renorm(s, g, 1, 0, sel_all());
}

/* Owned particles only: no refresh needs to land first. */
static void gpu_bounds(sim_t *s, double out[STEP_NBOUNDS])
{
    gpu_t *g = gpu_hook(s, 0);
    if (!g->bnd_fresh) { /* the first step, or a store changed since the check */
        bnd3 init = {{0, 0, 0}};
        prof_begin(g->st);
        gpu_acc_reduce(g);
        auto it = thrust::make_transform_iterator(thrust::counting_iterator<size_t>(0), bnd_of{g->d, s->step_c});
        reduce(g, it, (bnd3 *)g->dres, g->n, bnd_max(), init);
        CK(cudaMemcpyAsync(g->hres, g->dres, STEP_NBOUNDS * sizeof(double), cudaMemcpyDeviceToHost, g->st));
        CK(cudaStreamSynchronize(g->st));
        prof_end(g->st, P_BOUNDS_CHECK);
    }
    g->bnd_fresh = 0;
    for (int k = 0; k < 3; ++k) out[k] = g->hres[k];
    real acc;
    memcpy(&acc, g->hres + STEP_ACC, sizeof acc);
    out[STEP_ACC] = s->flow_on ? (double)acc : 0.0;
}

static long gpu_check(sim_t *s)
{
    gpu_t *g = gpu_hook(s, 0);
    prof_begin(g->st);
    const int acc = g->acc_pending; /* |acc| in the same pass */
    chkb_of f = {chk_of{g->d, s->step_c, s->t, g->xb[0], g->xb[1], g->xb[2]}, bnd_of{g->d, s->step_c},
                 acc ? g->amag : NULL};
    auto it = thrust::make_transform_iterator(thrust::counting_iterator<size_t>(0), f);
    chkb init = {{(long long)g->n, 0, 0}, {{0, 0, 0}}, R(0.0)};
    reduce(g, it, g->dchk, g->n, chkb_merge(), init);
    if (acc) { /* dres[STEP_ACC] as gpu_acc_reduce leaves it */
        CK(cudaMemcpyAsync(g->dres + STEP_ACC, &g->dchk->amax, sizeof(real), cudaMemcpyDeviceToDevice, g->st));
        g->acc_pending = 0;
    }
    CK(cudaMemcpyAsync(g->hchk, g->dchk, sizeof(chkb), cudaMemcpyDeviceToHost, g->st));
    CK(cudaMemcpyAsync(g->hres, g->dres, STEP_NBOUNDS * sizeof(double), cudaMemcpyDeviceToHost, g->st));
    CK(cudaStreamSynchronize(g->st));
    prof_end(g->st, P_BOUNDS_CHECK);
    for (int k = 0; k < 3; ++k) g->hres[k] = g->hchk->b.v[k];
    g->bnd_fresh = 1;
    if (s->halo) hx_resolve(g, s->halo); /* whole pairs only: one may be in flight */
    const chk *c = &g->hchk->c;
    double D = sqrt((double)c->build2), d = sqrt((double)c->step2), skin = g->skin;
    g->stale |= D + 2 * d > 0.5 * skin;
    g->every = !s->flow_on || d > 0.25 * skin; /* prescribed motion: x_n is not kept */
    return c->first >= (long long)g->n ? -1 : (long)c->first;
}

static void gpu_to_host(sim_t *s)
{
    gpu_t *g = gpu_hook(s, 0);
    gpu_settle(s, g);
    gpu_download(s, g);
    if (s->halo) hx_resolve(g, s->halo);
}

/* A load balance moved particles between ranks on the host: take them. */
static void gpu_from_host(sim_t *s)
{
    gpu_t *g = gpu_hook(s, 1);
    gpu_settle(s, g);
    gpu_acc_reduce(g);
    CK(cudaStreamSynchronize(g->st));
    gpu_reserve(g, s->p.n);
    gpu_counts(g, s->p.n, 0);
    gpu_upload(g, &s->p, 0, s->p.n);
    g->built = 0;
}

static void gpu_finish(sim_t *s)
{
    gpu_t *g = (gpu_t *)s->be_data;
    if (!g) return;
    gpu_settle(s, g);
    CK(cudaStreamSynchronize(g->st));
    if (s->halo) hx_resolve(g, s->halo);
    if (prof.on) {
        double tot = 0;
        for (int k = 0; k < P_NPROF; ++k) tot += prof.ms[k];
        message("gpu profile (SPHSEG_GPU_PROFILE, synchronised stages), %ld steps, %zu particles:", s->step, g->n);
        for (int k = 0; k < P_NPROF; ++k)
            if (prof.calls[k])
                message("  %-34s %10.2f ms %5.1f %%  %9.4f ms/step", prof_name[k], prof.ms[k],
                        tot > 0 ? 100 * prof.ms[k] / tot : 0.0, s->step ? prof.ms[k] / (double)s->step : 0.0);
        message("  %-34s %10.2f ms; %ld neighbour-list builds", "total", tot, g->builds);
    }
    if (g->hx) {
        dhalo *x = g->hx;
        message("gpu halo (rank %d): %ld exchanges at list builds (%.3f s, host), %ld refreshes, %zu ghosts, "
                "%.3f s of halo on the device timeline (exposed)", s->halo->rank, x->full, x->full_s, x->refresh,
                g->ng, s->halo->wall_exposed);
        void *db[] = {x->sidx, x->ridx, x->dsend, x->drecv};
        for (size_t k = 0; k < 4; ++k)
            if (db[k]) CK(cudaFree(db[k]));
        if (x->hsend) CK(cudaFreeHost(x->hsend));
        if (x->hrecv) CK(cudaFreeHost(x->hrecv));
        for (int k = 0; k < HX_EV; ++k) CK(cudaEventDestroy(x->ev[k]));
        free(x->soff), free(x->roff), free(x->sb), free(x->rb), free(x);
    }
    for (size_t k = 0; k < part_narrays(); ++k) {
        CK(cudaFree(part_array_get(&g->d, k)));
        CK(cudaFree(part_array_get(&g->alt, k)));
    }
    void *bufs[] = {g->start, g->end, g->cell_mat, g->cell_type, g->key, g->key2, g->idx, g->idx2,
                    g->cls, g->sums, g->nl, g->ncnt, g->amag, g->tmp, g->dbox, g->dres, g->dfirst,
                    g->dchk, g->xb[0], g->xb[1], g->xb[2], g->lvl, g->wact};
    for (size_t k = 0; k < sizeof bufs / sizeof bufs[0]; ++k)
        if (bufs[k]) CK(cudaFree(bufs[k]));
    CK(cudaFreeHost(g->hbox));
    CK(cudaFreeHost(g->hres));
    CK(cudaFreeHost(g->hfirst));
    CK(cudaFreeHost(g->hchk));
    CK(cudaStreamDestroy(g->st));
    free(g);
    s->be_data = NULL;
}

extern "C" const struct backend *backend_gpu(int local_rank)
{
    static const struct backend b = {"gpu",          gpu_prepare,    gpu_rates,  gpu_advance, gpu_conc_begin,
                                      gpu_conc_step,  gpu_save_start, gpu_filter, gpu_bounds,  gpu_check,
                                      gpu_to_host,    gpu_finish,     gpu_from_host, 3};
    g_local_rank = local_rank;
    return &b;
}
