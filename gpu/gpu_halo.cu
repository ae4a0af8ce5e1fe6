/* gpu/gpu_halo.cu — ghosts on several ranks: packing the refreshed fields,
 * the byte exchanges (hx_post, hx_land; CUDA IPC segments through
 * gpu_ipc.cu), the host path of the exchange at list builds, and the
 * refreshes between builds, synchronous or overlapped with the interior's
 * passes; which fields a refresh carries comes from the stage table
 * (src/sim/stages.h: fields_tab, moving_fields). */
#include "gpu.cuh"

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

/* A channel to this rank itself (periodic images, mpi/halo.h): the fields of
 * the owners src[e] straight into the ghost slots dst[e], on the device. */
__global__ void k_self(ftab t, const unsigned *src, const unsigned *dst, size_t cnt)
{
    size_t e = (size_t)blockIdx.x * blockDim.x + threadIdx.x;
    if (e >= cnt) return;
    size_t i = src[e], j = dst[e];
    for (int f = 0; f < t.n; ++f) switch (t.es[f]) {
        case 8: ((uint64_t *)t.p[f])[j] = ((const uint64_t *)t.p[f])[i]; break;
        case 4: ((uint32_t *)t.p[f])[j] = ((const uint32_t *)t.p[f])[i]; break;
        default: ((uint8_t *)t.p[f])[j] = ((const uint8_t *)t.p[f])[i];
        }
}

/* Is channel k of the halo a channel to this rank itself; its partner (the
 * channel that receives what k sends) in *kp. */
int hx_self(const halo_t *h, int k, int *kp)
{
    if (h->nb[k] != h->rank) return 0;
    for (int q = 0; q < h->nnb; ++q)
        if (h->nb[q] == h->rank && h->nbs[q] == HALO_NCODES - 1 - h->nbs[k]) return *kp = q, 1;
    error_exit(1, "backend_gpu: self channel %d of rank %d has no partner", k, h->rank);
}

void ft_add(ftab *t, void *p, size_t es)
{
    if (t->n >= FT_MAX) error_exit(1, "backend_gpu: more than %d refresh fields", FT_MAX);
    t->p[t->n] = p, t->es[t->n] = (unsigned char)es, t->n++;
}

void *grow_dev(void *p, size_t *cap, size_t need)
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

/* GPU time spent on the halo: an event pair around each piece of halo work
 * on the stream (pack and copy out; wait, copy in and unpack), summed into
 * halo_t.wall_exposed once both have completed (at the next check, or when
 * the ring is full). */
void hx_resolve(gpu_t *g, halo_t *h)
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

/* Periodic images (mpi/halo.h): add the channel's shift to the positions
 * among the refreshed fields of its ghosts (x real, x_n double). */
__global__ void k_shift_images(grid_image im, const unsigned *idx, size_t cnt)
{
    size_t e = (size_t)blockIdx.x * blockDim.x + threadIdx.x;
    if (e < cnt) grid_image_move(&im, idx[e]);
}

static void gpu_shift_images(sim_t *s, gpu_t *g, const ftab &t, int self)
{
    halo_t *h = s->halo;
    dhalo *x = g->hx;
    if (!h->per) return;
    grid_image im = {{NULL, NULL, NULL}, {NULL, NULL, NULL}, {0, 0, 0}};
    int any = 0;
    for (int f = 0; f < t.n; ++f)
        for (int d = 0; d < 3; ++d) {
            if (t.p[f] == (void *)g->d.x[d]) im.x[d] = g->d.x[d], any = 1;
            if (t.p[f] == (void *)g->d.x_n[d]) im.xn[d] = g->d.x_n[d], any = 1;
        }
    if (!any) return;
    for (int k = 0; k < h->nnb; ++k) {
        int kp;
        if (hx_self(h, k, &kp) != self) continue; /* self: the channels that k_self filled */
        size_t cnt = x->roff[k + 1] - x->roff[k];
        halo_image_shift(h, k, im.s);
        if (!cnt || (im.s[0] == 0 && im.s[1] == 0 && im.s[2] == 0)) continue;
        k_shift_images<<<(unsigned)((cnt + BLOCK - 1) / BLOCK), BLOCK, 0, g->st>>>(im, x->ridx + x->roff[k], cnt);
    }
    CK(cudaGetLastError());
}

/* Pack fields t of the send lists (sidx by soff) on the device, a channel
 * to this rank itself straight into its partner's slots (ridx by roff),
 * stage them (or hand the device buffer to a CUDA-aware MPI) and post the
 * exchange; shift: the periodic images' positions of the self channels
 * moved (a refresh, the ghosts of a build; not a migration). */
void hx_post(sim_t *s, gpu_t *g, const ftab &t, int shift)
{
    halo_t *h = s->halo;
    dhalo *x = g->hx;
    int m = h->nnb;
    double t0 = now();
    if (x->ipc_gen != h->gen) ipc_setup(s, g); /* the channels changed (on every rank at once) */
    x->sb[0] = x->rb[0] = x->ib[0] = x->irb[0] = 0;
    for (int k = 0; k < m; ++k) { /* a channel to this rank itself sends nothing through MPI, an IPC one
                                   * only its descriptor */
        int kp, self = hx_self(h, k, &kp), mpi = !self && !x->ipc[k];
        size_t bs = ft_bytes(t, x->soff[k + 1] - x->soff[k]), br = ft_bytes(t, x->roff[k + 1] - x->roff[k]);
        x->sb[k + 1] = x->sb[k] + (mpi ? bs : 0);
        x->rb[k + 1] = x->rb[k] + (mpi ? br : 0);
        x->ib[k + 1] = x->ib[k] + (x->ipc[k] ? bs : 0);
        x->irb[k + 1] = x->irb[k] + (x->ipc[k] ? br : 0);
    }
    x->dsend = (char *)grow_dev(x->dsend, &x->cap_dsend, x->sb[m]);
    x->drecv = (char *)grow_dev(x->drecv, &x->cap_drecv, x->rb[m]);
    char *ibuf = x->nipc ? ipc_send_buffer(g, x->ib[m]) : NULL;
    hx_mark(g, h, 0);
    for (int k = 0; k < m; ++k) {
        size_t cnt = x->soff[k + 1] - x->soff[k];
        int kp;
        if (!cnt) continue;
        if (hx_self(h, k, &kp)) { /* periodic images of this rank's own particles: device to device */
            if (x->roff[kp + 1] - x->roff[kp] != cnt)
                error_exit(1, "backend_gpu: self channel %d sends %zu, its partner expects %zu", k, cnt,
                           x->roff[kp + 1] - x->roff[kp]);
            k_self<<<(unsigned)((cnt + BLOCK - 1) / BLOCK), BLOCK, 0, g->st>>>(t, x->sidx + x->soff[k],
                                                                               x->ridx + x->roff[kp], cnt);
            continue;
        }
        k_pack<0><<<(unsigned)((cnt + BLOCK - 1) / BLOCK), BLOCK, 0, g->st>>>(
            t, x->sidx + x->soff[k], cnt, x->ipc[k] ? ibuf + x->ib[k] : x->dsend + x->sb[k]);
    }
    CK(cudaGetLastError());
    if (shift) gpu_shift_images(s, g, t, 1);
    char *sbuf = x->dsend, *rbuf = x->drecv;
    if (!x->cuda_aware) {
        x->hsend = (char *)grow_pinned(x->hsend, &x->cap_hsend, x->sb[m]);
        x->hrecv = (char *)grow_pinned(x->hrecv, &x->cap_hrecv, x->rb[m]);
        if (x->sb[m]) CK(cudaMemcpyAsync(x->hsend, x->dsend, x->sb[m], cudaMemcpyDeviceToHost, g->st));
        sbuf = x->hsend, rbuf = x->hrecv;
    }
    hx_mark(g, h, 1);
    /* the host buffer is read by MPI next; the IPC peers read ibuf once told, and this stream's copies
     * out of their buffers (gpu_ipc.cu) must have drained before they are told */
    if (x->sb[m] || x->nipc) CK(cudaStreamSynchronize(g->st));
    if (x->nipc) ipc_post(s, g);
    h->wall_comm += now() - t0;
    halo_post_bytes(h, sbuf, x->sb, rbuf, x->rb);
}

/* Complete the exchange hx_post posted: wait for the messages, unpack
 * fields t into the slots ridx (by roff). The GPU's wait for them (idle)
 * plus the copy and unpack count as exposed halo time. */
void hx_land(sim_t *s, gpu_t *g, const ftab &t)
{
    halo_t *h = s->halo;
    dhalo *x = g->hx;
    int m = h->nnb;
    hx_mark(g, h, 0);
    halo_wait_bytes(h);
    double t0 = now();
    if (!x->cuda_aware && x->rb[m]) CK(cudaMemcpyAsync(x->drecv, x->hrecv, x->rb[m], cudaMemcpyHostToDevice, g->st));
    if (x->nipc) ipc_land(s, g);
    for (int k = 0; k < m; ++k) {
        size_t cnt = x->roff[k + 1] - x->roff[k];
        int kp;
        if (cnt && !hx_self(h, k, &kp))
            k_pack<1><<<(unsigned)((cnt + BLOCK - 1) / BLOCK), BLOCK, 0, g->st>>>(
                t, x->ridx + x->roff[k], cnt, x->ipc[k] ? x->dripc + x->irb[k] : x->drecv + x->rb[k]);
    }
    CK(cudaGetLastError());
    hx_mark(g, h, 1);
    h->wall_comm += now() - t0;
}

/* Start a refresh of fields t of the ghosts: pack the send lists on the
 * device, stage, post (hx_post); gpu_refresh_finish lands it. */
void gpu_refresh_start(sim_t *s, gpu_t *g, const ftab &t)
{
    dhalo *x = g->hx;
    if (x->pending) error_exit(1, "backend_gpu: a refresh is already in flight");
    hx_post(s, g, t, 1);
    x->pend = t;
    x->pending = 1;
    x->refresh++;
}

/* Complete the refresh in flight: unpack into the ghost slots, shift the
 * periodic images' positions. */
void gpu_refresh_finish(sim_t *s, gpu_t *g)
{
    dhalo *x = g->hx;
    if (!x || !x->pending) return;
    hx_land(s, g, x->pend);
    gpu_shift_images(s, g, x->pend, 0);
    x->pending = 0;
}

/* Refresh fields t of the ghosts now (no overlap). */
void gpu_refresh(sim_t *s, gpu_t *g, const ftab &t)
{
    gpu_refresh_start(s, g, t);
    gpu_refresh_finish(s, g);
}

/* The refresh in flight lands; then the boundary passes it held back. */
void gpu_settle(sim_t *s, gpu_t *g)
{
    dhalo *x = g->hx;
    if (!x || !x->pending) return;
    gpu_refresh_finish(s, g);
    gpu_walls_renorm(s, g, x->pend_walls, x->pend_renorm, x->pend_kgc, sel_bd(g, 2));
    x->pend_renorm = x->pend_walls = x->pend_kgc = 0;
}

/* Every array of the owned particles into the host copy s->p (its ghosts
 * are not kept there). */
void gpu_download(sim_t *s, gpu_t *g)
{
    CK(cudaStreamSynchronize(g->st));
    part_reserve(&s->p, g->n); /* the device exchange may have grown the store */
    for (size_t k = 0; k < part_narrays(); ++k)
        if (part_array_get(&g->d, k)) /* a field the run holds */
            CK(cudaMemcpy(part_array_get(&s->p, k), part_array_get(&g->d, k), g->n * part_array_esize(k),
                      cudaMemcpyDeviceToHost));
    s->p.n = g->n, s->p.ng = 0;
}

/* At a list build on several ranks: the owned particles to the host, where
 * mpi/halo.c migrates them and makes fresh ghosts; everything back. */
void gpu_full_exchange(sim_t *s, gpu_t *g)
{
    double t0 = now();
    particles_t *hp = &s->p;
    gpu_download(s, g);
    halo_exchange(s->halo, hp);
    gpu_reserve(g, hp->n + hp->ng, 0);
    gpu_counts(g, hp->n, hp->ng);
    gpu_upload(g, hp, 0, hp->n + hp->ng);
    double dt = now() - t0;
    g->hx->full++, g->hx->full_s += dt;
    s->halo->wall_exposed += dt;
}

/* Room for the per-channel offsets of m channels (host). */
void hx_offsets(dhalo *x, int m)
{
    free(x->soff), free(x->roff), free(x->sb), free(x->rb), free(x->ib), free(x->irb);
    x->cap_nb = m + 1;
    x->soff = (size_t *)calloc((size_t)x->cap_nb, sizeof(size_t));
    x->roff = (size_t *)calloc((size_t)x->cap_nb, sizeof(size_t));
    x->sb = (size_t *)calloc((size_t)x->cap_nb, sizeof(size_t));
    x->rb = (size_t *)calloc((size_t)x->cap_nb, sizeof(size_t));
    x->ib = (size_t *)calloc((size_t)x->cap_nb, sizeof(size_t));
    x->irb = (size_t *)calloc((size_t)x->cap_nb, sizeof(size_t));
    if (!x->soff || !x->roff || !x->sb || !x->rb || !x->ib || !x->irb) error_exit(1, "out of memory");
}

/* After the build's sort: the send lists and ghost slots to the device. */
void gpu_halo_lists(sim_t *s, gpu_t *g)
{
    halo_t *h = s->halo;
    dhalo *x = g->hx;
    int m = h->nnb;
    x->nnb = m;
    if (m + 1 > x->cap_nb) hx_offsets(x, m);
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

/* The fields f (src/sim/stages.h) of the device store as a refresh table;
 * trim2d: a 2D store's z components and xz, yz stresses left out. */
ftab fields_tab(const gpu_t *g, uint32_t f, int trim2d)
{
    ftab t;
    t.n = 0;
    void *ptrs[PART_NARRAYS];
    int n = stage_arrays(&g->d, f, trim2d, ptrs);
    for (int k = 0; k < n; ++k) ft_add(&t, ptrs[k], part_array_esize((size_t)part_array_find(&g->d, ptrs[k])));
    return t;
}

/* What the ghosts need when the particles moved between list builds (the
 * GPU keeps its ghosts between builds): the stage table's moving fields
 * (stage_moving_fields; windows: C is refreshed by conc_step). */
const stage_sched *gpu_sched(const sim_t *s) { return stage_schedule(stage_flags(s)); }

ftab moving_fields(const sim_t *s, const gpu_t *g)
{
    return fields_tab(g, gpu_sched(s)->moving, 1);
}
