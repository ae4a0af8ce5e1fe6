/* gpu/gpu_dem.cu — the DEM grains on the device (issue 58): the
 * stage ST_DEM_COUPLE (the hook dem_couple, gpu_step.cu gpu_dem_hook) and the
 * hook dem_advance of struct backend (src/sim/sim.h) as the CPU's
 * src/dem/dem.c runs them, each loop a kernel calling the same bodies
 * (src/dem/dem_body.h) through a dem_view of device arrays; the scalars
 * (parameters, periods, the grid's extent) are the host's dem_t's.
 *
 * A device mirror of dem_t (gpu_dem) is made at the first hook (after
 * setup) and uploaded then; a scene without grains has none and launches
 * nothing. On several ranks every rank's device holds every grain, as the
 * CPU's ranks do (src/dem/dem.h). The fluid particles a grain's sums take
 * are the device store's owned ones, [0, g->n), as the CPU's are [0, p.n);
 * their positions are taken in the period
 * (dem_fluid_at: the device store wraps them only at list builds). The
 * coupling's cell grid: the bounding box of what it bins (a CUB min/max
 * reduction, read back: the host fits the grid as the CPU does,
 * dem_grid_fit), cell keys, a stable CUB radix sort of (key, index), so
 * that each cell lists its points in ascending index order as the CPU's
 * counting sort does, and each cell's start by a binary search of the
 * sorted keys. A coupling runs after the fluid's rates and before the
 * held-back advance (gpu_step_kernel) that reads the acc and dsig it adds
 * to. The sums over all grains (the exchanged momentum, a rigid body's
 * force, torque and inertia) are one block's, in a fixed tree: the same
 * bits run to run, the CPU's to round-off (its sums run in index order).
 * A grain's contact list that overflows is flagged (the lowest grain) and
 * reported once per fluid step, with the CPU's message. */
#include <cub/device/device_radix_sort.cuh>
#include "gpu_reduce.cuh"
extern "C" {
#include "dem/dem_body.h"
}

enum { DEM_RB = 128 }; /* threads of the one-block sums */

struct dbox {
    double lo[3], hi[3];
};

struct gpu_dem {
    double *x[3], *v[3], *w[3], *fint[3], *fd[3], *uf[3], *eps, *snorm;
    int64_t *id, *cid, *cid2;
    double *cxi, *cxi2;
    int *ncon, *ncon2;
    double *eps_f, *deps_f;
    size_t eps_cap;
    unsigned *key, *key2; /* the grid's sort: keys, and the points' indices before it */
    size_t *vin, kcap;
    size_t *gidx, *fidx, fcap;
    size_t *gstart, *fstart, gcell_cap, fcell_cap;
    double *F, *T, *Fi; /* [3 n] a DEM step's forces, torques, interaction forces */
    double *gsum;       /* [5 n] several ranks: the grains' partial sums over the fluid (dem_grain_partial) */
    double *exch;       /* [3] the exchanged momentum, N s, up to the last fold (gpu_dem_download) */
    double *xg;         /* [3 n] each grain's share of it since that fold: sum over DEM steps of F_int dt */
    dbox *box_d, *box_h; /* [2] the grains' and the fluid's boxes */
    unsigned long long *dbad, *hbad; /* the lowest grain whose contact list overflowed (n: none) */
};

struct dbox_grain {
    double *x0, *x1, *x2;
    __device__ dbox operator()(size_t i) const
    {
        return dbox{{x0[i], x1[i], x2[i]}, {x0[i], x1[i], x2[i]}};
    }
};
struct dbox_fluid { /* the material particles' positions as the CPU's dem_grid takes them */
    particles_t p;
    __device__ dbox operator()(size_t i) const
    {
        if (!dem_fluid(&p, i)) return dbox{{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
        double x0 = p.x[0][i], x1 = p.x[1][i], x2 = p.x[2][i];
        return dbox{{x0, x1, x2}, {x0, x1, x2}};
    }
};
struct dbox_merge {
    __device__ dbox operator()(const dbox &a, const dbox &b) const
    {
        dbox c;
        for (int q = 0; q < 3; ++q) c.lo[q] = fmin(a.lo[q], b.lo[q]), c.hi[q] = fmax(a.hi[q], b.hi[q]);
        return c;
    }
};

template <class T> static T *dalloc(size_t n) { return (T *)dev_alloc((n ? n : 1) * sizeof(T)); }
template <class T> static void up(T *dst, const T *src, size_t n, cudaStream_t st)
{
    CK(cudaMemcpyAsync(dst, src, n * sizeof(T), cudaMemcpyHostToDevice, st));
}
template <class T> static void down(T *dst, const T *src, size_t n, cudaStream_t st)
{
    CK(cudaMemcpyAsync(dst, src, n * sizeof(T), cudaMemcpyDeviceToHost, st));
}

/* The device mirror of s->dem, made and uploaded at the first call. */
static gpu_dem *gd_get(sim_t *s, gpu_t *g)
{
    if (g->dem) return g->dem;
    const dem_t *d = s->dem;
    const size_t n = d->n, nl = n * DEM_CMAX;
    gpu_dem *e = (gpu_dem *)calloc(1, sizeof *e);
    if (!e) error_exit(1, "out of memory");
    double *const *hv[6] = {d->x, d->v, d->w, d->fint, d->fd, d->uf};
    double **dv[6] = {e->x, e->v, e->w, e->fint, e->fd, e->uf};
    for (int k = 0; k < 6; ++k)
        for (int a = 0; a < 3; ++a) {
            dv[k][a] = dalloc<double>(n);
            up(dv[k][a], hv[k][a], n, g->st);
        }
    e->eps = dalloc<double>(n), e->snorm = dalloc<double>(n), e->id = dalloc<int64_t>(n);
    up(e->eps, d->eps, n, g->st), up(e->snorm, d->snorm, n, g->st), up(e->id, d->id, n, g->st);
    e->ncon = dalloc<int>(n), e->ncon2 = dalloc<int>(n);
    e->cid = dalloc<int64_t>(nl), e->cid2 = dalloc<int64_t>(nl);
    e->cxi = dalloc<double>(3 * nl), e->cxi2 = dalloc<double>(3 * nl);
    up(e->ncon, d->ncon, n, g->st), up(e->ncon2, d->ncon2, n, g->st);
    up(e->cid, d->cid, nl, g->st), up(e->cid2, d->cid2, nl, g->st);
    up(e->cxi, d->cxi, 3 * nl, g->st), up(e->cxi2, d->cxi2, 3 * nl, g->st);
    e->gidx = dalloc<size_t>(n);
    e->F = dalloc<double>(3 * n), e->T = dalloc<double>(3 * n), e->Fi = dalloc<double>(3 * n);
    e->exch = dalloc<double>(3);
    up(e->exch, d->exch, 3, g->st);
    e->xg = dalloc<double>(3 * n);
    CK(cudaMemsetAsync(e->xg, 0, 3 * (n ? n : 1) * sizeof(double), g->st));
    e->box_d = dalloc<dbox>(2);
    e->dbad = dalloc<unsigned long long>(1);
    CK(cudaMallocHost((void **)&e->box_h, 2 * sizeof(dbox)));
    CK(cudaMallocHost((void **)&e->hbad, sizeof(unsigned long long)));
    CK(cudaStreamSynchronize(g->st)); /* the host arrays may change after */
    g->dem = e;
    return e;
}

/* The bodies' view: the host's scalars, the device's arrays. */
static dem_view gd_view(const dem_t *d, const gpu_dem *e)
{
    dem_view v = dem_view_scalars(d);
    DEM_VIEW_ARRAYS(v, e);
    return v;
}

/* The periods of the fluid into the host's dem_t, and the grains wrapped
 * into them (dem.c dem_period). */
static void gd_period(sim_t *s, gpu_t *g, gpu_dem *e)
{
    dem_t *d = s->dem;
    dem_period_set(d, &s->flow.w);
    if (!d->per) return;
    const dem_view v = gd_view(d, e);
    each(g, d->n, [=] __device__(size_t i) { dem_wrap_grain(&v, i); });
}

static void gd_grow(size_t **p, size_t *cap, size_t need)
{
    if (need <= *cap && *p) return;
    if (*p) CK(cudaFree(*p));
    *p = dalloc<size_t>(need);
    *cap = need;
}

/* m points binned on the grid of d: keys (fluid: ncell for a particle that
 * is not material, sorted last), the stable radix sort of (key, index)
 * into idx, and start[ncell + 1] from the sorted keys. */
static void gd_bin(gpu_t *g, gpu_dem *e, const dem_view &v, const particles_t *pf, size_t m, size_t *idx,
                   size_t **start, size_t *start_cap)
{
    const size_t ncell = (size_t)v.nc[0] * (size_t)v.nc[1] * (size_t)v.nc[2];
    gd_grow(start, start_cap, ncell + 1);
    size_t *st = *start;
    if (m > e->kcap || !e->key) {
        if (e->key) {
            CK(cudaFree(e->key));
            CK(cudaFree(e->key2));
            CK(cudaFree(e->vin));
        }
        e->key = dalloc<unsigned>(m), e->key2 = dalloc<unsigned>(m), e->vin = dalloc<size_t>(m);
        e->kcap = m;
    }
    unsigned *key = e->key, *key2 = e->key2;
    size_t *vin = e->vin;
    const int fluid = pf != NULL;
    const particles_t p = fluid ? *pf : particles_t();
    each(g, m, [=] __device__(size_t i) {
        int c[3];
        double x[3];
        if (fluid && !dem_fluid(&p, i)) {
            key[i] = (unsigned)ncell;
        } else {
            if (fluid) dem_fluid_at(&v, &p, i, x);
            else x[0] = v.x[0][i], x[1] = v.x[1][i], x[2] = v.x[2][i];
            key[i] = (unsigned)dem_cell(&v, x, c);
        }
        vin[i] = i;
    });
    int bits = 1;
    while (bits < 32 && ((size_t)1 << bits) <= ncell) ++bits;
    size_t bytes = 0;
    CK(cub::DeviceRadixSort::SortPairs(NULL, bytes, key, key2, vin, idx, (int64_t)m, 0, bits, g->st));
    CK(cub::DeviceRadixSort::SortPairs(scratch(g, bytes), bytes, key, key2, vin, idx, (int64_t)m, 0, bits, g->st));
    each(g, ncell + 1, [=] __device__(size_t k) { /* the first sorted entry of cell k or above */
        size_t lo = 0, hi = m;
        while (lo < hi) {
            size_t mid = lo + (hi - lo) / 2;
            if ((size_t)key2[mid] < k) lo = mid + 1;
            else hi = mid;
        }
        st[k] = lo;
    });
}

/* The coupling's grid (dem.c dem_grid): its extent from the grains and, with
 * fluid, the owned material particles (read back), then both binned. */
static void gd_grid(sim_t *s, gpu_t *g, gpu_dem *e, int fluid)
{
    dem_t *d = s->dem;
    prof_begin(g->st);
    const dbox init = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    auto ig = thrust::make_transform_iterator(thrust::counting_iterator<size_t>(0), dbox_grain{e->x[0], e->x[1], e->x[2]});
    reduce(g, ig, e->box_d, d->n, dbox_merge(), init);
    if (fluid) {
        auto ifl = thrust::make_transform_iterator(thrust::counting_iterator<size_t>(0), dbox_fluid{g->d});
        reduce(g, ifl, e->box_d + 1, g->n, dbox_merge(), init);
    }
    down(e->box_h, e->box_d, fluid ? 2 : 1, g->st);
    CK(cudaStreamSynchronize(g->st));
    double lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
        lo[a] = e->box_h[0].lo[a], hi[a] = e->box_h[0].hi[a];
        if (fluid) lo[a] = fmin(lo[a], e->box_h[1].lo[a]), hi[a] = fmax(hi[a], e->box_h[1].hi[a]);
    }
    dem_grid_fit(d, lo, hi);
    const dem_view v = gd_view(d, e);
    gd_bin(g, e, v, NULL, d->n, e->gidx, &e->gstart, &e->gcell_cap);
    if (fluid) {
        gd_grow(&e->fidx, &e->fcap, g->n);
        const particles_t p = g->d;
        gd_bin(g, e, v, &p, g->n, e->fidx, &e->fstart, &e->fcell_cap);
    }
    prof_end(g->st, P_DEM_GRID);
}

/* The coupling at the fluid's state of its last rates (dem.c dem_couple):
 * the stage ST_DEM_COUPLE. The fraction (and two ways the volume phi / eps)
 * at every fluid particle of the store, owned and ghosts (the source's pair
 * term walks the flow pass's neighbours, g->view), the grains' sums over
 * the owned ones, then the forces and the source. On several ranks each
 * grain's sums are partial: read back, added over the ranks in rank order
 * as the CPU's (comm_sum_rows_ordered), sent back, so that every rank's
 * replicated grains take the same forces. */
void gpu_dem_couple(sim_t *s, double t)
{
    (void)t;
    gpu_t *g = gpu_hook(s, 1); /* the fluid's rates are in place; save and advance are not yet held */
    dem_t *d = s->dem;
    gpu_dem *e = gd_get(s, g);
    gd_period(s, g, e);
    const int two = d->coupling == DEM_TWO_WAY;
    const size_t nall = g->n + g->ng;
    if (nall > e->eps_cap || !e->eps_f) {
        if (e->eps_f) {
            CK(cudaFree(e->eps_f));
            CK(cudaFree(e->deps_f));
        }
        e->eps_f = dalloc<double>(nall), e->deps_f = dalloc<double>(nall);
        CK(cudaMemsetAsync(e->eps_f, 0, (nall ? nall : 1) * sizeof(double), g->st));
        CK(cudaMemsetAsync(e->deps_f, 0, (nall ? nall : 1) * sizeof(double), g->st));
        e->eps_cap = nall;
    }
    d->nown = g->n; /* a grain's sums take the owned fluid particles */
    gd_grid(s, g, e, 1);
    prof_begin(g->st);
    const dem_view v = gd_view(d, e);
    const particles_t p = g->d;
    const wall_geom w = s->flow.w;
    const grid_view gv = g->view;
    const double vn = (double)s->flow.visc_norm;
    each(g, nall, [=] __device__(size_t a) {
        if (!dem_fluid(&p, a)) return;
        dem_fluid_fraction(&v, &p, &w, a);
        if (two) dem_fluid_volume(&v, &p, a);
    });
    if (!s->halo || comm_size() == 1) {
        each(g, d->n, [=] __device__(size_t i) { dem_grain_couple(&v, &p, i); });
    } else {
        const size_t n = d->n;
        if (!e->gsum) e->gsum = dalloc<double>(5 * n);
        double *gs = e->gsum;
        each(g, n, [=] __device__(size_t i) { dem_grain_partial(&v, &p, i, &gs[5 * i]); });
        down(d->gsum, gs, 5 * n, g->st);
        CK(cudaStreamSynchronize(g->st));
        comm_sum_rows_ordered(d->gsum, n, 5);
        up(gs, d->gsum, 5 * n, g->st);
        each(g, n, [=] __device__(size_t i) {
            dem_grain_from_sums(&v, i, &gs[5 * i]);
            dem_grain_force(&v, i);
        });
    }
    if (d->coupling == DEM_TWO_WAY)
        each(g, g->n, [=] __device__(size_t a) {
            if (dem_fluid(&p, a)) dem_fluid_source(&v, &p, &gv, a, vn);
        });
    prof_end(g->st, P_DEM_COUPLE);
}

/* Sums of K values over the block's threads in a fixed tree; every thread
 * gets the totals in a[]. */
template <class T, int K> __device__ void block_sum(T (*sh)[K], T a[K])
{
    const int t = threadIdx.x;
    for (int k = 0; k < K; ++k) sh[t][k] = a[k];
    __syncthreads();
    for (int h = DEM_RB / 2; h > 0; h >>= 1) {
        if (t < h)
            for (int k = 0; k < K; ++k) sh[t][k] += sh[t + h][k];
        __syncthreads();
    }
    for (int k = 0; k < K; ++k) a[k] = sh[0][k];
    __syncthreads();
}

/* The momentum the fluid gave the grains, sum_i x_i dt, added to exch (one
 * block, a fixed tree). The DEM steps add each grain's F_int dt to its own
 * x_i (gd_substep); the fold runs when the host reads exch: a sum over the
 * grains at every DEM step, as the CPU takes it (dem.c dem_substep), would be
 * a one-block pass a DEM step (docs/dem.md, "Rate"). So the GPU sums over
 * the steps first, the CPU over the grains: the same total to round-off. */
__global__ void __launch_bounds__(DEM_RB) k_dem_exch(size_t n, const double *Fi, double dt, double *exch)
{
    __shared__ double sh[DEM_RB][3];
    double a[3] = {0, 0, 0};
    for (size_t i = threadIdx.x; i < n; i += DEM_RB)
        for (int q = 0; q < 3; ++q) a[q] += Fi[3 * i + q] * dt;
    block_sum<double, 3>(sh, a);
    if (threadIdx.x == 0)
        for (int q = 0; q < 3; ++q) exch[q] += a[q];
}

/* DEM:motion rigid, one DEM step (dem.c dem_rigid_step; one block): the
 * centre and mean velocity, the body's force, torque and inertia from each
 * grain's share (dem_rigid_share), its spin, then each grain moved
 * (dem_rigid_move). */
__global__ void __launch_bounds__(DEM_RB) k_dem_rigid(dem_view v, const double *F, const double *T, double dt)
{
    __shared__ double shc[DEM_RB][6];
    __shared__ real shs[DEM_RB][15];
    const size_t n = v.n;
    const double M = v.m * (double)n;
    double c[6] = {0, 0, 0, 0, 0, 0};
    for (size_t i = threadIdx.x; i < n; i += DEM_RB)
        for (int q = 0; q < 3; ++q) c[q] += v.x[q][i] / (double)n, c[3 + q] += v.v[q][i] / (double)n;
    block_sum<double, 6>(shc, c);
    const double xc[3] = {c[0], c[1], c[2]};
    double vc[3] = {c[3], c[4], c[5]};
    real w[3];
    for (int q = 0; q < 3; ++q) w[q] = (real)(n ? v.w[q][0] : 0);
    real a[15];
    for (int k = 0; k < 15; ++k) a[k] = 0;
    for (size_t i = threadIdx.x; i < n; i += DEM_RB) dem_rigid_share(&v, i, xc, &F[3 * i], &T[3 * i], a, a + 3, a + 6);
    block_sum<real, 15>(shs, a); /* after it, no thread reads another's grain: the moves may write */
    for (int q = 0; q < 3; ++q) vc[q] += (double)a[3 + q] / M * dt;
    if (!v.per) dem_spin_update(a + 6, a, (real)dt, w);
    for (size_t i = threadIdx.x; i < n; i += DEM_RB) dem_rigid_move(&v, i, xc, vc, w, dt);
}

/* One DEM step of length dt from t (dem.c dem_substep). */
static void gd_substep(sim_t *s, gpu_t *g, gpu_dem *e, double t, double dt)
{
    dem_t *d = s->dem;
    int64_t *oc = e->cid; /* last step's lists: the history; this step's go to the spare lists */
    double *ox = e->cxi;
    int *on = e->ncon;
    e->cid = e->cid2, e->cxi = e->cxi2, e->ncon = e->ncon2;
    e->cid2 = oc, e->cxi2 = ox, e->ncon2 = on;
    gd_period(s, g, e); /* a grain that crossed a period comes in from the other side */
    if (d->motion != DEM_RIGID) gd_grid(s, g, e, 0);
    prof_begin(g->st);
    const dem_view v = gd_view(d, e);
    const wall_geom w = s->flow.w;
    double *F = e->F, *T = e->T, *Fi = e->Fi;
    double *xg = e->xg;
    unsigned long long *bad = e->dbad;
    each(g, d->n, [=] __device__(size_t i) {
        if (dem_forces(&v, &w, i, t, dt, &F[3 * i], &T[3 * i], &Fi[3 * i])) atomicMin(bad, (unsigned long long)i);
        for (int q = 0; q < 3; ++q) xg[3 * i + q] += Fi[3 * i + q] * dt;
    });
    if (d->motion == DEM_RIGID) {
        k_dem_rigid<<<1, DEM_RB, 0, g->st>>>(v, F, T, dt);
        CK(cudaGetLastError());
    } else if (d->motion != DEM_FIXED) {
        each(g, d->n, [=] __device__(size_t i) { dem_move_free(&v, i, &F[3 * i], &T[3 * i], dt); });
    }
    prof_end(g->st, P_DEM_STEP);
}

/* The grains from t over the fluid step dt (dem.c dem_advance). */
void gpu_dem_advance(sim_t *s, double t, double dt)
{
    gpu_t *g = gpu_hook(s, 0); /* the grains only: the fluid is not read */
    dem_t *d = s->dem;
    gpu_dem *e = gd_get(s, g);
    *e->hbad = (unsigned long long)d->n;
    up(e->dbad, e->hbad, 1, g->st);
    gd_period(s, g, e);
    const long m = dem_substeps(d, dt);
    d->steps += m;
    const double h = dt / (double)m;
    for (long k = 0; k < m; ++k) gd_substep(s, g, e, t + (double)k * h, h);
    gd_period(s, g, e);
    down(e->hbad, e->dbad, 1, g->st);
    CK(cudaStreamSynchronize(g->st));
    if (*e->hbad < (unsigned long long)d->n) dem_overflow_exit((size_t)*e->hbad);
}

/* The host's grains up to date (to_host: output, diagnostics). */
void gpu_dem_download(sim_t *s, gpu_t *g)
{
    gpu_dem *e = g->dem;
    if (!e) return; /* no hook has run: the host's are the grains */
    dem_t *d = s->dem;
    const size_t n = d->n, nl = n * DEM_CMAX;
    double *const *hv[6] = {d->x, d->v, d->w, d->fint, d->fd, d->uf};
    double *const *dv[6] = {e->x, e->v, e->w, e->fint, e->fd, e->uf};
    for (int k = 0; k < 6; ++k)
        for (int a = 0; a < 3; ++a) down(hv[k][a], dv[k][a], n, g->st);
    down(d->eps, e->eps, n, g->st), down(d->snorm, e->snorm, n, g->st);
    down(d->ncon, e->ncon, n, g->st), down(d->cid, e->cid, nl, g->st), down(d->cxi, e->cxi, 3 * nl, g->st);
    k_dem_exch<<<1, DEM_RB, 0, g->st>>>(n, e->xg, 1.0, e->exch); /* the fold */
    CK(cudaGetLastError());
    CK(cudaMemsetAsync(e->xg, 0, 3 * (n ? n : 1) * sizeof(double), g->st));
    down(d->exch, e->exch, 3, g->st);
    CK(cudaStreamSynchronize(g->st));
}

void gpu_dem_free(gpu_t *g)
{
    gpu_dem *e = g->dem;
    if (!e) return;
    for (int a = 0; a < 3; ++a) {
        void *b[6] = {e->x[a], e->v[a], e->w[a], e->fint[a], e->fd[a], e->uf[a]};
        for (int k = 0; k < 6; ++k) CK(cudaFree(b[k]));
    }
    void *bufs[] = {e->eps, e->snorm, e->id, e->cid, e->cid2, e->cxi, e->cxi2, e->ncon, e->ncon2, e->eps_f,
                    e->deps_f, e->key, e->key2, e->vin, e->gidx, e->fidx, e->gstart, e->fstart, e->F, e->T,
                    e->Fi, e->gsum, e->exch, e->xg, e->box_d, e->dbad};
    for (size_t k = 0; k < sizeof bufs / sizeof bufs[0]; ++k)
        if (bufs[k]) CK(cudaFree(bufs[k]));
    CK(cudaFreeHost(e->box_h));
    CK(cudaFreeHost(e->hbad));
    free(e);
    g->dem = NULL;
}
