/* gpu/gpu_setup.cu — set-up: device selection, device allocation and the CUB
 * scratch, the store's allocation and growth (gpu_reserve), host-device
 * copies, the team size rule, gpu_get (the backend's state, created on
 * first use), gpu_hook, and the reductions' step_ctx on the device. */
#include "gpu.cuh"

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

static size_t mem_before, mem_peak; /* gpu_mem_use */

/* Device memory in use now (the device's total less its free). */
static size_t mem_in_use(void)
{
    size_t fr = 0, tot = 0;
    CK(cudaMemGetInfo(&fr, &tot));
    return tot - fr;
}

void gpu_mem_use(size_t *before, size_t *peak)
{
    *before = mem_before;
    *peak = mem_peak;
}

void *dev_alloc(size_t bytes)
{
    void *p = NULL;
    if (!mem_before) mem_before = mem_peak = mem_in_use();
    cudaError_t e = cudaMalloc(&p, bytes ? bytes : 1);
    if (e != cudaSuccess)
        error_exit(1, "GPU out of memory: %zu bytes (%s); use fewer particles per GPU (a larger Geometry:dr "
                   "or more ranks)", bytes, cudaGetErrorString(e));
    size_t u = mem_in_use();
    if (u > mem_peak) mem_peak = u;
    return p;
}

/* Grow the CUB scratch to at least bytes. */
void *scratch(gpu_t *g, size_t bytes)
{
    if (bytes > g->tmp_bytes) {
        if (g->tmp) CK(cudaFree(g->tmp));
        g->tmp = dev_alloc(bytes);
        g->tmp_bytes = bytes;
    }
    return g->tmp;
}

/* Per-particle device arrays for at least need particles: those the host
 * store holds (its fields; the others stay NULL) and the permutation's
 * spares. The first keep particles of the store are kept (the device
 * exchange grows the store under its owned particles), array by array, so
 * that one array at a time is held twice; with keep 0 nothing is (callers
 * upload after). The work arrays (keys, lists, levels) are never kept: a
 * build follows. */
void gpu_reserve(gpu_t *g, size_t need, size_t keep)
{
    if (need <= g->cap && g->key) return;
    size_t cap = g->key ? need + need / 8 + 1024 : need; /* one rank: exactly n, as before */
    if (cap >= 0xffffffffu) error_exit(1, "backend_gpu: %zu particles on one rank: more than 2^32 - 1", cap);
    size_t na = part_narrays();
    int slot_used[PSCR_N] = {0, 0, 0};
    for (size_t k = 0; k < na; ++k) {
        if (!(g->d.fields >> part_array_field(k) & 1)) continue; /* not this run's: NULL */
        size_t es = part_array_esize(k);
        slot_used[pscr_slot(es)] = 1;
        void *old = g->key ? part_array_get(&g->d, k) : NULL, *q = dev_alloc(cap * es);
        if (old && keep) {
            CK(cudaMemcpyAsync(q, old, keep * es, cudaMemcpyDeviceToDevice, g->st));
            CK(cudaStreamSynchronize(g->st)); /* the copy done before the old array goes */
        }
        if (old) CK(cudaFree(old));
        part_array_set(&g->d, k, q);
    }
    static const size_t slot_es[PSCR_N] = {8, 4, 1};
    for (int c = 0; c < PSCR_N; ++c) {
        if (g->pscr[c]) CK(cudaFree(g->pscr[c]));
        g->pscr[c] = slot_used[c] ? dev_alloc(cap * slot_es[c]) : NULL;
    }
    if (g->key) {
        void *bufs[] = {g->key, g->key2, g->idx, g->idx2, g->cls, g->sums, g->nl, g->ncnt, g->amag,
                        g->xb[0], g->xb[1], g->xb[2], g->lvl, g->wact};
        for (size_t k = 0; k < sizeof bufs / sizeof bufs[0]; ++k)
            if (bufs[k]) CK(cudaFree(bufs[k]));
    }
    g->key = (unsigned *)dev_alloc(cap * sizeof(unsigned));
    g->key2 = (unsigned *)dev_alloc(cap * sizeof(unsigned));
    g->idx = (unsigned *)dev_alloc(cap * sizeof(unsigned));
    g->idx2 = (unsigned *)dev_alloc(cap * sizeof(unsigned));
    g->cls = (unsigned char *)dev_alloc(cap);
    g->sums = g->hcsr ? (bound_sums *)dev_alloc(cap * sizeof(bound_sums)) : NULL;
    for (int d = 0; d < 3; ++d) {
        g->xb[d] = (real *)dev_alloc(cap * sizeof(real));
        CK(cudaMemset(g->xb[d], 0, cap * sizeof(real)));
    }
    g->nl = gpu_nl_esize(g) && g->nl_cap ? (unsigned *)dev_alloc(cap * g->nl_cap * gpu_nl_esize(g)) : NULL;
    g->ncnt = (unsigned *)dev_alloc(cap * sizeof(unsigned));
    g->amag = (real *)dev_alloc(cap * sizeof(real));
    CK(cudaMemset(g->amag, 0, cap * sizeof(real)));
    g->lvl = g->hx ? (uint8_t *)dev_alloc(cap) : NULL;
    g->wact = g->wskip ? (uint8_t *)dev_alloc(cap) : NULL;
    g->cap = cap;
    g->d.cap = cap;
    g->built = 0;
}

/* Host arrays [a, b) of every particle array to the device. */
void gpu_upload(gpu_t *g, const particles_t *h, size_t a, size_t b)
{
    for (size_t k = 0; k < part_narrays(); ++k) {
        size_t es = part_array_esize(k);
        if (!part_array_get(h, k)) continue; /* not this run's */
        CK(cudaMemcpyAsync((char *)part_array_get(&g->d, k) + a * es, (const char *)part_array_get(h, k) + a * es,
                           (b - a) * es, cudaMemcpyHostToDevice, g->st));
    }
    CK(cudaStreamSynchronize(g->st));
}

/* The counts in the device structs (kernels read p.n, p.ng). */
void gpu_counts(gpu_t *g, size_t n, size_t ng)
{
    g->n = n, g->ng = ng;
    g->d.n = n;
    g->d.ng = ng;
    g->d.cap = g->cap;
}

/* Threads per particle in the neighbour loops: SPHSEG_GPU_TEAM (1, 2, 4, 8
 * or 16; core/tuning.h), else GPU_TEAM_MAX of the dimension (by the length of the list:
 * 4 in 2D, about 30 neighbours; 8 in 3D, about 140), halved while n T
 * exceeds GPU_TEAM_THREADS, n the particles of all ranks (gpu_get): a small store runs more threads per particle
 * (latency), a large one fills the device with fewer; in 3D never fewer than
 * GPU_TEAM_MIN_3D: two lanes read a particle's list in pairs of adjacent
 * entries, 1.06-1.09x one lane's rate from 1.1e6 to 3.4e7 particles at
 * Run:preset fast (one H200, single; docs/gpu.md, "GPU kernels"). */
static int gpu_team_size(int dim, size_t n)
{
    const tuning *tu = tuning_get();
    if (tu->gpu_team < 0)
        error_exit(2, "SPHSEG_GPU_TEAM=%s: expected 1, 2, 4, 8 or 16 threads per particle", tu->gpu_team_text);
    if (tu->gpu_team > 0) return tu->gpu_team;
    int t = dim == 3 ? GPU_TEAM_MAX_3D : GPU_TEAM_MAX_2D;
    const int tmin = dim == 3 ? GPU_TEAM_MIN_3D : 1;
    while (t > tmin && (double)n * t > GPU_TEAM_THREADS) t /= 2;
    return t;
}

/* Bytes a particle of the permutation's spares for the arrays p holds. */
size_t gpu_spare_bytes(const particles_t *p)
{
    int used[PSCR_N] = {0, 0, 0};
    for (size_t k = 0; k < part_narrays(); ++k)
        if (part_array_get(p, k)) used[pscr_slot(part_array_esize(k))] = 1;
    return 8 * (size_t)used[PSCR_8] + 4 * (size_t)used[PSCR_4] + (size_t)used[PSCR_1];
}

/* The neighbour pass's form where SPHSEG_GPU_NBR names none: the 4-byte
 * list (the fastest) where the run fits the device's free memory with it,
 * else the 16-bit list (on the 1.1e7 3D drum, single, leapfrog: 0.92 of the
 * list's rate at 0.69 of its bytes a particle), else no list (cells: 0.28 of
 * the rate, 0.37 of the bytes; docs/gpu.md "Neighbour pass"). All three
 * meet a particle's neighbours in the same order: the same bits. The room
 * left: 10 % of the free memory and 15 % of the particles for growth; the
 * list's width as grid_list_est expects it; GPU_SCRATCH_EST bytes a particle
 * for the keys, counts and sums (52 B measured, single). Ranks sharing a
 * device each see it as at their start. */
#define GPU_SCRATCH_EST 96.0
static int gpu_form_fits(const gpu_t *g, const particles_t *h, size_t n)
{
    size_t fr = 0, tot = 0;
    CK(cudaMemGetInfo(&fr, &tot));
    const double base = (double)(part_store_bytes(h) + gpu_spare_bytes(h)) + GPU_SCRATCH_EST;
    const double room = 0.9 * (double)fr / (1.15 * (double)n + 1024.0);
    if (base + 4.0 * g->nl_est <= room) return GRID_NBR_LIST;
    if (base + 2.0 * g->nl_est <= room) return GRID_NBR_LIST16;
    return GRID_NBR_CELLS;
}

gpu_t *gpu_get(sim_t *s)
{
    if (s->be_data) return (gpu_t *)s->be_data;
    gpu_t *g = (gpu_t *)calloc(1, sizeof *g);
    if (!g) error_exit(1, "out of memory");
    g->step0 = s->step;
    int ndev = gpu_devices();
    g->dev = g_local_rank % (ndev > 0 ? ndev : 1);
    CK(cudaSetDevice(g->dev));
    CK(cudaStreamCreateWithFlags(&g->st, cudaStreamNonBlocking));
    prof.on = tuning_get()->gpu_profile;
    g->wskip = tuning_get()->gpu_wallskip;
    g->hcsr = s->hcsr;
    if (prof.on) {
        CK(cudaEventCreate(&prof.a));
        CK(cudaEventCreate(&prof.b));
    }
    cudaDeviceProp prop;
    CK(cudaGetDeviceProperties(&prop, g->dev));
    const particles_t *h = &s->p;
    size_t n = h->n;
    const double skin = s->sc->run.list_skin; /* Run:list_skin, in units of h */
    g->nbr_form = tuning_get()->gpu_nbr;
    if (g->nbr_form < 0)
        error_exit(2, "SPHSEG_GPU_NBR=%s: expected list, list16, cells or tile", tuning_get()->gpu_nbr_text);
    if (g->nbr_form == 4) g->tile = 1, g->nbr_form = GRID_NBR_LIST16; /* the list16, its flow pass staged */
    if (g->tile) CK(cudaMalloc(&g->tile_dmax, sizeof *g->tile_dmax));
    g->nl_est = grid_list_est(h->dim, (1 + 0.5 * skin) * (double)(s->seg.k.h / s->seg.k.dr));
    g->nl_cap = 0; /* the list is sized at the first build, from the counts (gpu_list) */
    if (!tuning_get()->gpu_nbr_text) g->nbr_form = gpu_form_fits(g, h, n);
    if (s->halo) {
        g->hx = (dhalo *)calloc(1, sizeof *g->hx);
        if (!g->hx) error_exit(1, "out of memory");
        g->hx->cuda_aware = halo_cuda_aware();
        g->hx->overlap = tuning_get()->gpu_overlap;
        g->hx->dev = !tuning_get()->gpu_hostx;
        s->halo->exposed_measured = 1;
        for (int k = 0; k < HX_EV; ++k) CK(cudaEventCreate(&g->hx->ev[k]));
    }
    /* the team from the particles of all ranks: the lanes' partial sums, and so
     * the bits, depend on the team size, which must not follow the rank count */
    g->team = gpu_team_size(h->dim, (size_t)comm_sum_ll((long long)n));
    message("gpu: device %d of %d, %s, %.1f GiB; %zu MiB of particle arrays (the run's fields and the "
            "permutation's spares), about %zu MiB of neighbour list (SPHSEG_GPU_NBR %s: %u per particle of %zu "
            "bytes estimated, sized at the first build; skin %.3g h%s), %d threads per particle in neighbour loops%s%s", g->dev, ndev, prop.name,
            (double)prop.totalGlobalMem / (1u << 30), n * (part_store_bytes(h) + gpu_spare_bytes(h)) >> 20,
            (n * g->nl_est * gpu_nl_esize(g)) >> 20,
            g->tile ? "tile" : g->nbr_form == GRID_NBR_LIST16 ? "list16" : g->nbr_form == GRID_NBR_CELLS ? "cells" : "list", g->nl_est,
            gpu_nl_esize(g), skin, tuning_get()->gpu_nbr_text ? "" : "; the fastest form that fits", g->team,
            !g->hx                  ? ""
            : g->hx->cuda_aware     ? "; halo: packed on the device, CUDA-aware MPI on device buffers"
                                    : "; halo: packed on the device, staged through pinned host memory",
            !g->hx ? "" : g->hx->dev ? "; list-build exchanges on the device" : "; list-build exchanges through the host (SPHSEG_GPU_HOSTX)");
    g->d = *h; /* its counts and fields; gpu_reserve puts device arrays in place of the host's */
    for (size_t k = 0; k < part_narrays(); ++k) part_array_set(&g->d, k, NULL);
    gpu_reserve(g, n, 0);
    gpu_counts(g, n, 0);
    gpu_upload(g, h, 0, n);
    g->skin = (real)(skin * s->seg.k.h);
    g->every = !s->flow_on; /* prescribed motion moves up to h a stage: from the first step on */
    g->dbox = (box *)dev_alloc(sizeof(box));
    g->dres = (double *)dev_alloc(STEP_NBOUNDS * sizeof(double));
    CK(cudaMemset(g->dres, 0, STEP_NBOUNDS * sizeof(double)));
    g->dfirst = (long long *)dev_alloc(sizeof(long long));
    g->dchk = (chkb *)dev_alloc(sizeof(chkb));
    g->dstep = (step_ctx *)dev_alloc(sizeof(step_ctx));
    g->hstep = (step_ctx *)malloc(sizeof(step_ctx)); /* pageable: a send is staged at once, so the copy may change after */
    if (!g->hstep) error_exit(1, "out of memory");
    memset(g->hstep, 0xff, sizeof(step_ctx)); /* differs from any context: the first use sends it */
    CK(cudaMallocHost((void **)&g->hchk, sizeof(chkb)));
    CK(cudaMallocHost((void **)&g->hbox, sizeof(box)));
    CK(cudaMallocHost((void **)&g->hres, STEP_NBOUNDS * sizeof(double)));
    CK(cudaMallocHost((void **)&g->hfirst, sizeof(long long)));
    gpu_graph_init(g);
    s->be_data = g;
    return g;
}

/* gpu_get for a hook: the held-back save and advance run first; for a hook
 * that changes the store (mut), the bounds taken by the last check no
 * longer hold. */
gpu_t *gpu_hook(sim_t *s, int mut)
{
    gpu_t *g = gpu_get(s);
    gpu_step_kernel(s, g, 0, 0.0);
    if (mut) g->bnd_fresh = 0;
    return g;
}

/* s->step_c on the device for the reductions, sent on the stream when it
 * has changed since the last send (in practice once). */
const step_ctx *gpu_step_ctx(sim_t *s, gpu_t *g)
{
    if (memcmp(g->hstep, &s->step_c, sizeof(step_ctx))) {
        memcpy(g->hstep, &s->step_c, sizeof(step_ctx));
        CK(cudaMemcpyAsync(g->dstep, g->hstep, sizeof(step_ctx), cudaMemcpyHostToDevice, g->st));
    }
    return g->dstep;
}
