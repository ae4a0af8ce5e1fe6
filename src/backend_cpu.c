/* backend_cpu.c — the CPU backend: OpenMP loops over the shared physics
 * bodies in src/physics. */
#include "error.h"
#include "sim.h"

/* Dummy velocities and stresses from the material (paper §4.1). */
static void cpu_walls(sim_t *s)
{
    particles_t *p = &s->p;
    const long n = (long)p->n;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i)
        if (p->kind[i] == KIND_DUMMY) flow_wall((size_t)i, p, &s->grid.view, &s->flow);
}

static void cpu_prepare(sim_t *s, double t, int classify)
{
    particles_t *p = &s->p;
    const long n = (long)p->n;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) {
        real X0[3] = {p->X0[0][i], p->X0[1][i], p->X0[2][i]}, x[3], v[3], gd;
        if (s->flow_on) { /* material integrated; the walls move as prescribed */
            if (p->kind[i] != KIND_DUMMY) continue;
            wall_motion(&s->flow.w, X0, t, x, v);
            for (int d = 0; d < 3; ++d) p->x[d][i] = x[d];
            continue;
        }
        kin_state(&s->kin, X0, t, x, v, &gd);
        for (int d = 0; d < 3; ++d) p->x[d][i] = x[d], p->v[d][i] = v[d];
        p->gdot[i] = gd;
    }
    nbr_build(&s->grid, p, R(2.0) * s->seg.k.h);
    if ((s->hcsr && classify) || classify == 2) bound_classify(&s->bw, p, &s->grid, &s->seg.k);
    if (s->seg_on && classify && s->seg.scheme == SEG_SCHEME_CONSERVATIVE && s->seg.renorm) {
#pragma omp parallel for schedule(static)
        for (long i = 0; i < n; ++i)
            if (p->kind[i] == KIND_MATERIAL) seg_renorm((size_t)i, p, &s->grid.view, &s->seg);
    }
    if (s->flow_on) cpu_walls(s);
}

static void cpu_flow_rates(sim_t *s)
{
    particles_t *p = &s->p;
    const long n = (long)p->n;
    double amax = 0;
#pragma omp parallel for schedule(static) reduction(max : amax)
    for (long i = 0; i < n; ++i) {
        if (p->kind[i] != KIND_MATERIAL) continue;
        double a = flow_rates((size_t)i, p, &s->grid.view, &s->flow);
        amax = a > amax ? a : amax;
    }
    s->amax = amax;
}

static void cpu_conc_rates(sim_t *s)
{
    particles_t *p = &s->p;
    const long n = (long)p->n;
    const int cons = s->seg.scheme == SEG_SCHEME_CONSERVATIVE;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i)
        if (p->kind[i] == KIND_MATERIAL) seg_coeffs((size_t)i, p, &s->seg);
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) {
        if (p->kind[i] != KIND_MATERIAL) {
            p->dCdt[i] = 0;
            continue;
        }
        seg_rate r = cons ? seg_rate_conservative((size_t)i, p, &s->grid.view, &s->seg)
                          : seg_rate_hcsr((size_t)i, p, &s->grid.view, &s->seg);
        p->dCdt[i] = r.seg + r.diff + r.src;
    }
}

/* The flow first: it sets the shear rate the segregation coefficients use. */
static void cpu_rates(sim_t *s)
{
    if (s->flow_on) cpu_flow_rates(s);
    if (s->seg_on) cpu_conc_rates(s);
}

static void cpu_save_start(sim_t *s)
{
    particles_t *p = &s->p;
    const long n = (long)p->n;
    const int flow = s->flow_on;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) {
        p->C_n[i] = p->C[i];
        if (!flow) continue;
        for (int d = 0; d < 3; ++d) p->x_n[d][i] = p->x[d][i], p->v_n[d][i] = p->v[d][i];
        for (int q = 0; q < 6; ++q) p->sig_n[q][i] = p->sig[q][i];
    }
}

static void cpu_advance(sim_t *s, double a)
{
    particles_t *p = &s->p;
    const long n = (long)p->n;
    const int flow = s->flow_on, seg = s->seg_on;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) {
        if (p->kind[i] != KIND_MATERIAL) continue;
        if (flow) flow_advance((size_t)i, p, (real)a, &s->flow); /* reads C before it moves */
        if (seg) p->C[i] = p->C_n[i] + (real)a * p->dCdt[i];
    }
}

/* Shepard filter (3.12) of the material stress, then the dummies again. */
static void cpu_filter(sim_t *s)
{
    particles_t *p = &s->p;
    const long n = (long)p->n;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i)
        if (p->kind[i] == KIND_MATERIAL) flow_shepard((size_t)i, p, &s->grid.view, &s->flow);
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i)
        if (p->kind[i] == KIND_MATERIAL)
            for (int q = 0; q < 6; ++q) p->sig[q][i] = p->dsig[q][i];
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

static void cpu_finish(sim_t *s)
{
    nbr_free(&s->grid);
    bound_free(&s->bw);
}

const struct backend *backend_cpu(void)
{
    static const struct backend b = {"cpu",      cpu_prepare, cpu_rates,   cpu_advance, cpu_save_start,
                                      cpu_filter, cpu_bounds,  cpu_check,   cpu_to_host, cpu_finish};
    return &b;
}
