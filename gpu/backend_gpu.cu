/* gpu/backend_gpu.cu — the CUDA backend (struct backend, src/sim/sim.h): its
 * registration, the copies to and from the host, the end of a run; the
 * design of the whole backend (gpu/README.md lists its units).
 *
 * The particle arrays live on the device for the whole run; the host copy
 * s->p is refreshed only by to_host (snapshots, diagnostics, error reports).
 * Every kernel calls the same HD_INLINE bodies of src/physics/ as the CPU
 * backend, gather style: a particle's thread sums over its neighbours and
 * writes only its own entries, so results do not depend on thread
 * scheduling and runs are bit-identical run to run. The neighbour loops of
 * small stores run a team of 2-16 threads per particle (k_team; each lane
 * takes every T-th neighbour and team_sum adds the lanes in a fixed order).
 * Reductions (bounding box, time-step bounds, blow-up guard) are max and min
 * with CUB, exact in any order; the check takes them all in one pass, the
 * step's one host synchronisation. save_start and advance are held back and
 * run in the next prepare's motion kernel (gpu_step_kernel).
 *
 * The neighbour build mirrors src/cpu/nbr.c: the same grid (grid_fit on the same
 * bounding box; on several ranks the same global lattice), the store sorted
 * by (cell, image last, global ID) with two stable CUB radix sorts (rank,
 * then cell: CPU and GPU hold particles in the same order), cell start/end
 * from key changes, then every array gathered into a spare set of
 * buffers and the two sets swapped; then a neighbour list per particle
 * (grid_list_fill_ranked, in the cell scan's order, a cell's owned
 * particles and ghosts merged by rank) that every neighbour loop reads.
 *
 * Verlet skin: the list holds the particles within 2h + skin (skin =
 * Run:list_skin h, default 0.1 h) and is kept, with the store's order and cells, for as long as
 * no particle can have moved skin/2 since the build: gpu_check measures the
 * largest displacement since the build (D) and in the last step (d) and
 * marks the list stale when D + 2 d > skin / 2, or for every stage when
 * d > skin / 4, and for prescribed kinematics (the shear box moves up to h
 * a step: it rebuilds every stage). A build for the HCSR classification (the paper scheme, every step;
 * snapshots) uses no skin and cells of edge 2h, as the CPU does, so that the
 * classes are the CPU's; the next stage rebuilds. Between builds the order
 * of the store differs from the CPU's (which sorts every stage), so sums are
 * taken in another order: CPU and GPU agree to round-off, not bitwise. Rank
 * counts are meant to agree bitwise (tests/test_ranks_bitwise.py --backend
 * gpu): the builds fall on the same steps on any rank count (the skin test
 * on the largest displacements over all ranks, gpu_check; a build at every
 * load-balance check, relist, as a re-cut makes one), on the lattice one rank
 * would use (the halo's corner, gpu_exchange), and the team size comes from
 * the particles of all ranks (gpu_get).
 *
 * Several ranks (mpi/halo.h; one GPU per rank, or several ranks sharing
 * one): the device store holds the owned particles at [0, n) and ghosts at
 * [n, n + ng), each range sorted by cell (the sort key carries a ghost bit;
 * the view's gstart/gend are the ghost half of start/end), as on the CPU.
 * Ghosts are HALO 3 lattice cells deep (ghost_depth), so that a set made at
 * a list build still covers the 2h + 2 skin that a Verlet list needs while
 * particles move. At a build the device migrates particles and makes fresh
 * ghosts itself (gpu_exchange.cu: the decisions of mpi/halo.c through
 * mpi/halo_geom.h, bit for bit; the host sees counts), and the send and
 * receive lists follow the device sort on the device (hx_sorted);
 * SPHSEG_GPU_HOSTX=1 takes the old path through the host (the owned arrays
 * down, halo_exchange, everything back up, halo_sorted), for measuring and
 * comparing. Between builds a stage's refresh
 * packs only the fields it needs for the send lists on the device, stages
 * them through pinned host memory (or hands device buffers to a CUDA-aware
 * MPI), and unpacks them into the ghost slots on the device. The exchange
 * overlaps interior work: each particle gets a level at the build (0 ghost,
 * 1 a ghost in its list, 2 a level-1 particle in its list, 3 else), and
 * while positions, velocities, stresses and C are in flight the GPU runs
 * the dummy walls and L of levels >= 2 and the flow rates of level 3 (their
 * lists read no ghost and nothing computed from one), then the rest after
 * the ghosts arrive; likewise the shear-rate refresh overlaps the
 * concentration rates of levels >= 2. Each particle is computed by the same
 * body whatever the pass, so results do not depend on the overlap. */
#include "gpu.cuh"

int g_local_rank;
struct gpu_prof prof;
static const char *prof_name[P_NPROF] = {"save start, advance, motion", "bounding box (+sync)",
                                          "cell keys, radix sort, start/end", "permute arrays", "neighbour list",
                                          "HCSR classification", "dummy walls, renormalisation L",
                                          "flow rates (+seg. coefficients, bed weights)", "concentration rates", "Shepard filter",
                                          "dt bounds, blow-up check (+sync)", "particle shifting (a neighbour pass)",
                                          "corrected gradient's moment matrix B", "DEM grid (box +sync, sort, starts)",
                                          "DEM coupling (fraction, drag, source)", "DEM steps (contacts, motion)",
                                          "DEM exchange (ranks: read-back, MPI, upload)",
                                          "DEM ghost refreshes, sums home (ranks)",
                                          "wall friction on the particles (a neighbour pass)"};

static void gpu_to_host(sim_t *s)
{
    gpu_t *g = gpu_hook(s, 0);
    gpu_settle(s, g);
    gpu_download(s, g);
    if (s->halo) hx_resolve(g, s->halo);
    if (s->halo) halo_wrap(s->halo, &s->p); /* periodic axes: the copy written is in the period */
    if (s->dem) gpu_dem_download(s, g);
}

/* A load balance moved particles between ranks on the host: take them. */
static void gpu_from_host(sim_t *s)
{
    gpu_t *g = gpu_hook(s, 1);
    gpu_settle(s, g);
    gpu_acc_reduce(g);
    CK(cudaStreamSynchronize(g->st));
    gpu_reserve(g, s->p.n, 0);
    gpu_counts(g, s->p.n, 0);
    gpu_upload(g, &s->p, 0, s->p.n);
    g->built = 0;
}

/* Every load-balance check, on any rank count (src/run.c parallel_balance):
 * the next prepare builds the lists afresh, as after a re-cut. */
static void gpu_relist(sim_t *s)
{
    gpu_t *g = gpu_hook(s, 1);
    g->built = 0;
}

/* The memory line (issue 56; tools/bench reads it): the device's peak in
 * use during the run (cudaMemGetInfo after every allocation) less what was
 * in use before its first, over this rank's particles, and its parts a
 * particle: the store (the run's fields), the permutation's spares, the
 * neighbour list, the rest (keys, sums, halo buffers, CUB's scratch). */
static void gpu_mem_report(sim_t *s, gpu_t *g)
{
    size_t before, peak;
    gpu_mem_use(&before, &peak);
    const double n = g->n ? (double)g->n : 1.0, c = (double)g->cap / n, all = (double)(peak - before) / n;
    const double store = c * (double)part_store_bytes(&g->d), spare = c * (double)gpu_spare_bytes(&g->d),
                 list = c * (double)g->nl_cap * (double)gpu_nl_esize(g); /* 0 for the cells form */
    message("gpu memory: peak %.3f GB in use (%.3f GB before the run's first allocation), %.0f bytes a particle over "
            "%zu particles (rank 0): store %.0f (%d of %d fields), permutation spares %.0f, neighbour list %.0f, "
            "other scratch %.0f", 1e-9 * (double)peak, 1e-9 * (double)before, all, g->n, store,
            __builtin_popcount(g->d.fields), __builtin_popcount(part_fields_all()), spare, list,
            all - store - spare - list);
    (void)s;
}

static void gpu_finish(sim_t *s)
{
    gpu_t *g = (gpu_t *)s->be_data;
    if (!g) return;
    gpu_settle(s, g);
    CK(cudaStreamSynchronize(g->st));
    if (s->halo) hx_resolve(g, s->halo);
    const long steps = s->step - g->step0; /* this run's, from its checkpoint on a restart */
    message("gpu: %ld neighbour-list builds in %ld steps (Run:list_skin %.3g h: one build in %.1f steps)", g->builds,
            steps, (double)(g->skin / s->seg.k.h), g->builds ? (double)steps / (double)g->builds : 0.0);
    gpu_mem_report(s, g);
    gpu_graph_report(g);
    if (g->tile)
        message("gpu: SPHSEG_GPU_NBR tile: %ld flow passes staged, %ld run as list16's (a tile past the shared "
                "memory); the last build's largest tile %u particles", g->tile_passes, g->tile_over_passes,
                g->tile_need);
    if (prof.on) {
        double tot = 0;
        for (int k = 0; k < P_NPROF; ++k) tot += prof.ms[k];
        message("gpu profile (SPHSEG_GPU_PROFILE, synchronised stages), %ld steps, %zu particles:", steps, g->n);
        for (int k = 0; k < P_NPROF; ++k)
            if (prof.calls[k])
                message("  %-38s %10.2f ms %5.1f %%  %9.4f ms/step", prof_name[k], prof.ms[k],
                        tot > 0 ? 100 * prof.ms[k] / tot : 0.0, steps ? prof.ms[k] / (double)steps : 0.0);
        message("  %-38s %10.2f ms; %ld neighbour-list builds", "total", tot, g->builds);
    }
    if (g->hx) {
        dhalo *x = g->hx;
        message("gpu halo (rank %d): %ld exchanges at list builds (%.3f s, %s), %ld refreshes, %zu ghosts, "
                "%.3f s of halo on the device timeline (exposed)", s->halo->rank, x->full, x->full_s,
                x->dev ? "device" : "host", x->refresh, g->ng, s->halo->wall_exposed);
        if (x->dev && x->full > 1) {
            double k = 1e3 / (double)(x->full - 1);
            message("gpu halo (rank %d): the first exchange at a build %.1f ms (it allocates), the %ld others %.1f ms "
                    "each: origin %.2f, migrants chosen %.2f, moved %.2f, ghosts chosen %.2f, sent %.2f ms",
                    s->halo->rank, 1e3 * x->first_s, x->full - 1, (x->full_s - x->first_s) * k, x->ph[0] * k,
                    x->ph[1] * k, x->ph[2] * k, x->ph[3] * k, x->ph[4] * k);
        }
        void *db[] = {x->sidx, x->ridx, x->dsend, x->drecv, x->gbound, x->gpart, x->gnb, x->cnt, x->off,
                      x->pk, x->pk2, x->pv, x->keep, x->inv, x->dcnt, x->derr};
        for (size_t k = 0; k < sizeof db / sizeof db[0]; ++k)
            if (db[k]) CK(cudaFree(db[k]));
        if (x->hsend) CK(cudaFreeHost(x->hsend));
        if (x->hrecv) CK(cudaFreeHost(x->hrecv));
        if (x->hcnt) CK(cudaFreeHost(x->hcnt));
        if (x->herr) CK(cudaFreeHost(x->herr));
        free(x->sbound), free(x->spart), free(x->snb);
        ipc_free(x);
        for (int k = 0; k < HX_EV; ++k) CK(cudaEventDestroy(x->ev[k]));
        free(x->soff), free(x->roff), free(x->sb), free(x->rb), free(x);
    }
    gpu_dem_free(g);
    for (size_t k = 0; k < part_narrays(); ++k) CK(cudaFree(part_array_get(&g->d, k))); /* NULL: not held */
    for (int c = 0; c < PSCR_N; ++c) CK(cudaFree(g->pscr[c]));
    CK(cudaFree(g->tile_dmax));
    void *bufs[] = {g->start, g->end, g->cell_mat, g->cell_type, g->key, g->key2, g->idx, g->idx2,
                    g->cls, g->sums, g->nl, g->ncnt, g->amag, g->tmp, g->dbox, g->dres, g->dfirst,
                    g->dchk, g->dstep, g->xb[0], g->xb[1], g->xb[2], g->lvl, g->wact};
    for (size_t k = 0; k < sizeof bufs / sizeof bufs[0]; ++k)
        if (bufs[k]) CK(cudaFree(bufs[k]));
    CK(cudaFreeHost(g->hbox));
    CK(cudaFreeHost(g->hres));
    CK(cudaFreeHost(g->hfirst));
    CK(cudaFreeHost(g->hchk));
    free(g->hstep);
    gpu_graph_free(g);
    CK(cudaStreamDestroy(g->st));
    free(g);
    s->be_data = NULL;
}

extern "C" const struct backend *backend_gpu(int local_rank)
{
    static const struct backend b = {"gpu",          gpu_prepare,    gpu_rates,  gpu_advance, gpu_conc_begin,
                                      gpu_conc_step,  gpu_save_start, gpu_filter, gpu_bounds,  gpu_check,
                                      gpu_to_host,    gpu_finish,     gpu_from_host, 3,
                                      gpu_relist,     gpu_dem_hook,   gpu_dem_advance, gpu_step_begin,
                                      0 /* ghosts kept in every run */};
    g_local_rank = local_rank;
    return &b;
}
