/* gpu/gpu_pairs.cu — the neighbour pass's pair loops: every kernel that walks
 * the neighbour lists (gpu_nbr.cu builds them), a team of threads per
 * particle (team, gpu_launch.cuh) around a shared body of src/physics/: the
 * HCSR classification, the dummy walls and the renormalisation L, the flow
 * rates (with the concentration coefficients), dC/dt, the particle shift,
 * the Shepard sums, a window's L. The hooks (gpu_step.cu) choose which and
 * when. */
#include "gpu.cuh"

/* The view with its form F (grid.h: list, list16, cells) known to the
 * compiler, so that a kernel carries the walk of its form alone (the three
 * walks in one kernel cost the list's kernels 10-24 more registers): each
 * launcher below is a template on F, and by_form launches the build's. */
template <int F> __device__ __forceinline__ grid_view view_as(grid_view v)
{
    v.form = F;
    v.tiled = 0, v.tile = NULL, v.tp = NULL; /* k_flow_tile sets its own */
    if (F != GRID_NBR_LIST) v.nl = NULL;
    if (F != GRID_NBR_LIST16) v.nl16 = NULL;
    return v;
}

#define BY_FORM(g, fn, args)                                                                 \
    switch ((g)->view.form) {                                                                \
    case GRID_NBR_LIST16: fn<GRID_NBR_LIST16> args; break;                                   \
    case GRID_NBR_CELLS: fn<GRID_NBR_CELLS> args; break;                                     \
    default: fn<GRID_NBR_LIST> args; break;                                                  \
    }

/* HCSR classification (bound.c on the CPU): cell types, then the two sweeps,
 * over owned particles and ghosts. */
template <int F> static void gpu_classify_f(gpu_t *g, const sph_ctx *kc)
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
    /* Two kernels per case, not one choosing &sums[i] or a local inside the
     * lambda: so written, the list form's first sweep (nvcc 13.0, sm_90)
     * left sums[] unwritten, and the paper scheme's classes, normals and psi~
     * came out wrong (psi~ NaN) under the list alone (list16 and cells right). */
    if (sums) { /* the sums kept between the sweeps (the HCSR schemes: every step) */
        each(g, n, [=] __device__(size_t i) {
            const grid_view w = view_as<F>(v);
            p.bclass[i] = (uint8_t)bound_class_first(i, &p, &w, &k, type, &sums[i]);
        });
        each(g, n, [=] __device__(size_t i) {
            particles_t q = p;
            const grid_view w = view_as<F>(v);
            cls[i] = (unsigned char)bound_class_second(i, &q, &w, &k, type, &sums[i]);
        });
    } else { /* none kept: the second sweep gathers them again (the same loop over x, vol, kind) */
        each(g, n, [=] __device__(size_t i) {
            const grid_view w = view_as<F>(v);
            bound_sums s;
            p.bclass[i] = (uint8_t)bound_class_first(i, &p, &w, &k, type, &s);
        });
        each(g, n, [=] __device__(size_t i) {
            particles_t q = p;
            const grid_view w = view_as<F>(v);
            const bound_sums s = bound_gather(i, &q, &w, &k);
            cls[i] = (unsigned char)bound_class_second(i, &q, &w, &k, type, &s);
        });
    }
    CK(cudaMemcpyAsync(p.bclass, cls, n, cudaMemcpyDeviceToDevice, g->st));
    prof_end(g->st, P_CLASSIFY);
}

void gpu_classify(gpu_t *g, const sph_ctx *kc) { BY_FORM(g, gpu_classify_f, (g, kc)) }

/* Over owned particles and ghosts in sl: the dummy walls (paper §4.1;
 * walls), the conservative scheme's L of the material (renorm) and the
 * corrected gradient's B (kgc). None reads what another writes: a small
 * store (several threads per particle, latency-bound) runs them as one
 * kernel (the walls and L with 2 or more threads a particle; B with them at
 * 4 or more: the 2D drums, docs/performance.md "Small stores"), a large one
 * apart (the merged kernel would run at the larger register count: 2 %
 * slower on the 3D drum, docs/gpu.md). SPHSEG_GPU_PROFILE keeps B apart, on
 * its own line. */
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

template <int F> static void gpu_walls_renorm_f(sim_t *s, gpu_t *g, int walls, int renorm, int kgc, sel sl)
{
    particles_t p = g->d;
    grid_view v = g->view;
    flow_ctx c = s->flow;
    seg_ctx sc = s->seg;
    const size_t n = g->n + g->ng;
    const size_t rlo = s->renorm_due ? g->n : 0; /* the owned L due in the flow rates: the ghosts' here */
    const uint8_t *wa = g->wact;
    if (rlo >= n) renorm = 0;
    if (!walls && !renorm && !kgc) return;
    prof_begin(g->st);
    if (kgc && g->team >= 4 && !prof.on) { /* a small store: B, the walls and L in one kernel (below) */
        team(g, n, [=] __device__(size_t i, int lane, int T) {
            if (!sel_on(sl, i)) return;
            particles_t q = p;
            const grid_view w = view_as<F>(v);
            if (q.kind[i] == KIND_DUMMY) {
                if (walls) wall_one(i, &q, &w, &c, wa, lane, T);
            } else if (q.kind[i] == KIND_MATERIAL) {
                flow_kgc_team(i, &q, &w, &c, lane, T);
                if (renorm && i >= rlo) seg_renorm_team(i, &q, &w, &sc, lane, T);
            }
        });
        prof_end(g->st, P_WALLS);
        return;
    }
    if (kgc) { /* ST_KGC: B of the material, owned and ghosts (reads positions only) */
        team(g, n, [=] __device__(size_t i, int lane, int T) {
            const grid_view w = view_as<F>(v);
            if (p.kind[i] == KIND_MATERIAL && sel_on(sl, i)) flow_kgc_team(i, &p, &w, &c, lane, T);
        });
        prof_end(g->st, P_KGC);
        prof_begin(g->st);
    }
    if (walls && renorm && g->team > 1) {
        team(g, n, [=] __device__(size_t i, int lane, int T) {
            if (!sel_on(sl, i)) return;
            particles_t q = p;
            const grid_view w = view_as<F>(v);
            if (q.kind[i] == KIND_DUMMY) wall_one(i, &q, &w, &c, wa, lane, T);
            else if (q.kind[i] == KIND_MATERIAL && i >= rlo) seg_renorm_team(i, &q, &w, &sc, lane, T);
        });
    } else {
        if (walls)
            team(g, n, [=] __device__(size_t i, int lane, int T) {
                particles_t q = p;
                const grid_view w = view_as<F>(v);
                if (q.kind[i] == KIND_DUMMY && sel_on(sl, i)) wall_one(i, &q, &w, &c, wa, lane, T);
            });
        if (renorm) /* particles rlo.. only: with the owned L due later, just the ghosts */
            team(g, n - rlo, [=] __device__(size_t k, int lane, int T) {
                const size_t i = rlo + k;
                const grid_view w = view_as<F>(v);
                if (p.kind[i] == KIND_MATERIAL && sel_on(sl, i)) seg_renorm_team(i, &p, &w, &sc, lane, T);
            });
    }
    prof_end(g->st, P_WALLS);
}

void gpu_walls_renorm(sim_t *s, gpu_t *g, int walls, int renorm, int kgc, sel sl)
{
    BY_FORM(g, gpu_walls_renorm_f, (s, g, walls, renorm, kgc, sl))
}

/* The flow rates of the owned particles in sl, and with segregation their
 * concentration coefficients (seg_coeffs reads only i's C and the shear
 * rate just computed). */
template <int RENORM, int KGC, int SHIFT, int F, int SPEC = FLOW_SPEC_ANY>
static void gpu_flow_pass(sim_t *s, gpu_t *g, sel sl)
{
    particles_t p = g->d;
    grid_view v = g->view;
    flow_ctx c = s->flow;
    shift_ctx sh = s->shift;
    const dscal sdt = gpu_scalar(g, &s->dt, SHIFT); /* the step's dt (gpu.cuh) */
    seg_ctx sc = s->seg;
    const int seg = gpu_plans(s, HOOK_RATES, ST_SEG_COEFFS); /* not in windows: at their close */
    real *amag = g->amag;
    const real *bq = g->bq;
    /* the fused pass's bounds (gpu_launch.cuh); _T2 in the list form without the owned L alone
     * (list16 and cells spill 80 and 96 bytes there, the owned L's case 152: not kept, or unmeasured) */
    constexpr int MB = SHIFT ? SPHSEG_FUSED_MINB : SPHSEG_TEAM_MINB;
    constexpr int MB2 = SHIFT && F == GRID_NBR_LIST && !RENORM ? SPHSEG_FUSED_MINB_T2 : MB;
    team<MB, MB2>(g, g->n, [=] __device__(size_t i, int lane, int T) {
        if (!sel_on(sl, i)) return;
        particles_t q = p;
        const int mat = q.kind[i] == KIND_MATERIAL;
        const grid_view w = view_as<F>(v);
        real a = mat ? flow_rates_body(i, &q, &w, &c, lane, T, RENORM, KGC, SHIFT ? &sh : (const shift_ctx *)0,
                                       SHIFT ? (real)sdt.at(0) : R(0.0), bq, SPEC)
                     : R(0.0);
        if (lane != 0) return;
        amag[i] = a;
        if (seg && mat) seg_coeffs(i, &q, &sc);
    });
}

/* The staged flow pass (SPHSEG_GPU_NBR=tile; docs/performance.md, "Neighbour
 * pass"): a block per cell of the build, 32 teams of T threads. The block
 * first copies what the flow rates read of a neighbour (x, u, sigma, V,
 * kind; B with the corrected gradient) for the 3^d cells around its cell
 * into shared memory, in the order of grid_tile (each cell's owned run, then
 * its ghost run), once for all the cell's particles; each team then walks
 * its particle's 16-bit list and reads neighbour j at its tile slot
 * (NBR_BEGIN_TJ): a lane meets the list16's neighbours in its order with
 * the same values, and so gives the same bits. Each build finds the largest
 * tile (gpu_tile_need); where it exceeds the shared memory, that build's
 * passes run as list16's (counted in tile_over_passes). */
struct flow_tile_args {
    particles_t p;
    grid_view v;
    flow_ctx c;
    shift_ctx sh;
    seg_ctx sc;
    real sdt;
    int seg;
    sel sl;
    real *amag;
    unsigned cap;
};

/* The arrays a tile stages, in shared memory: x, u (3 each), sigma (6), V,
 * and B (6) with the corrected gradient; then kind, a byte each. */
template <int KGC> __host__ __device__ constexpr int tile_nreal() { return 13 + (KGC ? 6 : 0); }
template <int KGC> static size_t tile_bytes(unsigned cap)
{
    return (size_t)cap * (tile_nreal<KGC>() * sizeof(real) + 1);
}

template <int T, int RENORM, int KGC, int SHIFT>
__global__ void __launch_bounds__(32 * T, 512 / (32 * T)) k_flow_tile(const __grid_constant__ flow_tile_args A)
{
    extern __shared__ __align__(16) unsigned char tile_sm[];
    __shared__ grid_tile tb;
    __shared__ unsigned ngs[27];
    const size_t cell = blockIdx.x;
    const size_t a0 = A.v.start[cell], n0 = A.v.end[cell] - a0;
    if (n0 == 0) return;
    const int tid = (int)threadIdx.x;
    const particles_t p = A.p;
    int any = 0; /* a material particle of the pass here: else the block has nothing to stage */
    for (size_t k = (size_t)tid; k < n0; k += blockDim.x) {
        const size_t i = a0 + k;
        if (!sel_on(A.sl, i)) continue;
        if (p.kind[i] == KIND_MATERIAL) any = 1;
        else A.amag[i] = R(0.0);
    }
    if (!__syncthreads_or(any)) return;
    const grid_view &v = A.v;
    const size_t nxy = (size_t)v.nc[0] * (size_t)v.nc[1];
    const int c0[3] = {(int)(cell % (size_t)v.nc[0]), (int)((cell / (size_t)v.nc[0]) % (size_t)v.nc[1]),
                       (int)(cell / nxy)};
    const int ns = v.dim == 3 ? 27 : 9;
    if (tid < ns) ngs[tid] = grid_tile_slot(&v, c0, tid, &tb);
    __syncthreads();
    if (tid == 0) grid_tile_bases(&tb, ngs, v.dim);
    __syncthreads();
    const unsigned cap = A.cap, tot = tb.base[ns]; /* tot <= cap: gpu_tile_need */
    real *sr = (real *)tile_sm;
    particles_t tp = p; /* the tile's arrays in place of the store's */
    for (int d = 0; d < 3; ++d) tp.x[d] = sr + d * cap, tp.v[d] = sr + (3 + d) * cap;
    for (int q = 0; q < 6; ++q) tp.sig[q] = sr + (6 + q) * cap;
    tp.vol = sr + 12 * cap;
    if (KGC)
        for (int q = 0; q < 6; ++q) tp.B[q] = sr + (13 + q) * cap;
    tp.kind = (uint8_t *)(sr + tile_nreal<KGC>() * cap);
    for (unsigned k = (unsigned)tid; k < tot; k += blockDim.x) {
        const size_t j = grid_tile_at(&tb, k, v.dim);
        for (int d = 0; d < 3; ++d) tp.x[d][k] = p.x[d][j], tp.v[d][k] = p.v[d][j];
        for (int q = 0; q < 6; ++q) tp.sig[q][k] = p.sig[q][j];
        tp.vol[k] = p.vol[j];
        if (KGC)
            for (int q = 0; q < 6; ++q) tp.B[q][k] = p.B[q][j];
        tp.kind[k] = p.kind[j];
    }
    __syncthreads();
    /* every particle's list is read (the list is as wide as its longest,
     * gpu_list), as a view with a tile requires */
    grid_view wt = view_as<GRID_NBR_LIST16>(v);
    wt.tiled = 1, wt.tile = &tb, wt.tp = &tp;
    const flow_ctx c = A.c;
    const shift_ctx sh = A.sh;
    const int lane = tid % T;
    for (size_t k0 = 0; k0 < n0; k0 += 32) {
        const size_t i = a0 + k0 + (size_t)(tid / T);
        if (i >= a0 + n0 || !sel_on(A.sl, i)) continue;
        particles_t q = p;
        if (q.kind[i] != KIND_MATERIAL) continue;
        const real a = flow_rates_body(i, &q, &wt, &c, lane, T, RENORM, KGC, SHIFT ? &sh : (const shift_ctx *)0, A.sdt,
                                       (const real *)0, FLOW_SPEC_ANY);
        if (lane != 0) continue;
        A.amag[i] = a;
        if (A.seg) seg_coeffs(i, &q, &A.sc);
    }
}

/* A tile's capacity at most: the shared memory of an SM (228 kB on sm_90,
 * less 1 kB a block) for one block; the blocks an SM runs at once follow
 * from the build's largest tile (gpu_flow_tile sizes it). */
template <int KGC> static unsigned tile_cap()
{
    const size_t per = 227u * 1024u - 1024u - sizeof(grid_tile) - 256u;
    const size_t cap = per / (tile_nreal<KGC>() * sizeof(real) + 1);
    return (unsigned)(cap & ~(size_t)15);
}

template <int T, int RENORM, int KGC, int SHIFT> static void flow_tile_launch(gpu_t *g, const flow_tile_args &A)
{
    static int set; /* the dynamic shared memory past 48 kB, once per kernel */
    const size_t bytes = tile_bytes<KGC>(A.cap);
    if (!set) {
        CK(cudaFuncSetAttribute(k_flow_tile<T, RENORM, KGC, SHIFT>, cudaFuncAttributeMaxDynamicSharedMemorySize,
                                (int)tile_bytes<KGC>(tile_cap<KGC>())));
        set = 1;
    }
    k_flow_tile<T, RENORM, KGC, SHIFT><<<(unsigned)g->ncell, 32 * T, bytes, g->st>>>(A);
    CK(cudaGetLastError());
}

/* At a list build (gpu_list): the largest tile of the build's cells that
 * hold particles, into g->tile_need (one read-back). */
void gpu_tile_need(gpu_t *g)
{
    const grid_view v = g->view;
    unsigned *dmax = g->tile_dmax;
    CK(cudaMemsetAsync(dmax, 0, sizeof *dmax, g->st));
    each(g, g->ncell, [=] __device__(size_t cell) {
        if (v.end[cell] == v.start[cell]) return;
        const size_t nxy = (size_t)v.nc[0] * (size_t)v.nc[1];
        const int c0[3] = {(int)(cell % (size_t)v.nc[0]), (int)((cell / (size_t)v.nc[0]) % (size_t)v.nc[1]),
                           (int)(cell / nxy)};
        grid_tile t;
        unsigned tot = 0;
        for (int k = 0; k < (v.dim == 3 ? 27 : 9); ++k) {
            const unsigned ng = grid_tile_slot(&v, c0, k, &t);
            tot += ng + t.na[k];
        }
        atomicMax(dmax, tot);
    });
    CK(cudaMemcpyAsync(&g->tile_need, dmax, sizeof *dmax, cudaMemcpyDeviceToHost, g->st));
    CK(cudaStreamSynchronize(g->st));
}

template <int RENORM, int KGC, int SHIFT> static void gpu_flow_tile(sim_t *s, gpu_t *g, sel sl)
{
    if (g->tile_need > tile_cap<KGC>()) { /* the build's largest tile past the shared memory */
        g->tile_over_passes++;
        return gpu_flow_pass<RENORM, KGC, SHIFT, GRID_NBR_LIST16>(s, g, sl);
    }
    flow_tile_args A;
    A.p = g->d, A.v = g->view, A.c = s->flow, A.sh = s->shift, A.sc = s->seg;
    A.sdt = (real)s->dt;
    A.seg = gpu_plans(s, HOOK_RATES, ST_SEG_COEFFS);
    A.sl = sl, A.amag = g->amag;
    A.cap = (g->tile_need + 31u) & ~31u;
    g->tile_passes++;
    switch (g->team) {
    case 1: flow_tile_launch<1, RENORM, KGC, SHIFT>(g, A); break;
    case 2: flow_tile_launch<2, RENORM, KGC, SHIFT>(g, A); break;
    case 4: flow_tile_launch<4, RENORM, KGC, SHIFT>(g, A); break;
    case 8: flow_tile_launch<8, RENORM, KGC, SHIFT>(g, A); break;
    default: flow_tile_launch<16, RENORM, KGC, SHIFT>(g, A); break;
    }
}

template <int RENORM, int KGC, int SHIFT, int SPEC = FLOW_SPEC_ANY> static void gpu_flow_form(sim_t *s, gpu_t *g, sel sl)
{
    if (g->tile && g->view.form == GRID_NBR_LIST16) return gpu_flow_tile<RENORM, KGC, SHIFT>(s, g, sl);
    switch (g->view.form) {
    case GRID_NBR_LIST16: gpu_flow_pass<RENORM, KGC, SHIFT, GRID_NBR_LIST16, SPEC>(s, g, sl); break;
    case GRID_NBR_CELLS: gpu_flow_pass<RENORM, KGC, SHIFT, GRID_NBR_CELLS>(s, g, sl); break; /* not specialised */
    default: gpu_flow_pass<RENORM, KGC, SHIFT, GRID_NBR_LIST, SPEC>(s, g, sl); break;
    }
}

/* The flow pass's spec (flow.h flow_spec_of): FLOW_SPEC_RIEMANN, the drum
 * scenes' flow with its switches as constants, where the run's flow allows
 * it and SPHSEG_GPU_SPEC is not 0 (guide.md, "Tuning and diagnostics
 * settings": the general kernel, the same bits, for comparing): 1.07x on
 * the 1.1e7 3D drum (docs/gpu.md, "The flow pass's code"). Specialised are
 * the kernels that pass runs under the scenes' settings alone: the corrected
 * gradient, no owned L (concentration windows), the list forms (cells and
 * the staged tile keep the general kernel): 4 kernels more, not 12 (the
 * unit's compile 124 s against 117 s before, 146 s with 12: kernel_frames on
 * the development machine). */
static int gpu_flow_spec(const sim_t *s)
{
    return tuning_get()->gpu_spec == 0 ? FLOW_SPEC_ANY : flow_spec_of(&s->flow);
}

/* (and the owned particles' L when prepare left them due: a kernel of its
 * own, so that the other passes keep the smaller register count; the
 * corrected gradient and the fused shift (sim.h shift_due) likewise) */
template <int SHIFT> static void gpu_flow_kgc(sim_t *s, gpu_t *g, sel sl)
{
    const int kgc = s->flow.kgc; /* its own kernels: the others keep their register count */
    if (kgc && !s->renorm_due && gpu_flow_spec(s) == FLOW_SPEC_RIEMANN) /* the drum scenes' flow */
        gpu_flow_form<0, 1, SHIFT, FLOW_SPEC_RIEMANN>(s, g, sl);
    else if (s->renorm_due) kgc ? gpu_flow_form<1, 1, SHIFT>(s, g, sl) : gpu_flow_form<1, 0, SHIFT>(s, g, sl);
    else kgc ? gpu_flow_form<0, 1, SHIFT>(s, g, sl) : gpu_flow_form<0, 0, SHIFT>(s, g, sl);
}

/* Flow:bed_damping: the weight flow_bed_q of each particle, once a particle
 * rather than once a pair (its static cone's q costs a pair a square root
 * and two divisions), into g->bq for the list forms' flow pass to read at
 * the neighbour's index (the CPU's bq; the same bits as per pair). It lives
 * in the permutation's spare of a real's size (gpu_permute), which holds
 * nothing between builds. The particles whose stress is current: all, or
 * with the ghosts' refresh in flight (sel_in, levels 3) the owned, then at
 * the boundary pass (sel_bd) the ghosts just received. The staged pass
 * (tile) indexes its neighbours by tile slot and computes q per pair. A
 * store of fewer than GPU_BEDQ_MIN_3D (2D: _2D) particles, owned and
 * ghosts, computes it per pair too: there the kernel costs more than it
 * saves (SPHSEG_GPU_BEDQ=0|1 sets either way; docs/performance.md, "The flow
 * pass's code"). */
static void gpu_bed_q(sim_t *s, gpu_t *g, sel sl)
{
    g->bq = NULL;
    if (!(s->flow.bed_alpha > 0) || (g->tile && g->view.form == GRID_NBR_LIST16)) return;
    const int want = tuning_get()->gpu_bedq;
    const double least = s->flow.k.dim == 3 ? GPU_BEDQ_MIN_3D : GPU_BEDQ_MIN_2D;
    if (want == 0 || (want < 0 && (double)(g->n + g->ng) < least)) return;
    real *bq = (real *)g->pscr[pscr_slot(sizeof(real))];
    const size_t lo = sl.lvl && sl.hi < 3 ? g->n : 0, hi = sl.lvl && sl.hi == 3 ? g->n : g->n + g->ng;
    particles_t p = g->d;
    flow_ctx c = s->flow;
    if (hi > lo)
        each(g, hi - lo, [=] __device__(size_t k) {
            particles_t q = p;
            bq[lo + k] = flow_bed_q(lo + k, &q, &c);
        });
    g->bq = bq;
}

void gpu_flow_rates(sim_t *s, gpu_t *g, sel sl)
{
    prof_begin(g->st);
    gpu_bed_q(s, g, sl);
    if (s->shift_due) gpu_flow_kgc<1>(s, g, sl);
    else gpu_flow_kgc<0>(s, g, sl);
    g->acc_pending = 1;
    prof_end(g->st, P_FLOW);
}

template <int F> static void gpu_dcdt_f(sim_t *s, gpu_t *g, particles_t p, sel sl)
{
    grid_view v = g->view;
    seg_ctx c = s->seg;
    team(g, g->n, [=] __device__(size_t i, int lane, int T) {
        const grid_view w = view_as<F>(v);
        if (sel_on(sl, i)) seg_dCdt_team(i, &p, &w, &c, lane, T);
    });
}

void gpu_dcdt(sim_t *s, gpu_t *g, particles_t p, sel sl) { BY_FORM(g, gpu_dcdt_f, (s, g, p, sl)) }

/* ST_SHIFT: the shift of every material particle, with its Taylor steps into
 * the saved copies (shift_team). */
template <int F> static void gpu_shift_f(sim_t *s, gpu_t *g)
{
    particles_t p = g->d;
    grid_view v = g->view;
    shift_ctx c = s->shift;
    const dscal dt = gpu_scalar(g, &s->dt, 1); /* (gpu.cuh) */
    team(g, g->n, [=] __device__(size_t i, int lane, int T) {
        particles_t q = p;
        const grid_view w = view_as<F>(v);
        if (q.kind[i] == KIND_MATERIAL) shift_team(i, &q, &w, &c, (real)dt.at(0), lane, T);
    });
}

void gpu_shift_pass(sim_t *s, gpu_t *g) { BY_FORM(g, gpu_shift_f, (s, g)) }

/* ST_CONTACT: the Coulomb walls' friction on the owned material particles
 * (Walls:coulomb_force particles; flow_contact_team), after the flow pass. */
template <int F> static void gpu_contact_f(sim_t *s, gpu_t *g)
{
    particles_t p = g->d;
    grid_view v = g->view;
    flow_ctx c = s->flow;
    const dscal dt = gpu_scalar(g, &s->dt, 1); /* (gpu.cuh) */
    team(g, g->n, [=] __device__(size_t i, int lane, int T) {
        particles_t q = p;
        const grid_view w = view_as<F>(v);
        if (q.kind[i] == KIND_MATERIAL) flow_contact_team(i, &q, &w, &c, (real)dt.at(0), lane, T);
    });
}

void gpu_contact_pass(sim_t *s, gpu_t *g) { BY_FORM(g, gpu_contact_f, (s, g)) }

/* ST_SHEPARD: the Shepard sums of every material particle (stored by
 * ST_SHEPARD_STORE, gpu_filter). */
template <int F> static void gpu_shepard_f(sim_t *s, gpu_t *g)
{
    particles_t p = g->d;
    grid_view v = g->view;
    flow_ctx c = s->flow;
    team(g, g->n, [=] __device__(size_t i, int lane, int T) {
        particles_t q = p;
        const grid_view w = view_as<F>(v);
        if (q.kind[i] == KIND_MATERIAL) flow_shepard_team(i, &q, &w, &c, lane, T);
    });
}

void gpu_shepard_pass(sim_t *s, gpu_t *g) { BY_FORM(g, gpu_shepard_f, (s, g)) }

/* ST_WIN_RENORM: L of every material particle, owned and ghost, at a
 * concentration window's end. */
template <int F> static void gpu_win_renorm_f(sim_t *s, gpu_t *g)
{
    particles_t p = g->d;
    grid_view v = g->view;
    seg_ctx sc = s->seg;
    team(g, g->n + g->ng, [=] __device__(size_t i, int lane, int T) {
        const grid_view w = view_as<F>(v);
        if (p.kind[i] == KIND_MATERIAL) seg_renorm_team(i, &p, &w, &sc, lane, T);
    });
}

void gpu_win_renorm(sim_t *s, gpu_t *g) { BY_FORM(g, gpu_win_renorm_f, (s, g)) }
