/* gpu/gpu_exchange.cu — the exchange at a list build on several ranks, on the
 * device (issue 31): the lattice origin from a device reduction, the periodic wrap, the
 * migrants and the ghosts chosen by kernels with the same decisions as
 * mpi/halo.c (mpi/halo_geom.h), compacted and sorted by channel on the
 * device, packed, exchanged as byte segments (pinned host staging, or the
 * device buffers to a CUDA-aware MPI), unpacked; the send lists and ghost
 * slots stay on the device and follow the build's sort there. The host sees
 * counts, not particles.
 *
 * It reproduces halo_exchange bit for bit: the owned particles keep their
 * order, the arrivals and the ghosts come in channel order, each channel's
 * particles in ascending store index, every value copied, every image
 * shifted by the same arithmetic. SPHSEG_GPU_HOSTX=1 takes the host path
 * instead (gpu_full_exchange: download, halo_exchange, upload), for
 * measuring and comparing the two. */
#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>
#include "gpu_reduce.cuh"

/* ---- the decomposition on the device ------------------------------------ */

/* Copy n bytes of host array a to the device array *d (grown), unless the
 * shadow copy says the device already holds them. */
static void hx_mirror(gpu_t *g, void **d, void **shadow, size_t *cap, const void *a, size_t n)
{
    if (*d && *cap >= n && !memcmp(*shadow, a, n)) return;
    if (*cap < n) {
        if (*d) CK(cudaFree(*d));
        free(*shadow);
        *d = dev_alloc(n ? n : 1);
        *shadow = malloc(n ? n : 1);
        if (!*shadow) error_exit(1, "out of memory");
        *cap = n;
    }
    memcpy(*shadow, a, n);
    CK(cudaMemcpyAsync(*d, *shadow, n, cudaMemcpyHostToDevice, g->st));
}

/* halo_geom of the halo in force, its arrays pointing at device copies. */
static halo_geom hx_geom(sim_t *s, gpu_t *g)
{
    halo_t *h = s->halo;
    dhalo *x = g->hx;
    halo_geom v;
    halo_geom_of(h, &v);
    hx_mirror(g, (void **)&x->gbound, &x->sbound, &x->cap_gbound, h->bound, ((size_t)h->size + 1) * sizeof(long));
    v.bound = x->gbound;
    if (v.metis) {
        size_t nv = (size_t)h->cg_n[0] * (size_t)h->cg_n[1] * (size_t)h->cg_n[2];
        hx_mirror(g, (void **)&x->gpart, &x->spart, &x->cap_gpart, h->part, nv * sizeof(int));
        v.part = x->gpart;
    }
    size_t nb = (size_t)h->nnb * sizeof(int);
    int *both = (int *)malloc(2 * nb + 1);
    if (!both) error_exit(1, "out of memory");
    memcpy(both, h->nb, nb), memcpy((char *)both + nb, h->nbs, nb);
    hx_mirror(g, (void **)&x->gnb, &x->snb, &x->cap_gnb, both, 2 * nb);
    free(both);
    v.nb = x->gnb, v.nbs = x->gnb + h->nnb;
    return v;
}

/* ---- choosing, counting, sorting ------------------------------------------ */

/* Per owned particle: its targets (ghosts) or its new owner (migration),
 * each as the channel it travels on. COUNT: how many into cnt[i]; else the
 * pairs (channel, i) from off[i] on. A target without a channel is the
 * host's "not a neighbour" failure: its rank into err. */
enum { HX_GHOSTS = 0, HX_MIGRATE = 1 };
template <int MODE, int COUNT>
__global__ void k_targets(halo_geom v, particles_t p, size_t n, unsigned *cnt, const unsigned *off, unsigned *pk,
                          unsigned *pv, unsigned *keep, int *err)
{
    size_t i = (size_t)blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n) return;
    real x[3] = {p.x[0][i], p.x[1][i], p.x[2][i]};
    if (MODE == HX_MIGRATE) {
        long c[3];
        for (int d = 0; d < 3; ++d) c[d] = d < v.dim ? hg_column(&v, d, x[d]) : 0;
        int r = hg_owner(&v, c), k = r == v.rank ? -1 : hg_channel(v.nnb, v.nb, v.nbs, r, -1);
        if (r != v.rank && k < 0) atomicExch(err, r);
        if (COUNT) cnt[i] = r != v.rank;
        else if (r == v.rank) keep[i - off[i]] = (unsigned)i; /* off counts the migrants before i */
        else if (k >= 0) pk[off[i]] = (unsigned)k, pv[off[i]] = (unsigned)i;
        return;
    }
    int tg[HG_MAX_TARGETS], tc[HG_MAX_TARGETS];
    int nt = hg_particle_targets(&v, x, tg, tc);
    unsigned q = COUNT ? 0 : off[i];
    for (int t = 0; t < nt; ++t) {
        int k = hg_channel(v.nnb, v.nb, v.nbs, tg[t], tc[t]);
        if (k < 0) {
            atomicExch(err, tg[t]);
            continue;
        }
        if (!COUNT) pk[q] = (unsigned)k, pv[q] = (unsigned)i;
        ++q;
    }
    if (COUNT) cnt[i] = q;
}

template <class T> static T *grow_dev_t(T *p, size_t *cap, size_t n)
{
    return (T *)grow_dev(p, cap, (n ? n : 1) * sizeof(T));
}

/* Exclusive sums of cnt[0..n) into off; the total (a synchronisation). */
static size_t hx_scan(gpu_t *g, const unsigned *cnt, unsigned *off, size_t n)
{
    if (!n) return 0;
    size_t bytes = 0;
    CK(cub::DeviceScan::ExclusiveSum(NULL, bytes, cnt, off, (int64_t)n, g->st));
    CK(cub::DeviceScan::ExclusiveSum(scratch(g, bytes), bytes, cnt, off, (int64_t)n, g->st));
    unsigned last[2];
    CK(cudaMemcpyAsync(&last[0], off + n - 1, sizeof(unsigned), cudaMemcpyDeviceToHost, g->st));
    CK(cudaMemcpyAsync(&last[1], cnt + n - 1, sizeof(unsigned), cudaMemcpyDeviceToHost, g->st));
    CK(cudaStreamSynchronize(g->st));
    return (size_t)last[0] + last[1];
}

/* The npair pairs (channel pk, particle pv), written in ascending particle
 * order, stably sorted by channel into x->sidx (each channel's particles
 * still ascending), and the per-channel counts into x->soff; the exchange
 * of counts gives x->roff. Returns the number received. */
static size_t hx_lists(sim_t *s, gpu_t *g, size_t npair)
{
    halo_t *h = s->halo;
    dhalo *x = g->hx;
    int m = h->nnb;
    x->nnb = m;
    if (m + 1 > x->cap_nb) hx_offsets(x, m);
    x->sidx = (unsigned *)grow_dev_t(x->sidx, &x->cap_s, npair);
    if (npair) {
        int bits = 1;
        while ((1 << bits) < m) ++bits;
        cub::DoubleBuffer<unsigned> kb(x->pk, x->pk2), vb(x->pv, x->sidx);
        size_t bytes = 0;
        CK(cub::DeviceRadixSort::SortPairs(NULL, bytes, kb, vb, (int64_t)npair, 0, bits, g->st));
        CK(cub::DeviceRadixSort::SortPairs(scratch(g, bytes), bytes, kb, vb, (int64_t)npair, 0, bits, g->st));
        if (vb.Current() != x->sidx)
            CK(cudaMemcpyAsync(x->sidx, vb.Current(), npair * sizeof(unsigned), cudaMemcpyDeviceToDevice, g->st));
        const unsigned *key = kb.Current();
        unsigned long long *c = x->dcnt;
        CK(cudaMemsetAsync(c, 0, (size_t)m * sizeof *c, g->st));
        each(g, npair, [=] __device__(size_t e) { atomicAdd(&c[key[e]], 1ull); });
        CK(cudaMemcpyAsync(x->hcnt, c, (size_t)m * sizeof *c, cudaMemcpyDeviceToHost, g->st));
        CK(cudaStreamSynchronize(g->st));
    } else
        for (int k = 0; k < m; ++k) x->hcnt[k] = 0;
    size_t *ns = (size_t *)calloc(2 * (size_t)m + 1, sizeof(size_t)), *got = ns + m;
    if (!ns) error_exit(1, "out of memory");
    for (int k = 0; k < m; ++k) ns[k] = (size_t)x->hcnt[k];
    halo_swap_counts(h, ns, got);
    x->soff[0] = x->roff[0] = 0;
    for (int k = 0; k < m; ++k) {
        x->soff[k + 1] = x->soff[k] + ns[k];
        x->roff[k + 1] = x->roff[k] + got[k];
        h->nsend[k] = ns[k], h->nrecv[k] = got[k]; /* the counts; the lists live on the device */
    }
    free(ns);
    return x->roff[m];
}

/* The receiving slots base, base + 1, ... into x->ridx. */
static void hx_slots(gpu_t *g, size_t base, size_t nr)
{
    dhalo *x = g->hx;
    x->ridx = (unsigned *)grow_dev_t(x->ridx, &x->cap_r, nr);
    unsigned *r = x->ridx;
    each(g, nr, [=] __device__(size_t e) { r[e] = (unsigned)(base + e); });
}

/* Per-particle and per-pair work space for n owned particles and npair
 * pairs; the count buffers for the channels. */
static void hx_space(gpu_t *g, int m, size_t n, size_t npair)
{
    dhalo *x = g->hx;
    x->cnt = grow_dev_t(x->cnt, &x->cap_cnt, n + 1);
    x->off = grow_dev_t(x->off, &x->cap_off, n + 1);
    x->pk = grow_dev_t(x->pk, &x->cap_pk, npair);
    x->pk2 = grow_dev_t(x->pk2, &x->cap_pk2, npair);
    x->pv = grow_dev_t(x->pv, &x->cap_pv, npair);
    if ((size_t)m > x->cap_hcnt) {
        if (x->dcnt) CK(cudaFree(x->dcnt));
        if (x->hcnt) CK(cudaFreeHost(x->hcnt));
        x->cap_hcnt = (size_t)m + 8;
        x->dcnt = (unsigned long long *)dev_alloc(x->cap_hcnt * sizeof(unsigned long long));
        CK(cudaMallocHost((void **)&x->hcnt, x->cap_hcnt * sizeof(unsigned long long)));
    }
    if (!x->derr) {
        x->derr = (int *)dev_alloc(sizeof(int));
        CK(cudaMallocHost((void **)&x->herr, sizeof(int)));
    }
}

/* The rank a kernel found that is not a neighbour: the host's failure. */
static void hx_check(gpu_t *g, halo_t *h, const char *what)
{
    dhalo *x = g->hx;
    CK(cudaMemcpyAsync(x->herr, x->derr, sizeof(int), cudaMemcpyDeviceToHost, g->st));
    CK(cudaStreamSynchronize(g->st));
    if (*x->herr >= 0)
        error_exit(EXIT_NUMERICAL, "%s: rank %d is not a neighbour of rank %d (a particle crossed more than "
                   "one domain in a step: the flow is unstable)", what, *x->herr, h->rank);
}

/* Every array of the store as a field table (migration). */
static ftab all_tab(const particles_t *p)
{
    ftab t;
    t.n = 0;
    for (size_t k = 0; k < part_narrays(); ++k) /* the fields the run holds */
        if (part_array_get(p, k)) ft_add(&t, part_array_get(p, k), part_array_esize(k));
    return t;
}

/* The arrays a ghost carries (halo_t.arr) as a field table. */
static ftab arr_tab(const halo_t *h, const particles_t *p)
{
    ftab t;
    t.n = 0;
    for (int a = 0; a < h->narr; ++a) ft_add(&t, part_array_get(p, (size_t)h->arr[a]), part_array_esize((size_t)h->arr[a]));
    return t;
}

/* ---- the exchange ----------------------------------------------------------- */

/* halo_corner: the lattice origin from the owned particles' lower corner. */
static void hx_origin(sim_t *s, gpu_t *g)
{
    box init;
    for (int d = 0; d < 3; ++d) init.lo[d] = R(1e30), init.hi[d] = R(-1e30);
    auto bx = thrust::make_transform_iterator(thrust::counting_iterator<size_t>(0), box_of{g->d});
    if (g->n) reduce(g, bx, g->dbox, g->n, box_merge(), init);
    else CK(cudaMemcpyAsync(g->dbox, &init, sizeof init, cudaMemcpyHostToDevice, g->st));
    CK(cudaMemcpyAsync(g->hbox, g->dbox, sizeof(box), cudaMemcpyDeviceToHost, g->st));
    CK(cudaStreamSynchronize(g->st));
    real lo[3];
    for (int d = 0; d < 3; ++d) lo[d] = d < s->p.dim ? g->hbox->lo[d] : R(1e30);
    halo_set_origin(s->halo, lo);
}

/* halo_wrap on the device: the owned particles back into the period. */
static void hx_wrap(sim_t *s, gpu_t *g)
{
    const halo_t *h = s->halo;
    particles_t p = g->d;
    for (int d = 0; d < h->dim; ++d) {
        if (!(h->per >> d & 1)) continue;
        double lo = h->plo[d], len = h->plen[d];
        each(g, g->n, [=] __device__(size_t i) {
            double sh = hg_wrap_shift((double)p.x[d][i] + (POS_REMAINDER ? (double)p.xr[d][i] : 0.0), lo, len);
            if (sh != 0) hg_move(&p.x[d][i], &p.xr[d][i], &p.x_n[d][i], sh);
        });
    }
}

/* The (channel, particle) pairs of MODE (k_targets) for the owned particles,
 * in ascending particle order in x->pk, x->pv (and, migrating, the kept
 * ones' indices in x->keep): a counting pass, a scan, a writing pass.
 * Returns the number of pairs; what names the host's failure. */
template <int MODE> static size_t hx_choose(sim_t *s, gpu_t *g, const halo_geom &v, const char *what)
{
    halo_t *h = s->halo;
    dhalo *x = g->hx;
    const size_t n = g->n;
    hx_space(g, h->nnb, n, 0);
    CK(cudaMemsetAsync(x->derr, 0xff, sizeof(int), g->st));
    const unsigned grid = (unsigned)((n + BLOCK - 1) / BLOCK);
    if (n) k_targets<MODE, 1><<<grid, BLOCK, 0, g->st>>>(v, g->d, n, x->cnt, NULL, NULL, NULL, NULL, x->derr);
    CK(cudaGetLastError());
    size_t npair = hx_scan(g, x->cnt, x->off, n);
    hx_check(g, h, what);
    hx_space(g, h->nnb, n, npair);
    if (MODE == HX_MIGRATE) x->keep = grow_dev_t(x->keep, &x->cap_keep, n);
    if (n)
        k_targets<MODE, 0><<<grid, BLOCK, 0, g->st>>>(v, g->d, n, NULL, x->off, x->pk, x->pv,
                                                        MODE == HX_MIGRATE ? x->keep : NULL, x->derr);
    CK(cudaGetLastError());
    return npair;
}

/* halo_migrate on the device: the particles another rank owns go to it,
 * whole; the kept ones keep their order at [0, nkeep), the arrivals follow
 * in channel order. */
static void hx_migrate(sim_t *s, gpu_t *g, const halo_geom &v)
{
    halo_t *h = s->halo;
    dhalo *x = g->hx;
    const size_t n = g->n;
    size_t nmig = hx_choose<HX_MIGRATE>(s, g, v, "migration");
    size_t nin = hx_lists(s, g, nmig), nkeep = n - nmig;
    x->tmark[2] = now();
    h->migrated += (long long)nmig;
    /* posted even when nothing moves here: a neighbour waits for this rank's (empty) segments */
    gpu_reserve(g, nkeep + nin > n ? nkeep + nin : n, n);
    hx_slots(g, nkeep, nin);
    const ftab from = all_tab(&g->d);
    hx_post(s, g, from, 0); /* packs the migrants before the compaction below overwrites the spare set */
    if (nkeep < n) gpu_permute(g, x->keep, nkeep); /* the kept ones in order into the spare set, which
                                                      * becomes the store */
    hx_land(s, g, all_tab(&g->d));
    gpu_counts(g, nkeep + nin, 0);
    CK(cudaStreamSynchronize(g->st)); /* the next phase waits on its scan anyway; this times the move alone */
    x->tmark[3] = now();
}

/* halo_make_ghosts on the device: every owned particle near another
 * rank's cells (or an image's) to that rank, carrying the arrays the
 * stages read of ghosts (halo_t.arr), arrivals at [n, n + ng). */
static void hx_ghosts(sim_t *s, gpu_t *g, const halo_geom &v)
{
    halo_t *h = s->halo;
    dhalo *x = g->hx;
    const size_t n = g->n;
    size_t ng = hx_lists(s, g, hx_choose<HX_GHOSTS>(s, g, v, "ghosts"));
    x->tmark[4] = now();
    gpu_reserve(g, n + ng, n);
    gpu_counts(g, n, ng);
    hx_slots(g, n, ng);
    gpu_refresh(s, g, arr_tab(h, &g->d)); /* the ghosts' fields, images shifted, as a refresh carries them */
    x->refresh--; /* counted as part of the exchange, not as a refresh */
}

/* At a list build on several ranks: migrate and make ghosts on the device. */
void gpu_device_exchange(sim_t *s, gpu_t *g)
{
    double t0 = now(), comm0 = s->halo->wall_comm;
    dhalo *x = g->hx;
    gpu_counts(g, g->n, 0); /* the old ghosts are dropped */
    x->tmark[0] = t0;
    hx_origin(s, g);
    x->tmark[1] = now();
    hx_wrap(s, g);
    halo_geom v = hx_geom(s, g);
    hx_migrate(s, g, v);
    hx_ghosts(s, g, v);
    CK(cudaStreamSynchronize(g->st));
    x->tmark[HX_PHASES] = now();
    double dt = x->tmark[HX_PHASES] - t0;
    if (!x->full) x->first_s = dt;
    else
        for (int k = 0; k < HX_PHASES; ++k) x->ph[k] += x->tmark[k + 1] - x->tmark[k];
    x->full++, x->full_s += dt;
    s->halo->wall_comm = comm0 + dt; /* all of it, as halo_exchange counts its own */
    s->halo->wall_exposed += dt;
}

/* After the build's sort (perm[k] = old index now at k, over all n
 * particles): the send lists and the ghost slots follow on the device. */
void hx_sorted(gpu_t *g, const unsigned *perm, size_t n)
{
    dhalo *x = g->hx;
    x->inv = grow_dev_t(x->inv, &x->cap_inv, n);
    unsigned *inv = x->inv, *si = x->sidx, *ri = x->ridx;
    size_t ns = x->soff[x->nnb], nr = x->roff[x->nnb];
    each(g, n, [=] __device__(size_t k) { inv[perm[k]] = (unsigned)k; });
    each(g, ns, [=] __device__(size_t e) { si[e] = inv[si[e]]; });
    each(g, nr, [=] __device__(size_t e) { ri[e] = inv[ri[e]]; });
}
