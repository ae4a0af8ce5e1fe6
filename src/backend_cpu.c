/* backend_cpu.c — the CPU backend: OpenMP loops over the shared physics
 * bodies in src/physics. Loops that stream over the store use
 * schedule(static), the slices part_alloc first-touched; the neighbour
 * loops, whose cost per index depends on its kind and surroundings, use
 * schedule(dynamic, CPU_CHUNK): the store is sorted by cell, so a static
 * slice of the 3D block is a slab whose end slabs hold the walls (16 threads:
 * the busiest slice had 1.32 times the mean material and 2.7 times the mean
 * dummies). Each index's result is its own, so any schedule gives the same bits. */
#include "error.h"
#include "sim.h"

/* Indices per dynamic chunk: a 3D material particle's flow rates cost about
 * 10 us, so a chunk is far above the cost of taking it. */
#define CPU_CHUNK 32

/* Copy the arrays at ptrs[0..n-1] (members of s->p) from their owners into
 * the ghosts (multi-rank runs; nothing on one rank). */
static void cpu_refresh(sim_t *s, void *const *ptrs, int n)
{
    if (!s->halo) return;
    int arr[16];
    for (int k = 0; k < n; ++k) arr[k] = part_array_find(&s->p, ptrs[k]);
    halo_refresh(s->halo, &s->p, arr, n);
}

/* Dummy velocities and stresses from the material (paper §4.1), ghosts
 * included: a ghost dummy next to the slab has its whole support here. */
static void cpu_walls(sim_t *s)
{
    particles_t *p = &s->p;
    const long n = (long)(p->n + p->ng);
#pragma omp parallel for schedule(dynamic, CPU_CHUNK)
    for (long i = 0; i < n; ++i)
        if (p->kind[i] == KIND_DUMMY) flow_wall((size_t)i, p, &s->grid.view, &s->flow);
}

/* Place the owned particles; on several ranks migrate them and make the
 * ghosts; sort by cell; classify, renormalise and extrapolate the walls for
 * owned particles and ghosts alike (a ghost within a support of the slab has
 * its whole support here: mpi/halo.h). */
static void cpu_prepare(sim_t *s, double t, int classify)
{
    particles_t *p = &s->p;
    long n = (long)p->n;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) step_place((size_t)i, p, s->flow_on, &s->flow.w, &s->kin, t);
    if (s->halo) halo_exchange(s->halo, p);
    nbr_build(&s->grid, p, R(2.0) * s->seg.k.h, s->halo ? s->halo->origin : NULL);
    if (s->halo) halo_sorted(s->halo, s->grid.perm, p->n + p->ng);
    n = (long)(p->n + p->ng);
    if ((s->hcsr && classify) || classify == 2) {
        bound_classify(&s->bw, p, &s->grid, &s->seg.k);
        /* the ghosts an owned particle reads hold their whole support here
         * and classify themselves alike; the refresh makes them the owner's
         * values bit for bit whatever the summation order. Without psi in
         * it the paper-scheme shear box and EN drum on 2 and 3 ranks were
         * bit-identical (issue 20, tools/mutants.py ghost_psi_stale) */
        void *cls[] = {p->bclass, p->nrm[0], p->nrm[1], p->nrm[2], p->psi};
        cpu_refresh(s, cls, 5);
    }
    if (s->seg_on && classify && s->seg.scheme == SEG_SCHEME_CONSERVATIVE && s->seg.renorm) {
        /* with computed flow the owned particles' L come with the next flow
         * rates (same pairs, no pass of their own); here the ghosts' */
        const long lo = s->flow_on ? (long)p->n : 0;
        s->renorm_due = s->flow_on;
#pragma omp parallel for schedule(dynamic, CPU_CHUNK)
        for (long i = lo; i < n; ++i)
            if (p->kind[i] == KIND_MATERIAL) seg_renorm((size_t)i, p, &s->grid.view, &s->seg);
    }
    if (s->flow_on) cpu_walls(s);
}

static void cpu_flow_rates(sim_t *s)
{
    particles_t *p = &s->p;
    const long n = (long)p->n;
    const int renorm = s->renorm_due;
    double amax = 0;
#pragma omp parallel for schedule(dynamic, CPU_CHUNK) reduction(max : amax)
    for (long i = 0; i < n; ++i) {
        if (p->kind[i] != KIND_MATERIAL) continue;
        double a = flow_rates_team((size_t)i, p, &s->grid.view, &s->flow, 0, 1, renorm);
        amax = a > amax ? a : amax;
    }
    s->amax = amax;
    s->renorm_due = 0;
}

/* V, Q, D of ghosts too (neighbours read them), dC/dt of owned particles;
 * from the shear rate p->gdot (the window's mean, gsum, in a window). */
static void cpu_conc_rates(sim_t *s, particles_t *p)
{
    const long n = (long)p->n, ng = (long)(p->n + p->ng);
#pragma omp parallel
    {
#pragma omp for schedule(static)
        for (long i = 0; i < ng; ++i)
            if (p->kind[i] == KIND_MATERIAL) seg_coeffs((size_t)i, p, &s->seg);
#pragma omp for schedule(dynamic, CPU_CHUNK)
        for (long i = 0; i < n; ++i) seg_dCdt((size_t)i, p, &s->grid.view, &s->seg);
    }
}

/* The flow first: it sets the shear rate the segregation coefficients use. */
static void cpu_rates(sim_t *s)
{
    if (s->flow_on) cpu_flow_rates(s);
    if (s->flow_on && s->seg_on && !s->win.on) {
        void *g[] = {s->p.gdot};
        cpu_refresh(s, g, 1);
    }
    if (s->seg_on && !s->win.on) cpu_conc_rates(s, &s->p);
}

/* Concentration windows (sim.h): the mean shear rate over the window, here
 * and in the ghosts; L at the window's end; the bounds at that rate. */
static void cpu_conc_begin(sim_t *s, double T, double out[STEP_NBOUNDS])
{
    particles_t *p = &s->p, q = *p;
    const long n = (long)p->n, ng = (long)(p->n + p->ng);
    const real inv = (real)(1.0 / T);
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) step_shear_mean((size_t)i, p, inv);
    void *g[] = {p->gsum};
    cpu_refresh(s, g, 1);
    if (s->seg.scheme == SEG_SCHEME_CONSERVATIVE && s->seg.renorm) {
#pragma omp parallel for schedule(dynamic, CPU_CHUNK)
        for (long i = 0; i < ng; ++i)
            if (p->kind[i] == KIND_MATERIAL) seg_renorm((size_t)i, p, &s->grid.view, &s->seg);
    }
    q.gdot = p->gsum;
    double dmax = 0, wmax = 0;
#pragma omp parallel for schedule(static) reduction(max : dmax, wmax)
    for (long i = 0; i < n; ++i) {
        if (p->kind[i] != KIND_MATERIAL) continue;
        double b[3];
        step_bounds_of((size_t)i, &q, &s->step_c, b);
        dmax = b[0] > dmax ? b[0] : dmax;
        wmax = b[1] > wmax ? b[1] : wmax;
    }
    out[STEP_D] = dmax, out[STEP_WAVE] = wmax, out[STEP_SPEED] = 0, out[STEP_ACC] = 0;
}

/* One midpoint step of C alone (length a) at the window's mean shear rate. */
static void cpu_conc_step(sim_t *s, double a, int last)
{
    particles_t *p = &s->p, q = *p;
    const long n = (long)p->n, ng = (long)(p->n + p->ng);
    q.gdot = p->gsum;
    void *c[] = {p->C};
    for (int stage = 0; stage < 2; ++stage) {
        cpu_conc_rates(s, &q);
        const real as = (real)(stage ? a : 0.5 * a);
#pragma omp parallel for schedule(static)
        for (long i = 0; i < n; ++i) step_conc_advance((size_t)i, p, as, stage);
        cpu_refresh(s, c, 1);
    }
    if (!last) return;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < ng; ++i) p->gsum[i] = 0;
}

static void cpu_save_start(sim_t *s)
{
    particles_t *p = &s->p;
    const long n = (long)p->n;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) step_save((size_t)i, p, s->flow_on);
}

static void cpu_advance(sim_t *s, double a, double w)
{
    particles_t *p = &s->p;
    const long n = (long)p->n;
    const int seg = s->seg_on && !s->win.on;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) step_advance((size_t)i, p, (real)a, &s->flow, s->flow_on, seg, (real)w);
}

/* Shepard filter (3.12) of the material stress, then the dummies again. */
static void cpu_filter(sim_t *s)
{
    particles_t *p = &s->p;
    const long n = (long)p->n;
#pragma omp parallel
    {
#pragma omp for schedule(dynamic, CPU_CHUNK)
        for (long i = 0; i < n; ++i)
            if (p->kind[i] == KIND_MATERIAL) flow_shepard((size_t)i, p, &s->grid.view, &s->flow);
#pragma omp for schedule(static)
        for (long i = 0; i < n; ++i) flow_shepard_store((size_t)i, p);
    }
    void *sig[] = {p->sig[0], p->sig[1], p->sig[2], p->sig[3], p->sig[4], p->sig[5]};
    cpu_refresh(s, sig, 6);
    cpu_walls(s);
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

static void cpu_from_host(sim_t *s) { (void)s; }

static void cpu_finish(sim_t *s)
{
    nbr_free(&s->grid);
    bound_free(&s->bw);
}

const struct backend *backend_cpu(void)
{
    static const struct backend b = {"cpu",          cpu_prepare,   cpu_rates,      cpu_advance, cpu_conc_begin,
                                      cpu_conc_step,  cpu_save_start, cpu_filter,     cpu_bounds,  cpu_check,
                                      cpu_to_host,    cpu_finish,     cpu_from_host,  HALO_DEPTH};
    return &b;
}
