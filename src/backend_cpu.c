/* backend_cpu.c — the CPU backend: OpenMP loops over the shared physics
 * bodies in src/physics. */
#include "error.h"
#include "sim.h"

static void cpu_prepare(sim_t *s, double t, int classify)
{
    particles_t *p = &s->p;
    const long n = (long)p->n;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) {
        real X0[3] = {p->X0[0][i], p->X0[1][i], p->X0[2][i]}, x[3], v[3], gd;
        kin_state(&s->kin, X0, t, x, v, &gd);
        for (int d = 0; d < 3; ++d) p->x[d][i] = x[d], p->v[d][i] = v[d];
        p->gdot[i] = gd;
    }
    nbr_build(&s->grid, p, R(2.0) * s->seg.k.h);
    if ((s->hcsr && classify) || classify == 2) bound_classify(&s->bw, p, &s->grid, &s->seg.k);
    if (classify && s->seg.scheme == SEG_SCHEME_CONSERVATIVE && s->seg.renorm) {
#pragma omp parallel for schedule(static)
        for (long i = 0; i < n; ++i)
            if (p->kind[i] == KIND_MATERIAL) seg_renorm((size_t)i, p, &s->grid.view, &s->seg);
    }
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

static void cpu_save_start(sim_t *s)
{
    particles_t *p = &s->p;
    const long n = (long)p->n;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i) p->C_n[i] = p->C[i];
}

static void cpu_advance(sim_t *s, double a)
{
    particles_t *p = &s->p;
    const long n = (long)p->n;
#pragma omp parallel for schedule(static)
    for (long i = 0; i < n; ++i)
        if (p->kind[i] == KIND_MATERIAL) p->C[i] = p->C_n[i] + (real)a * p->dCdt[i];
}

static void cpu_finish(sim_t *s)
{
    nbr_free(&s->grid);
    bound_free(&s->bw);
}

const struct backend *backend_cpu(void)
{
    static const struct backend b = {"cpu", cpu_prepare, cpu_conc_rates, cpu_advance,
                                      cpu_save_start, cpu_finish};
    return &b;
}
