/* gpu/gpu_graph.cu — the step as a CUDA graph (issue 56: a 10^4-particle
 * drum's kernels take a few microseconds each, and a launch from the host
 * about as long, so the host, not the device, set the step's pace).
 *
 * A step of one rank between list builds runs the same kernels with the
 * same arguments as the step before: only the step's time and length
 * change, and while held the kernels read those from device slots
 * (gpu_scalar, dscal), not from their arguments. So from the step's start (gpu_step_begin, the hook
 * struct backend's step_begin) to the check's read-back (gpu_check), each
 * launch (each, team in gpu_launch.cuh; the check's reduction) is held as
 * a function and the bytes of its arguments (gpu_defer_push). At the
 * check, gpu_defer_flush looks for a graph that held the same functions
 * with the same bytes: found, it replays that graph (one launch). A graph of
 * the same shape (the same functions, as many bytes each) whose bytes differ
 * only in single launches of a kernel takes those launches' new arguments
 * in its nodes (cudaGraphExecKernelNodeSetParams) and is replayed: a
 * closure's padding holds whatever the stack held, which differs from step
 * to step. Otherwise the held work is captured on the stream into a graph
 * that updates one of the same shape in place, or is instantiated anew. The
 * device runs the same kernels with the same arguments in the same order
 * every way, so the results are bit for bit those of launching them one by
 * one (SPHSEG_GPU_GRAPH=0; tests/validate_gpu.py).
 *
 * What is not held runs in order: any other CUDA call of the backend goes
 * through CK, which first issues what is held (and ends the holding). Steps
 * with a list build, several ranks, DEM grains, the staged flow pass
 * (SPHSEG_GPU_NBR=tile) or SPHSEG_GPU_PROFILE are not held at all. */
#include "gpu.cuh"

struct gpu_defer *g_defer; /* the holding in progress, or NULL */

enum { GRAPH_SLOTS = 4, SC_SLOTS = 64 };

/* One held launch or call: its function, the kernel it launches once (or
 * NULL), the bytes of its arguments (then the bytes, 16-aligned). */
struct held_entry {
    gpu_thunk fn;
    const void *kfn;
    size_t bytes, pad;
};

struct graph_slot {
    cudaGraph_t gr;      /* the graph the executable was made from: its nodes take patches */
    cudaGraphExec_t ex;
    cudaGraphNode_t *node; /* node[k]: held entry k's kernel node in gr, or NULL (not one kernel) */
    int nent;
    unsigned char *key;  /* the held work's bytes that the executable now runs (held_key) */
    size_t len, cap;
    long used;           /* for the least recently used */
};

struct gpu_defer {
    gpu_t *g;
    unsigned char *buf; /* the held work: entries */
    size_t len, cap;
    int nent;
    int sc_lo, sc_hi;   /* device slots written while held, not yet copied to the device */
    graph_slot slot[GRAPH_SLOTS];
    long tick;
    long held, direct, replays, patched, updates, instances; /* steps held and not; graphs replayed as they
                                                                * were, patched, updated, made */
};

static size_t pad16(size_t n) { return (n + 15) & ~(size_t)15; }

static void grow(unsigned char **p, size_t *cap, size_t need)
{
    if (need <= *cap) return;
    size_t c = *cap ? *cap : 4096;
    while (c < need) c *= 2;
    void *q = NULL;
    if (posix_memalign(&q, 16, c)) error_exit(1, "gpu_graph: out of host memory (%zu bytes)", c);
    if (*p) memcpy(q, *p, *cap), free(*p);
    *p = (unsigned char *)q, *cap = c;
}

void gpu_graph_init(gpu_t *g)
{
    CK(cudaMallocHost((void **)&g->sc_h, SC_SLOTS * sizeof(double)));
    g->sc_d = (double *)dev_alloc(SC_SLOTS * sizeof(double));
    g->nsc = 0;
    if (!tuning_get()->gpu_graph) return;
    g->df = (gpu_defer *)calloc(1, sizeof(gpu_defer));
    if (!g->df) error_exit(1, "gpu_graph: out of host memory");
    g->df->g = g;
}

void gpu_defer_push(gpu_thunk fn, const void *kfn, const void *args, size_t bytes)
{
    gpu_defer *d = g_defer;
    const size_t need = d->len + sizeof(held_entry) + pad16(bytes);
    grow(&d->buf, &d->cap, need);
    held_entry e = {fn, kfn, bytes, 0};
    memcpy(d->buf + d->len, &e, sizeof e);
    memset(d->buf + d->len + sizeof e, 0, pad16(bytes));
    memcpy(d->buf + d->len + sizeof e, args, bytes);
    d->len = need;
    d->nent++;
}

/* A kernel's k (<= 3) scalars v: not held, by value; held, in slots
 * k0.. of the step's device scalars, which the step's graph copies from
 * pinned memory first. A slot is written once between two synchronisations
 * of the check (gpu_scalar_reset), so a graph in flight reads what it was
 * given. */
dscal gpu_scalar(gpu_t *g, const double *v, int k)
{
    dscal r;
    memset(&r, 0, sizeof r);
    if (k == 0) return r;
    gpu_defer *d = g_defer;
    if (d && g->nsc + k > SC_SLOTS) { /* many hooks without a check between: the rest direct */
        gpu_defer_flush();
        d = NULL;
    }
    if (!d) {
        memcpy(r.v, v, (size_t)k * sizeof(double));
        return r;
    }
    const int k0 = g->nsc;
    memcpy(g->sc_h + k0, v, (size_t)k * sizeof(double));
    g->nsc += k;
    if (d->sc_hi == d->sc_lo) d->sc_lo = k0;
    d->sc_hi = g->nsc;
    r.p = g->sc_d + k0;
    return r;
}

void gpu_scalar_reset(gpu_t *g) { g->nsc = 0; }

void gpu_step_begin(sim_t *s)
{
    gpu_t *g = gpu_get(s);
    gpu_defer *d = g->df;
    if (!d || g_defer) return;
    if (s->halo || s->dem || prof.on || g->tile || g->hcsr || !g->built || g->stale || g->every) {
        d->direct++;
        return;
    }
    d->held++;
    d->sc_lo = d->sc_hi = 0;
    g_defer = d;
}

/* The held work's key: the slots to copy (r), then the entries. */
static size_t key_len(const gpu_defer *d) { return 2 * sizeof(int) + d->len; }

static void slot_drop(graph_slot *q)
{
    if (q->ex) CK(cudaGraphExecDestroy(q->ex));
    if (q->gr) CK(cudaGraphDestroy(q->gr));
    free(q->node);
    q->ex = NULL, q->gr = NULL, q->node = NULL, q->nent = 0;
}

/* The kernel node of each held entry of one launch, along the captured
 * chain (one stream: each node has one dependent): the slots' copy first
 * (r[1] > r[0]), then one node an entry, up to the first entry that is not
 * one launch (the check's reduction and read-backs). A node whose kernel is
 * not the entry's leaves the entry unmapped (its changes then update the
 * whole graph). */
static void slot_map(graph_slot *q, const gpu_defer *d, const int r[2])
{
    q->node = (cudaGraphNode_t *)calloc((size_t)d->nent + 1, sizeof(cudaGraphNode_t));
    if (!q->node) error_exit(1, "gpu_graph: out of host memory");
    q->nent = d->nent;
    size_t nroot = 1;
    cudaGraphNode_t cur = NULL;
    CK(cudaGraphGetRootNodes(q->gr, &cur, &nroot));
    if (nroot != 1) return;
    if (r[1] > r[0]) { /* the slots' copy */
        size_t nd = 1;
        cudaGraphNode_t next = NULL;
        CK(cudaGraphNodeGetDependentNodes(cur, &next, NULL, &nd));
        cur = nd == 1 ? next : NULL;
    }
    size_t o = 0;
    for (int k = 0; k < d->nent && cur; ++k) {
        held_entry e;
        memcpy(&e, d->buf + o, sizeof e);
        o += sizeof e + pad16(e.bytes);
        if (!e.kfn) break;
        cudaGraphNodeType t;
        CK(cudaGraphNodeGetType(cur, &t));
        if (t != cudaGraphNodeTypeKernel) break;
        cudaKernelNodeParams kp;
        CK(cudaGraphKernelNodeGetParams(cur, &kp));
        if (kp.func != e.kfn) break;
        q->node[k] = cur;
        size_t nd = 1;
        cudaGraphNode_t next = NULL;
        CK(cudaGraphNodeGetDependentNodes(cur, &next, NULL, &nd));
        cur = nd == 1 ? next : NULL;
    }
}

/* Slot q held work of the shape held now: give its nodes the launches'
 * new arguments where they differ. 1 if done, 0 if the shapes differ or a
 * differing entry has no node. */
static int slot_patch(gpu_defer *d, graph_slot *q, const int r[2])
{
    if (!q->ex || q->len != key_len(d) || q->nent != d->nent || memcmp(q->key, r, 2 * sizeof(int))) return 0;
    const unsigned char *a = q->key + 2 * sizeof(int), *b = d->buf;
    for (size_t o = 0; o < d->len;) { /* the same functions and sizes, and every difference in a mapped launch */
        held_entry ea, eb;
        memcpy(&ea, a + o, sizeof ea);
        memcpy(&eb, b + o, sizeof eb);
        if (ea.fn != eb.fn || ea.kfn != eb.kfn || ea.bytes != eb.bytes) return 0;
        o += sizeof ea + pad16(ea.bytes);
    }
    int k = 0;
    for (size_t o = 0; o < d->len; ++k) {
        held_entry e;
        memcpy(&e, b + o, sizeof e);
        const size_t at = o + sizeof e;
        o = at + pad16(e.bytes);
        if (!memcmp(a + at, b + at, e.bytes)) continue;
        if (!q->node[k]) return 0;
    }
    k = 0;
    for (size_t o = 0; o < d->len; ++k) {
        held_entry e;
        memcpy(&e, b + o, sizeof e);
        const size_t at = o + sizeof e;
        o = at + pad16(e.bytes);
        if (!memcmp(a + at, b + at, e.bytes)) continue;
        unsigned grid;
        memcpy(&grid, b + at + 8, sizeof grid);
        void *args[2] = {(void *)(b + at), (void *)(b + at + 16)}; /* nf_blob: n, the functor */
        cudaKernelNodeParams kp = {};
        kp.func = (void *)e.kfn;
        kp.gridDim = dim3(grid), kp.blockDim = dim3(BLOCK);
        kp.kernelParams = args;
        CK(cudaGraphExecKernelNodeSetParams(q->ex, q->node[k], &kp));
    }
    return 1;
}

static void slot_key(gpu_defer *d, graph_slot *q, const int r[2])
{
    grow(&q->key, &q->cap, key_len(d));
    memcpy(q->key, r, 2 * sizeof(int));
    memcpy(q->key + 2 * sizeof(int), d->buf, d->len);
    q->len = key_len(d);
}

void gpu_defer_flush(void)
{
    gpu_defer *d = g_defer;
    if (!d) return;
    g_defer = NULL; /* from here CK issues at once */
    gpu_t *g = d->g;
    const int r[2] = {d->sc_lo, d->sc_hi};
    d->sc_lo = d->sc_hi = 0;
    if (d->len == 0) { /* nothing held: the slots alone */
        if (r[1] > r[0])
            CK(cudaMemcpyAsync(g->sc_d + r[0], g->sc_h + r[0], (size_t)(r[1] - r[0]) * sizeof(double),
                               cudaMemcpyHostToDevice, g->st));
        return;
    }
    graph_slot *hit = NULL, *lru = &d->slot[0];
    for (int k = 0; k < GRAPH_SLOTS && !hit; ++k) {
        graph_slot *q = &d->slot[k];
        if (q->ex && q->len == key_len(d) && !memcmp(q->key, r, sizeof r) &&
            !memcmp(q->key + sizeof r, d->buf, d->len))
            hit = q, d->replays++;
        if (!q->ex || (lru->ex && q->used < lru->used)) lru = q;
    }
    for (int k = 0; k < GRAPH_SLOTS && !hit; ++k)
        if (slot_patch(d, &d->slot[k], r)) hit = &d->slot[k], d->patched++, slot_key(d, hit, r);
    if (!hit) { /* capture the held work in its order, after the slots' copy */
        cudaGraph_t gr;
        CK(cudaStreamBeginCapture(g->st, cudaStreamCaptureModeRelaxed));
        if (r[1] > r[0])
            CK(cudaMemcpyAsync(g->sc_d + r[0], g->sc_h + r[0], (size_t)(r[1] - r[0]) * sizeof(double),
                               cudaMemcpyHostToDevice, g->st));
        for (size_t o = 0; o < d->len;) {
            held_entry e;
            memcpy(&e, d->buf + o, sizeof e);
            e.fn(d->buf + o + sizeof e, g->st);
            o += sizeof e + pad16(e.bytes);
        }
        CK(cudaStreamEndCapture(g->st, &gr));
        hit = lru; /* a graph of the same shape is updated in place, if there is one */
        for (int k = 0; k < GRAPH_SLOTS; ++k) {
            graph_slot *q = &d->slot[k];
            if (q->ex && q->nent == d->nent && q->len == key_len(d)) {
                hit = q;
                break;
            }
        }
        cudaGraphExecUpdateResultInfo info;
        if (hit->ex && cudaGraphExecUpdate(hit->ex, gr, &info) == cudaSuccess) {
            d->updates++; /* its nodes stay those of the graph it was made from */
            CK(cudaGraphDestroy(gr));
        } else {
            (void)cudaGetLastError();
            slot_drop(hit);
            CK(cudaGraphInstantiate(&hit->ex, gr, 0));
            hit->gr = gr;
            slot_map(hit, d, r);
            d->instances++;
        }
        slot_key(d, hit, r);
    }
    hit->used = ++d->tick;
    d->len = 0, d->nent = 0;
    CK(cudaGraphLaunch(hit->ex, g->st));
}

void gpu_graph_report(const gpu_t *g)
{
    const gpu_defer *d = g->df;
    if (!d || d->held + d->direct == 0) return;
    message("gpu graphs: %ld of %ld steps held as a graph; %ld graphs replayed as they were, %ld with new "
            "arguments in their nodes, %ld updated, %ld made (SPHSEG_GPU_GRAPH=0: every launch direct)",
            d->held, d->held + d->direct, d->replays, d->patched, d->updates, d->instances);
}

void gpu_graph_free(gpu_t *g)
{
    gpu_defer *d = g->df;
    if (d) {
        for (int k = 0; k < GRAPH_SLOTS; ++k) {
            slot_drop(&d->slot[k]);
            free(d->slot[k].key);
        }
        free(d->buf);
        free(d);
        g->df = NULL;
    }
    if (g->sc_d) CK(cudaFree(g->sc_d));
    if (g->sc_h) CK(cudaFreeHost(g->sc_h));
}
