/* gpu/gpu_pairs.cu — the neighbour pass's pair loops: every kernel that walks
 * the neighbour lists (gpu_nbr.cu builds them), a team of threads per
 * particle (team, gpu_launch.cuh) around a shared body of src/physics/: the
 * HCSR classification, the dummy walls and the renormalisation L, the flow
 * rates (with the concentration coefficients), dC/dt, the particle shift,
 * the Shepard sums, a window's L. The hooks (gpu_step.cu) choose which and
 * when. */
#include "gpu.cuh"

/* The view with its form F (grid.h: list, list16, cells) known to the
 * compiler, so that a kernel carries the walk of its form alone (the three
 * walks in one kernel cost the list's kernels 10-24 more registers): each
 * launcher below is a template on F, and by_form launches the build's. */
template <int F> __device__ __forceinline__ grid_view view_as(grid_view v)
{
    v.form = F;
    if (F != GRID_NBR_LIST) v.nl = NULL;
    if (F != GRID_NBR_LIST16) v.nl16 = NULL;
    return v;
}

#define BY_FORM(g, fn, args)                                                                 \
    switch ((g)->view.form) {                                                                \
    case GRID_NBR_LIST16: fn<GRID_NBR_LIST16> args; break;                                   \
    case GRID_NBR_CELLS: fn<GRID_NBR_CELLS> args; break;                                     \
    default: fn<GRID_NBR_LIST> args; break;                                                  \
    }

/* HCSR classification (bound.c on the CPU): cell types, then the two sweeps,
 * over owned particles and ghosts. */
template <int F> static void gpu_classify_f(gpu_t *g, const sph_ctx *kc)
{
    particles_t p = g->d;
    grid_view v = g->view;
    sph_ctx k = *kc;
    size_t *mat = g->cell_mat, n = g->n + g->ng;
    unsigned char *type = g->cell_type, *cls = g->cls;
    bound_sums *sums = g->sums;
    prof_begin(g->st);
    each(g, g->ncell, [=] __device__(size_t c) {
        mat[c] = bound_cell_material(&v, &p, c);
    });
    for (int pass = 0; pass < 2; ++pass)
        each(g, g->ncell, [=] __device__(size_t c) { type[c] = bound_cell_type(&v, type, mat, c, pass); });
    /* Two kernels per case, not one choosing &sums[i] or a local inside the
     * lambda: so written, the list form's first sweep (nvcc 13.0, sm_90)
     * left sums[] unwritten, and the paper scheme's classes, normals and psi~
     * came out wrong (psi~ NaN) under the list alone (list16 and cells right). */
    if (sums) { /* the sums kept between the sweeps (the HCSR schemes: every step) */
        each(g, n, [=] __device__(size_t i) {
            const grid_view w = view_as<F>(v);
            p.bclass[i] = (uint8_t)bound_class_first(i, &p, &w, &k, type, &sums[i]);
        });
        each(g, n, [=] __device__(size_t i) {
            particles_t q = p;
            const grid_view w = view_as<F>(v);
            cls[i] = (unsigned char)bound_class_second(i, &q, &w, &k, type, &sums[i]);
        });
    } else { /* none kept: the second sweep gathers them again (the same loop over x, vol, kind) */
        each(g, n, [=] __device__(size_t i) {
            const grid_view w = view_as<F>(v);
            bound_sums s;
            p.bclass[i] = (uint8_t)bound_class_first(i, &p, &w, &k, type, &s);
        });
        each(g, n, [=] __device__(size_t i) {
            particles_t q = p;
            const grid_view w = view_as<F>(v);
            const bound_sums s = bound_gather(i, &q, &w, &k);
            cls[i] = (unsigned char)bound_class_second(i, &q, &w, &k, type, &s);
        });
    }
    CK(cudaMemcpyAsync(p.bclass, cls, n, cudaMemcpyDeviceToDevice, g->st));
    prof_end(g->st, P_CLASSIFY);
}

void gpu_classify(gpu_t *g, const sph_ctx *kc) { BY_FORM(g, gpu_classify_f, (g, kc)) }

/* Over owned particles and ghosts in sl: the dummy walls (paper §4.1;
 * walls) and the conservative scheme's L of the material (renorm). Neither
 * reads what the other writes: a small store (several threads per
 * particle, latency-bound) runs them as one kernel, a large one as two (the
 * merged kernel would run both at the larger register count: 2 % slower on
 * the 3D drum, docs/gpu.md). */
/* Dummy i's wall state: its loop when material may be in reach (wa[i]),
 * else flow_wall_none, the same result without the loop (the list holds no
 * material, so the loop's sums would be zero): about half the dummies of a
 * drum lie above the bed or deep in an end wall. */
__device__ __forceinline__ void wall_one(size_t i, particles_t *q, const grid_view *v, const flow_ctx *c,
                                         const uint8_t *wa, int lane, int T)
{
    if (!wa || wa[i]) flow_wall_team(i, q, v, c, lane, T);
    else if (lane == 0) flow_wall_none(i, q, c);
}

template <int F> static void gpu_walls_renorm_f(sim_t *s, gpu_t *g, int walls, int renorm, int kgc, sel sl)
{
    particles_t p = g->d;
    grid_view v = g->view;
    flow_ctx c = s->flow;
    seg_ctx sc = s->seg;
    const size_t n = g->n + g->ng;
    const size_t rlo = s->renorm_due ? g->n : 0; /* the owned L due in the flow rates: the ghosts' here */
    const uint8_t *wa = g->wact;
    if (rlo >= n) renorm = 0;
    if (!walls && !renorm && !kgc) return;
    prof_begin(g->st);
    if (kgc) { /* ST_KGC: B of the material, owned and ghosts (reads positions only) */
        team(g, n, [=] __device__(size_t i, int lane, int T) {
            const grid_view w = view_as<F>(v);
            if (p.kind[i] == KIND_MATERIAL && sel_on(sl, i)) flow_kgc_team(i, &p, &w, &c, lane, T);
        });
        prof_end(g->st, P_KGC);
        prof_begin(g->st);
    }
    if (walls && renorm && g->team > 1) {
        team(g, n, [=] __device__(size_t i, int lane, int T) {
            if (!sel_on(sl, i)) return;
            particles_t q = p;
            const grid_view w = view_as<F>(v);
            if (q.kind[i] == KIND_DUMMY) wall_one(i, &q, &w, &c, wa, lane, T);
            else if (q.kind[i] == KIND_MATERIAL && i >= rlo) seg_renorm_team(i, &q, &w, &sc, lane, T);
        });
    } else {
        if (walls)
            team(g, n, [=] __device__(size_t i, int lane, int T) {
                particles_t q = p;
                const grid_view w = view_as<F>(v);
                if (q.kind[i] == KIND_DUMMY && sel_on(sl, i)) wall_one(i, &q, &w, &c, wa, lane, T);
            });
        if (renorm) /* particles rlo.. only: with the owned L due later, just the ghosts */
            team(g, n - rlo, [=] __device__(size_t k, int lane, int T) {
                const size_t i = rlo + k;
                const grid_view w = view_as<F>(v);
                if (p.kind[i] == KIND_MATERIAL && sel_on(sl, i)) seg_renorm_team(i, &p, &w, &sc, lane, T);
            });
    }
    prof_end(g->st, P_WALLS);
}

void gpu_walls_renorm(sim_t *s, gpu_t *g, int walls, int renorm, int kgc, sel sl)
{
    BY_FORM(g, gpu_walls_renorm_f, (s, g, walls, renorm, kgc, sl))
}

/* The flow rates of the owned particles in sl, and with segregation their
 * concentration coefficients (seg_coeffs reads only i's C and the shear
 * rate just computed). */
template <int RENORM, int KGC, int SHIFT, int F> static void gpu_flow_pass(sim_t *s, gpu_t *g, sel sl)
{
    particles_t p = g->d;
    grid_view v = g->view;
    flow_ctx c = s->flow;
    shift_ctx sh = s->shift;
    const real sdt = (real)s->dt;
    seg_ctx sc = s->seg;
    const int seg = gpu_plans(s, HOOK_RATES, ST_SEG_COEFFS); /* not in windows: at their close */
    real *amag = g->amag;
    team(g, g->n, [=] __device__(size_t i, int lane, int T) {
        if (!sel_on(sl, i)) return;
        particles_t q = p;
        const int mat = q.kind[i] == KIND_MATERIAL;
        const grid_view w = view_as<F>(v);
        real a = mat ? flow_rates_body(i, &q, &w, &c, lane, T, RENORM, KGC, SHIFT ? &sh : (const shift_ctx *)0, sdt)
                     : R(0.0);
        if (lane != 0) return;
        amag[i] = a;
        if (seg && mat) seg_coeffs(i, &q, &sc);
    });
}

template <int RENORM, int KGC, int SHIFT> static void gpu_flow_form(sim_t *s, gpu_t *g, sel sl)
{
    switch (g->view.form) {
    case GRID_NBR_LIST16: gpu_flow_pass<RENORM, KGC, SHIFT, GRID_NBR_LIST16>(s, g, sl); break;
    case GRID_NBR_CELLS: gpu_flow_pass<RENORM, KGC, SHIFT, GRID_NBR_CELLS>(s, g, sl); break;
    default: gpu_flow_pass<RENORM, KGC, SHIFT, GRID_NBR_LIST>(s, g, sl); break;
    }
}

/* (and the owned particles' L when prepare left them due: a kernel of its
 * own, so that the other passes keep the smaller register count; the
 * corrected gradient and the fused shift (sim.h shift_due) likewise) */
template <int SHIFT> static void gpu_flow_kgc(sim_t *s, gpu_t *g, sel sl)
{
    const int kgc = s->flow.kgc; /* its own kernels: the others keep their register count */
    if (s->renorm_due) kgc ? gpu_flow_form<1, 1, SHIFT>(s, g, sl) : gpu_flow_form<1, 0, SHIFT>(s, g, sl);
    else kgc ? gpu_flow_form<0, 1, SHIFT>(s, g, sl) : gpu_flow_form<0, 0, SHIFT>(s, g, sl);
}

void gpu_flow_rates(sim_t *s, gpu_t *g, sel sl)
{
    prof_begin(g->st);
    if (s->shift_due) gpu_flow_kgc<1>(s, g, sl);
    else gpu_flow_kgc<0>(s, g, sl);
    g->acc_pending = 1;
    prof_end(g->st, P_FLOW);
}

template <int F> static void gpu_dcdt_f(sim_t *s, gpu_t *g, particles_t p, sel sl)
{
    grid_view v = g->view;
    seg_ctx c = s->seg;
    team(g, g->n, [=] __device__(size_t i, int lane, int T) {
        const grid_view w = view_as<F>(v);
        if (sel_on(sl, i)) seg_dCdt_team(i, &p, &w, &c, lane, T);
    });
}

void gpu_dcdt(sim_t *s, gpu_t *g, particles_t p, sel sl) { BY_FORM(g, gpu_dcdt_f, (s, g, p, sl)) }

/* ST_SHIFT: the shift of every material particle, with its Taylor steps into
 * the saved copies (shift_team). */
template <int F> static void gpu_shift_f(sim_t *s, gpu_t *g)
{
    particles_t p = g->d;
    grid_view v = g->view;
    shift_ctx c = s->shift;
    const real dt = (real)s->dt;
    team(g, g->n, [=] __device__(size_t i, int lane, int T) {
        particles_t q = p;
        const grid_view w = view_as<F>(v);
        if (q.kind[i] == KIND_MATERIAL) shift_team(i, &q, &w, &c, dt, lane, T);
    });
}

void gpu_shift_pass(sim_t *s, gpu_t *g) { BY_FORM(g, gpu_shift_f, (s, g)) }

/* ST_SHEPARD: the Shepard sums of every material particle (stored by
 * ST_SHEPARD_STORE, gpu_filter). */
template <int F> static void gpu_shepard_f(sim_t *s, gpu_t *g)
{
    particles_t p = g->d;
    grid_view v = g->view;
    flow_ctx c = s->flow;
    team(g, g->n, [=] __device__(size_t i, int lane, int T) {
        particles_t q = p;
        const grid_view w = view_as<F>(v);
        if (q.kind[i] == KIND_MATERIAL) flow_shepard_team(i, &q, &w, &c, lane, T);
    });
}

void gpu_shepard_pass(sim_t *s, gpu_t *g) { BY_FORM(g, gpu_shepard_f, (s, g)) }

/* ST_WIN_RENORM: L of every material particle, owned and ghost, at a
 * concentration window's end. */
template <int F> static void gpu_win_renorm_f(sim_t *s, gpu_t *g)
{
    particles_t p = g->d;
    grid_view v = g->view;
    seg_ctx sc = s->seg;
    team(g, g->n + g->ng, [=] __device__(size_t i, int lane, int T) {
        const grid_view w = view_as<F>(v);
        if (p.kind[i] == KIND_MATERIAL) seg_renorm_team(i, &p, &w, &sc, lane, T);
    });
}

void gpu_win_renorm(sim_t *s, gpu_t *g) { BY_FORM(g, gpu_win_renorm_f, (s, g)) }
