/* dem.c — DEM grains: their store, contacts, sub-cycled motion and the
 * coupling with the SPH fluid (dem.h): OpenMP loops over grains or fluid
 * particles calling the bodies of dem_body.h (whose formulas are
 * src/physics/dem.h's), as the GPU's kernels do (gpu/gpu_dem.cu); each
 * writes only its own entries (gather form), so results do not depend on
 * the thread count. */
#include "dem.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "core/error.h"
#include "core/omp_shim.h"
#include "mpi/comm.h"
#include "dem_body.h"
/* Loops over fewer grains than this run on one thread: a DEM step of a few
 * grains is shorter than waking a team (measured: one grain in a 2744-particle
 * fluid ran 35 times slower with a team at every DEM step on a loaded
 * 2-core machine). */
#define DEM_OMP_MIN 256

static void *dem_calloc(size_t n, size_t sz)
{
    void *q = calloc(n ? n : 1, sz);
    if (!q) error_exit(EXIT_SYSTEM, "out of memory for %zu DEM entries", n);
    return q;
}

/* ---- the per-grain arrays ------------------------------------------------------ */

void dem_arrays(dem_t *d, dem_arr t[DEM_NARR])
{
    int k = 0;
    double **vec[6] = {d->x, d->v, d->w, d->fint, d->fd, d->uf};
    for (int q = 0; q < 6; ++q)
        for (int a = 0; a < 3; ++a) t[k++] = (dem_arr){(void **)&vec[q][a], sizeof(double)};
    t[k++] = (dem_arr){(void **)&d->eps, sizeof(double)};
    t[k++] = (dem_arr){(void **)&d->snorm, sizeof(double)};
    t[k++] = (dem_arr){(void **)&d->id, sizeof(int64_t)};
    t[k++] = (dem_arr){(void **)&d->ncon, sizeof(int)};
    t[k++] = (dem_arr){(void **)&d->cid, DEM_CMAX * sizeof(int64_t)};
    t[k++] = (dem_arr){(void **)&d->cxi, 3 * DEM_CMAX * sizeof(double)};
    t[k++] = (dem_arr){(void **)&d->ncon2, sizeof(int)};    /* 24: scratch from here */
    t[k++] = (dem_arr){(void **)&d->cid2, DEM_CMAX * sizeof(int64_t)};
    t[k++] = (dem_arr){(void **)&d->cxi2, 3 * DEM_CMAX * sizeof(double)};
    t[k] = (dem_arr){(void **)&d->gsum, 5 * sizeof(double)}; /* k = DEM_NARR - 1 */
}

void dem_reserve(dem_t *d, size_t m)
{
    if (m <= d->cap) return;
    size_t cap = d->cap + d->cap / 2;
    if (cap < m) cap = m;
    dem_arr t[DEM_NARR];
    dem_arrays(d, t);
    for (int k = 0; k < DEM_NARR; ++k) {
        void *q = realloc(*t[k].a, cap * t[k].bytes);
        if (!q) error_exit(EXIT_SYSTEM, "out of memory for %zu DEM grains", cap);
        *t[k].a = q;
    }
    d->cap = cap;
}

dem_t *dem_alloc(size_t n)
{
    dem_t *d = dem_calloc(1, sizeof *d);
    dem_reserve(d, n ? n : 1);
    dem_arr t[DEM_NARR];
    dem_arrays(d, t);
    for (int k = 0; k < DEM_NARR; ++k) memset(*t[k].a, 0, d->cap * t[k].bytes);
    d->n = d->no = d->ntot = n;
    for (size_t i = 0; i < n; ++i) d->id[i] = (int64_t)i, d->eps[i] = 1.0;
    return d;
}

/* Mass, inertia, damping and the DEM step from d->c (d, rho, kn) and e. */
void dem_derive(dem_t *d, double e)
{
    d->V = (double)dem_volume(d->c.d);
    d->m = d->V * (double)d->c.rho;
    d->I = 0.1 * d->m * (double)(d->c.d * d->c.d); /* 2/5 m r^2 */
    const double mstar = 0.5 * d->m;                 /* two equal grains; a wall's contact (m* = m) is slower */
    d->c.gn = dem_damping((real)e, (real)mstar, d->c.kn);
    d->dt = (double)dem_contact_time(d->c.kn, (real)mstar, d->c.gn) / DEM_STEPS_PER_CONTACT;
}

dem_t *dem_create(const struct scene *sc, double h, double rho_f, double nu, double K, const double g[3])
{
    const struct scene_dem *k = &sc->dem;
    if (!k->on) return NULL;
    size_t nb[3] = {1, 1, 1};
    if (k->placement == DEM_BLOCK)
        for (int a = 0; a < 3; ++a) nb[a] = (size_t)k->block_n[a];
    dem_t *d = dem_alloc(nb[0] * nb[1] * nb[2]);
    size_t i = 0;
    for (size_t c = 0; c < nb[2]; ++c)
        for (size_t b = 0; b < nb[1]; ++b)
            for (size_t a = 0; a < nb[0]; ++a, ++i) {
                const size_t q[3] = {a, b, c};
                for (int ax = 0; ax < 3; ++ax)
                    d->x[ax][i] = k->placement == DEM_BLOCK ? k->block_origin[ax] + (double)q[ax] * k->block_spacing
                                                            : k->at[ax];
            }
    d->c.d = (real)k->d, d->c.rho = (real)k->rho, d->c.kn = (real)k->kn;
    d->c.kt = (real)(k->kt > 0 ? k->kt : 2.0 / 7.0 * k->kn);
    d->c.mu = (real)k->mu;
    d->coupling = (int)k->coupling, d->motion = (int)k->motion;
    dem_derive(d, k->e);
    d->h = h, d->rho_f = rho_f, d->nu = nu, d->K = K, d->t_damp = k->t_damp;
    for (int a = 0; a < 3; ++a) d->g[a] = g[a];
    return d;
}

void dem_free(dem_t *d)
{
    if (!d) return;
    dem_arr t[DEM_NARR];
    dem_arrays(d, t);
    for (int k = 0; k < DEM_NARR; ++k) free(*t[k].a);
    free(d->eps_f), free(d->deps_f);
    free(d->gstart), free(d->gidx), free(d->fstart), free(d->fidx);
    free(d->soff), free(d->slist), free(d->goff), free(d->scnt), free(d->gcnt), free(d->bound0);
    for (int a = 0; a < 3; ++a) free(d->x0[a]);
    free(d);
}

/* ---- the state a checkpoint carries (dem.h) -------------------------------------- */

dem_state_array dem_state_get(dem_t *d, size_t k)
{
    static const char *const vec[18] = {/* a dataset per component */
                                        "CoordinatesX",       "CoordinatesY",       "CoordinatesZ",
                                        "VelocitiesX",        "VelocitiesY",        "VelocitiesZ",
                                        "AngularVelocitiesX", "AngularVelocitiesY", "AngularVelocitiesZ",
                                        "InteractionForceX",  "InteractionForceY",  "InteractionForceZ",
                                        "DragForceX",         "DragForceY",         "DragForceZ",
                                        "FluidVelocityX",     "FluidVelocityY",     "FluidVelocityZ"};
    if (k < 18) {
        double *const *v[6] = {d->x, d->v, d->w, d->fint, d->fd, d->uf};
        return (dem_state_array){vec[k], v[k / 3][k % 3], sizeof(double), 1, 1};
    }
    switch (k) {
    case 18: return (dem_state_array){"FluidFraction", d->eps, sizeof(double), 1, 1};
    case 19: return (dem_state_array){"KernelSum", d->snorm, sizeof(double), 1, 1};
    case 20: return (dem_state_array){"ParticleIDs", d->id, sizeof(int64_t), 1, 0};
    case 21: return (dem_state_array){"Contacts", d->ncon, sizeof(int), 1, 0};
    case 22: return (dem_state_array){"ContactPartners", d->cid, sizeof(int64_t), DEM_CMAX, 0};
    default: return (dem_state_array){"ContactSprings", d->cxi, sizeof(double), 3 * DEM_CMAX, 1}; /* 23 */
    }
}

const char *dem_state_check(const dem_t *d, int nwalls, char *why, size_t len)
{
    const size_t n = d->n;
    for (size_t k = 0; k < DEM_STATE_NARRAYS; ++k) {
        dem_state_array s = dem_state_get((dem_t *)d, k);
        const double *a = s.a;
        for (size_t i = 0; s.is_double && i < n * s.per; ++i)
            if (!isfinite(a[i]))
                return snprintf(why, len, "/DEM/%s[%zu] is not finite", s.name, i), why;
    }
    for (size_t i = 0; i < n; ++i) {
        if (d->id[i] != (int64_t)i)
            return snprintf(why, len, "/DEM/ParticleIDs[%zu] = %lld, not %zu", i, (long long)d->id[i], i),
                   why;
        if (d->ncon[i] < 0 || d->ncon[i] > DEM_CMAX)
            return snprintf(why, len, "/DEM/Contacts[%zu] = %d is out of range [0, %d]", i, d->ncon[i],
                            DEM_CMAX),
                   why;
        for (int c = 0; c < d->ncon[i]; ++c) {
            int64_t q = d->cid[i * DEM_CMAX + (size_t)c];
            if (q >= (int64_t)n || q < -(int64_t)nwalls || q == (int64_t)i)
                return snprintf(why, len, "/DEM/ContactPartners of grain %zu: %lld is neither another grain "
                                "(0..%zu) nor a wall (-1..-%d)", i, (long long)q, n - 1, nwalls), why;
        }
    }
    if (!isfinite(d->exch[0]) || !isfinite(d->exch[1]) || !isfinite(d->exch[2]) || d->steps < 0)
        return snprintf(why, len, "/DEM's Exchange or Steps is out of range"), why;
    return NULL;
}

/* ---- the view and the cell grid (cells of at least 2h and d) ------------------ */

dem_view dem_view_of(dem_t *d)
{
    dem_view v = dem_view_scalars(d);
    DEM_VIEW_ARRAYS(v, d);
    return v;
}

/* Is store entry a of p a fluid particle that the coupling bins: an owned
 * one (a grain's sums, eq. 20, take each rank's own; the source's pair term
 * walks the flow pass's neighbours, ghosts included: dem_fluid_source)? */
static int dem_binned(const particles_t *p, size_t a) { return a < p->n && dem_fluid(p, a); }

/* Counting sort of m points (grains, or the owned fluid particles of p)
 * into start[ncell + 1] and idx[m]: each cell's in ascending index order. */
static void dem_bin(dem_t *d, size_t m, const particles_t *p, size_t **start, size_t **idx, size_t *cap)
{
    size_t ncell = (size_t)d->nc[0] * (size_t)d->nc[1] * (size_t)d->nc[2];
    size_t *st = *start = realloc(*start, (ncell + 1) * sizeof(size_t));
    if (m > *cap || !*idx) *idx = realloc(*idx, (m ? m : 1) * sizeof(size_t)), *cap = m;
    if (!st || !*idx) error_exit(EXIT_SYSTEM, "out of memory for the DEM cell grid");
    memset(st, 0, (ncell + 1) * sizeof(size_t));
    const dem_view v = dem_view_scalars(d);
    int c[3];
    for (size_t i = 0; i < m; ++i) {
        if (p && !dem_binned(p, i)) continue;
        double x[3] = {d->x[0][i], d->x[1][i], d->x[2][i]};
        if (p) dem_fluid_at(&v, p, i, x);
        st[dem_cell(&v, x, c) + 1]++;
    }
    for (size_t k = 0; k < ncell; ++k) st[k + 1] += st[k];
    size_t *fill = dem_calloc(ncell, sizeof(size_t));
    for (size_t i = 0; i < m; ++i) {
        if (p && !dem_binned(p, i)) continue;
        double x[3] = {d->x[0][i], d->x[1][i], d->x[2][i]};
        if (p) dem_fluid_at(&v, p, i, x);
        size_t k = dem_cell(&v, x, c);
        (*idx)[st[k] + fill[k]++] = i;
    }
    free(fill);
}

void dem_grid_fit(dem_t *d, const double lo[3], const double hi[3])
{
    d->cell = fmax(2.0 * d->h, (double)d->c.d);
    for (int a = 0; a < 3; ++a) {
        if (d->per >> a & 1) { /* the period from 0 in whole cells, the last one wider (at least one cell) */
            double n = floor(d->plen[a] / d->cell);
            d->lo[a] = 0, d->nc[a] = n < 1 ? 1 : n > 1024 ? 1024 : (int)n;
            continue;
        }
        if (!(hi[a] >= lo[a])) { /* nothing to bin (a rank holding no grain, between couplings): one cell */
            d->lo[a] = 0, d->nc[a] = 1;
            continue;
        }
        d->lo[a] = lo[a];
        double n = floor((hi[a] - lo[a]) / d->cell) + 1;
        d->nc[a] = n > 1024 ? 1024 : (int)n; /* a grain flung far away shares the edge cells */
    }
}

/* The grid over the grains and, with p, the fluid particles. */
static void dem_grid(dem_t *d, const particles_t *p)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < d->n; ++i)
        for (int a = 0; a < 3; ++a) lo[a] = fmin(lo[a], d->x[a][i]), hi[a] = fmax(hi[a], d->x[a][i]);
    const size_t m = p ? p->n : 0;
    for (size_t i = 0; i < m; ++i)
        if (dem_binned(p, i))
            for (int a = 0; a < 3; ++a) lo[a] = fmin(lo[a], p->x[a][i]), hi[a] = fmax(hi[a], p->x[a][i]);
    dem_grid_fit(d, lo, hi);
    size_t gcap = d->n;
    dem_bin(d, d->n, NULL, &d->gstart, &d->gidx, &gcap);
    if (p) dem_bin(d, m, p, &d->fstart, &d->fidx, &d->fidx_cap);
}

/* ---- the coupling with the fluid ------------------------------------------------- */

void dem_period_set(dem_t *d, const wall_geom *w)
{
    d->per = w->periodic;
    for (int a = 0; a < 3; ++a) d->plen[a] = (double)w->period[a];
}

/* The fluid's periodic axes and periods (w) into d, and the grains wrapped
 * into the periods. */
static void dem_period(dem_t *d, const wall_geom *w)
{
    dem_period_set(d, w);
    if (!d->per) return;
    const dem_view v = dem_view_of(d);
    for (size_t i = 0; i < d->n; ++i) dem_wrap_grain(&v, i);
}

/* The grains' sums over the fluid (eq. 20): this rank's owned particles'
 * for every grain it holds, added at each grain's owner over the ranks in
 * rank order (dem_sums_home); then the owned grains' interaction forces,
 * and their results to the ghosts. */
static void dem_grains_couple(dem_t *d, const dem_view *v, const particles_t *p)
{
    const long ng = (long)d->n, no = (long)d->no;
    double *gs = d->gsum;
#pragma omp parallel for schedule(static) if (ng >= DEM_OMP_MIN)
    for (long i = 0; i < ng; ++i) dem_grain_partial(v, p, (size_t)i, &gs[5 * i]);
    dem_sums_home(d); /* one rank: as they are */
#pragma omp parallel for schedule(static) if (no >= DEM_OMP_MIN)
    for (long i = 0; i < no; ++i) {
        dem_grain_from_sums(v, (size_t)i, &gs[5 * i]);
        dem_grain_force(v, (size_t)i);
    }
    dem_refresh(d, DEM_SEND_COUPLING);
}

void dem_couple(dem_t *d, particles_t *p, const grid_view *g, const wall_geom *w, double t, double visc_norm,
                const struct halo *h)
{
    (void)t;
    dem_period(d, w);
    if (h && comm_size() > 1) {
        if (dem_exchange_due(d, h, dem_max_shift(d))) dem_exchange(d, h);
        else dem_refresh(d, DEM_SEND_GHOSTS);
    }
    const size_t nall = p->n + p->ng;
    if (nall > d->eps_cap) {
        free(d->eps_f), free(d->deps_f);
        d->eps_f = dem_calloc(nall, sizeof(double)), d->deps_f = dem_calloc(nall, sizeof(double));
        d->eps_cap = nall;
    }
    d->nown = p->n;
    dem_grid(d, p);
    const dem_view v = dem_view_of(d);
    const particles_t *pc = p;
    const int two = d->coupling == DEM_TWO_WAY;
    const long nf = (long)p->n, na = (long)nall;
    /* the fraction at the ghosts too (from the grains this rank holds, its
     * own and the ghost grains within the reach of its domain; a periodic
     * image's at its place in the period), for the source's pair term: no
     * exchange; two ways, the volume phi / eps of each, a ghost's from the
     * phi it carries, before the sums read them */
#pragma omp parallel for schedule(dynamic, 64)
    for (long a = 0; a < na; ++a)
        if (dem_fluid(pc, (size_t)a)) {
            dem_fluid_fraction(&v, pc, w, (size_t)a);
            if (two) dem_fluid_volume(&v, pc, (size_t)a);
        }
    dem_grains_couple(d, &v, pc);
    if (d->coupling != DEM_TWO_WAY) return;
#pragma omp parallel for schedule(dynamic, 64)
    for (long a = 0; a < nf; ++a)
        if (dem_fluid(pc, (size_t)a)) dem_fluid_source(&v, pc, g, (size_t)a, visc_norm);
}

/* ---- contacts and motion --------------------------------------------------------- */

void dem_overflow_exit(size_t i)
{
    error_exit(EXIT_NUMERICAL, "DEM grain %zu has more than %d contacts (overlapping grains: a stiffer DEM:kn)", i,
               DEM_CMAX);
}

/* DEM:motion rigid: the grains as one rigid body (symplectic Euler as the
 * free grains): its centre (the grains' mean: equal masses) moves by the
 * total force F_i over the total mass; its angular momentum I w grows by the
 * total torque about the centre, sum r_i x F_i + T_i (T_i the contacts'
 * torques on grain i), I = sum m (|r_i|^2 1 - r_i r_i^T) + n I_grain 1 the
 * inertia tensor of the grains as spheres about the centre, at the present
 * positions; then each r_i turns by |w| dt about w (Rodrigues) and v_i = v_c +
 * w x r_i (the bodies: dem_body.h, physics/dem.h). Across a periodic axis the body (continuous through the period,
 * as a laterally periodic block) translates only: its rotation is zero by
 * the lateral symmetry, and its grains' wrapped positions have no one
 * centre. The sums run over the grains in index order (the GPU's in a fixed
 * tree: gpu_dem.cu). */
static void dem_rigid_step(dem_t *d, const double *F, const double *T, double dt)
{
    const long n = (long)d->no; /* split: this rank's grains; the sums over the ranks in rank order */
    const double nt = (double)d->ntot, M = d->m * nt;
    const dem_view v = dem_view_of(d);
    double c[6] = {0, 0, 0, 0, 0, 0};
    real Tt[3] = {0, 0, 0}, J[9] = {0}, w[3], Ft[3] = {0, 0, 0};
    for (long i = 0; i < n; ++i)
        for (int q = 0; q < 3; ++q) c[q] += d->x[q][i] / nt, c[3 + q] += d->v[q][i] / nt;
    dem_sum_ranks(d, c, 6);
    const double xc[3] = {c[0], c[1], c[2]};
    double vc[3] = {c[3], c[4], c[5]};
    for (int q = 0; q < 3; ++q) w[q] = (real)(n ? d->w[q][0] : 0); /* every grain's: a rank without grains moves none */
    /* v_c: the grains' mean velocity (their spin's share, sum w x r_i / n, is zero) */
    for (long i = 0; i < n; ++i) dem_rigid_share(&v, (size_t)i, xc, &F[3 * i], &T[3 * i], Tt, Ft, J);
    if (d->split) {
        double s[15];
        for (int q = 0; q < 3; ++q) s[q] = (double)Tt[q], s[3 + q] = (double)Ft[q];
        for (int q = 0; q < 9; ++q) s[6 + q] = (double)J[q];
        dem_sum_ranks(d, s, 15);
        for (int q = 0; q < 3; ++q) Tt[q] = (real)s[q], Ft[q] = (real)s[3 + q];
        for (int q = 0; q < 9; ++q) J[q] = (real)s[6 + q];
    }
    for (int q = 0; q < 3; ++q) vc[q] += (double)Ft[q] / M * dt;
    if (!d->per) dem_spin_update(J, Tt, (real)dt, w);
    for (long i = 0; i < n; ++i) dem_rigid_move(&v, (size_t)i, xc, vc, w, dt);
}

/* Swap the contact lists: the last step's become the history (cid2, ...),
 * this step's go to the others. */
static void dem_lists_swap(dem_t *d)
{
    int64_t *ocid = d->cid;
    double *ocxi = d->cxi;
    int *oncon = d->ncon;
    d->cid = d->cid2, d->cxi = d->cxi2, d->ncon = d->ncon2;
    d->cid2 = ocid, d->cxi2 = ocxi, d->ncon2 = oncon;
}

/* One DEM step of length dt from t (symplectic Euler: v, w from the forces
 * at x; then x from the new v). */
static void dem_substep(dem_t *d, const wall_geom *w, double t, double dt, double *F, double *T, double *Fi, double *ex)
{
    const long n = (long)d->no; /* the owned grains: the ghosts are their owners' */
    dem_lists_swap(d);
    dem_period(d, w); /* a grain that crossed a period comes in from the other side */
    dem_refresh(d, DEM_SEND_MOTION);
    if (d->motion != DEM_RIGID) dem_grid(d, NULL);
    const dem_view v = dem_view_of(d);
    long bad = n; /* the lowest grain whose list overflowed */
    /* a rigid body's grains meet only walls: too little work a DEM step for a team */
#pragma omp parallel for schedule(static) if (n >= DEM_OMP_MIN && d->motion != DEM_RIGID) reduction(min : bad)
    for (long i = 0; i < n; ++i)
        if (dem_forces(&v, w, (size_t)i, t, dt, &F[3 * i], &T[3 * i], &Fi[3 * i]) && i < bad) bad = i;
    if (bad < n) dem_overflow_exit((size_t)d->id[bad]); /* its ID: split, the index is this rank's */
    if (!d->split) {
        for (long i = 0; i < n; ++i)
            for (int q = 0; q < 3; ++q) d->exch[q] += Fi[3 * i + q] * dt;
    } else { /* this rank's grains' sum of the step (dem_exch_steps adds the ranks') */
        for (long i = 0; i < n; ++i)
            for (int q = 0; q < 3; ++q) ex[q] += Fi[3 * i + q] * dt;
    }
    if (d->motion == DEM_FIXED) return;
    if (d->motion == DEM_RIGID) {
        dem_rigid_step(d, F, T, dt);
        return;
    }
#pragma omp parallel for schedule(static) if (n >= DEM_OMP_MIN)
    for (long i = 0; i < n; ++i) dem_move_free(&v, (size_t)i, &F[3 * i], &T[3 * i], dt);
}

long dem_substeps(const dem_t *d, double dt)
{
    /* fixed grains: their forces (the interaction force at the held fluid) are
     * the same at each DEM step of the fluid step, so one step of dt gives the
     * same exchange */
    long m = d->motion == DEM_FIXED ? 1 : (long)ceil(dt / d->dt);
    return m < 1 ? 1 : m;
}

void dem_advance(dem_t *d, const wall_geom *w, double t, double dt)
{
    dem_period(d, w);
    const long m = dem_substeps(d, dt);
    d->steps += m;
    double h = dt / (double)m;
    double *F = dem_calloc(3 * d->n, sizeof(double)), *T = dem_calloc(3 * d->n, sizeof(double));
    double *Fi = dem_calloc(3 * d->n, sizeof(double)), *ex = dem_calloc(3 * (size_t)m, sizeof(double));
    for (long k = 0; k < m; ++k) dem_substep(d, w, t + (double)k * h, h, F, T, Fi, &ex[3 * k]);
    dem_exch_steps(d, ex, m);
    dem_period(d, w);
    free(F), free(T), free(Fi), free(ex);
}

double dem_kinetic_energy(const dem_t *d)
{
    double e = 0;
    for (size_t i = 0; i < d->no; ++i)
        for (int q = 0; q < 3; ++q) e += 0.5 * (d->m * d->v[q][i] * d->v[q][i] + d->I * d->w[q][i] * d->w[q][i]);
    return e;
}

double dem_wall_load(const dem_t *d, const wall_geom *w, size_t i)
{
    const double R = 0.5 * (double)d->c.d;
    double load = 0;
    for (int k = 0; k < w->n; ++k) {
        real xr[3] = {(real)d->x[0][i], (real)d->x[1][i], (real)d->x[2][i]}, nr[3], uw[3];
        double delta = R + (double)wall_prim_depth(&w->prim[k], xr);
        if (delta <= 0) continue;
        wall_prim_normal(&w->prim[k], xr, nr);
        wall_velocity_at(&w->prim[k], xr, uw);
        /* dem_contact's normal force: n from the wall to the grain, vn the approach's sign (< 0 closing) */
        double vn = 0;
        for (int q = 0; q < 3; ++q) vn += (d->v[q][i] - (double)uw[q]) * (double)nr[q];
        load += fmax((double)d->c.kn * delta - (double)d->c.gn * vn, 0.0);
    }
    return load;
}
