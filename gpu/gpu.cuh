/* gpu/gpu.cuh — the CUDA backend's private header, included by each unit of gpu/
 * (compiled apart, without relocatable device code: every kernel lives in
 * the unit that launches it; templates and __device__ inline helpers here).
 * The CUDA backend's types: the CK error check, sizes and limits, the
 * permutation and refresh tables, the pass selections, the device halo
 * state, gpu_t (the device store, the cell and neighbour lists, the pending
 * stages), the per-stage profiler (SPHSEG_GPU_PROFILE); the launches and
 * the reductions' functors (gpu_launch.cuh; reduce itself, with CUB, in
 * gpu_reduce.cuh); the functions one unit calls in another, by the unit
 * that defines them. */
#ifndef SPHSEG_GPU_CUH
#define SPHSEG_GPU_CUH

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <cuda_runtime.h>
extern "C" {
#include "core/error.h"
#include "core/tuning.h"
#include "mpi/comm.h"
#include "physics/bound_kern.h"
#include "sim/sim.h"
#include "sim/stages.h"
}

/* The deferred step (gpu_graph.cu): while a step's work is held for its
 * graph (g_defer non-NULL), a CUDA call that is not held (CK) first issues
 * what is, so that the stream keeps the order the code wrote. */
struct gpu_defer;
extern struct gpu_defer *g_defer;
void gpu_defer_flush(void);

#define CK(call)                                                                                     \
    do {                                                                                             \
        if (g_defer) gpu_defer_flush();                                                              \
        cudaError_t e_ = (call);                                                                     \
        if (e_ != cudaSuccess)                                                                       \
            error_exit(1, "CUDA error at %s:%d: %s (%s)", __FILE__, __LINE__, cudaGetErrorString(e_), \
                       #call);                                                                       \
    } while (0)

/* The migration tables hold every per-particle array of the field table
 * (core/fields.h): sized from it, so a new field needs no edit here. */
enum { PERM_MAX = PART_NARRAYS, BLOCK = 128 };
/* The permutation's spare arrays, one per element size (gpu_permute). */
enum { PSCR_8, PSCR_4, PSCR_1, PSCR_N };
#define GPU_TEAM_MAX_2D 4 /* threads per particle in the neighbour loops (gpu_team_size) */
#define GPU_TEAM_MAX_3D 8
#define GPU_TEAM_MIN_3D 2 /* the fewest in 3D, however large the store (gpu_team_size) */
#define GPU_TEAM_THREADS 2097152.0
/* The store of a rank (owned and ghosts) from which the flow pass reads the bed damping's weights
 * made once a particle (gpu_bed_q) rather than computing them per pair, in 3D and in 2D: below it
 * the extra kernel costs more than the pairs save (one H200, single: 3D 1.02x at 2.4e5 particles,
 * 1.05x at 1.1e7; 2D, a quarter of the pairs a particle, 0.94-0.96x at 1.1e4, 0.98-1.00x at 1.6e5,
 * 1.01x at 6.2e5; docs/gpu.md, "The flow pass's code") */
#define GPU_BEDQ_MIN_3D 2e5
#define GPU_BEDQ_MIN_2D 5e5


struct box {
    real lo[3], hi[3];
};

/* Fields of a ghost refresh: device array and element size. */
enum { FT_MAX = PERM_MAX }; /* a migration carries every array */
struct ftab {
    int n;
    unsigned char es[FT_MAX];
    void *p[FT_MAX];
};

/* Which particles a kernel pass runs on: all (lvl NULL), or those whose
 * halo level (0 ghost, 1..3 owned; backend_gpu.cu, at the top) lies in [lo, hi]. */
struct sel {
    const uint8_t *lvl;
    uint8_t lo, hi;
};
__device__ __forceinline__ bool sel_on(const sel &s, size_t i)
{
    return !s.lvl || (s.lvl[i] >= s.lo && s.lvl[i] <= s.hi);
}

/* Halo state of a multi-rank run on the device. */
enum { HX_EV = 64 };
/* The phases of a device exchange at a build, timed at points where the host waits anyway
 * (gpu_exchange.cu): the origin; the migrants chosen and counted; moved (sent, the store
 * compacted, received); the ghosts chosen and counted; their fields sent and received. */
enum { HX_PHASES = 5 };
struct dhalo {
    unsigned *sidx, *ridx;       /* send lists (neighbour order), ghost slots of the received */
    size_t cap_s, cap_r;
    size_t *soff, *roff;         /* entry offsets per neighbour (host, nnb + 1) */
    size_t *sb, *rb;             /* byte offsets of the current refresh (host, nnb + 1) */
    int cap_nb;
    char *dsend, *drecv, *hsend, *hrecv; /* device and pinned host buffers */
    size_t cap_dsend, cap_drecv, cap_hsend, cap_hrecv;
    int cuda_aware;
    int overlap;                 /* SPHSEG_GPU_OVERLAP=0 turns the overlap off (for measuring it) */
    int pending;                 /* a refresh is in flight (gpu_settle completes it) */
    int pend_walls, pend_renorm, pend_kgc; /* boundary passes to run when it lands */
    ftab pend;
    cudaEvent_t ev[HX_EV];       /* pairs (start, end) of GPU time spent on the halo */
    int nev;
    long full, refresh;          /* exchanges at builds; refreshes */
    double full_s;               /* host seconds in the exchanges at builds */
    double first_s;              /* of which the first (it allocates the exchange's buffers) */
    double ph[HX_PHASES];        /* the device exchange's phases after the first, host seconds summed */
    double tmark[HX_PHASES + 1]; /* the current exchange's phase boundaries (now()) */
    int dev;                     /* exchanges at builds on the device (gpu_exchange.cu); 0: through the
                                  * host (SPHSEG_GPU_HOSTX=1) */
    int nnb;                     /* channels of the lists held */
    /* the device exchange: the decomposition's arrays (and host shadows), per-particle counts and
     * offsets, the (channel, particle) pairs, the kept order, the sort's inverse, channel counts */
    long *gbound;
    int *gpart, *gnb;
    void *sbound, *spart, *snb;
    size_t cap_gbound, cap_gpart, cap_gnb;
    unsigned *cnt, *off, *pk, *pk2, *pv, *keep, *inv;
    size_t cap_cnt, cap_off, cap_pk, cap_pk2, cap_pv, cap_keep, cap_inv;
    unsigned long long *dcnt, *hcnt;
    size_t cap_hcnt;
    int *derr, *herr;
    /* CUDA IPC channels (gpu_ipc.cu): which, for which channel set; two send buffers used in turn,
     * their handles and generations; the peers' descriptors and mapped buffers; the receive buffer;
     * the per-channel byte offsets of the IPC segments (host, nnb + 1) */
    int *ipc, nipc, ipc_par, ipc_said;
    long ipc_gen;
    char *ipc_buf[2], **ipc_old; /* the send buffers, and those replaced when they grew */
    int nold;
    size_t ipc_cap[2];
    cudaIpcMemHandle_t ipc_handle[2];
    long long ipc_bgen[2], ipc_count;
    struct ipc_desc *ipc_in;
    struct ipc_map *map;
    int nmap;
    char *dripc;
    size_t cap_dripc;
    size_t *ib, *irb;
};

typedef struct gpu {
    int dev;
    cudaStream_t st;
    particles_t d;      /* device arrays: the fields the host store holds (s->p.fields), the others NULL */
    void *pscr[PSCR_N]; /* the permutation's spare array of each element size (8, 4, 1 bytes; NULL: none
                         * of that size), cap elements: gpu_permute gathers into it and swaps */
    size_t n, ng, cap;  /* owned particles, ghosts (at [n, n + ng)), allocated */
    uint8_t *lvl;       /* halo level of each particle (several ranks), else NULL */
    uint8_t *wact;      /* a dummy with material in its list (gpu_build); NULL: every dummy
                         * runs its loop (SPHSEG_GPU_WALLSKIP=0, for measuring the skip) */
    int wskip;
    int hcsr;           /* s->hcsr: the classification runs every step (g->sums kept) */
    struct dhalo *hx;   /* several ranks, else NULL */
    grid_view view;     /* start/end point to device memory */
    size_t *start, *end, ncell, cap_cell;
    unsigned *key, *key2, *idx, *idx2;
    unsigned char *cell_type, *cls;
    size_t *cell_mat;
    bound_sums *sums;   /* the classification's support sums between its two sweeps, where it runs every
                         * step (the HCSR schemes, s->hcsr); NULL otherwise: the second sweep gathers
                         * them again (gpu_classify; a snapshot's classes, the conservative scheme) */
    unsigned *nl, *ncnt, nl_cap; /* neighbour list (grid_view), rebuilt with the cells; nl_cap entries a
                         * particle: 0 until the first build, then the largest count + 1/16 (gpu_list) */
    unsigned nl_est;    /* the setup's estimate of nl_cap (grid_list_est): the form's choice, gpu_form_fits */
    int nbr_form;       /* the list's form (GRID_NBR_*, SPHSEG_GPU_NBR): nl holds 4-byte entries, 2-byte
                         * ones (list16), or is NULL (cells) */
    int tile;           /* SPHSEG_GPU_NBR=tile: list16, its flow pass staged cell by cell in shared memory
                         * (gpu_pairs.cu, k_flow_tile) */
    unsigned *tile_dmax; /* gpu_tile_need's device maximum (NULL without tile) */
    unsigned tile_need; /* the build's largest tile (particles), gpu_tile_need */
    long tile_passes, tile_over_passes; /* the staged passes, and those run as list16's (a tile too large) */
    real *xb[3];        /* positions at the last build */
    real skin;          /* m */
    int built, stale, every; /* the list: exists; must be rebuilt; rebuild every stage */
    long builds;
    long step0;         /* s->step when this backend started: a restart counts its own steps */
    real *amag;         /* |acc| of the last flow rate evaluation */
    const real *bq;     /* Flow:bed_damping's weights of the flow pass under way (gpu_bed_q; in a spare), or NULL */
    int acc_pending;    /* amag not yet reduced into dres[STEP_ACC] (gpu_acc_reduce, gpu_check) */
    int pend_save, pend_adv; /* save_start and advance held back for the next kernel (gpu_step_kernel) */
    double pend_a, pend_w; /* its lengths (gpu_advance's a and w) */
    flow_ctx pend_fc;
    int team;           /* threads per particle in the neighbour loops: 1, 2, 4, 8 or 16 */
    void *tmp;          /* CUB scratch */
    size_t tmp_bytes;
    struct box *dbox;   /* device results */
    double *dres;       /* [STEP_NBOUNDS]: D, wave, speed, acc */
    long long *dfirst;  /* also the list-length maximum */
    struct chkb *dchk, *hchk;
    step_ctx *dstep, *hstep; /* the reductions' step_ctx on the device (gpu_step_ctx) and the copy last sent */
    int bnd_fresh;      /* hres[0..2] hold the bounds of the current store (gpu_check) */
    struct box *hbox;   /* pinned host copies */
    double *hres;
    long long *hfirst;
    struct gpu_dem *dem; /* the DEM grains' device mirror (gpu_dem.cu), made at its first hook; NULL without grains */
    struct gpu_defer *df; /* the step's graphs (gpu_graph.cu); NULL: every launch direct (SPHSEG_GPU_GRAPH=0) */
    double *sc_h, *sc_d; /* the step's scalars (gpu_scalar): pinned host slots and their device copies */
    int nsc;            /* slots in use since the last synchronisation of the check */
} gpu_t;

extern int g_local_rank; /* backend_gpu(local_rank) (backend_gpu.cu) */

/* Stage timing (SPHSEG_GPU_PROFILE=1 in the environment): events around each
 * stage with a synchronisation after it, so the stages do not overlap and
 * the total runs slower than without; a table at the end of the run
 * (gpu_finish; the state is defined in backend_gpu.cu). */
enum { P_MOTION, P_BBOX, P_SORT, P_PERMUTE, P_LIST, P_CLASSIFY, P_WALLS, P_FLOW, P_SEG, P_FILTER, P_BOUNDS_CHECK,
       P_SHIFT, P_KGC, P_DEM_GRID, P_DEM_COUPLE, P_DEM_STEP, P_DEM_XCHG, P_DEM_REFRESH, P_CONTACT, P_NPROF };
struct gpu_prof {
    int on;
    cudaEvent_t a, b;
    double ms[P_NPROF];
    long calls[P_NPROF];
};
extern struct gpu_prof prof;

static inline void prof_begin(cudaStream_t st)
{
    if (prof.on) CK(cudaEventRecord(prof.a, st));
}
static inline void prof_end(cudaStream_t st, int k)
{
    if (!prof.on) return;
    CK(cudaEventRecord(prof.b, st));
    CK(cudaEventSynchronize(prof.b));
    float ms;
    CK(cudaEventElapsedTime(&ms, prof.a, prof.b));
    prof.ms[k] += ms;
    prof.calls[k]++;
}

static inline double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* A stage of host work (the DEM grains' exchanges on several ranks: their
 * read-backs, MPI and uploads), timed on the host's clock from t0. */
static inline void prof_host(int k, double t0)
{
    if (!prof.on) return;
    prof.ms[k] += 1e3 * (now() - t0);
    prof.calls[k]++;
}

/* Pass selections: everything (one rank, or right after a build), the
 * particles whose support reads no ghost data (level >= lo), the rest. */
static inline sel sel_all(void) { return sel{NULL, 0, 0}; }
static inline sel sel_in(const gpu_t *g, int lo) { return g->lvl ? sel{g->lvl, (uint8_t)lo, 3} : sel_all(); }
static inline sel sel_bd(const gpu_t *g, int lo) { return sel{g->lvl, 0, (uint8_t)(lo - 1)}; }

/* ---- set-up (gpu_setup.cu) ----------------------------------------------- */
void *dev_alloc(size_t bytes);
void *scratch(gpu_t *g, size_t bytes);
/* Bytes of one list entry in the list's form (0: no list). */
static inline size_t gpu_nl_esize(const gpu_t *g)
{
    return g->nbr_form == GRID_NBR_LIST ? sizeof(unsigned) : g->nbr_form == GRID_NBR_LIST16 ? sizeof(unsigned short) : 0;
}
void gpu_reserve(gpu_t *g, size_t need, size_t keep);
void gpu_upload(gpu_t *g, const particles_t *h, size_t a, size_t b);
void gpu_counts(gpu_t *g, size_t n, size_t ng);
gpu_t *gpu_get(sim_t *s);
gpu_t *gpu_hook(sim_t *s, int mut);
const step_ctx *gpu_step_ctx(sim_t *s, gpu_t *g);

/* ---- the step's graphs (gpu_graph.cu) ------------------------------------ */
/* Work held for a graph: a function that issues it on a stream, and its
 * arguments, bytes that gpu_defer_push copies (a graph is replayed when a
 * step holds the same functions with the same bytes as one before); kfn,
 * where the function is one launch of kernel kfn with the arguments (size_t
 * n at byte 0, the grid at 8, the functor at 16: nf_blob), lets a graph
 * take new arguments in place of the node's own. */
typedef void (*gpu_thunk)(const void *args, cudaStream_t st);
void gpu_defer_push(gpu_thunk fn, const void *kfn, const void *args, size_t bytes);
void gpu_graph_init(gpu_t *g);
void gpu_graph_free(gpu_t *g);
void gpu_graph_report(const gpu_t *g);
void gpu_step_begin(sim_t *s);
/* Up to three of a kernel's scalars that change from step to step (the
 * step's time and lengths): while a step is held, read from device slots
 * that the graph fills first (p), so that the arguments repeat; else by
 * value (v), as a direct launch takes them. The same values either way. */
struct dscal {
    const double *p;
    double v[3];
    __host__ __device__ double at(int i) const { return p ? p[i] : v[i]; }
};
dscal gpu_scalar(gpu_t *g, const double *v, int k);
void gpu_scalar_reset(gpu_t *g);

#include "gpu_launch.cuh"

/* ---- the neighbour pass: build (gpu_nbr.cu), pair loops (gpu_pairs.cu) --- */
void gpu_permute(gpu_t *g, const unsigned *perm, size_t n);
int pscr_slot(size_t es);
/* Device memory in use (cudaMemGetInfo) at the first allocation and at its
 * peak, sampled after every dev_alloc (usage grows only there). */
void gpu_mem_use(size_t *before, size_t *peak);
size_t gpu_spare_bytes(const particles_t *p);
void gpu_build(gpu_t *g, halo_t *hl, int dim, real support, real list2, const real *origin);
void gpu_classify(gpu_t *g, const sph_ctx *kc);
void gpu_walls_renorm(sim_t *s, gpu_t *g, int walls, int renorm, int kgc, sel sl);
void gpu_flow_rates(sim_t *s, gpu_t *g, sel sl);
void gpu_tile_need(gpu_t *g);
void gpu_dcdt(sim_t *s, gpu_t *g, particles_t p, sel sl);
void gpu_shift_pass(sim_t *s, gpu_t *g);
void gpu_contact_pass(sim_t *s, gpu_t *g);
void gpu_shepard_pass(sim_t *s, gpu_t *g);
void gpu_win_renorm(sim_t *s, gpu_t *g);

/* ---- ghosts on several ranks (gpu_halo.cu) ------------------------------- */
int hx_self(const halo_t *h, int k, int *kp);
void ft_add(ftab *t, void *p, size_t es);
void *grow_dev(void *p, size_t *cap, size_t need);
void hx_resolve(gpu_t *g, halo_t *h);
void hx_post(sim_t *s, gpu_t *g, const ftab &t, int shift);
void hx_land(sim_t *s, gpu_t *g, const ftab &t);
void gpu_refresh_start(sim_t *s, gpu_t *g, const ftab &t);
void gpu_refresh_finish(sim_t *s, gpu_t *g);
void gpu_refresh(sim_t *s, gpu_t *g, const ftab &t);
void gpu_settle(sim_t *s, gpu_t *g);
void gpu_download(sim_t *s, gpu_t *g);
void gpu_full_exchange(sim_t *s, gpu_t *g);
void hx_offsets(dhalo *x, int m);
void gpu_halo_lists(sim_t *s, gpu_t *g);
ftab fields_tab(const gpu_t *g, uint32_t f, int trim2d);
const stage_sched *gpu_sched(const sim_t *s);
ftab moving_fields(const sim_t *s, const gpu_t *g);

/* ---- CUDA IPC between the ranks of one node (gpu_ipc.cu) ----------------- */
void ipc_setup(sim_t *s, gpu_t *g);
char *ipc_send_buffer(gpu_t *g, size_t bytes);
void ipc_post(sim_t *s, gpu_t *g);
void ipc_land(sim_t *s, gpu_t *g);
void ipc_free(dhalo *x);

/* ---- the exchange at a list build on the device (gpu_exchange.cu) -------- */
void gpu_device_exchange(sim_t *s, gpu_t *g);
void hx_sorted(gpu_t *g, const unsigned *perm, size_t n);

/* ---- the DEM grains (gpu_dem.cu) ----------------------------------------- */
void gpu_dem_couple(sim_t *s, double t); /* the stage ST_DEM_COUPLE (gpu_dem_hook runs it) */
void gpu_dem_advance(sim_t *s, double t, double dt);
void gpu_dem_download(sim_t *s, gpu_t *g);
void gpu_dem_free(gpu_t *g);

/* ---- the step's hooks (gpu_step.cu) -------------------------------------- */
void gpu_acc_reduce(gpu_t *g);
int gpu_plans(const sim_t *s, int h, int id);
void gpu_step_kernel(sim_t *s, gpu_t *g, int place, double t);
void gpu_prepare(sim_t *s, double t, int classify);
void gpu_rates(sim_t *s);
void gpu_dem_hook(sim_t *s, double t);
void gpu_save_start(sim_t *s);
void gpu_advance(sim_t *s, double a, double w);
void gpu_conc_begin(sim_t *s, double T, double out[STEP_NBOUNDS]);
void gpu_conc_step(sim_t *s, double a, int last);
void gpu_filter(sim_t *s);
void gpu_bounds(sim_t *s, double out[STEP_NBOUNDS]);
long gpu_check(sim_t *s);

#endif
