/* gpu/gpu_step.cu — the step's hooks: prepare (motion, list build or refresh,
 * walls, L), rates (flow pass, concentration coefficients and dC/dt), the
 * held-back save and advance, the concentration windows (conc_begin,
 * conc_step) and the Shepard filter; each walks the stage table's plan for
 * its hook (src/sim/stages.h), a case per stage; the time-step bounds and the
 * check (the step's one synchronisation). The kernels over the neighbour
 * lists are gpu_pairs.cu's; the per-particle ones are here. */
#include "gpu_reduce.cuh"

/* ---- the hooks ----------------------------------------------------------- */

/* The largest |acc| of the last flow-rate evaluation into dres[STEP_ACC] (a
 * real, widened on read), if not reduced yet: the check folds it into its
 * own pass; a build or a load balance, which reorder the store, take it
 * first. */
void gpu_acc_reduce(gpu_t *g)
{
    if (!g->acc_pending) return;
    reduce(g, g->amag, (real *)(g->dres + STEP_ACC), g->n, max_real(), R(0.0));
    g->acc_pending = 0;
}

/* The stage table's ST_EXCHANGE on the GPU: a list build (the store
 * migrated and sorted, the ghosts made afresh) when the list is stale or the
 * classification needs an exact one; otherwise the ghosts kept and their
 * moving fields refreshed (started only, with the overlap). Returns 1 after
 * a build. */
static int gpu_exchange(sim_t *s, gpu_t *g, int exact)
{
    int build = !g->built || g->stale || g->every || exact;
    if (s->halo) build = comm_max((double)build) > 0; /* a build exchanges: every rank or none */
    if (!build) {
        if (s->halo && !g->hx->overlap) gpu_refresh(s, g, moving_fields(s, g));
        if (s->halo && g->hx->overlap) gpu_refresh_start(s, g, moving_fields(s, g)); /* while the interior goes on */
        return 0;
    }
    gpu_acc_reduce(g); /* before the store is re-sorted */
    if (s->halo && g->hx->dev) gpu_device_exchange(s, g);
    else if (s->halo) gpu_full_exchange(s, g);
    real skin = exact ? R(0.0) : g->skin, sup = R(2.0) * s->seg.k.h + skin;
    /* Several ranks bin on the global lattice of cells of edge sup that one
     * rank's grid_fit makes (its corner less 1e-6 sup; a periodic axis's
     * fixed origin), so that the lists meet neighbours in the one-rank order */
    real org[3];
    if (s->halo)
        for (int d = 0; d < 3; ++d)
            org[d] = exact || (s->halo->per >> d & 1) ? s->halo->origin[d] : s->halo->corner[d] - R(1e-6) * sup;
    gpu_build(g, s->halo, s->p.dim, sup, exact ? s->seg.k.support2 : sup * sup, s->halo ? org : NULL);
    if (s->halo && !g->hx->dev) gpu_halo_lists(s, g);
    g->built = 1;
    g->stale = exact; /* a list without skin is stale as soon as anything moves */
    return 1;
}

/* The hooks run the stage table's plan (src/sim/stages.h) for their hook, each
 * stage's kernels in a case of their own. Where the GPU departs from one
 * kernel per stage in the plan's order, the case says so: ST_PLACE takes
 * the held-back save and advance with it; ST_WALLS and ST_RENORM are one
 * pass; the owned particles' ST_SEG_COEFFS ride in the ST_FLOW pass; a stage
 * that reads ghosts whose refresh is in flight runs its interior first. */
void gpu_prepare(sim_t *s, double t, int classify)
{
    gpu_t *g = gpu_get(s);
    g->bnd_fresh = 0;
    gpu_settle(s, g);
    const stage_sched *m = gpu_sched(s);
    const int exact = classify == 2 || (s->hcsr && classify);
    int build = 0, walls = 0, renorm = 0, kgc = 0;
    for (int k = 0; k < m->n[HOOK_PREPARE]; ++k) switch (m->ids[HOOK_PREPARE][k]) {
        case ST_PLACE: gpu_step_kernel(s, g, 1, t); break; /* with the held-back save and advance */
        case ST_EXCHANGE: build = gpu_exchange(s, g, exact); break;
        case ST_CLASSIFY:
            if (!exact) break; /* exact forced a build */
            gpu_classify(g, &s->seg.k);
            if (s->halo) /* deep ghosts lack part of their support: the owners' classes */
                gpu_refresh(s, g, fields_tab(g, m->refresh[1][ST_CLASSIFY], 0));
            break;
        case ST_RENORM: /* the ghosts' L here, the owned ones' with the next flow rates (sim.h) */
            renorm = classify != 0;
            if (renorm) s->renorm_due = s->flow_on;
            break;
        case ST_KGC: kgc = !s->kgc_skip; break; /* with ST_WALLS' pass; none when no rates read it (sim.h) */
        case ST_WALLS: walls = 1; break;
        default: error_exit(1, "backend_gpu: stage %d has no body in prepare", m->ids[HOOK_PREPARE][k]);
        }
    /* ST_WALLS, ST_RENORM and ST_KGC: one pass, its boundary after the refresh in flight */
    if (!build && s->halo && g->hx->overlap) {
        g->hx->pend_renorm = renorm;
        g->hx->pend_walls = walls;
        g->hx->pend_kgc = kgc;
        gpu_walls_renorm(s, g, walls, renorm, kgc, sel_in(g, 2));
        return;
    }
    gpu_walls_renorm(s, g, walls, renorm, kgc, sel_all());
}

/* Whether hook h runs stage id in this run. */
int gpu_plans(const sim_t *s, int h, int id)
{
    const stage_sched *m = gpu_sched(s);
    for (int k = 0; k < m->n[h]; ++k)
        if (m->ids[h][k] == id) return 1;
    return 0;
}

/* (p: g->d, or g->d reading the window's mean shear rate as gdot) */
static void gpu_seg_coeffs(sim_t *s, gpu_t *g, particles_t p, size_t a, size_t b, int mean = 0)
{
    const seg_ctx c = mean ? seg_ctx_mean(s->seg) : s->seg;
    each(g, b - a, [=] __device__(size_t k) {
        size_t i = a + k;
        if (p.kind[i] == KIND_MATERIAL) seg_coeffs(i, &p, &c);
    });
}

/* ST_DCDT, with ST_SEG_COEFFS of the particles the flow pass did not take
 * (the ghosts, after their shear rate's refresh; all without computed flow). */
static void gpu_conc_rates(sim_t *s, gpu_t *g)
{
    prof_begin(g->st);
    const ftab t = fields_tab(g, gpu_sched(s)->refresh[1][ST_FLOW], 1); /* the shear rate */
    if (s->halo && s->flow_on && !g->hx->overlap) {
        gpu_refresh(s, g, t);
        gpu_seg_coeffs(s, g, g->d, g->n, g->n + g->ng); /* the owned: with the flow rates */
        gpu_dcdt(s, g, g->d, sel_all());
    } else if (s->halo && s->flow_on) { /* the ghosts' shear rate, while the interior goes on */
        gpu_refresh_start(s, g, t);
        gpu_dcdt(s, g, g->d, sel_in(g, 2));
        gpu_refresh_finish(s, g);
        gpu_seg_coeffs(s, g, g->d, g->n, g->n + g->ng);
        gpu_dcdt(s, g, g->d, sel_bd(g, 2));
    } else {
        if (!s->flow_on) gpu_seg_coeffs(s, g, g->d, 0, g->n + g->ng);
        gpu_dcdt(s, g, g->d, sel_all());
    }
    prof_end(g->st, P_SEG);
}

void gpu_rates(sim_t *s)
{
    gpu_t *g = gpu_hook(s, 1);
    const stage_sched *m = gpu_sched(s);
    for (int k = 0; k < m->n[HOOK_RATES]; ++k) switch (m->ids[HOOK_RATES][k]) {
        case ST_FLOW:
            if (g->hx && g->hx->pending) { /* level 3 reads nothing the refresh in flight brings */
                gpu_flow_rates(s, g, sel_in(g, 3));
                gpu_settle(s, g);
                gpu_flow_rates(s, g, sel_bd(g, 3));
            } else {
                gpu_settle(s, g);
                gpu_flow_rates(s, g, sel_all());
            }
            s->renorm_due = 0;
            s->shift_due = 0;
            break;
        case ST_CONTACT: /* after the flow pass, which reads the dummies it reads */
            prof_begin(g->st);
            gpu_contact_pass(s, g);
            prof_end(g->st, P_CONTACT);
            break;
        case ST_SEG_COEFFS: break; /* in the flow pass, and the rest with dC/dt */
        case ST_DCDT:
            gpu_settle(s, g);
            gpu_conc_rates(s, g);
            break;
        default: error_exit(1, "backend_gpu: stage %d has no body in rates", m->ids[HOOK_RATES][k]);
        }
    gpu_settle(s, g);
}

/* struct backend's dem_couple (the DEM grains, after each rates): its
 * stage, gpu_dem.cu's, then the ghosts' volumes (two ways) from their
 * owners: the ghosts are kept until the next list build. */
void gpu_dem_hook(sim_t *s, double t)
{
    const stage_sched *m = gpu_sched(s);
    for (int k = 0; k < m->n[HOOK_DEM]; ++k) switch (m->ids[HOOK_DEM][k]) {
        case ST_DEM_COUPLE: {
            gpu_dem_couple(s, t);
            gpu_t *g = gpu_get(s);
            const uint32_t f = m->refresh[1][ST_DEM_COUPLE];
            if (s->halo && f) gpu_refresh(s, g, fields_tab(g, f, 1));
            break;
        }
        default: error_exit(1, "backend_gpu: stage %d has no body in the DEM coupling", m->ids[HOOK_DEM][k]);
        }
}

/* save_start and advance only note what to do: the per-particle updates
 * run in one kernel with the next prepare's wall or kinematic motion
 * (integrate_step calls save_start, advance, prepare in a row), or alone
 * when another hook comes first (gpu_hook). Each particle's updates are its
 * own, so running them together changes nothing. */
void gpu_step_kernel(sim_t *s, gpu_t *g, int place, double t)
{
    const int sv = g->pend_save, ad = g->pend_adv;
    if (!sv && !ad && !place) return;
    g->pend_save = g->pend_adv = 0;
    particles_t p = g->d;
    flow_ctx c = g->pend_fc;
    const int flow = s->flow_on, seg = stage_runs(stage_flags(s), ST_ADVANCE_C), segon = s->seg_on;
    const double v[3] = {g->pend_a, g->pend_w, t}; /* device scalars: a step's graph holds their slots */
    const dscal ds = gpu_scalar(g, v, 3);
    wall_geom w = s->flow.w;
    kin_params kin = s->kin;
    prof_begin(g->st);
    each(g, g->n, [=] __device__(size_t i) {
        particles_t q = p;
        if (sv) step_save(i, &q, flow, segon);
        if (ad) step_advance(i, &q, (real)ds.at(0), &c, flow, seg, (real)ds.at(1));
        if (place) step_place(i, &q, flow, &w, &kin, ds.at(2));
    });
    prof_end(g->st, P_MOTION);
}

/* ST_SAVE is held back (above); ST_SHIFT runs the held-back save first,
 * since it adds the shift to the saved copies. */
void gpu_save_start(sim_t *s)
{
    gpu_t *g = gpu_hook(s, 1);
    const stage_sched *m = gpu_sched(s);
    for (int k = 0; k < m->n[HOOK_SAVE]; ++k) switch (m->ids[HOOK_SAVE][k]) {
        case ST_SAVE: g->pend_save = 1; break;
        case ST_SHIFT:
            if (s->shift_due) break; /* with the next flow rates (sim.h) */
            gpu_settle(s, g);
            gpu_step_kernel(s, g, 0, 0.0);
            prof_begin(g->st);
            gpu_shift_pass(s, g);
            prof_end(g->st, P_SHIFT);
            break;
        default: error_exit(1, "backend_gpu: stage %d has no body in save_start", m->ids[HOOK_SAVE][k]);
        }
}

void gpu_advance(sim_t *s, double a, double w)
{
    gpu_t *g = gpu_get(s); /* a save_start just before stays held */
    const stage_sched *m = gpu_sched(s);
    for (int k = 0; k < m->n[HOOK_ADVANCE]; ++k) switch (m->ids[HOOK_ADVANCE][k]) {
        case ST_ADVANCE:      /* x, u, sigma; */
        case ST_ADVANCE_C:    /* C, unless it advances in windows; */
        case ST_ADVANCE_GSUM: /* gsum, in windows: all in one held-back pass, gpu_step_kernel */
            break;
        default: error_exit(1, "backend_gpu: stage %d has no body in advance", m->ids[HOOK_ADVANCE][k]);
        }
    if (g->pend_adv) gpu_step_kernel(s, g, 0, 0.0);
    g->bnd_fresh = 0;
    g->pend_adv = 1;
    g->pend_a = a;
    g->pend_w = w;
    g->pend_fc = s->flow;
}

/* Concentration windows (sim.h): the mean shear rate over the window, here
 * and in the ghosts; L of every material particle at the window's end; the
 * bounds at that rate (into dres[0..2]: the next gpu_bounds takes its own). */
void gpu_conc_begin(sim_t *s, double T, double out[STEP_NBOUNDS])
{
    gpu_t *g = gpu_hook(s, 1);
    gpu_settle(s, g);
    const stage_sched *m = gpu_sched(s);
    particles_t p = g->d;
    prof_begin(g->st);
    for (int k = 0; k < m->n[HOOK_CONC_BEGIN]; ++k) switch (m->ids[HOOK_CONC_BEGIN][k]) {
        case ST_SHEAR_MEAN: {
            const real inv = (real)(1.0 / T);
            each(g, g->n, [=] __device__(size_t i) {
                particles_t q = p;
                step_shear_mean(i, &q, inv);
            });
            if (s->halo) gpu_refresh(s, g, fields_tab(g, m->refresh[1][ST_SHEAR_MEAN], 1));
            break;
        }
        case ST_WIN_RENORM: gpu_win_renorm(s, g); break;
        case ST_WIN_BOUNDS: {
            particles_t q = p;
            q.gdot = p.gsum;
            bnd3 init = {{0, 0, 0}};
            auto it = thrust::make_transform_iterator(thrust::counting_iterator<size_t>(0), bnd_of{q, gpu_step_ctx(s, g)});
            reduce(g, it, (bnd3 *)g->dres, g->n, bnd_max(), init);
            CK(cudaMemcpyAsync(g->hres, g->dres, 3 * sizeof(double), cudaMemcpyDeviceToHost, g->st));
            CK(cudaStreamSynchronize(g->st));
            out[STEP_D] = g->hres[0], out[STEP_WAVE] = g->hres[1], out[STEP_SPEED] = 0, out[STEP_ACC] = 0;
            break;
        }
        default: error_exit(1, "backend_gpu: stage %d has no body in conc_begin", m->ids[HOOK_CONC_BEGIN][k]);
        }
    prof_end(g->st, P_SEG);
}

/* One midpoint step of C alone (length a) at the window's mean shear rate;
 * the ghosts' C refreshed after each stage. */
void gpu_conc_step(sim_t *s, double a, int last)
{
    gpu_t *g = gpu_hook(s, 1);
    gpu_settle(s, g);
    const stage_sched *m = gpu_sched(s);
    particles_t p = g->d, q = g->d;
    q.gdot = p.gsum;
    prof_begin(g->st);
    for (int stage = 0; stage < 2; ++stage)
        for (int k = 0; k < m->n[HOOK_CONC_STEP]; ++k) switch (m->ids[HOOK_CONC_STEP][k]) {
            case ST_WIN_COEFFS: gpu_seg_coeffs(s, g, q, 0, g->n + g->ng, 1); break;
            case ST_WIN_DCDT: gpu_dcdt(s, g, q, sel_all()); break;
            case ST_WIN_ADVANCE: {
                const real as = (real)(stage ? a : 0.5 * a);
                each(g, g->n, [=] __device__(size_t i) {
                    particles_t r = p;
                    step_conc_advance(i, &r, as, stage);
                });
                if (s->halo) gpu_refresh(s, g, fields_tab(g, m->refresh[1][ST_WIN_ADVANCE], 1));
                break;
            }
            default: error_exit(1, "backend_gpu: stage %d has no body in conc_step", m->ids[HOOK_CONC_STEP][k]);
            }
    if (last) CK(cudaMemsetAsync(p.gsum, 0, (g->n + g->ng) * sizeof(real), g->st));
    prof_end(g->st, P_SEG);
}

void gpu_filter(sim_t *s)
{
    gpu_t *g = gpu_hook(s, 1);
    gpu_settle(s, g);
    const stage_sched *m = gpu_sched(s);
    particles_t p = g->d;
    for (int k = 0; k < m->n[HOOK_FILTER]; ++k) switch (m->ids[HOOK_FILTER][k]) {
        case ST_SHEPARD:
            prof_begin(g->st);
            gpu_shepard_pass(s, g);
            break;
        case ST_SHEPARD_STORE:
            each(g, g->n, [=] __device__(size_t i) { flow_shepard_store(i, &p); });
            prof_end(g->st, P_FILTER);
            if (s->halo) gpu_refresh(s, g, fields_tab(g, m->refresh[1][ST_SHEPARD_STORE], 1));
            break;
        case ST_WALLS: gpu_walls_renorm(s, g, 1, 0, 0, sel_all()); break;
        default: error_exit(1, "backend_gpu: stage %d has no body in filter", m->ids[HOOK_FILTER][k]);
        }
}

/* ---- the step's bounds and check ------------------------------------------ */

/* Owned particles only: no refresh needs to land first. */
void gpu_bounds(sim_t *s, double out[STEP_NBOUNDS])
{
    gpu_t *g = gpu_hook(s, 0);
    if (!g->bnd_fresh) { /* the first step, or a store changed since the check */
        bnd3 init = {{0, 0, 0}};
        prof_begin(g->st);
        gpu_acc_reduce(g);
        auto it = thrust::make_transform_iterator(thrust::counting_iterator<size_t>(0), bnd_of{g->d, gpu_step_ctx(s, g)});
        reduce(g, it, (bnd3 *)g->dres, g->n, bnd_max(), init);
        CK(cudaMemcpyAsync(g->hres, g->dres, STEP_NBOUNDS * sizeof(double), cudaMemcpyDeviceToHost, g->st));
        CK(cudaStreamSynchronize(g->st));
        prof_end(g->st, P_BOUNDS_CHECK);
    }
    g->bnd_fresh = 0;
    for (int k = 0; k < 3; ++k) out[k] = g->hres[k];
    real acc;
    memcpy(&acc, g->hres + STEP_ACC, sizeof acc);
    out[STEP_ACC] = s->flow_on ? (double)acc : 0.0;
}

/* The check's reduction and read-backs, as a step's graph holds them. */
struct chk_args {
    gpu_t *g;
    chkb_of f;
    int acc;
};
static void th_check(const void *a, cudaStream_t st)
{
    chk_args A;
    memcpy(&A, a, sizeof A);
    gpu_t *g = A.g;
    auto it = thrust::make_transform_iterator(thrust::counting_iterator<size_t>(0), A.f);
    chkb init = {{(long long)g->n, 0, 0}, {{0, 0, 0}}, R(0.0)};
    reduce(g, it, g->dchk, g->n, chkb_merge(), init);
    if (A.acc) /* dres[STEP_ACC] as gpu_acc_reduce leaves it */
        CK(cudaMemcpyAsync(g->dres + STEP_ACC, &g->dchk->amax, sizeof(real), cudaMemcpyDeviceToDevice, st));
    CK(cudaMemcpyAsync(g->hchk, g->dchk, sizeof(chkb), cudaMemcpyDeviceToHost, st));
    CK(cudaMemcpyAsync(g->hres, g->dres, STEP_NBOUNDS * sizeof(double), cudaMemcpyDeviceToHost, st));
}

long gpu_check(sim_t *s)
{
    gpu_t *g = gpu_hook(s, 0);
    prof_begin(g->st);
    chk_args A;
    memset(&A, 0, sizeof A); /* the graph compares these bytes: no stray padding */
    A.g = g;
    A.acc = g->acc_pending; /* |acc| in the same pass */
    const step_ctx *dc = gpu_step_ctx(s, g);
    A.f.c.p = g->d, A.f.c.c = dc, A.f.c.t = gpu_scalar(g, &s->t, 1);
    A.f.c.xb0 = g->xb[0], A.f.c.xb1 = g->xb[1], A.f.c.xb2 = g->xb[2];
    A.f.b.p = g->d, A.f.b.c = dc, A.f.amag = A.acc ? g->amag : NULL;
    if (g_defer) gpu_defer_push(th_check, NULL, &A, sizeof A);
    else th_check(&A, g->st);
    g->acc_pending = 0;
    gpu_defer_flush(); /* the step's graph, ending with these read-backs */
    CK(cudaStreamSynchronize(g->st));
    gpu_scalar_reset(g);
    prof_end(g->st, P_BOUNDS_CHECK);
    for (int k = 0; k < 3; ++k) g->hres[k] = g->hchk->b.v[k];
    g->bnd_fresh = 1;
    if (s->halo) hx_resolve(g, s->halo); /* whole pairs only: one may be in flight */
    const chk *c = &g->hchk->c;
    double D = sqrt((double)c->build2), d = sqrt((double)c->step2), skin = g->skin;
    if (s->halo) { /* the largest over all ranks, as one rank measures them: builds on the same steps */
        double m[2] = {D, d};
        comm_max_n(m, 2); /* one reduction for both */
        D = m[0], d = m[1];
    }
    g->stale |= D + 2 * d > 0.5 * skin;
    g->every = !s->flow_on || d > 0.25 * skin; /* prescribed motion: x_n is not kept */
    return c->first >= (long long)g->n ? -1 : (long)c->first;
}
