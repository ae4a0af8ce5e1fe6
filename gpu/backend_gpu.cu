/* backend_gpu.cu — the CUDA backend (struct backend, src/sim.h).
 *
 * The particle arrays live on the device for the whole run; the host copy
 * s->p is refreshed only by to_host (snapshots, diagnostics, error reports).
 * Every kernel runs one thread per particle (or per cell) and calls the same
 * HD_INLINE bodies of src/physics/ as the CPU backend, gather style: a thread
 * sums over its particle's neighbours and writes only its own entries, so
 * results do not depend on thread scheduling and runs are bit-identical run
 * to run. Reductions (bounding box, time-step bounds, blow-up guard) are max
 * and min with CUB, exact in any order.
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
 * taken in another order: CPU and GPU agree to round-off, not bitwise. */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cuda_runtime.h>
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_reduce.cuh>
#include <thrust/iterator/counting_iterator.h>
#include <thrust/iterator/transform_iterator.h>
extern "C" {
#include "error.h"
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

/* Source and destination of every per-particle array (the permutation). */
struct perm_tab {
    int n;
    unsigned char es[PERM_MAX];
    void *src[PERM_MAX], *dst[PERM_MAX];
};

struct box {
    real lo[3], hi[3];
};

typedef struct gpu {
    int dev;
    cudaStream_t st;
    particles_t d, alt; /* device arrays: current and the permutation's spare set */
    size_t n;
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
    void *tmp;          /* CUB scratch */
    size_t tmp_bytes;
    struct box *dbox;   /* device results */
    double *dres;       /* [STEP_NBOUNDS]: D, wave, speed, acc */
    long long *dfirst;  /* also the list-length maximum */
    struct chk *dchk, *hchk;
    struct box *hbox;   /* pinned host copies */
    double *hres;
    long long *hfirst;
} gpu_t;

static int g_local_rank;

/* Stage timing (SPHSEG_GPU_PROFILE=1 in the environment): events around each
 * stage with a synchronisation after it, so the stages do not overlap and
 * the total runs slower than without; a table at the end of the run. */
enum { P_MOTION, P_BBOX, P_SORT, P_PERMUTE, P_LIST, P_CLASSIFY, P_RENORM, P_WALLS, P_FLOW, P_SEG,
       P_SAVE_ADVANCE, P_FILTER, P_BOUNDS_CHECK, P_NPROF };
static const char *prof_name[P_NPROF] = {"wall/kinematic motion", "bounding box (+sync)", "cell keys, radix sort, start/end",
                                          "permute arrays", "neighbour list", "HCSR classification",
                                          "renormalisation L", "dummy walls", "flow rates (+max |a|)",
                                          "concentration rates", "save start, advance", "Shepard filter",
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
    if (prof.on) {
        CK(cudaEventCreate(&prof.a));
        CK(cudaEventCreate(&prof.b));
    }
    cudaDeviceProp prop;
    CK(cudaGetDeviceProperties(&prop, g->dev));
    const particles_t *h = &s->p;
    size_t n = h->n, na = part_narrays();
    if (na > PERM_MAX) error_exit(1, "backend_gpu: %zu particle arrays > PERM_MAX", na);
    unsigned cap = grid_list_cap(h->dim, (1 + 0.5 * GPU_SKIN) * (double)(s->seg.k.h / s->seg.k.dr));
    message("gpu: device %d of %d, %s, %.1f GiB; %zu MiB of particle arrays (two sets), %zu MiB of neighbour "
            "list (%u per particle)", g->dev, ndev, prop.name, (double)prop.totalGlobalMem / (1u << 30),
            2 * n * part_bytes_per_particle() >> 20, (n * cap * sizeof(unsigned)) >> 20, cap);
    g->n = n;
    g->d = *h;
    g->alt = *h;
    for (size_t k = 0; k < na; ++k) {
        size_t bytes = n * part_array_esize(k);
        void *a = dev_alloc(bytes), *b = dev_alloc(bytes);
        CK(cudaMemcpy(a, part_array_get(h, k), bytes, cudaMemcpyHostToDevice));
        part_array_set(&g->d, k, a);
        part_array_set(&g->alt, k, b);
    }
    g->key = (unsigned *)dev_alloc(n * sizeof(unsigned));
    g->key2 = (unsigned *)dev_alloc(n * sizeof(unsigned));
    g->idx = (unsigned *)dev_alloc(n * sizeof(unsigned));
    g->idx2 = (unsigned *)dev_alloc(n * sizeof(unsigned));
    g->cls = (unsigned char *)dev_alloc(n);
    g->sums = (bound_sums *)dev_alloc(n * sizeof(bound_sums));
    g->skin = (real)(GPU_SKIN * s->seg.k.h);
    g->nl_cap = grid_list_cap(h->dim, (1 + 0.5 * GPU_SKIN) * (double)(s->seg.k.h / s->seg.k.dr));
    for (int d = 0; d < 3; ++d) {
        g->xb[d] = (real *)dev_alloc(n * sizeof(real));
        CK(cudaMemset(g->xb[d], 0, n * sizeof(real)));
    }
    g->nl = (unsigned *)dev_alloc(n * g->nl_cap * sizeof(unsigned));
    g->ncnt = (unsigned *)dev_alloc(n * sizeof(unsigned));
    g->amag = (real *)dev_alloc(n * sizeof(real));
    CK(cudaMemset(g->amag, 0, n * sizeof(real)));
    g->dbox = (box *)dev_alloc(sizeof(box));
    g->dres = (double *)dev_alloc(STEP_NBOUNDS * sizeof(double));
    CK(cudaMemset(g->dres, 0, STEP_NBOUNDS * sizeof(double)));
    g->dfirst = (long long *)dev_alloc(sizeof(long long));
    g->dchk = (chk *)dev_alloc(sizeof(chk));
    CK(cudaMallocHost((void **)&g->hchk, sizeof(chk)));
    CK(cudaMallocHost((void **)&g->hbox, sizeof(box)));
    CK(cudaMallocHost((void **)&g->hres, STEP_NBOUNDS * sizeof(double)));
    CK(cudaMallocHost((void **)&g->hfirst, sizeof(long long)));
    if (n >= 0xffffffffu) error_exit(1, "backend_gpu: %zu particles on one rank: more than 2^32 - 1", n);
    s->be_data = g;
    return g;
}

/* ---- the neighbour build ------------------------------------------------- */

struct max_uint {
    __device__ unsigned operator()(unsigned a, unsigned b) const { return b > a ? b : a; }
};

/* Cells of edge `support`, the list of the particles within sqrt(list2). */
static void gpu_build(gpu_t *g, int dim, real support, real list2)
{
    g->builds++;
    const size_t n = g->n;
    particles_t p = g->d;
    box init;
    for (int d = 0; d < 3; ++d) init.lo[d] = R(INFINITY), init.hi[d] = -R(INFINITY);
    prof_begin(g->st);
    auto bx = thrust::make_transform_iterator(thrust::counting_iterator<size_t>(0), box_of{p});
    reduce(g, bx, g->dbox, n, box_merge(), init);
    CK(cudaMemcpyAsync(g->hbox, g->dbox, sizeof(box), cudaMemcpyDeviceToHost, g->st));
    CK(cudaStreamSynchronize(g->st));
    prof_end(g->st, P_BBOX);
    g->ncell = grid_fit(&g->view, dim, n, g->hbox->lo, g->hbox->hi, support);
    if (g->ncell >= 0xffffffffu)
        error_exit(EXIT_NUMERICAL, "the particles spread over %zu cells of edge 2h (more than 2^32): a particle "
                   "flew far from the rest", g->ncell);
    if (g->ncell > g->cap_cell) {
        if (g->start) {
            CK(cudaFree(g->start));
            CK(cudaFree(g->end));
            CK(cudaFree(g->cell_mat));
            CK(cudaFree(g->cell_type));
        }
        g->cap_cell = g->ncell + g->ncell / 4;
        g->start = (size_t *)dev_alloc(g->cap_cell * sizeof(size_t));
        g->end = (size_t *)dev_alloc(g->cap_cell * sizeof(size_t));
        g->cell_mat = (size_t *)dev_alloc(g->cap_cell * sizeof(size_t));
        g->cell_type = (unsigned char *)dev_alloc(g->cap_cell);
    }
    grid_view v = g->view;
    unsigned *key = g->key, *idx = g->idx;
    prof_begin(g->st);
    each(g, n, [=] __device__(size_t i) {
        int c[3];
        grid_cell_coords(&v, p.x[0], p.x[1], p.x[2], i, c);
        key[i] = (unsigned)grid_cell_index(&v, c[0], c[1], c[2]);
        idx[i] = (unsigned)i;
    });
    int bits = 1;
    while (bits < 32 && ((size_t)1 << bits) < g->ncell) ++bits;
    cub::DoubleBuffer<unsigned> kb(g->key, g->key2), vb(g->idx, g->idx2);
    size_t bytes = 0;
    CK(cub::DeviceRadixSort::SortPairs(NULL, bytes, kb, vb, (int64_t)n, 0, bits, g->st));
    CK(cub::DeviceRadixSort::SortPairs(scratch(g, bytes), bytes, kb, vb, (int64_t)n, 0, bits, g->st));
    const unsigned *sk = kb.Current(), *perm = vb.Current();
    size_t *start = g->start, *end = g->end;
    CK(cudaMemsetAsync(start, 0, g->ncell * sizeof(size_t), g->st));
    CK(cudaMemsetAsync(end, 0, g->ncell * sizeof(size_t), g->st));
    each(g, n, [=] __device__(size_t k) {
        unsigned c = sk[k];
        if (k == 0 || sk[k - 1] != c) start[c] = k;
        if (k == n - 1 || sk[k + 1] != c) end[c] = k + 1;
    });
    prof_end(g->st, P_SORT);
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
        g->nl = (unsigned *)dev_alloc(n * g->nl_cap * sizeof(unsigned));
    }
    for (int d = 0; d < dim; ++d)
        CK(cudaMemcpyAsync(g->xb[d], q.x[d], n * sizeof(real), cudaMemcpyDeviceToDevice, g->st));
    unsigned *nl = g->nl, cap = g->nl_cap;
    prof_end(g->st, P_LIST);
    g->view.nl = nl;
    g->view.ncnt = cnt;
    g->view.nl_stride = n;
    g->view.nl_cap = cap;
}

/* HCSR classification (bound.c on the CPU): cell types, then the two sweeps. */
static void gpu_classify(gpu_t *g, const sph_ctx *kc)
{
    particles_t p = g->d;
    grid_view v = g->view;
    sph_ctx k = *kc;
    size_t *mat = g->cell_mat;
    unsigned char *type = g->cell_type, *cls = g->cls;
    bound_sums *sums = g->sums;
    prof_begin(g->st);
    each(g, g->ncell, [=] __device__(size_t c) {
        mat[c] = bound_cell_material(&v, &p, c);
    });
    for (int pass = 0; pass < 2; ++pass)
        each(g, g->ncell, [=] __device__(size_t c) { type[c] = bound_cell_type(&v, type, mat, c, pass); });
    each(g, g->n, [=] __device__(size_t i) {
        p.bclass[i] = (uint8_t)bound_class_first(i, &p, &v, &k, type, &sums[i]);
    });
    each(g, g->n, [=] __device__(size_t i) {
        particles_t q = p;
        cls[i] = (unsigned char)bound_class_second(i, &q, &v, &k, type, &sums[i]);
    });
    CK(cudaMemcpyAsync(p.bclass, cls, g->n, cudaMemcpyDeviceToDevice, g->st));
    prof_end(g->st, P_CLASSIFY);
}

static void gpu_walls(gpu_t *g, const flow_ctx *fc)
{
    particles_t p = g->d;
    grid_view v = g->view;
    flow_ctx c = *fc;
    prof_begin(g->st);
    each(g, g->n, [=] __device__(size_t i) {
        particles_t q = p;
        if (q.kind[i] == KIND_DUMMY) flow_wall(i, &q, &v, &c);
    });
    prof_end(g->st, P_WALLS);
}

/* ---- the hooks ----------------------------------------------------------- */

static void gpu_prepare(sim_t *s, double t, int classify)
{
    gpu_t *g = gpu_get(s);
    particles_t p = g->d;
    prof_begin(g->st);
    const int flow = s->flow_on;
    wall_geom w = s->flow.w;
    kin_params kin = s->kin;
    each(g, g->n, [=] __device__(size_t i) { step_place(i, &p, flow, &w, &kin, t); });
    prof_end(g->st, P_MOTION);
    int exact = classify == 2 || (s->hcsr && classify);
    if (!g->built || g->stale || g->every || exact) {
        real skin = exact ? R(0.0) : g->skin, sup = R(2.0) * s->seg.k.h + skin;
        gpu_build(g, s->p.dim, sup, exact ? s->seg.k.support2 : sup * sup);
        g->built = 1;
        g->stale = exact; /* a list without skin is stale as soon as anything moves */
    }
    if ((s->hcsr && classify) || classify == 2) gpu_classify(g, &s->seg.k);
    if (s->seg_on && classify && s->seg.scheme == SEG_SCHEME_CONSERVATIVE && s->seg.renorm) {
        particles_t q = g->d;
        grid_view v = g->view;
        seg_ctx c = s->seg;
        prof_begin(g->st);
        each(g, g->n, [=] __device__(size_t i) {
            if (q.kind[i] == KIND_MATERIAL) seg_renorm(i, &q, &v, &c);
        });
        prof_end(g->st, P_RENORM);
    }
    if (s->flow_on) gpu_walls(g, &s->flow);
}

static void gpu_rates(sim_t *s)
{
    gpu_t *g = gpu_get(s);
    particles_t p = g->d;
    grid_view v = g->view;
    if (s->flow_on) {
        flow_ctx c = s->flow;
        real *amag = g->amag;
        prof_begin(g->st);
        each(g, g->n, [=] __device__(size_t i) {
            particles_t q = p;
            amag[i] = q.kind[i] == KIND_MATERIAL ? flow_rates(i, &q, &v, &c) : R(0.0);
        });
        /* the largest |acc| goes to dres[STEP_ACC] as a real, widened on read */
        reduce(g, g->amag, (real *)(g->dres + STEP_ACC), g->n, max_real(), R(0.0));
        prof_end(g->st, P_FLOW);
    }
    if (s->seg_on) {
        seg_ctx c = s->seg;
        prof_begin(g->st);
        each(g, g->n, [=] __device__(size_t i) {
            if (p.kind[i] == KIND_MATERIAL) seg_coeffs(i, &p, &c);
        });
        each(g, g->n, [=] __device__(size_t i) { seg_dCdt(i, &p, &v, &c); });
        prof_end(g->st, P_SEG);
    }
}

static void gpu_save_start(sim_t *s)
{
    gpu_t *g = gpu_get(s);
    particles_t p = g->d;
    const int flow = s->flow_on;
    prof_begin(g->st);
    each(g, g->n, [=] __device__(size_t i) { step_save(i, &p, flow); });
    prof_end(g->st, P_SAVE_ADVANCE);
}

static void gpu_advance(sim_t *s, double a)
{
    gpu_t *g = gpu_get(s);
    particles_t p = g->d;
    flow_ctx c = s->flow;
    const int flow = s->flow_on, seg = s->seg_on;
    const real ar = (real)a;
    prof_begin(g->st);
    each(g, g->n, [=] __device__(size_t i) {
        particles_t q = p;
        step_advance(i, &q, ar, &c, flow, seg);
    });
    prof_end(g->st, P_SAVE_ADVANCE);
}

static void gpu_filter(sim_t *s)
{
    gpu_t *g = gpu_get(s);
    particles_t p = g->d;
    grid_view v = g->view;
    flow_ctx c = s->flow;
    prof_begin(g->st);
    each(g, g->n, [=] __device__(size_t i) {
        particles_t q = p;
        if (q.kind[i] == KIND_MATERIAL) flow_shepard(i, &q, &v, &c);
    });
    each(g, g->n, [=] __device__(size_t i) { flow_shepard_store(i, &p); });
    prof_end(g->st, P_FILTER);
    gpu_walls(g, &s->flow);
}

static void gpu_bounds(sim_t *s, double out[STEP_NBOUNDS])
{
    gpu_t *g = gpu_get(s);
    bnd3 init = {{0, 0, 0}};
    prof_begin(g->st);
    auto it = thrust::make_transform_iterator(thrust::counting_iterator<size_t>(0), bnd_of{g->d, s->step_c});
    reduce(g, it, (bnd3 *)g->dres, g->n, bnd_max(), init);
    CK(cudaMemcpyAsync(g->hres, g->dres, STEP_NBOUNDS * sizeof(double), cudaMemcpyDeviceToHost, g->st));
    CK(cudaStreamSynchronize(g->st));
    prof_end(g->st, P_BOUNDS_CHECK);
    for (int k = 0; k < 3; ++k) out[k] = g->hres[k];
    real acc;
    memcpy(&acc, g->hres + STEP_ACC, sizeof acc);
    out[STEP_ACC] = s->flow_on ? (double)acc : 0.0;
}

static long gpu_check(sim_t *s)
{
    gpu_t *g = gpu_get(s);
    prof_begin(g->st);
    auto it = thrust::make_transform_iterator(thrust::counting_iterator<size_t>(0),
                                              chk_of{g->d, s->step_c, s->t, g->xb[0], g->xb[1], g->xb[2]});
    chk init = {(long long)g->n, 0, 0};
    reduce(g, it, g->dchk, g->n, chk_merge(), init);
    CK(cudaMemcpyAsync(g->hchk, g->dchk, sizeof(chk), cudaMemcpyDeviceToHost, g->st));
    CK(cudaStreamSynchronize(g->st));
    prof_end(g->st, P_BOUNDS_CHECK);
    double D = sqrt((double)g->hchk->build2), d = sqrt((double)g->hchk->step2), skin = g->skin;
    g->stale |= D + 2 * d > 0.5 * skin;
    g->every = !s->flow_on || d > 0.25 * skin; /* prescribed motion: x_n is not kept */
    return g->hchk->first >= (long long)g->n ? -1 : (long)g->hchk->first;
}

static void gpu_to_host(sim_t *s)
{
    gpu_t *g = gpu_get(s);
    CK(cudaStreamSynchronize(g->st));
    for (size_t k = 0; k < part_narrays(); ++k)
        CK(cudaMemcpy(part_array_get(&s->p, k), part_array_get(&g->d, k), g->n * part_array_esize(k),
                      cudaMemcpyDeviceToHost));
}

static void gpu_finish(sim_t *s)
{
    gpu_t *g = (gpu_t *)s->be_data;
    if (!g) return;
    CK(cudaStreamSynchronize(g->st));
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
    for (size_t k = 0; k < part_narrays(); ++k) {
        CK(cudaFree(part_array_get(&g->d, k)));
        CK(cudaFree(part_array_get(&g->alt, k)));
    }
    void *bufs[] = {g->start, g->end, g->cell_mat, g->cell_type, g->key, g->key2, g->idx, g->idx2,
                    g->cls, g->sums, g->nl, g->ncnt, g->amag, g->tmp, g->dbox, g->dres, g->dfirst,
                    g->dchk, g->xb[0], g->xb[1], g->xb[2]};
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
    static const struct backend b = {"gpu",      gpu_prepare, gpu_rates, gpu_advance, gpu_save_start,
                                      gpu_filter, gpu_bounds,  gpu_check, gpu_to_host, gpu_finish};
    g_local_rank = local_rank;
    return &b;
}
