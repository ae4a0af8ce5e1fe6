/* gpu/gpu_launch.cuh — launching, included by gpu.cuh (templates: each unit
 * instantiates the kernels it launches): one thread per particle (each),
 * teams of T threads per particle for the neighbour loops (team, the launch
 * bounds); and the functors of the reductions (bounding box, bounds, the
 * blow-up check; reduce itself is gpu_reduce.cuh's). */
#ifndef SPHSEG_GPU_LAUNCH_CUH
#define SPHSEG_GPU_LAUNCH_CUH

/* ---- launching ----------------------------------------------------------- */

template <class F> __global__ void k_each(size_t n, F f)
{
    size_t i = (size_t)blockIdx.x * blockDim.x + threadIdx.x;
    if (i < n) f(i);
}

/* A held launch's arguments as bytes (gpu_graph.cu compares them from
 * step to step): the count, the grid (16 bytes, zeroed where unused) and
 * the functor. Not held, each and team launch at once. */
template <class F> struct nf_blob {
    alignas(16) unsigned char b[16 + sizeof(F)];
    nf_blob(size_t n, unsigned grid, const F &f)
    {
        static_assert(alignof(F) <= 16, "a functor aligned past 16 bytes");
        memset(b, 0, 16);
        memcpy(b, &n, sizeof n);
        memcpy(b + 8, &grid, sizeof grid);
        memcpy(b + 16, (const void *)&f, sizeof(F));
        /* the closure's padding holds whatever the stack held: zeroed where
         * the compiler finds it (GCC 12 leaves some of a large closure's,
         * which gpu_graph.cu's patches then take) */
        __builtin_clear_padding((F *)(b + 16));
    }
};
template <class F> static inline void nf_read(const void *a, size_t *n, unsigned *grid, const F **f)
{
    const unsigned char *b = (const unsigned char *)a;
    memcpy(n, b, sizeof *n);
    memcpy(grid, b + 8, sizeof *grid);
    *f = (const F *)(b + 16);
}

template <class F> static void th_each(const void *a, cudaStream_t st)
{
    size_t n;
    unsigned grid;
    const F *f;
    nf_read(a, &n, &grid, &f);
    k_each<<<grid, BLOCK, 0, st>>>(n, *f);
    CK(cudaGetLastError());
}

template <class F> static void each(const gpu_t *g, size_t n, F f)
{
    if (n == 0) return;
    const unsigned grid = (unsigned)((n + BLOCK - 1) / BLOCK);
    if (!g_defer) {
        k_each<<<grid, BLOCK, 0, g->st>>>(n, f);
        CK(cudaGetLastError());
        return;
    }
    const nf_blob<F> b(n, grid, f);
    gpu_defer_push(th_each<F>, (const void *)k_each<F>, b.b, sizeof b.b);
}

/* At least SPHSEG_TEAM_MINB blocks of BLOCK threads per SM: at most 128
 * registers a thread on sm_90 (65536 / (128 * 4)). The flow rates want 144
 * and spill a little at 128, yet the fourth block's warps hide more of the
 * neighbour-gather latency: 1.20x on the 3D drum at 1.1e7 particles with the
 * fused L, neutral on the 2D drums (docs/gpu.md, H100). 0 lets nvcc choose. */
#ifndef SPHSEG_TEAM_MINB
#define SPHSEG_TEAM_MINB 4
#endif
/* The fused leapfrog flow pass's own bound (gpu_pairs.cu, gpu_flow_pass
 * with SHIFT): in the double build its values take twice the registers, and
 * at 128 it kept a 416-byte frame and spilled 804 bytes a thread
 * (tools.dev.kernel_frames --precision double). At 3 blocks (168 registers)
 * the 1.1e7 3D drum ran 1.35x (2 blocks: 1.22x), the 2D drums 1.02x; the
 * predictor-corrector's passes, which spill 144 bytes, ran 0.89x at 3 and
 * keep 4 (docs/gpu.md, "The flow pass's code"). The single build
 * keeps 4 where a team has 4 or more threads (small 3D stores, the 2D
 * drums: 0.96x at 5 on the 2D EN drum), and in the list form without the
 * owned L (gpu_flow_pass's RENORM) runs 5 at 1 or 2 (3D stores past about
 * 5e5 particles): 96 registers and a 56-byte frame
 * of spills with gpu_pairs.cu's fast division (NVFLAGS_PAIRS in the
 * Makefile), 1.05x against 4 on the 1.1e7 drum (one H200;
 * docs/gpu.md, "The flow pass's code"): SPHSEG_FUSED_MINB_T2. */
#ifndef SPHSEG_FUSED_MINB
#ifdef SPHSEG_SINGLE
#define SPHSEG_FUSED_MINB SPHSEG_TEAM_MINB
#else
#define SPHSEG_FUSED_MINB 3
#endif
#endif
#ifndef SPHSEG_FUSED_MINB_T2
#ifdef SPHSEG_SINGLE
#define SPHSEG_FUSED_MINB_T2 5
#else
#define SPHSEG_FUSED_MINB_T2 SPHSEG_FUSED_MINB
#endif
#endif
/* Teams (src/core/hd.h): T consecutive threads per particle, f(i, lane,
 * T), T a power of two dividing the warp, so that a team never straddles a
 * warp and a team past n is out as a whole. MB: at least MB blocks of BLOCK
 * threads a SM (the register bound; 0: nvcc's choice). */
template <int T, int MB, class F> __global__ void __launch_bounds__(BLOCK, MB > 0 ? MB : 1) k_team(size_t n, F f)
{
    size_t t = (size_t)blockIdx.x * blockDim.x + threadIdx.x, i = t / T;
    if (i < n) f(i, (int)(t % T), T);
}

template <int T, int MB, class F> static void th_team(const void *a, cudaStream_t st)
{
    size_t n;
    unsigned grid;
    const F *f;
    nf_read(a, &n, &grid, &f);
    k_team<T, MB><<<grid, BLOCK, 0, st>>>(n, *f);
    CK(cudaGetLastError());
}

template <int T, int MB, class F> static void team_launch(const gpu_t *g, size_t n, F f)
{
    const unsigned grid = (unsigned)((n * T + BLOCK - 1) / BLOCK);
    if (!g_defer) {
        k_team<T, MB><<<grid, BLOCK, 0, g->st>>>(n, f);
        CK(cudaGetLastError());
        return;
    }
    const nf_blob<F> b(n, grid, f);
    gpu_defer_push(th_team<T, MB, F>, (const void *)k_team<T, MB, F>, b.b, sizeof b.b);
}

/* The neighbour-loop kernels, g->team threads per particle, at least MB
 * blocks a SM, MB2 where a team has 1 or 2 threads (SPHSEG_TEAM_MINB unless
 * given: the fused leapfrog pass's are SPHSEG_FUSED_MINB and _T2). */
template <int MB = SPHSEG_TEAM_MINB, int MB2 = MB, class F> static void team(const gpu_t *g, size_t n, F f)
{
    if (n == 0) return;
    switch (g->team) {
    case 1: team_launch<1, MB2>(g, n, f); break;
    case 2: team_launch<2, MB2>(g, n, f); break;
    case 4: team_launch<4, MB>(g, n, f); break;
    case 8: team_launch<8, MB>(g, n, f); break;
    default: team_launch<16, MB>(g, n, f); break;
    }
}

/* ---- the reductions' functors (reduce, gpu_reduce.cuh) ------------------ */

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
/* The reductions' functors hold the step_ctx by pointer, to a device copy
 * (gpu_step_ctx): CUB copies a functor into each thread's local memory, and
 * the context with its wall table is kilobytes. */
struct bnd_of {
    particles_t p;
    const step_ctx *c;
    __device__ bnd3 operator()(size_t i) const
    {
        bnd3 b = {{0, 0, 0}};
        if (p.kind[i] == KIND_MATERIAL) step_bounds_of(i, &p, c, b.v);
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
    const step_ctx *c;
    dscal t; /* the step's time (gpu_scalar) */
    const real *xb0, *xb1, *xb2;
    __device__ chk operator()(size_t i) const
    {
        chk r;
        r.first = p.kind[i] == KIND_MATERIAL && step_guard(i, &p, c, t.at(0)) ? (long long)i : (long long)p.n;
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

struct max_uint {
    __device__ unsigned operator()(unsigned a, unsigned b) const { return b > a ? b : a; }
};

#endif
