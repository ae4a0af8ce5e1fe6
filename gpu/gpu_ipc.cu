/* gpu/gpu_ipc.cu — CUDA IPC between the ranks of one node (issue 31): where MPI is not
 * CUDA-aware, a channel between two ranks whose GPUs can reach each other
 * (the same device, or peers over NVLink or PCIe) carries its segments
 * device to device instead of through pinned host memory and MPI. The MPI
 * messages left on such a channel are small descriptors.
 *
 * Pull protocol. The sender packs its IPC channels into one of two device
 * buffers (alternating at every exchange), waits for the pack, and sends
 * each IPC neighbour a descriptor (the buffer's IPC handle, a generation
 * that changes when the buffer is reallocated, the segment's offset); the
 * receiver copies the segment from the mapped buffer into its own and
 * unpacks it. Safety without further messages: a sender reuses a buffer two
 * exchanges later, after it has received that neighbour's next descriptor,
 * which the neighbour sends only after its own stream (and so its copy out
 * of this buffer) has drained. A buffer that grows is replaced, never freed
 * while the run lasts (CUDA leaves freeing memory a peer maps undefined):
 * the peers close their mapping when the new generation arrives, and the
 * old buffers go at the end, after every rank has closed its mappings.
 *
 * Which channels: decided whenever the channels are set (halo_t.gen), from
 * two rounds of small messages among neighbours: host name, PCI bus id and
 * whether IPC is on (SPHSEG_GPU_IPC=0 turns it off; a CUDA-aware MPI gets
 * the device buffers instead), then each side's "I can map yours"; a channel
 * is IPC when both can. Self channels (periodic images) never are. */
#include "gpu.cuh"

struct ipc_hello {
    char host[64], bus[32];
    int on;
};
struct ipc_desc {
    cudaIpcMemHandle_t handle;
    long long gen;
    unsigned long long off;
    int parity;
};
/* A peer's buffer mapped into this process, shared by its channels. */
struct ipc_map {
    int rank, parity;
    long long gen;
    char *ptr;
};

static int ipc_wanted(const dhalo *x)
{
    return !x->cuda_aware && tuning_get()->gpu_ipc;
}

/* Decide, per channel, whether it goes by IPC (x->ipc[k]). Collective among
 * neighbours; runs on every rank at once (halo_t.gen changes everywhere). */
void ipc_setup(sim_t *s, gpu_t *g)
{
    halo_t *h = s->halo;
    dhalo *x = g->hx;
    int m = h->nnb;
    x->ipc_gen = h->gen;
    free(x->ipc);
    x->ipc = (int *)calloc((size_t)m + 1, sizeof(int));
    ipc_hello me, *them = (ipc_hello *)calloc((size_t)m + 1, sizeof(ipc_hello)), *mine =
                                          (ipc_hello *)calloc((size_t)m + 1, sizeof(ipc_hello));
    int *can = (int *)calloc(2 * (size_t)m + 2, sizeof(int)), *theirs = can + m + 1;
    if (!x->ipc || !them || !mine || !can) error_exit(1, "out of memory");
    memset(&me, 0, sizeof me);
    gethostname(me.host, sizeof me.host - 1);
    me.on = ipc_wanted(x) && cudaDeviceGetPCIBusId(me.bus, (int)sizeof me.bus, g->dev) == cudaSuccess;
    for (int k = 0; k < m; ++k) mine[k] = me;
    halo_swap_small(h, mine, them, sizeof(ipc_hello), NULL);
    for (int k = 0; k < m; ++k) {
        int d = -1, kp;
        if (hx_self(h, k, &kp) || !me.on || !them[k].on || strcmp(me.host, them[k].host)) continue;
        if (cudaDeviceGetByPCIBusId(&d, them[k].bus) != cudaSuccess) {
            (void)cudaGetLastError();
            continue;
        }
        int ok = d == g->dev;
        if (!ok && cudaDeviceCanAccessPeer(&ok, g->dev, d) != cudaSuccess) (void)cudaGetLastError(), ok = 0;
        can[k] = ok;
    }
    halo_swap_small(h, can, theirs, sizeof(int), NULL);
    x->nipc = 0;
    for (int k = 0; k < m; ++k) x->nipc += x->ipc[k] = can[k] && theirs[k];
    if (x->nipc || x->ipc_said != me.on) /* the first decision, and any that differs from it */
        message("gpu halo (rank %d): %d of %d channels by CUDA IPC device to device%s", h->rank, x->nipc, m,
                me.on ? "" : x->cuda_aware ? " (CUDA-aware MPI instead)" : " (SPHSEG_GPU_IPC=0)");
    x->ipc_said = me.on;
    free(them), free(mine), free(can);
}

/* The send buffer of this exchange's parity, at least bytes long; a new
 * allocation gets a new generation and handle. */
char *ipc_send_buffer(gpu_t *g, size_t bytes)
{
    dhalo *x = g->hx;
    int p = x->ipc_par;
    if (bytes > x->ipc_cap[p] || !x->ipc_buf[p]) {
        if (x->ipc_buf[p]) { /* kept until the end: freeing memory a peer still maps is undefined (CUDA) */
            x->ipc_old = (char **)realloc(x->ipc_old, (size_t)(x->nold + 1) * sizeof(char *));
            if (!x->ipc_old) error_exit(1, "out of memory");
            x->ipc_old[x->nold++] = x->ipc_buf[p];
        }
        x->ipc_cap[p] = bytes + bytes / 2 + 4096;
        x->ipc_buf[p] = (char *)dev_alloc(x->ipc_cap[p]);
        CK(cudaIpcGetMemHandle(&x->ipc_handle[p], x->ipc_buf[p]));
        x->ipc_bgen[p] = ++x->ipc_count;
    }
    return x->ipc_buf[p];
}

/* After the pack has completed: a descriptor to every IPC neighbour (the
 * segment of channel k at x->ib[k]); theirs into x->ipc_in. Blocking. */
void ipc_post(sim_t *s, gpu_t *g)
{
    halo_t *h = s->halo;
    dhalo *x = g->hx;
    int m = h->nnb, p = x->ipc_par;
    ipc_desc *out = (ipc_desc *)calloc((size_t)m + 1, sizeof(ipc_desc));
    x->ipc_in = (ipc_desc *)realloc(x->ipc_in, ((size_t)m + 1) * sizeof(ipc_desc));
    if (!out || !x->ipc_in) error_exit(1, "out of memory");
    for (int k = 0; k < m; ++k)
        if (x->ipc[k])
            out[k].handle = x->ipc_handle[p], out[k].gen = x->ipc_bgen[p], out[k].off = x->ib[k], out[k].parity = p;
    halo_swap_small(h, out, x->ipc_in, sizeof(ipc_desc), x->ipc);
    free(out);
    x->ipc_par ^= 1;
}

/* The peer's buffer of descriptor d (rank r), mapped once per generation. */
static const char *ipc_peer(gpu_t *g, int r, const ipc_desc *d)
{
    dhalo *x = g->hx;
    int par = d->parity, e = 0;
    for (; e < x->nmap; ++e)
        if (x->map[e].rank == r && x->map[e].parity == par) break;
    if (e == x->nmap) {
        x->map = (ipc_map *)realloc(x->map, (size_t)(x->nmap + 1) * sizeof(ipc_map));
        if (!x->map) error_exit(1, "out of memory");
        x->map[e].rank = r, x->map[e].parity = par, x->map[e].gen = -1, x->map[e].ptr = NULL;
        x->nmap++;
    }
    ipc_map *q = &x->map[e];
    if (q->gen != d->gen) {
        if (q->ptr) CK(cudaIpcCloseMemHandle(q->ptr));
        void *ptr = NULL;
        CK(cudaIpcOpenMemHandle(&ptr, d->handle, cudaIpcMemLazyEnablePeerAccess));
        q->ptr = (char *)ptr, q->gen = d->gen;
    }
    return q->ptr;
}

/* Copy every IPC channel's segment from its sender into x->dripc (at
 * x->irb[k]), on the stream. */
void ipc_land(sim_t *s, gpu_t *g)
{
    halo_t *h = s->halo;
    dhalo *x = g->hx;
    int m = h->nnb;
    x->dripc = (char *)grow_dev(x->dripc, &x->cap_dripc, x->irb[m]);
    for (int k = 0; k < m; ++k) {
        size_t bytes = x->irb[k + 1] - x->irb[k];
        if (!x->ipc[k]) continue;
        const char *src = ipc_peer(g, h->nb[k], &x->ipc_in[k]) + x->ipc_in[k].off; /* mapped even when empty:
                                                                                   * a new generation closes the old */
        if (bytes) CK(cudaMemcpyAsync(x->dripc + x->irb[k], src, bytes, cudaMemcpyDeviceToDevice, g->st));
    }
}

/* At the end of the run (every rank): the peers' buffers unmapped, then,
 * once every rank has unmapped (a collective), this rank's own freed. */
void ipc_free(dhalo *x)
{
    for (int e = 0; e < x->nmap; ++e)
        if (x->map[e].ptr) CK(cudaIpcCloseMemHandle(x->map[e].ptr));
    (void)comm_max(0.0);
    for (int p = 0; p < 2; ++p)
        if (x->ipc_buf[p]) CK(cudaFree(x->ipc_buf[p]));
    for (int e = 0; e < x->nold; ++e) CK(cudaFree(x->ipc_old[e]));
    free(x->ipc_old);
    if (x->dripc) CK(cudaFree(x->dripc));
    free(x->map), free(x->ipc), free(x->ipc_in), free(x->ib), free(x->irb);
}
