/* backend_cpu.c — the CPU backend: OpenMP loops over the shared physics
 * bodies in src/physics. Loops that stream over the store use
 * schedule(static), the slices part_alloc first-touched; the neighbour
 * loops, whose cost per index depends on its kind and surroundings, use
 * schedule(dynamic, CPU_CHUNK): the store is sorted by cell, so a static
 * slice of the 3D block is a slab whose end slabs hold the walls (16 threads:
 * the busiest slice had 1.32 times the mean material and 2.7 times the mean
 * dummies). Each index's result is its own, so any schedule gives the same bits. */
#include <stdlib.h>
#include "bound.h"
#include "core/error.h"
#include "nbr.h"
#include "nlist.h"
#include "mpi/comm.h"
#include "sim/sim.h"
#include "sim/stages.h"

/* Indices per dynamic chunk: a 3D material particle's flow rates cost about
 * 10 us, so a chunk is far above the cost of taking it. */
#define CPU_CHUNK 32

/* The CPU backend's own state (s->be_data): the sorted cell list, the
 * Verlet list over it (nlist.h: every neighbour loop walks it through
 * grid.view) and the boundary classification's work arrays, allocated at
 * the first call. */
typedef struct cpu_state {
    nbr_grid grid;
    nlist list;
    int list_init;
    int keep;             /* a halo's ghosts are kept between list builds (several ranks; not with periodic
                           * axes, DEM grains or the cells: cpu_keeps_why) */
    long exchanges, kept; /* prepares with a halo: ghosts made afresh; kept */
    long steps0; /* s->step at the first call (the list's log) */
    real *bq;    /* Flow:bed_damping: flow_bed_q of the store and its ghosts, made before each flow pass */
    size_t bq_cap;
    bound_work bw;
} cpu_state;

static cpu_state *cpu_of(sim_t *s)
{
    if (!s->be_data) {
        s->be_data = calloc(1, sizeof(cpu_state));
        if (!s->be_data) error_exit(1, "cpu backend: out of memory for its cell list");
    }
    return (cpu_state *)s->be_data;
}

/* Copy the fields (src/sim/stages.h) from their owners into the ghosts
 * (multi-rank runs; nothing on one rank). */
static void cpu_refresh(sim_t *s, uint32_t fields)
{
    if (!s->halo || !fields) return;
    void *ptrs[PART_NARRAYS];
    int arr[PART_NARRAYS], n = stage_arrays(&s->p, fields, 0, ptrs);
    for (int k = 0; k < n; ++k) arr[k] = part_array_find(&s->p, ptrs[k]);
    halo_refresh(s->halo, &s->p, arr, n);
}

/* What a hook's call brings to its stages. */
typedef struct cpu_call {
    double t;       /* prepare, the DEM coupling: the time */
    int classify;   /* prepare: 1 classify (HCSR schemes), 2 classify whatever the scheme, 0 not */
    double a, w;    /* advance: step and window weight; a window's midpoint stage: its length */
    int half;       /* a window's midpoint stage: 0 the half step, 1 the full one */
    double T;       /* conc_begin: the window's length */
    double *out;    /* conc_begin: the bounds */
} cpu_call;

/* V, Q, D of ghosts too (neighbours read them), from the shear rate of q. */
static void cpu_seg_coeffs(const seg_ctx *c, particles_t *q)
{
    const long ng = (long)(q->n + q->ng);
#pragma omp parallel for schedule(static)
    for (long i = 0; i < ng; ++i)
        if (q->kind[i] == KIND_MATERIAL) seg_coeffs((size_t)i, q, c);
}

static void cpu_dcdt(sim_t *s, particles_t *q)
{
    const long n = (long)q->n;
#pragma omp parallel for schedule(dynamic, CPU_CHUNK)
    for (long i = 0; i < n; ++i) seg_dCdt((size_t)i, q, &cpu_of(s)->grid.view, &s->seg);
}

/* L of material particles [lo, n + ng). */
static void cpu_renorm(sim_t *s, long lo)
{
    particles_t *p = &s->p;
    const long n = (long)(p->n + p->ng);
#pragma omp parallel for schedule(dynamic, CPU_CHUNK)
    for (long i = lo; i < n; ++i)
        if (p->kind[i] == KIND_MATERIAL) seg_renorm((size_t)i, p, &cpu_of(s)->grid.view, &s->seg);
}

/* Flow:bed_damping's weight of every particle, store and ghosts, for the
 * flow pass to read per pair (flow_bed_q: once a particle, not once a pair;
 * the same bits); NULL where the pass does not damp the bed. */
static const real *cpu_bed_q(sim_t *s)
{
    const particles_t *p = &s->p;
    cpu_state *c = cpu_of(s);
    if (!(s->flow.bed_alpha > 0) || s->flow.stab == STAB_MONAGHAN) return NULL;
    const size_t n = p->n + p->ng;
    if (n > c->bq_cap) {
        free(c->bq);
        c->bq_cap = n + n / 8;
        c->bq = malloc(c->bq_cap * sizeof *c->bq);
        if (!c->bq) error_exit(1, "cpu backend: out of memory for the bed damping's weights");
    }
    real *bq = c->bq;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < (long)n; ++i) bq[i] = flow_bed_q((size_t)i, p, &s->flow);
    return bq;
}

/* The flow rates of the material (and, when due, its L) and the largest
 * acceleration. */
static void cpu_flow_rates(sim_t *s)
{
    particles_t *p = &s->p;
    const long n = (long)p->n;
    const int renorm = s->renorm_due;
    const shift_ctx *sh = s->shift_due ? &s->shift : NULL; /* the step's shift, fused (sim.h) */
    const real sdt = (real)s->dt;
    const real *bq = cpu_bed_q(s);
    double amax = 0;
#pragma omp parallel for schedule(dynamic, CPU_CHUNK) reduction(max : amax)
    for (long i = 0; i < n; ++i) {
        if (p->kind[i] != KIND_MATERIAL) continue;
        double a =
            flow_rates_body((size_t)i, p, &cpu_of(s)->grid.view, &s->flow, 0, 1, renorm, s->flow.kgc, sh, sdt, bq,
                            FLOW_SPEC_ANY);
        amax = a > amax ? a : amax;
    }
    s->amax = amax;
    s->renorm_due = 0;
    s->shift_due = 0;
}

/* A concentration window's time-step bounds, from the material of q (the
 * store with the window's mean shear rate), into out[STEP_*]. */
static void cpu_win_bounds(sim_t *s, const particles_t *q, double *out)
{
    const long n = (long)q->n;
    double dmax = 0, wmax = 0;
#pragma omp parallel for schedule(static) reduction(max : dmax, wmax)
    for (long i = 0; i < n; ++i) {
        if (q->kind[i] != KIND_MATERIAL) continue;
        double b[3];
        step_bounds_of((size_t)i, q, &s->step_c, b);
        dmax = b[0] > dmax ? b[0] : dmax;
        wmax = b[1] > wmax ? b[1] : wmax;
    }
    out[STEP_D] = dmax, out[STEP_WAVE] = wmax, out[STEP_SPEED] = 0, out[STEP_ACC] = 0;
}

/* Particle shifting (physics/shift.h) of the owned material particles. */
static void cpu_shift(sim_t *s)
{
    particles_t *p = &s->p;
    const long n = (long)p->n;
#pragma omp parallel for schedule(dynamic, CPU_CHUNK)
    for (long i = 0; i < n; ++i)
        if (p->kind[i] == KIND_MATERIAL) shift_team((size_t)i, p, &cpu_of(s)->grid.view, &s->shift, (real)s->dt, 0, 1);
}

/* The Shepard filter (3.12) of the owned material particles, into dsig. */
static void cpu_shepard(sim_t *s)
{
    particles_t *p = &s->p;
    const long n = (long)p->n;
#pragma omp parallel for schedule(dynamic, CPU_CHUNK)
    for (long i = 0; i < n; ++i)
        if (p->kind[i] == KIND_MATERIAL) flow_shepard((size_t)i, p, &cpu_of(s)->grid.view, &s->flow);
}

/* Run stage id of the table (src/sim/stages.h) for call c; returns 0 when the
 * call leaves it out (prepare without classification, say). The loops:
 * streaming ones schedule(static), neighbour loops dynamic (top). */
static int cpu_stage(sim_t *s, int id, cpu_call *c)
{
    particles_t *p = &s->p, q = *p;
    const long n = (long)p->n, ng = (long)(p->n + p->ng);
    q.gdot = p->gsum; /* the window stages read the window's mean shear rate */
    switch (id) {
    case ST_PLACE:
#pragma omp parallel for schedule(static)
        for (long i = 0; i < n; ++i) step_place((size_t)i, p, s->flow_on, &s->flow.w, &s->kin, c->t);
        return 1;
    case ST_EXCHANGE: { /* the ghosts (kept, or made afresh), the sort, the Verlet list built or following
                         * the sort (nlist.h) */
        cpu_state *cs = cpu_of(s);
        /* with a halo the ghosts are kept while the list can follow on every rank and no exact
         * classification is due (as the GPU's, gpu_step.cu gpu_exchange): their moving fields
         * refreshed; else migration and ghosts made afresh, and the list built */
        int keep = 0;
        if (cs->list_init && cs->keep) {
            const int exact = c->classify == 2 || (s->hcsr && c->classify);
            keep = comm_max((double)(exact || nlist_stale(&cs->list, p))) == 0;
        }
        if (keep) {
            cpu_refresh(s, stage_schedule(stage_flags(s))->moving);
            /* the lattice at this prepare's corner, as an exchange takes it and one rank's grid_fit at
             * every sort: the cells, and so the sums' order, are the one-rank run's (left at the last
             * exchange's corner, a rotating drum on two ranks left the one-rank run by 2e-15 in 8 steps) */
            halo_reorigin(s->halo, p);
        } else if (s->halo)
            halo_exchange(s->halo, p);
        if (s->halo) nbr_set_period(&cs->grid, s->halo->per, s->halo->plo, s->halo->plen);
        nbr_build(&cs->grid, p, R(2.0) * s->seg.k.h, s->halo ? s->halo->origin : NULL);
        if (s->halo) halo_sorted(s->halo, cs->grid.perm, p->n + p->ng);
        if (!cs->list_init) { /* where ghosts are made at every prepare (cs->keep 0), the list is read before
                               * anything moves: no skin but a hair (NLIST_SKIN_FRESH) */
            nlist_init(&cs->list, p, (double)s->seg.k.h, (double)s->seg.k.dr,
                       s->halo && (s->halo->per || s->dem) ? NLIST_SKIN_FRESH : s->sc->run.list_skin);
            cs->list_init = 1, cs->steps0 = s->step;
            cs->keep = s->halo && !s->halo->per && !s->dem && cs->list.on;
        }
        nlist_update(&cs->list, &cs->grid, p, !s->halo ? NLIST_AUTO : keep ? NLIST_FOLLOW : NLIST_BUILD);
        if (s->halo) cs->exchanges += !keep, cs->kept += keep;
        return 1;
    }
    case ST_CLASSIFY: /* the ghosts an owned particle reads hold their whole support here and
                       * classify themselves alike; the refresh (from_owner) makes them the
                       * owner's values bit for bit whatever the summation order. Without psi in
                       * it the paper-scheme shear box and EN drum on 2 and 3 ranks were
                       * bit-identical (issue 20, tools/dev/mutants.py ghost_psi_stale) */
        if (!((s->hcsr && c->classify) || c->classify == 2)) return 0;
        bound_classify(&cpu_of(s)->bw, p, &cpu_of(s)->grid, &s->seg.k);
        return 1;
    case ST_RENORM: /* with computed flow the owned L come with the next flow rates (same
                     * pairs, no pass of their own); here the ghosts' */
        if (!c->classify) return 0;
        s->renorm_due = s->flow_on;
        cpu_renorm(s, s->flow_on ? n : 0);
        return 1;
    case ST_KGC: /* ghosts included: a ghost within 2h of the slab has its whole support here */
        if (s->kgc_skip) return 0; /* no rates read it before the next prepare (sim.h) */
#pragma omp parallel for schedule(dynamic, CPU_CHUNK)
        for (long i = 0; i < ng; ++i)
            if (p->kind[i] == KIND_MATERIAL) flow_kgc_team((size_t)i, p, &cpu_of(s)->grid.view, &s->flow, 0, 1);
        return 1;
    case ST_WALLS: /* ghosts included: a ghost dummy next to the slab has its whole support here; a
                    * dummy no material reaches until the list's next build skips its loop (nlist.h) */
#pragma omp parallel for schedule(dynamic, CPU_CHUNK)
        for (long i = 0; i < ng; ++i)
            if (p->kind[i] == KIND_DUMMY) {
                if (nlist_wall_due(&cpu_of(s)->list, (size_t)i))
                    flow_wall((size_t)i, p, &cpu_of(s)->grid.view, &s->flow);
                else
                    flow_wall_none((size_t)i, p, &s->flow);
            }
        return 1;
    case ST_FLOW: cpu_flow_rates(s); return 1;
    case ST_CONTACT: /* the Coulomb walls' friction on the owned material (Walls:coulomb_force particles) */
#pragma omp parallel for schedule(dynamic, CPU_CHUNK)
        for (long i = 0; i < n; ++i)
            if (p->kind[i] == KIND_MATERIAL)
                flow_contact_team((size_t)i, p, &cpu_of(s)->grid.view, &s->flow, (real)s->dt, 0, 1);
        return 1;
    case ST_SEG_COEFFS: cpu_seg_coeffs(&s->seg, p); return 1;
    case ST_DCDT: cpu_dcdt(s, p); return 1;
    case ST_SAVE:
#pragma omp parallel for schedule(static)
        for (long i = 0; i < n; ++i) step_save((size_t)i, p, s->flow_on, s->seg_on);
        return 1;
    case ST_SHIFT: /* or with the next flow rates (sim.h shift_due) */
        if (s->shift_due) return 0;
        cpu_shift(s);
        return 1;
    case ST_ADVANCE: { /* step_advance does x, u, sigma, C and gsum in one pass: ST_ADVANCE_C, _GSUM */
        const int seg = stage_runs(stage_flags(s), ST_ADVANCE_C);
#pragma omp parallel for schedule(static)
        for (long i = 0; i < n; ++i)
            step_advance((size_t)i, p, (real)c->a, &s->flow, s->flow_on, seg, (real)c->w);
        return 1;
    }
    case ST_ADVANCE_C:
    case ST_ADVANCE_GSUM: return !s->flow_on ? cpu_stage(s, ST_ADVANCE, c) : 1; /* with ST_ADVANCE's pass */
    case ST_SHEAR_MEAN: {
        const real inv = (real)(1.0 / c->T);
#pragma omp parallel for schedule(static)
        for (long i = 0; i < n; ++i) step_shear_mean((size_t)i, p, inv);
        return 1;
    }
    case ST_WIN_RENORM: cpu_renorm(s, 0); return 1;
    case ST_WIN_BOUNDS: cpu_win_bounds(s, &q, c->out); return 1;
    case ST_WIN_COEFFS: {
        const seg_ctx mc = seg_ctx_mean(s->seg);
        cpu_seg_coeffs(&mc, &q);
        return 1;
    }
    case ST_WIN_DCDT: cpu_dcdt(s, &q); return 1;
    case ST_WIN_ADVANCE: {
        const real as = (real)(c->half ? c->a : 0.5 * c->a);
#pragma omp parallel for schedule(static)
        for (long i = 0; i < n; ++i) step_conc_advance((size_t)i, p, as, c->half);
        return 1;
    }
    case ST_DEM_COUPLE: /* the owned fluid particles; the fraction and volume at every ghost too */
        dem_couple(s->dem, p, &cpu_of(s)->grid.view, &s->flow.w, c->t, (double)s->flow.visc_norm, s->halo);
        return 1;
    case ST_SHEPARD: cpu_shepard(s); return 1;
    case ST_SHEPARD_STORE:
#pragma omp parallel for schedule(static)
        for (long i = 0; i < n; ++i) flow_shepard_store((size_t)i, p);
        return 1;
    default: error_exit(1, "backend_cpu: stage %d has no body", id);
    }
    return 0;
}

/* A hook: its stages in the table's order, each stage's refresh after it. */
static void cpu_hook(sim_t *s, int hook, cpu_call *c)
{
    const stage_sched *m = stage_schedule(stage_flags(s));
    for (int k = 0; k < m->n[hook]; ++k) { /* the refreshes of a run that keeps its ghosts ([1]) reach past
                                             * ST_EXCHANGE; keep is set at the first one */
        const int id = m->ids[hook][k];
        if (cpu_stage(s, id, c)) cpu_refresh(s, m->refresh[s->be_data && cpu_of(s)->keep][id]);
    }
}

/* Place the owned particles; on several ranks migrate them and make the
 * ghosts; sort by cell; classify, renormalise and extrapolate the walls for
 * owned particles and ghosts alike (a ghost within a support of the slab has
 * its whole support here: mpi/halo.h). */
static void cpu_prepare(sim_t *s, double t, int classify)
{
    cpu_call c = {.t = t, .classify = classify};
    cpu_hook(s, HOOK_PREPARE, &c);
}

/* The flow first: it sets the shear rate the segregation coefficients use. */
static void cpu_rates(sim_t *s)
{
    cpu_call c = {0};
    cpu_hook(s, HOOK_RATES, &c);
}

/* Concentration windows (sim.h): the mean shear rate over the window, here
 * and in the ghosts; L at the window's end; the bounds at that rate. */
static void cpu_conc_begin(sim_t *s, double T, double out[STEP_NBOUNDS])
{
    cpu_call c = {.T = T, .out = out};
    cpu_hook(s, HOOK_CONC_BEGIN, &c);
}

/* One midpoint step of C alone (length a) at the window's mean shear rate. */
static void cpu_conc_step(sim_t *s, double a, int last)
{
    particles_t *p = &s->p;
    const long ng = (long)(p->n + p->ng);
    for (int half = 0; half < 2; ++half) {
        cpu_call c = {.a = a, .half = half};
        cpu_hook(s, HOOK_CONC_STEP, &c);
    }
    if (!last) return;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < ng; ++i) p->gsum[i] = 0;
}

static void cpu_save_start(sim_t *s)
{
    cpu_call c = {0};
    cpu_hook(s, HOOK_SAVE, &c);
}

static void cpu_advance(sim_t *s, double a, double w)
{
    cpu_call c = {.a = a, .w = w};
    cpu_hook(s, HOOK_ADVANCE, &c);
}

/* Shepard filter (3.12) of the material stress, then the dummies again. */
static void cpu_filter(sim_t *s)
{
    cpu_call c = {0};
    cpu_hook(s, HOOK_FILTER, &c);
}

static void cpu_bounds(sim_t *s, double out[STEP_NBOUNDS])
{
    const particles_t *p = &s->p;
    const long n = (long)p->n;
    double dmax = 0, wmax = 0, umax = 0;
#pragma omp parallel for schedule(static) reduction(max : dmax, wmax, umax)
    for (long i = 0; i < n; ++i) {
        if (p->kind[i] != KIND_MATERIAL) continue;
        double b[3];
        step_bounds_of((size_t)i, p, &s->step_c, b);
        dmax = b[0] > dmax ? b[0] : dmax;
        wmax = b[1] > wmax ? b[1] : wmax;
        umax = b[2] > umax ? b[2] : umax;
    }
    out[STEP_D] = dmax, out[STEP_WAVE] = wmax, out[STEP_SPEED] = umax, out[STEP_ACC] = s->amax;
}

/* The lowest index meeting a blow-up condition: deterministic. */
static long cpu_check(sim_t *s)
{
    const particles_t *p = &s->p;
    const long n = (long)p->n;
    long first = n;
#pragma omp parallel for schedule(static) reduction(min : first)
    for (long i = 0; i < n; ++i)
        if (p->kind[i] == KIND_MATERIAL && i < first && step_guard((size_t)i, p, &s->step_c, s->t)) first = i;
    return first == n ? -1 : first;
}

static void cpu_to_host(sim_t *s) { (void)s; }

/* The store was changed on the host (a drain, a load balance): the list's
 * rows no longer name its particles. */
static void cpu_from_host(sim_t *s)
{
    if (s->be_data) nlist_forget(&cpu_of(s)->list);
}

/* Why a run with a halo keeps its ghosts between list builds or not (the
 * end's log line). Periodic axes make them afresh at every prepare: an
 * exchange wraps the owned particles into the period, which moves their
 * positions at round-off (x - L against an image's x + L), so its steps
 * must not depend on the list's builds, which differ between a run and its
 * restart and between rank counts (tried: 2 and 3 ranks of the periodic
 * chutes of tests/validate_mpi.py left the one-rank run by 1e-15). DEM
 * grains divide among the ranks at every coupling (src/dem/dem_halo.c). */
static const char *cpu_keeps_why(const sim_t *s, const cpu_state *c)
{
    if (c->keep) return "kept while the list follows the sort";
    if (s->halo->per) return "periodic axes: afresh at every prepare, wrapping into the period";
    if (s->dem) return "DEM grains: afresh at every prepare";
    return "the cells: afresh at every prepare";
}

static void cpu_finish(sim_t *s)
{
    cpu_state *c = (cpu_state *)s->be_data;
    if (!c) return;
    /* the memory line (issue 56): the store's fields and the backend's per-particle scratch */
    const size_t cl = c->grid.cap_part ? 2 * sizeof(size_t) + sizeof(uint64_t) : 0, /* key, perm, rank */
        bc = c->bw.cap_part ? sizeof(bound_sums) + 1 : 0,                              /* sums, classes */
        vl = nlist_bytes(&c->list),                                                    /* the Verlet list */
        bd = c->bq_cap ? sizeof(real) : 0;                                             /* the bed's weights */
    message("cpu memory: store %zu bytes a particle (%d of %d fields), scratch %zu bytes a particle (cell list %zu, "
            "neighbour list %zu, classification %zu, bed damping %zu), rank 0", part_store_bytes(&s->p),
            __builtin_popcount(s->p.fields), __builtin_popcount(part_fields_all()), cl + vl + bc + bd, cl, vl, bc, bd);
    if (c->list.on)
        message("cpu: %ld neighbour-list builds, %ld sorts followed, in %ld steps (skin %.3g h), rank 0",
                c->list.builds, c->list.follows, s->step - c->steps0, c->list.skin / (double)s->seg.k.h);
    if (s->halo)
        message("cpu: ghosts made afresh at %ld prepares, kept at %ld (%s), rank 0", c->exchanges, c->kept,
                cpu_keeps_why(s, c));
    nbr_free(&c->grid);
    nlist_free(&c->list);
    bound_free(&c->bw);
    free(c->bq);
    free(c);
    s->be_data = NULL;
}

/* The DEM grains (src/dem/dem.c) on the host store: the coupling, a stage. */
static void cpu_dem_couple(sim_t *s, double t)
{
    cpu_call c = {.t = t};
    cpu_hook(s, HOOK_DEM, &c);
}

static void cpu_dem_advance(sim_t *s, double t, double dt) { dem_advance(s->dem, &s->flow.w, t, dt); }

const struct backend *backend_cpu(void)
{
    static const struct backend b = {"cpu",          cpu_prepare,   cpu_rates,      cpu_advance, cpu_conc_begin,
                                      cpu_conc_step,  cpu_save_start, cpu_filter,     cpu_bounds,  cpu_check,
                                      cpu_to_host,    cpu_finish,     cpu_from_host,  3 /* ghosts kept */,
                                      NULL /* relist: every prepare sorts */, cpu_dem_couple, cpu_dem_advance,
                                      NULL /* step_begin: no graphs */, HALO_DEPTH /* with DEM grains */};
    return &b;
}
