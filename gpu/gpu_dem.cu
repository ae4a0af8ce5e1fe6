/* gpu/gpu_dem.cu — the DEM grains on the device (issue 58): the
 * stage ST_DEM_COUPLE (the hook dem_couple, gpu_step.cu gpu_dem_hook) and the
 * hook dem_advance of struct backend (src/sim/sim.h) as the CPU's
 * src/dem/dem.c runs them, each loop a kernel calling the same bodies
 * (src/dem/dem_body.h) through a dem_view of device arrays; the scalars
 * (parameters, periods, the grid's extent) are the host's dem_t's.
 *
 * A device mirror of dem_t (gpu_dem) is made at the first hook (after
 * setup) and uploaded then; a scene without grains has none and launches
 * nothing. On several ranks the grains are divided as the CPU's are
 * (src/dem/dem_halo.c): each device holds its rank's grains at [0, no) and
 * ghosts at [no, n). The exchange, the ghosts' refresh at each DEM step and
 * the sums over the ranks run on the host between read-backs of the owned
 * grains' few arrays (gd_exchange, gd_refresh, gd_rigid_split); every loop
 * over grains or fluid runs on the device. The fluid particles a grain's sums take
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

/* Device arrays whose rows a kernel packs or unpacks (a refresh's: dem_refresh's order). */
struct drows {
    double *a[11];
};

struct gpu_dem {
    double *x[3], *v[3], *w[3], *fint[3], *fd[3], *uf[3], *eps, *snorm;
    double *x0[3];      /* split: the owned grains' centres at the last exchange (dem_exchange_due) */
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
    size_t cap;         /* the per-grain arrays' room, grains */
    /* split: the refreshes' index lists (dem_refresh_lists; [w] for DEM_SEND_MOTION, DEM_SEND_COUPLING), made
     * at each exchange, and their rows' buffers, device and pinned host */
    size_t *sidx[2], *ridx[2], ns[2], nr[2], icap[2];
    double *dbuf, *hbuf;
    size_t bcap;
    double *dxb, *hxb;  /* split: the exchange's packed rows (centre, velocity, spin, ID), device and pinned */
    size_t xcap;
    double *exs;        /* [3 m] split: each DEM step's exchanged momentum over this rank's grains, a fluid step's */
    size_t exs_cap;
    double *rs;         /* [21] split, a rigid body: this rank's centre sums (6), then its shares (15) */
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

/* The per-grain device arrays released (gd_arrays' list). */
static void gd_arrays_free(gpu_dem *e)
{
    if (!e->cap) return;
    for (int a = 0; a < 3; ++a) {
        void *b[7] = {e->x[a], e->v[a], e->w[a], e->fint[a], e->fd[a], e->uf[a], e->x0[a]};
        for (int k = 0; k < 7; ++k) CK(cudaFree(b[k]));
    }
    void *bufs[] = {e->eps, e->snorm, e->id, e->cid, e->cid2, e->cxi, e->cxi2, e->ncon, e->ncon2,
                    e->gidx, e->F, e->T, e->Fi, e->xg, e->gsum};
    for (size_t k = 0; k < sizeof bufs / sizeof bufs[0]; ++k) CK(cudaFree(bufs[k]));
    e->cap = 0;
}

/* The per-grain device arrays for cap grains (their values not kept). */
static void gd_arrays(gpu_dem *e, size_t cap)
{
    gd_arrays_free(e);
    const size_t nl = cap * DEM_CMAX;
    double **dv[6] = {e->x, e->v, e->w, e->fint, e->fd, e->uf};
    for (int k = 0; k < 6; ++k)
        for (int a = 0; a < 3; ++a) dv[k][a] = dalloc<double>(cap);
    for (int a = 0; a < 3; ++a) e->x0[a] = dalloc<double>(cap);
    e->eps = dalloc<double>(cap), e->snorm = dalloc<double>(cap), e->id = dalloc<int64_t>(cap);
    e->ncon = dalloc<int>(cap), e->ncon2 = dalloc<int>(cap);
    e->cid = dalloc<int64_t>(nl), e->cid2 = dalloc<int64_t>(nl);
    e->cxi = dalloc<double>(3 * nl), e->cxi2 = dalloc<double>(3 * nl);
    e->gidx = dalloc<size_t>(cap);
    e->F = dalloc<double>(3 * cap), e->T = dalloc<double>(3 * cap), e->Fi = dalloc<double>(3 * cap);
    e->xg = dalloc<double>(3 * cap), e->gsum = dalloc<double>(5 * cap);
    e->cap = cap;
}

/* The host's grains [i0, i1) to the device: the state a step reads
 * (centre, velocity, spin, the coupling's results, IDs, both contact
 * lists). */
static void gd_upload(gpu_t *g, gpu_dem *e, const dem_t *d, size_t i0, size_t i1, int lists = 1)
{
    const size_t n = i1 - i0, c = DEM_CMAX;
    if (!n) return;
    double *const *hv[6] = {d->x, d->v, d->w, d->fint, d->fd, d->uf};
    double **dv[6] = {e->x, e->v, e->w, e->fint, e->fd, e->uf};
    for (int k = 0; k < 6; ++k)
        for (int a = 0; a < 3; ++a) up(dv[k][a] + i0, hv[k][a] + i0, n, g->st);
    up(e->eps + i0, d->eps + i0, n, g->st), up(e->snorm + i0, d->snorm + i0, n, g->st);
    up(e->id + i0, d->id + i0, n, g->st);
    if (!lists) return;
    up(e->ncon + i0, d->ncon + i0, n, g->st), up(e->ncon2 + i0, d->ncon2 + i0, n, g->st);
    up(e->cid + i0 * c, d->cid + i0 * c, n * c, g->st), up(e->cid2 + i0 * c, d->cid2 + i0 * c, n * c, g->st);
    up(e->cxi + 3 * i0 * c, d->cxi + 3 * i0 * c, 3 * n * c, g->st);
    up(e->cxi2 + 3 * i0 * c, d->cxi2 + 3 * i0 * c, 3 * n * c, g->st);
}

/* The device mirror of s->dem, made and uploaded at the first call. */
static gpu_dem *gd_get(sim_t *s, gpu_t *g)
{
    if (g->dem) return g->dem;
    const dem_t *d = s->dem;
    gpu_dem *e = (gpu_dem *)calloc(1, sizeof *e);
    if (!e) error_exit(1, "out of memory");
    gd_arrays(e, d->cap > d->n ? d->cap : d->n);
    gd_upload(g, e, d, 0, d->n);
    CK(cudaMemsetAsync(e->xg, 0, 3 * (e->cap ? e->cap : 1) * sizeof(double), g->st));
    e->exch = dalloc<double>(3);
    up(e->exch, d->exch, 3, g->st);
    e->rs = dalloc<double>(21);
    e->box_d = dalloc<dbox>(2);
    e->dbad = dalloc<unsigned long long>(1);
    CK(cudaMallocHost((void **)&e->box_h, 2 * sizeof(dbox)));
    CK(cudaMallocHost((void **)&e->hbad, sizeof(unsigned long long)));
    CK(cudaStreamSynchronize(g->st)); /* the host arrays may change after */
    g->dem = e;
    return e;
}

/* Split: the refreshes' index lists for the device (after an exchange). */
static void gd_lists(sim_t *s, gpu_t *g, gpu_dem *e)
{
    const dem_t *d = s->dem;
    const size_t ns_max = d->soff[d->nrank], nr_max = d->n - d->no;
    size_t *h = (size_t *)malloc((ns_max + nr_max + 2) * sizeof(size_t));
    if (!h) error_exit(1, "out of memory");
    size_t bneed = 0;
    for (int w = 0; w < 2; ++w) {
        e->ns[w] = dem_refresh_lists(d, w, h, h + ns_max, &e->nr[w]);
        const size_t need = ns_max + nr_max;
        if (need > e->icap[w] || !e->sidx[w]) {
            if (e->sidx[w]) CK(cudaFree(e->sidx[w]));
            e->sidx[w] = dalloc<size_t>(need), e->icap[w] = need;
        }
        e->ridx[w] = e->sidx[w] + ns_max;
        up(e->sidx[w], h, e->ns[w], g->st), up(e->ridx[w], h + ns_max, e->nr[w], g->st);
        CK(cudaStreamSynchronize(g->st)); /* h is reused */
        const size_t b = (e->ns[w] + e->nr[w]) * (w == DEM_SEND_MOTION ? 9 : 11);
        bneed = b > bneed ? b : bneed;
    }
    free(h);
    if (bneed > e->bcap || !e->dbuf) {
        if (e->dbuf) {
            CK(cudaFree(e->dbuf));
            CK(cudaFreeHost(e->hbuf));
        }
        e->dbuf = dalloc<double>(bneed);
        CK(cudaMallocHost((void **)&e->hbuf, (bneed ? bneed : 1) * sizeof(double)));
        e->bcap = bneed;
    }
}

/* Several ranks: the grains divided as the fluid is (src/dem/dem_halo.c),
 * the exchange on the host. The owned grains' centres, velocities and
 * spins down (the ghosts' records); when a grain changes owner on any
 * rank, the rest of the owned state too (what a migrating grain carries:
 * the coupling's results, contact lists and springs) and, after
 * dem_exchange, every held grain up; otherwise the owned grains stay as
 * they are on the device and only the new ghosts go up. */
static void gd_xroom(gpu_dem *e, size_t need)
{
    if (need <= e->xcap && e->dxb) return;
    if (e->dxb) {
        CK(cudaFree(e->dxb));
        CK(cudaFreeHost(e->hxb));
    }
    need += need / 2;
    e->dxb = dalloc<double>(need);
    CK(cudaMallocHost((void **)&e->hxb, (need ? need : 1) * sizeof(double)));
    e->xcap = need;
}

static void gd_refresh(sim_t *s, gpu_t *g, gpu_dem *e, int what);
static dem_view gd_view(const dem_t *d, const gpu_dem *e);

/* The largest squared distance an owned grain moved since the last
 * exchange (dem_max_shift's, minimum images across the periods). */
struct dshift {
    dem_view v;
    const double *y0, *y1, *y2;
    __device__ double operator()(size_t i) const
    {
        const double *const x0[3] = {y0, y1, y2};
        return dem_shift2(&v, i, x0);
    }
};
struct dmax {
    __device__ double operator()(double a, double b) const { return fmax(a, b); }
};

static void gd_exchange(sim_t *s, gpu_t *g, gpu_dem *e)
{
    dem_t *d = s->dem;
    const double t0 = now();
    int all = 1;
    if (d->split) { /* due (dem_exchange_due)? else every ghost's centre, velocity and spin refreshed */
        double m2 = 0;
        if (d->no) {
            auto it = thrust::make_transform_iterator(
                thrust::counting_iterator<size_t>(0),
                dshift{gd_view(d, e), e->x0[0], e->x0[1], e->x0[2]});
            reduce(g, it, e->rs, d->no, dmax(), 0.0);
            down(&m2, e->rs, 1, g->st);
            CK(cudaStreamSynchronize(g->st));
        }
        if (!dem_exchange_due(d, s->halo, sqrt(m2))) {
            gd_refresh(s, g, e, DEM_SEND_GHOSTS);
            d->refreshes++;
            prof_host(P_DEM_XCHG, t0);
            return;
        }
        const size_t no = d->no, nl = no * DEM_CMAX;
        double *const *hv[6] = {d->x, d->v, d->w, d->fint, d->fd, d->uf};
        double *const *dv[6] = {e->x, e->v, e->w, e->fint, e->fd, e->uf};
        /* the owned centres, velocities and spins in one read-back: 9 blocks of no */
        gd_xroom(e, 9 * no);
        drows R;
        for (int k = 0; k < 3; ++k)
            for (int a = 0; a < 3; ++a) R.a[3 * k + a] = dv[k][a];
        double *xb = e->dxb;
        if (no)
            each(g, no, [=] __device__(size_t i) {
                for (int q = 0; q < 9; ++q) xb[(size_t)q * no + i] = R.a[q][i];
            });
        down(e->hxb, xb, 9 * no, g->st);
        CK(cudaStreamSynchronize(g->st));
        for (int k = 0; k < 3; ++k)
            for (int a = 0; a < 3; ++a) memcpy(hv[k][a], e->hxb + (size_t)(3 * k + a) * no, no * sizeof(double));
        all = comm_max((double)dem_migrating(d, s->halo)) > 0;
        if (all) {
            for (int k = 3; k < 6; ++k)
                for (int a = 0; a < 3; ++a) down(hv[k][a], dv[k][a], no, g->st);
            down(d->eps, e->eps, no, g->st), down(d->snorm, e->snorm, no, g->st);
            down(d->ncon, e->ncon, no, g->st), down(d->cid, e->cid, nl, g->st), down(d->cxi, e->cxi, 3 * nl, g->st);
            CK(cudaStreamSynchronize(g->st));
        }
    }
    dem_exchange(d, s->halo);
    if (d->n > e->cap) {
        gd_arrays(e, d->cap);
        all = 1;
    }
    if (all) {
        gd_upload(g, e, d, 0, d->n);
    } else if (d->n > d->no) { /* the new ghosts in one upload: centre, velocity, spin, ID; the rest set here */
        const size_t no = d->no, ng = d->n - d->no;
        gd_xroom(e, 10 * ng);
        double *const *hv[3] = {d->x, d->v, d->w};
        for (int k = 0; k < 3; ++k)
            for (int a = 0; a < 3; ++a) memcpy(e->hxb + (size_t)(3 * k + a) * ng, hv[k][a] + no, ng * sizeof(double));
        memcpy(e->hxb + 9 * ng, d->id + no, ng * sizeof(int64_t));
        up(e->dxb, e->hxb, 10 * ng, g->st);
        drows R;
        double *const *dv[6] = {e->x, e->v, e->w, e->fint, e->fd, e->uf};
        for (int k = 0; k < 3; ++k)
            for (int a = 0; a < 3; ++a) R.a[3 * k + a] = dv[k][a];
        drows Z;
        for (int k = 0; k < 3; ++k)
            for (int a = 0; a < 3; ++a) Z.a[3 * k + a] = dv[3 + k][a];
        const double *xb = e->dxb;
        double *eps = e->eps, *snorm = e->snorm;
        int64_t *id = e->id;
        int *ncon = e->ncon, *ncon2 = e->ncon2;
        each(g, ng, [=] __device__(size_t m) {
            const size_t j = no + m;
            for (int q = 0; q < 9; ++q) R.a[q][j] = xb[(size_t)q * ng + m], Z.a[q][j] = 0;
            id[j] = ((const int64_t *)(xb + 9 * ng))[m];
            eps[j] = 1, snorm[j] = 0, ncon[j] = 0, ncon2[j] = 0;
        });
    }
    gd_lists(s, g, e);
    for (int a = 0; a < 3; ++a)
        CK(cudaMemcpyAsync(e->x0[a], e->x[a], d->no * sizeof(double), cudaMemcpyDeviceToDevice, g->st));
    if (prof.on) CK(cudaStreamSynchronize(g->st));
    prof_host(P_DEM_XCHG, t0);
}

/* Split: a refresh of the ghosts (dem_refresh's) with its rows packed and
 * unpacked on the device: the owned grains' rows gathered, read back into
 * pinned memory, dem_refresh_swap, sent up and scattered into the ghosts. */
static void gd_refresh(sim_t *s, gpu_t *g, gpu_dem *e, int what)
{
    dem_t *d = s->dem;
    const double t0 = now();
    const int cpl = what == DEM_SEND_COUPLING, k = cpl ? 11 : 9, li = what == DEM_SEND_MOTION ? 0 : 1;
    const size_t ns = e->ns[li], nr = e->nr[li];
    drows R;
    double *const *src[3] = {cpl ? e->fint : e->x, cpl ? e->fd : e->v, cpl ? e->uf : e->w};
    for (int q = 0; q < 3; ++q)
        for (int a = 0; a < 3; ++a) R.a[3 * q + a] = src[q][a];
    R.a[9] = e->eps, R.a[10] = e->snorm;
    double *db = e->dbuf, *dr = e->dbuf + ns * (size_t)k;
    const size_t *si = e->sidx[li], *ri = e->ridx[li];
    if (ns)
        each(g, ns, [=] __device__(size_t m) {
            for (int q = 0; q < k; ++q) db[m * (size_t)k + (size_t)q] = R.a[q][si[m]];
        });
    down(e->hbuf, db, ns * (size_t)k, g->st);
    CK(cudaStreamSynchronize(g->st));
    dem_refresh_swap(d, what, k, e->hbuf, e->hbuf + ns * (size_t)k);
    if (nr) {
        up(dr, e->hbuf + ns * (size_t)k, nr * (size_t)k, g->st);
        each(g, nr, [=] __device__(size_t m) {
            for (int q = 0; q < k; ++q) R.a[q][ri[m]] = dr[m * (size_t)k + (size_t)q];
        });
    }
    if (prof.on) CK(cudaStreamSynchronize(g->st));
    if (what != DEM_SEND_GHOSTS) prof_host(P_DEM_REFRESH, t0); /* a coupling's: the exchange's line */
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
 * the owned ones, then the forces and the source. On several ranks the
 * grains are divided first (gd_exchange: on the host, the CPU's
 * dem_exchange); each held grain's sums are partial: read back, added at
 * its owner in rank order (dem_sums_home), the owned rows sent back; the
 * owned grains' forces go to the ghosts (gd_refresh) before the source. */
void gpu_dem_couple(sim_t *s, double t)
{
    (void)t;
    gpu_t *g = gpu_hook(s, 1); /* the fluid's rates are in place; save and advance are not yet held */
    dem_t *d = s->dem;
    gpu_dem *e = gd_get(s, g);
    gd_period(s, g, e);
    const int split = s->halo && comm_size() > 1;
    if (split) gd_exchange(s, g, e);
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
    if (!split) {
        each(g, d->n, [=] __device__(size_t i) { dem_grain_couple(&v, &p, i); });
    } else { /* every held grain's partial sums, home to the owners, the owned grains' forces to the ghosts */
        const size_t n = d->n, no = d->no;
        double *gs = e->gsum;
        each(g, n, [=] __device__(size_t i) { dem_grain_partial(&v, &p, i, &gs[5 * i]); });
        CK(cudaStreamSynchronize(g->st));
        const double t0 = now();
        down(d->gsum, gs, 5 * n, g->st);
        CK(cudaStreamSynchronize(g->st));
        dem_sums_home(d);
        up(gs, d->gsum, 5 * no, g->st);
        if (prof.on) CK(cudaStreamSynchronize(g->st));
        prof_host(P_DEM_REFRESH, t0);
        each(g, no, [=] __device__(size_t i) {
            dem_grain_from_sums(&v, i, &gs[5 * i]);
            dem_grain_force(&v, i);
        });
        gd_refresh(s, g, e, DEM_SEND_COUPLING);
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

/* Split, a rigid body (dem.c dem_rigid_step on several ranks): this rank's
 * grains' centre and mean-velocity sums over the run's nt grains into
 * r[0..6), one block. */
__global__ void __launch_bounds__(DEM_RB) k_dem_rigid_centre(dem_view v, size_t n, double nt, double *r)
{
    __shared__ double shc[DEM_RB][6];
    double c[6] = {0, 0, 0, 0, 0, 0};
    for (size_t i = threadIdx.x; i < n; i += DEM_RB)
        for (int q = 0; q < 3; ++q) c[q] += v.x[q][i] / nt, c[3 + q] += v.v[q][i] / nt;
    block_sum<double, 6>(shc, c);
    if (threadIdx.x == 0)
        for (int k = 0; k < 6; ++k) r[k] = c[k];
}

struct dvec3 {
    double x[3];
};
struct rvec3 {
    real x[3];
};

/* ... and their shares of the body's torque, force and inertia about the
 * centre xc into r[6..21), one block. */
__global__ void __launch_bounds__(DEM_RB)
    k_dem_rigid_shares(dem_view v, size_t n, dvec3 xc, const double *F, const double *T, double *r)
{
    __shared__ real shs[DEM_RB][15];
    real a[15];
    for (int k = 0; k < 15; ++k) a[k] = 0;
    for (size_t i = threadIdx.x; i < n; i += DEM_RB)
        dem_rigid_share(&v, i, xc.x, &F[3 * i], &T[3 * i], a, a + 3, a + 6);
    block_sum<real, 15>(shs, a);
    if (threadIdx.x == 0)
        for (int k = 0; k < 15; ++k) r[6 + k] = (double)a[k];
}

/* Split, a rigid body, one DEM step: each rank's sums read back and added
 * over the ranks in rank order (dem_sum_ranks), the body's motion on the
 * host (a few numbers), each owned grain moved on the device. The spin is
 * every grain's: an owned grain's, read back. */
static void gd_rigid_split(sim_t *s, gpu_t *g, gpu_dem *e, const dem_view &v, double dt)
{
    dem_t *d = s->dem;
    const size_t no = d->no;
    const double nt = (double)d->ntot, M = d->m * nt;
    double c[21];
    k_dem_rigid_centre<<<1, DEM_RB, 0, g->st>>>(v, no, nt, e->rs);
    CK(cudaGetLastError());
    down(c, e->rs, 6, g->st);
    CK(cudaStreamSynchronize(g->st));
    dem_sum_ranks(d, c, 6);
    const dvec3 xc = {{c[0], c[1], c[2]}};
    dvec3 vc = {{c[3], c[4], c[5]}};
    k_dem_rigid_shares<<<1, DEM_RB, 0, g->st>>>(v, no, xc, e->F, e->T, e->rs);
    CK(cudaGetLastError());
    down(c + 6, e->rs + 6, 15, g->st);
    CK(cudaStreamSynchronize(g->st));
    dem_sum_ranks(d, c + 6, 15);
    real a[15];
    for (int k = 0; k < 15; ++k) a[k] = (real)c[6 + k];
    rvec3 w; /* every grain's spin: an owned grain's */
    double w0[3] = {0, 0, 0};
    for (int q = 0; q < 3 && no; ++q) down(&w0[q], e->w[q], 1, g->st);
    CK(cudaStreamSynchronize(g->st));
    for (int q = 0; q < 3; ++q) w.x[q] = (real)w0[q];
    for (int q = 0; q < 3; ++q) vc.x[q] += (double)a[3 + q] / M * dt;
    if (!d->per) dem_spin_update(a + 6, a, (real)dt, w.x);
    each(g, no, [=] __device__(size_t i) { dem_rigid_move(&v, i, xc.x, vc.x, w.x, dt); });
}

/* One DEM step of length dt from t (dem.c dem_substep). Split: the
 * ghosts' centres, velocities and spins from their owners first, and the
 * exchanged momentum summed over the ranks at each step, as the CPU's. */
static void gd_substep(sim_t *s, gpu_t *g, gpu_dem *e, double t, double dt, long k)
{
    dem_t *d = s->dem;
    int64_t *oc = e->cid; /* last step's lists: the history; this step's go to the spare lists */
    double *ox = e->cxi;
    int *on = e->ncon;
    e->cid = e->cid2, e->cxi = e->cxi2, e->ncon = e->ncon2;
    e->cid2 = oc, e->cxi2 = ox, e->ncon2 = on;
    gd_period(s, g, e); /* a grain that crossed a period comes in from the other side */
    const int split = d->split, fold = !split;
    if (split) gd_refresh(s, g, e, DEM_SEND_MOTION);
    if (d->motion != DEM_RIGID) gd_grid(s, g, e, 0);
    prof_begin(g->st);
    const dem_view v = gd_view(d, e);
    const wall_geom w = s->flow.w;
    double *F = e->F, *T = e->T, *Fi = e->Fi;
    double *xg = e->xg;
    unsigned long long *bad = e->dbad;
    each(g, d->no, [=] __device__(size_t i) { /* the owned grains (all of them on one rank) */
        if (dem_forces(&v, &w, i, t, dt, &F[3 * i], &T[3 * i], &Fi[3 * i])) atomicMin(bad, (unsigned long long)i);
        if (fold)
            for (int q = 0; q < 3; ++q) xg[3 * i + q] += Fi[3 * i + q] * dt;
    });
    if (split) { /* this step's sum over this rank's grains (gpu_dem_advance adds the ranks') */
        k_dem_exch<<<1, DEM_RB, 0, g->st>>>(d->no, Fi, dt, e->exs + 3 * k);
        CK(cudaGetLastError());
    }
    if (d->motion == DEM_RIGID && split) {
        gd_rigid_split(s, g, e, v, dt);
    } else if (d->motion == DEM_RIGID) {
        k_dem_rigid<<<1, DEM_RB, 0, g->st>>>(v, F, T, dt);
        CK(cudaGetLastError());
    } else if (d->motion != DEM_FIXED) {
        each(g, d->no, [=] __device__(size_t i) { dem_move_free(&v, i, &F[3 * i], &T[3 * i], dt); });
    }
    prof_end(g->st, P_DEM_STEP);
}

/* The grains from t over the fluid step dt (dem.c dem_advance). */
void gpu_dem_advance(sim_t *s, double t, double dt)
{
    gpu_t *g = gpu_hook(s, 0); /* the grains only: the fluid is not read */
    dem_t *d = s->dem;
    gpu_dem *e = gd_get(s, g);
    *e->hbad = (unsigned long long)d->no;
    up(e->dbad, e->hbad, 1, g->st);
    gd_period(s, g, e);
    const long m = dem_substeps(d, dt);
    d->steps += m;
    const double h = dt / (double)m;
    if (d->split && (size_t)m > e->exs_cap) {
        if (e->exs) CK(cudaFree(e->exs));
        e->exs = dalloc<double>(3 * (size_t)m), e->exs_cap = (size_t)m;
    }
    if (d->split) CK(cudaMemsetAsync(e->exs, 0, 3 * (size_t)m * sizeof(double), g->st));
    for (long k = 0; k < m; ++k) gd_substep(s, g, e, t + (double)k * h, h, k);
    if (d->split) { /* the steps' sums over the ranks, in one reduction (dem_exch_steps, as the CPU's) */
        double *ex = (double *)malloc(3 * (size_t)m * sizeof(double));
        if (!ex) error_exit(1, "out of memory");
        down(ex, e->exs, 3 * (size_t)m, g->st);
        CK(cudaStreamSynchronize(g->st));
        dem_exch_steps(d, ex, m);
        free(ex);
    }
    gd_period(s, g, e);
    down(e->hbad, e->dbad, 1, g->st);
    CK(cudaStreamSynchronize(g->st));
    if (*e->hbad < (unsigned long long)d->no) dem_overflow_exit((size_t)d->id[*e->hbad]);
}

/* The host's grains up to date (to_host: output, diagnostics): the owned
 * ones (split: the ghosts are their owners'; the exchanged momentum is the
 * host's, summed at each DEM step). */
void gpu_dem_download(sim_t *s, gpu_t *g)
{
    gpu_dem *e = g->dem;
    if (!e) return; /* no hook has run: the host's are the grains */
    dem_t *d = s->dem;
    const size_t n = d->no, nl = n * DEM_CMAX;
    double *const *hv[6] = {d->x, d->v, d->w, d->fint, d->fd, d->uf};
    double *const *dv[6] = {e->x, e->v, e->w, e->fint, e->fd, e->uf};
    for (int k = 0; k < 6; ++k)
        for (int a = 0; a < 3; ++a) down(hv[k][a], dv[k][a], n, g->st);
    down(d->eps, e->eps, n, g->st), down(d->snorm, e->snorm, n, g->st);
    down(d->ncon, e->ncon, n, g->st), down(d->cid, e->cid, nl, g->st), down(d->cxi, e->cxi, 3 * nl, g->st);
    if (d->split) {
        CK(cudaStreamSynchronize(g->st));
        return;
    }
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
    gd_arrays_free(e);
    void *bufs[] = {e->eps_f, e->deps_f, e->key, e->key2, e->vin, e->fidx, e->gstart, e->fstart, e->exch,
                    e->box_d, e->dbad, e->exs, e->rs, e->sidx[0], e->sidx[1], e->dbuf, e->dxb};
    for (size_t k = 0; k < sizeof bufs / sizeof bufs[0]; ++k)
        if (bufs[k]) CK(cudaFree(bufs[k]));
    CK(cudaFreeHost(e->box_h));
    CK(cudaFreeHost(e->hbad));
    if (e->hbuf) CK(cudaFreeHost(e->hbuf));
    if (e->hxb) CK(cudaFreeHost(e->hxb));
    free(e);
    g->dem = NULL;
}
