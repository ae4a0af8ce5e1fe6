/* gpu/gpu_nbr.cu — the neighbour pass's build: the cells (bounding box,
 * keys, CUB radix sort, cell ranges), the staging of the store in cell order
 * (the permutation into the spare set; the halo lists follow), the Verlet
 * lists with their skin, and what the new lists mark (the dummies out of
 * reach, the halo levels). The pair loops that read the lists are in
 * gpu_pairs.cu. */
#include <cub/device/device_radix_sort.cuh>
#include "gpu_reduce.cuh"

/* ---- the neighbour build ------------------------------------------------- */

/* A particle's rank in its cell, as the CPU's (src/cpu/nbr.c nbr_rank): bit
 * 31 for a periodic image (outside the period along a periodic axis), the
 * global ID below (IDs under 2^31). */
struct rank_of {
    particles_t p;
    int per;
    double lo[3], hi[3];
    __device__ unsigned operator()(size_t i) const
    {
        unsigned img = 0;
        for (int d = 0; d < 3; ++d)
            if (per >> d & 1) img |= (double)p.x[d][i] < lo[d] || (double)p.x[d][i] >= hi[d];
        return ((unsigned)p.id[i] & 0x7fffffffu) | img << 31;
    }
};

static rank_of rank_fn(const gpu_t *g, const halo_t *hl)
{
    rank_of f;
    f.p = g->d;
    f.per = hl ? hl->per : 0;
    for (int d = 0; d < 3; ++d) {
        f.lo[d] = hl ? (double)hl->plo[d] : 0;
        f.hi[d] = hl ? f.lo[d] + (double)hl->plen[d] : 0;
    }
    return f;
}

template <typename T> __global__ void k_gather(T *__restrict__ dst, const T *__restrict__ src,
                                               const unsigned *__restrict__ perm, size_t n)
{
    size_t k = (size_t)blockIdx.x * blockDim.x + threadIdx.x;
    if (k < n) dst[k] = src[perm[k]];
}

/* The spare slot of an element size (gpu.cuh PSCR_). */
int pscr_slot(size_t es)
{
    if (es == 8) return PSCR_8;
    if (es == 4) return PSCR_4;
    if (es == 1) return PSCR_1;
    error_exit(1, "backend_gpu: a particle array of %zu-byte elements: the permutation has spares of 8, 4 and 1",
               es);
    return -1;
}

/* The store gathered by perm (perm[k] = old index now at k, over n; the
 * build's sort, the kept particles of a migration), array by array: each
 * into the spare of its element size, which then takes its place, the old
 * array becoming the spare. A spare of 8, 4 and 1 bytes a particle, not a
 * second store (issue 56); an array the store does not hold is skipped. */
void gpu_permute(gpu_t *g, const unsigned *perm, size_t n)
{
    if (!n) return;
    const unsigned grid = (unsigned)((n + 255) / 256);
    for (size_t k = 0; k < part_narrays(); ++k) {
        void *a = part_array_get(&g->d, k);
        if (!a) continue;
        const size_t es = part_array_esize(k);
        void *&spare = g->pscr[pscr_slot(es)];
        if (es == 8) k_gather<<<grid, 256, 0, g->st>>>((uint64_t *)spare, (const uint64_t *)a, perm, n);
        else if (es == 4) k_gather<<<grid, 256, 0, g->st>>>((uint32_t *)spare, (const uint32_t *)a, perm, n);
        else k_gather<<<grid, 256, 0, g->st>>>((uint8_t *)spare, (const uint8_t *)a, perm, n);
        CK(cudaGetLastError());
        part_array_set(&g->d, k, spare);
        spare = a;
    }
}

/* The halo lists follow the particles through the sort (perm[k] = old
 * index now at k, over n): on the device, or through the host. */
static void gpu_follow(gpu_t *g, halo_t *hl, const unsigned *perm, size_t n)
{
    if (hl && g->hx->dev) hx_sorted(g, perm, n); /* the halo lists follow the particles, on the device */
    else if (hl) { /* through the host */
        unsigned *hp = (unsigned *)malloc((n ? n : 1) * sizeof(unsigned));
        size_t *pz = (size_t *)malloc((n ? n : 1) * sizeof(size_t));
        if (!hp || !pz) error_exit(1, "out of memory (%zu particles)", n);
        CK(cudaMemcpyAsync(hp, perm, n * sizeof(unsigned), cudaMemcpyDeviceToHost, g->st));
        CK(cudaStreamSynchronize(g->st));
        for (size_t k = 0; k < n; ++k) pz[k] = hp[k];
        halo_sorted(hl, pz, n);
        free(hp), free(pz);
    }
}

/* The store permuted by the sort and the view's cell ranges set. */
static void gpu_permute_store(gpu_t *g, const unsigned *perm, size_t n)
{
    prof_begin(g->st);
    gpu_permute(g, perm, n);
    prof_end(g->st, P_PERMUTE);
    g->view.start = g->start;
    g->view.end = g->end;
    g->view.gstart = g->ng ? g->start + g->ncell : NULL;
    g->view.gend = g->ng ? g->end + g->ncell : NULL;
}

/* The Verlet list of every particle within sqrt(list2), from the cell scan in
 * its order, a cell's owned particles and ghosts merged by their ranks rk
 * (grid_list_fill_ranked: cells of 2h + skin on several ranks hold both);
 * the positions at the build (xb) kept for the Verlet test. In the list's
 * form (g->nbr_form): 4-byte entries, 2-byte ones (grid_enc16; a cell past
 * their offsets takes this build to the cells form), or none (the cells
 * form: the pair loops count the same particles from the cells, xb and rk). */
static void gpu_list(gpu_t *g, int dim, real list2, size_t n, const unsigned *rk)
{
    grid_view vc = g->view;
    vc.nl = vc.ncnt = NULL;
    vc.nl16 = NULL;
    vc.form = GRID_NBR_LIST;
    particles_t q = g->d;
    unsigned *cnt = g->ncnt;
    int form = g->nbr_form;
    prof_begin(g->st);
    /* The list's width is the largest count + 1/16, rounded up to 8: the first
     * build counts (width 0: nothing written) and allocates; a list too short
     * for the densest particle grows, once in a while (a compacting bed), and
     * never shrinks. The setup's estimate (grid_list_est) only chooses the
     * form. On the 1.1e7 3D drum (single) the width is 144, where the
     * estimate it was allocated at before (grid_list_cap, 30 % + 8) was 184:
     * 932 bytes a particle with the 4-byte list, 644 with list16, against
     * 1 092 and 724, at the same rate and bits (docs/performance.md). */
    while (form != GRID_NBR_CELLS) {
        unsigned *nl = form == GRID_NBR_LIST ? g->nl : NULL, cap = g->nl_cap;
        unsigned short *nl16 = form == GRID_NBR_LIST16 ? (unsigned short *)g->nl : NULL;
        each(g, n, [=] __device__(size_t i) {
            cnt[i] = grid_list_fill_form(&vc, q.x, i, list2, nl, nl16, n, cap, rk);
        });
        reduce(g, cnt, (unsigned *)g->dfirst, n, max_uint(), 0u);
        CK(cudaMemcpyAsync(g->hfirst, g->dfirst, sizeof(long long), cudaMemcpyDeviceToHost, g->st));
        CK(cudaStreamSynchronize(g->st));
        unsigned most;
        memcpy(&most, g->hfirst, sizeof most);
        if (form == GRID_NBR_LIST16 && most == GRID_ENC16_OVER) {
            static int told;
            if (!told++)
                message("gpu: a cell holds more than %u particles, past the 16-bit list's offsets: the cells form "
                        "for such builds (the same sums)", GRID_ENC16_OFF + 1);
            form = GRID_NBR_CELLS;
            break;
        }
        if (most <= cap) break;
        if (g->nl) CK(cudaFree(g->nl));
        g->nl_cap = grid_list_width(most);
        g->nl = (unsigned *)dev_alloc(g->cap * g->nl_cap * gpu_nl_esize(g));
    }
    for (int d = 0; d < dim; ++d)
        CK(cudaMemcpyAsync(g->xb[d], q.x[d], n * sizeof(real), cudaMemcpyDeviceToDevice, g->st));
    prof_end(g->st, P_LIST);
    g->view.form = form;
    g->view.nl = form == GRID_NBR_LIST ? g->nl : NULL;
    g->view.nl16 = form == GRID_NBR_LIST16 ? (const unsigned short *)g->nl : NULL;
    g->view.ncnt = form == GRID_NBR_CELLS ? NULL : cnt;
    g->view.nl_stride = n;
    g->view.nl_cap = g->nl_cap;
    for (int d = 0; d < 3; ++d) g->view.xb[d] = g->xb[d];
    g->view.rk = rk;
    g->view.list2 = list2;
    if (g->tile && form == GRID_NBR_LIST16) gpu_tile_need(g);
}

/* From the new list: the dummies no material reaches (wact) and the halo
 * levels (backend_gpu.cu, at the top). */
static void gpu_marks(gpu_t *g, size_t n, size_t nown)
{
    particles_t q = g->d;
    if (g->wact) { /* dummies that no material reaches until the next build (the list's skin) */
        uint8_t *wa = g->wact;
        grid_view vw = g->view;
        each(g, n, [=] __device__(size_t i) {
            particles_t pq = q;
            wa[i] = (uint8_t)(q.kind[i] == KIND_DUMMY && flow_wall_reached(i, &pq, &vw));
        });
    }
    if (g->lvl) { /* halo levels (backend_gpu.cu, at the top) from the new list */
        uint8_t *lvl = g->lvl;
        grid_view vl = g->view;
        each(g, n, [=] __device__(size_t i) { lvl[i] = i >= nown ? 0 : 3; });
        each(g, nown, [=] __device__(size_t i) {
            int ghost = 0;
            NBR_BEGIN(&vl, q.x, i, j)
                ghost |= j >= nown;
            NBR_END
            if (ghost) lvl[i] = 1;
        });
        each(g, nown, [=] __device__(size_t i) {
            if (lvl[i] != 3) return;
            int near = 0;
            NBR_BEGIN(&vl, q.x, i, j)
                near |= lvl[j] == 1;
            NBR_END
            if (near) lvl[i] = 2;
        });
    }
}

/* Cells of edge `support` over owned particles and ghosts, each range
 * sorted apart (a ghost bit above the cell index), each cell in the CPU's
 * canonical order (images last, each part by ID), on the global lattice
 * when origin is given (multi-rank exact builds: HCSR cell types as on one
 * rank); the list of the particles within sqrt(list2). With ghosts, the
 * permutation goes back to the halo lists (halo_sorted). */
void gpu_build(gpu_t *g, halo_t *hl, int dim, real support, real list2, const real *origin)
{
    g->builds++;
    const size_t n = g->n + g->ng, nown = g->n;
    particles_t p = g->d;
    box init;
    for (int d = 0; d < 3; ++d) init.lo[d] = R(INFINITY), init.hi[d] = -R(INFINITY);
    prof_begin(g->st);
    auto bx = thrust::make_transform_iterator(thrust::counting_iterator<size_t>(0), box_of{p});
    reduce(g, bx, g->dbox, n, box_merge(), init);
    CK(cudaMemcpyAsync(g->hbox, g->dbox, sizeof(box), cudaMemcpyDeviceToHost, g->st));
    CK(cudaStreamSynchronize(g->st));
    prof_end(g->st, P_BBOX);
    g->ncell = origin ? grid_fit_lattice(&g->view, dim, n, origin, g->hbox->lo, g->hbox->hi, support)
                      : grid_fit(&g->view, dim, n, g->hbox->lo, g->hbox->hi, support);
    if (2 * g->ncell >= 0xffffffffu)
        error_exit(EXIT_NUMERICAL, "the particles spread over %zu cells of edge 2h (more than 2^31): a particle "
                   "flew far from the rest", g->ncell);
    if (g->ncell > g->cap_cell) {
        if (g->start) {
            CK(cudaFree(g->start));
            CK(cudaFree(g->end));
            CK(cudaFree(g->cell_mat));
            CK(cudaFree(g->cell_type));
        }
        g->cap_cell = g->ncell + g->ncell / 4;
        g->start = (size_t *)dev_alloc(2 * g->cap_cell * sizeof(size_t)); /* owned, then ghost cells */
        g->end = (size_t *)dev_alloc(2 * g->cap_cell * sizeof(size_t));
        g->cell_mat = (size_t *)dev_alloc(g->cap_cell * sizeof(size_t));
        g->cell_type = (unsigned char *)dev_alloc(g->cap_cell);
    }
    grid_view v = g->view;
    const unsigned gbit = (unsigned)g->ncell;
    prof_begin(g->st);
    /* The order of a cell's particles is canonical, as on the CPU
     * (src/cpu/nbr.c nbr_rank): periodic images last, each part in global
     * ID order, whatever the store's order before, so that the lists, and
     * every sum over them, meet a particle's neighbours in the same order on
     * any rank count: a stable sort by that rank (bit 31 the image, the ID
     * below: IDs under 2^31), then a stable sort by cell of that order. */
    {
        unsigned *key = g->key, *idx = g->idx;
        const rank_of rk = rank_fn(g, hl);
        each(g, n, [=] __device__(size_t i) {
            key[i] = rk(i);
            idx[i] = (unsigned)i;
        });
    }
    cub::DoubleBuffer<unsigned> kb(g->key, g->key2), vb(g->idx, g->idx2);
    size_t bytes = 0;
    CK(cub::DeviceRadixSort::SortPairs(NULL, bytes, kb, vb, (int64_t)n, 0, 32, g->st));
    CK(cub::DeviceRadixSort::SortPairs(scratch(g, bytes), bytes, kb, vb, (int64_t)n, 0, 32, g->st));
    {
        unsigned *key = kb.Alternate();
        const unsigned *ord = vb.Current();
        each(g, n, [=] __device__(size_t k) {
            const size_t i = ord[k];
            int c[3];
            grid_cell_coords(&v, p.x[0], p.x[1], p.x[2], i, c);
            key[k] = (unsigned)grid_cell_index(&v, c[0], c[1], c[2]) + (i >= nown ? gbit : 0u);
        });
    }
    kb.selector ^= 1; /* the cell keys (in ID order) are the keys now */
    const size_t nkey = g->ng ? 2 * g->ncell : g->ncell;
    int bits = 1;
    while (bits < 32 && ((size_t)1 << bits) < nkey) ++bits;
    bytes = 0;
    CK(cub::DeviceRadixSort::SortPairs(NULL, bytes, kb, vb, (int64_t)n, 0, bits, g->st));
    CK(cub::DeviceRadixSort::SortPairs(scratch(g, bytes), bytes, kb, vb, (int64_t)n, 0, bits, g->st));
    const unsigned *sk = kb.Current(), *perm = vb.Current();
    size_t *start = g->start, *end = g->end;
    CK(cudaMemsetAsync(start, 0, nkey * sizeof(size_t), g->st));
    CK(cudaMemsetAsync(end, 0, nkey * sizeof(size_t), g->st));
    each(g, n, [=] __device__(size_t k) {
        unsigned c = sk[k];
        if (k == 0 || sk[k - 1] != c) start[c] = k;
        if (k == n - 1 || sk[k + 1] != c) end[c] = k + 1;
    });
    prof_end(g->st, P_SORT);
    gpu_follow(g, hl, perm, n);
    gpu_permute_store(g, perm, n);
    { /* the ranks in the new order, for the lists' merged walk of a cell */
        unsigned *key = g->key;
        const rank_of rk = rank_fn(g, hl);
        each(g, n, [=] __device__(size_t i) { key[i] = rk(i); });
    }
    gpu_list(g, dim, list2, n, g->key);
    gpu_marks(g, n, nown);
}
