/* dem.c — DEM grains: their store, contacts, sub-cycled motion and the
 * coupling with the SPH fluid (dem.h; the bodies are src/physics/dem.h).
 * OpenMP loops over grains or fluid particles, each writing only its own
 * entries (gather form), so results do not depend on the thread count. */
#include "dem.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "core/error.h"
#include "core/omp_shim.h"

/* The lowest fluid fraction a fluid particle or a grain is given (eq. 15
 * reaches 0 or below where a grain sits on a fluid particle and the kernel
 * is narrower than the grain, h < d; eq. 19 has no meaning there). */
#define DEM_EPS_MIN 0.1
/* The DEM step is the contact time over this (usual DEM practice: 20 to 50
 * steps a contact). A numerical choice, measured by tests/test_dem.c: the
 * head-on restitution's error against the clamped spring-dashpot is 1.6 %
 * at e = 0.7 with 20 steps, 0.7 % with 50 (first order). */
#define DEM_STEPS_PER_CONTACT 50
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

dem_t *dem_alloc(size_t n)
{
    dem_t *d = dem_calloc(1, sizeof *d);
    d->n = n;
    for (int a = 0; a < 3; ++a) {
        d->x[a] = dem_calloc(n, sizeof(double)), d->v[a] = dem_calloc(n, sizeof(double));
        d->w[a] = dem_calloc(n, sizeof(double)), d->fint[a] = dem_calloc(n, sizeof(double));
        d->fd[a] = dem_calloc(n, sizeof(double));
        d->uf[a] = dem_calloc(n, sizeof(double));
    }
    d->eps = dem_calloc(n, sizeof(double));
    d->snorm = dem_calloc(n, sizeof(double));
    d->id = dem_calloc(n, sizeof(int64_t));
    d->ncon = dem_calloc(n, sizeof(int));
    d->cid = dem_calloc(n * DEM_CMAX, sizeof(int64_t));
    d->cxi = dem_calloc(n * DEM_CMAX * 3, sizeof(double));
    d->ncon2 = dem_calloc(n, sizeof(int));
    d->cid2 = dem_calloc(n * DEM_CMAX, sizeof(int64_t));
    d->cxi2 = dem_calloc(n * DEM_CMAX * 3, sizeof(double));
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
    for (int a = 0; a < 3; ++a) free(d->x[a]), free(d->v[a]), free(d->w[a]), free(d->fint[a]), free(d->uf[a]), free(d->fd[a]);
    free(d->eps), free(d->snorm), free(d->id), free(d->ncon), free(d->cid), free(d->cxi);
    free(d->ncon2), free(d->cid2), free(d->cxi2);
    free(d->eps_f), free(d->deps_f);
    free(d->gstart), free(d->gidx), free(d->fstart), free(d->fidx);
    free(d);
}

/* ---- the cell grid (cells of at least 2h and d) -------------------------------- */

static int dem_fluid(const particles_t *p, size_t a) { return p->kind[a] == KIND_MATERIAL; }

static size_t dem_cell(const dem_t *d, const double x[3], int c[3])
{
    for (int a = 0; a < 3; ++a) {
        int q = (int)floor((x[a] - d->lo[a]) / d->cell);
        c[a] = q < 0 ? 0 : q >= d->nc[a] ? d->nc[a] - 1 : q;
    }
    return ((size_t)c[2] * (size_t)d->nc[1] + (size_t)c[1]) * (size_t)d->nc[0] + (size_t)c[0];
}

/* Counting sort of m points (grains, or the fluid particles of p) into
 * start[ncell + 1] and idx[m]. */
static void dem_bin(dem_t *d, size_t m, const particles_t *p, size_t **start, size_t **idx, size_t *cap)
{
    size_t ncell = (size_t)d->nc[0] * (size_t)d->nc[1] * (size_t)d->nc[2];
    size_t *st = *start = realloc(*start, (ncell + 1) * sizeof(size_t));
    if (m > *cap || !*idx) *idx = realloc(*idx, (m ? m : 1) * sizeof(size_t)), *cap = m;
    if (!st || !*idx) error_exit(EXIT_SYSTEM, "out of memory for the DEM cell grid");
    memset(st, 0, (ncell + 1) * sizeof(size_t));
    int c[3];
    for (size_t i = 0; i < m; ++i) {
        if (p && !dem_fluid(p, i)) continue;
        double x[3] = {p ? p->x[0][i] : d->x[0][i], p ? p->x[1][i] : d->x[1][i], p ? p->x[2][i] : d->x[2][i]};
        st[dem_cell(d, x, c) + 1]++;
    }
    for (size_t k = 0; k < ncell; ++k) st[k + 1] += st[k];
    size_t *fill = dem_calloc(ncell, sizeof(size_t));
    for (size_t i = 0; i < m; ++i) {
        if (p && !dem_fluid(p, i)) continue;
        double x[3] = {p ? p->x[0][i] : d->x[0][i], p ? p->x[1][i] : d->x[1][i], p ? p->x[2][i] : d->x[2][i]};
        size_t k = dem_cell(d, x, c);
        (*idx)[st[k] + fill[k]++] = i;
    }
    free(fill);
}

/* The grid over the grains and, with p, the fluid particles. */
static void dem_grid(dem_t *d, const particles_t *p)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < d->n; ++i)
        for (int a = 0; a < 3; ++a) lo[a] = fmin(lo[a], d->x[a][i]), hi[a] = fmax(hi[a], d->x[a][i]);
    if (p)
        for (size_t i = 0; i < p->n; ++i)
            if (dem_fluid(p, i))
                for (int a = 0; a < 3; ++a) lo[a] = fmin(lo[a], p->x[a][i]), hi[a] = fmax(hi[a], p->x[a][i]);
    d->cell = fmax(2.0 * d->h, (double)d->c.d);
    for (int a = 0; a < 3; ++a) {
        if (d->per >> a & 1) { /* the period from 0 in whole cells, the last one wider (at least one cell) */
            double n = floor(d->plen[a] / d->cell);
            d->lo[a] = 0, d->nc[a] = n < 1 ? 1 : n > 1024 ? 1024 : (int)n;
            continue;
        }
        d->lo[a] = lo[a];
        double n = floor((hi[a] - lo[a]) / d->cell) + 1;
        d->nc[a] = n > 1024 ? 1024 : (int)n; /* a grain flung far away shares the edge cells */
    }
    size_t gcap = d->n;
    dem_bin(d, d->n, NULL, &d->gstart, &d->gidx, &gcap);
    if (p) dem_bin(d, p->n, p, &d->fstart, &d->fidx, &d->fidx_cap);
}

/* The cells about cell c along axis a, from lo to hi: c - 1 to c + 1; along a
 * periodic axis of fewer than 3 cells, each of its cells once. */
static void dem_cell_span(const dem_t *d, int a, int c, int *lo, int *hi)
{
    *lo = c - 1, *hi = c + 1;
    if ((d->per >> a & 1) && d->nc[a] < 3) *lo = 0, *hi = d->nc[a] - 1;
}

/* Cell c along axis a wrapped into the grid (a periodic axis), or -1 when
 * it lies outside it. */
static int dem_cell_wrap(const dem_t *d, int a, int c)
{
    if (d->per >> a & 1) return ((c % d->nc[a]) + d->nc[a]) % d->nc[a];
    return c < 0 || c >= d->nc[a] ? -1 : c;
}

/* r = x - y, the minimum image along the periodic axes (the periods are
 * over 4 supports 2h and 2 grains: the scene's check). */
static void dem_sep(const dem_t *d, const double x[3], double y0, double y1, double y2, double r[3])
{
    r[0] = x[0] - y0, r[1] = x[1] - y1, r[2] = x[2] - y2;
    for (int a = 0; a < 3; ++a)
        if (d->per >> a & 1) r[a] -= d->plen[a] * floor(r[a] / d->plen[a] + 0.5);
}

/* Loops over the entries of the 27 cells about point x of a binned set
 * (across a periodic axis, the cells of the other side). */
#define DEM_CELLS_BEGIN(d, x, start, idx, j)                                                      \
    {                                                                                              \
        int c0_[3], lo_[3], hi_[3];                                                                \
        dem_cell(d, x, c0_);                                                                       \
        for (int a_ = 0; a_ < 3; ++a_) dem_cell_span(d, a_, c0_[a_], &lo_[a_], &hi_[a_]);         \
        for (int cz_ = lo_[2]; cz_ <= hi_[2]; ++cz_)                                               \
            for (int cy_ = lo_[1]; cy_ <= hi_[1]; ++cy_)                                           \
                for (int cx_ = lo_[0]; cx_ <= hi_[0]; ++cx_) {                                     \
                    int wx_ = dem_cell_wrap(d, 0, cx_), wy_ = dem_cell_wrap(d, 1, cy_),            \
                        wz_ = dem_cell_wrap(d, 2, cz_);                                            \
                    if (wx_ < 0 || wy_ < 0 || wz_ < 0) continue;                                   \
                    size_t k_ = ((size_t)wz_ * (size_t)d->nc[1] + (size_t)wy_) * (size_t)d->nc[0] + \
                                (size_t)wx_;                                                       \
                    for (size_t q_ = (start)[k_]; q_ < (start)[k_ + 1]; ++q_) {                    \
                        size_t j = (idx)[q_];
#define DEM_CELLS_END \
    }                 \
    }                 \
    }

/* ---- the coupling with the fluid ------------------------------------------------- */

/* Gamma of eq. (16) at x: the nearest wall's (the paper's choice; a corner,
 * where two walls cut the kernel, is not corrected further). */
static double dem_gamma_at(const dem_t *d, const wall_geom *w, const real x[3])
{
    double y = INFINITY;
    for (int k = 0; k < w->n; ++k) y = fmin(y, -(double)wall_prim_depth(&w->prim[k], x));
    return y == INFINITY ? 1.0 : (double)dem_gamma_wall(3, (real)y, (real)d->h);
}

/* Fluid particle a: eps_a (15-16) and d eps_a / dt following a, =
 * -sum_i V_i grad_a W_ai . (u_a - v_i). */
static void dem_fluid_fraction(dem_t *d, const particles_t *p, const wall_geom *w, size_t a)
{
    const double x[3] = {p->x[0][a], p->x[1][a], p->x[2][a]}, h = d->h, alpha = kernel_alpha(3, (real)h);
    double s = 0, de = 0;
    DEM_CELLS_BEGIN(d, x, d->gstart, d->gidx, i)
        double r[3];
        dem_sep(d, x, d->x[0][i], d->x[1][i], d->x[2][i], r);
        double rr = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
        if (rr >= 2.0 * h) continue;
        s += d->V * (double)kernel_w((real)rr, (real)h, (real)alpha);
        double f = (double)kernel_f((real)rr, (real)h, (real)alpha), du = 0;
        for (int q = 0; q < 3; ++q) du += r[q] * ((double)p->v[q][a] - d->v[q][i]);
        de -= d->V * f * du;
    DEM_CELLS_END
    const real xr[3] = {p->x[0][a], p->x[1][a], p->x[2][a]};
    d->eps_f[a] = (double)dem_fraction((real)s, (real)dem_gamma_at(d, w, xr), (real)DEM_EPS_MIN);
    d->deps_f[a] = de;
}

/* Grain i: eps_i and u_f,i (eq. 20), the denominator of (14), and the
 * interaction force (19-23) at its present velocity. */
static void dem_grain_sums(dem_t *d, const particles_t *p, size_t i)
{
    const double x[3] = {d->x[0][i], d->x[1][i], d->x[2][i]}, h = d->h, alpha = kernel_alpha(3, (real)h);
    double S = 0, E = 0, U[3] = {0, 0, 0};
    DEM_CELLS_BEGIN(d, x, d->fstart, d->fidx, a)
        double r[3];
        dem_sep(d, x, p->x[0][a], p->x[1][a], p->x[2][a], r);
        double rr = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
        if (rr >= 2.0 * h) continue;
        double vw = (double)p->vol[a] * (double)kernel_w((real)rr, (real)h, (real)alpha);
        S += vw, E += d->eps_f[a] * vw;
        for (int q = 0; q < 3; ++q) U[q] += (double)p->v[q][a] * vw;
    DEM_CELLS_END
    d->snorm[i] = S;
    d->eps[i] = S > 0 ? fmax(E / S, DEM_EPS_MIN) : 1.0;
    for (int q = 0; q < 3; ++q) d->uf[q][i] = S > 0 ? U[q] / S : 0.0;
}

/* The interaction force on grain i (eq. 23) at its velocity now, and its
 * drag part F_D (eq. 19) into Fd when Fd is not NULL. */
static void dem_force_int(const dem_t *d, size_t i, double F[3], double *Fd)
{
    real u[3], FD[3], Fi[3], g[3];
    for (int q = 0; q < 3; ++q) u[q] = (real)(d->uf[q][i] - d->v[q][i]), g[q] = (real)d->g[q];
    dem_drag(d->c.d, (real)d->rho_f, (real)d->nu, (real)d->eps[i], u, FD);
    dem_interaction(FD, (real)d->eps[i], (real)d->V, (real)d->rho_f, g, Fi);
    for (int q = 0; q < 3; ++q) F[q] = (double)Fi[q];
    if (Fd)
        for (int q = 0; q < 3; ++q) Fd[q] = (double)FD[q];
}

/* two_way, fluid particle a (model A of the DEM paper's eq. 6 per unit mass
 * of fluid, rho_bar = eps rho_f): the source -sum_i w_ai F_D,i / (eps_a
 * rho_f V_a), w_ai = V_a W_ai / sum_b V_b W_bi (eqs. 13-14, with eq. 24's
 * drag, as model A takes it: the fluid's -eps grad p carries the pressure's
 * share, and the grain's -V grad p of eq. 23, F_D / eps - V rho_f g, is
 * what -eps grad p = eps rho_f g - n F_D gives inside a uniform bed; handing
 * the fluid all of F_int as well, as model B's -grad p does, counts the
 * pressure's share twice: at rest the bed's pressure then grows by rho_f g /
 * eps, not rho_f g, and a settling grain drags the fluid down with it,
 * docs/validation.md "DEM grains in a fluid"); div(eps tau) / eps
 * less the fluid's own div(tau) (Morris's pair term with the mean
 * (eps_a + eps_b) / 2: + V_b 2 nu f u_ab ((eps_a + eps_b) / (2 eps_a) - 1));
 * -eps grad p / (eps rho_f) is the fluid's own -grad p / rho_f. The
 * superficial density's continuity D(eps rho)/Dt = -eps rho div u adds
 * dp/dt = -(K / eps_a) D eps_a / Dt to the pressure rate. */
static void dem_fluid_source(dem_t *d, particles_t *p, size_t a, double visc_norm)
{
    const double x[3] = {p->x[0][a], p->x[1][a], p->x[2][a]}, h = d->h, alpha = kernel_alpha(3, (real)h);
    const double ea = d->eps_f[a];
    double acc[3] = {0, 0, 0};
    DEM_CELLS_BEGIN(d, x, d->gstart, d->gidx, i)
        double r[3];
        dem_sep(d, x, d->x[0][i], d->x[1][i], d->x[2][i], r);
        double rr = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
        if (rr >= 2.0 * h || !(d->snorm[i] > 0)) continue;
        double Wc = (double)kernel_w((real)rr, (real)h, (real)alpha) / (d->snorm[i] * ea * d->rho_f);
        for (int q = 0; q < 3; ++q) acc[q] -= Wc * d->fd[q][i];
    DEM_CELLS_END
    const double nu2 = 2.0 * d->nu * visc_norm;
    DEM_CELLS_BEGIN(d, x, d->fstart, d->fidx, b)
        if (b == a) continue;
        double r[3];
        dem_sep(d, x, p->x[0][b], p->x[1][b], p->x[2][b], r);
        double rr = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
        double c = 0.5 * (ea + d->eps_f[b]) / ea - 1.0;
        if (rr >= 2.0 * h || c == 0) continue;
        double f = (double)kernel_f((real)rr, (real)h, (real)alpha) * nu2 * (double)p->vol[b] * c;
        for (int q = 0; q < 3; ++q) acc[q] += f * ((double)p->v[q][a] - (double)p->v[q][b]);
    DEM_CELLS_END
    for (int q = 0; q < 3; ++q) p->acc[q][a] += (real)acc[q];
    const double dp = -d->K / ea * d->deps_f[a]; /* Pa/s; sigma is tension positive */
    for (int q = 0; q < 3; ++q) p->dsig[q][a] -= (real)dp;
}

/* The fluid's periodic axes and periods (w) into d, and the grains wrapped
 * into the periods. */
static void dem_period(dem_t *d, const wall_geom *w)
{
    d->per = w->periodic;
    for (int a = 0; a < 3; ++a) {
        d->plen[a] = (double)w->period[a];
        if (!(d->per >> a & 1)) continue;
        for (size_t i = 0; i < d->n; ++i) d->x[a][i] -= d->plen[a] * floor(d->x[a][i] / d->plen[a]);
    }
}

void dem_couple(dem_t *d, particles_t *p, const wall_geom *w, double t, double visc_norm)
{
    (void)t;
    dem_period(d, w);
    if (p->n > d->eps_cap) {
        free(d->eps_f), free(d->deps_f);
        d->eps_f = dem_calloc(p->n, sizeof(double)), d->deps_f = dem_calloc(p->n, sizeof(double));
        d->eps_cap = p->n;
    }
    dem_grid(d, p);
    const long nf = (long)p->n, ng = (long)d->n, n = ng;
#pragma omp parallel for schedule(dynamic, 64)
    for (long a = 0; a < nf; ++a)
        if (dem_fluid(p, (size_t)a)) dem_fluid_fraction(d, p, w, (size_t)a);
#pragma omp parallel for schedule(static) if (n >= DEM_OMP_MIN)
    for (long i = 0; i < ng; ++i) {
        dem_grain_sums(d, p, (size_t)i);
        double F[3], Fd[3];
        dem_force_int(d, (size_t)i, F, Fd);
        for (int q = 0; q < 3; ++q) d->fint[q][i] = F[q], d->fd[q][i] = Fd[q];
    }
    if (d->coupling != DEM_TWO_WAY) return;
#pragma omp parallel for schedule(dynamic, 64)
    for (long a = 0; a < nf; ++a)
        if (dem_fluid(p, (size_t)a)) dem_fluid_source(d, p, (size_t)a, visc_norm);
}

/* ---- contacts and motion --------------------------------------------------------- */

/* The history of grain i's contact with partner pid in its list before
 * this step (xi[3], zero for a new contact). */
static void dem_history(const int64_t *cid, const double *cxi, const int *ncon, size_t i,
                        int64_t pid, real xi[3])
{
    xi[0] = xi[1] = xi[2] = 0;
    for (int k = 0; k < ncon[i]; ++k)
        if (cid[i * DEM_CMAX + (size_t)k] == pid) {
            for (int q = 0; q < 3; ++q) xi[q] = (real)cxi[(i * DEM_CMAX + (size_t)k) * 3 + q];
            return;
        }
}

/* One contact of grain i into its new list and its force and torque sums:
 * n from the partner to i, overlap delta, the partner's contact-point
 * velocity vp (its centre's velocity plus its spin's share; a wall's). */
static void dem_touch(dem_t *d, size_t i, int64_t pid, const double n[3], double delta, const double vp[3],
                      double dt, const int64_t *ocid, const double *ocxi, const int *oncon, int *nk, double F[3],
                      double T[3])
{
    const double R = 0.5 * (double)d->c.d;
    real xi[3], nn[3], vrel[3], Fc[3];
    dem_history(ocid, ocxi, oncon, i, pid, xi);
    for (int q = 0; q < 3; ++q) nn[q] = (real)n[q];
    /* contact point of i: x_i - R n, its velocity v_i + w_i x (-R n) */
    const double wi[3] = {d->w[0][i], d->w[1][i], d->w[2][i]};
    const double wxn[3] = {wi[1] * n[2] - wi[2] * n[1], wi[2] * n[0] - wi[0] * n[2], wi[0] * n[1] - wi[1] * n[0]};
    for (int q = 0; q < 3; ++q) vrel[q] = (real)(d->v[q][i] - R * wxn[q] - vp[q]);
    dem_contact(&d->c, nn, (real)delta, vrel, xi, (real)dt, Fc);
    for (int q = 0; q < 3; ++q) F[q] += (double)Fc[q];
    /* torque (-R n) x F */
    T[0] += -R * (n[1] * (double)Fc[2] - n[2] * (double)Fc[1]);
    T[1] += -R * (n[2] * (double)Fc[0] - n[0] * (double)Fc[2]);
    T[2] += -R * (n[0] * (double)Fc[1] - n[1] * (double)Fc[0]);
    if (*nk >= DEM_CMAX) error_exit(EXIT_NUMERICAL, "DEM grain %zu has more than %d contacts (overlapping grains: a stiffer DEM:kn)", i, DEM_CMAX);
    d->cid[i * DEM_CMAX + (size_t)*nk] = pid;
    for (int q = 0; q < 3; ++q) d->cxi[(i * DEM_CMAX + (size_t)*nk) * 3 + q] = (double)xi[q];
    ++*nk;
}

/* The force F and torque T on grain i at time t: gravity (3-4), the
 * interaction force (23), and its contacts with grains and walls, whose
 * list and history it rewrites. */
static void dem_forces(dem_t *d, const wall_geom *w, size_t i, double t, double dt, const int64_t *ocid,
                       const double *ocxi, const int *oncon, double F[3], double T[3], double Fi[3])
{
    const double D = (double)d->c.d, R = 0.5 * D, x[3] = {d->x[0][i], d->x[1][i], d->x[2][i]};
    real g[3] = {(real)d->g[0], (real)d->g[1], (real)d->g[2]}, Fg[3];
    dem_gravity((real)d->V, g, (real)d->rho_f, d->c.rho, dem_gravity_ramp(t, d->t_damp), Fg);
    dem_force_int(d, i, Fi, NULL);
    for (int q = 0; q < 3; ++q) F[q] = (double)Fg[q] + Fi[q], T[q] = 0;
    int nk = 0;
    if (d->motion != DEM_RIGID) /* a rigid body's own contacts cancel in its sums */
    DEM_CELLS_BEGIN(d, x, d->gstart, d->gidx, j)
        if (j == i) continue;
        double r[3];
        dem_sep(d, x, d->x[0][j], d->x[1][j], d->x[2][j], r);
        double rr = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
        if (rr >= D || !(rr > 0)) continue;
        double n[3] = {r[0] / rr, r[1] / rr, r[2] / rr}, vp[3];
        const double wj[3] = {d->w[0][j], d->w[1][j], d->w[2][j]};
        /* j's contact point x_j + R n: v_j + w_j x (R n) */
        vp[0] = d->v[0][j] + R * (wj[1] * n[2] - wj[2] * n[1]);
        vp[1] = d->v[1][j] + R * (wj[2] * n[0] - wj[0] * n[2]);
        vp[2] = d->v[2][j] + R * (wj[0] * n[1] - wj[1] * n[0]);
        dem_touch(d, i, d->id[j], n, D - rr, vp, dt, ocid, ocxi, oncon, &nk, F, T);
    DEM_CELLS_END
    for (int k = 0; k < w->n; ++k) {
        const wall_prim *q = &w->prim[k];
        if (q->open_at >= 0 && t >= q->open_at) continue; /* an open gate */
        real xr[3] = {(real)x[0], (real)x[1], (real)x[2]}, nr[3], uw[3];
        double delta = R + (double)wall_prim_depth(q, xr);
        if (delta <= 0) continue;
        wall_prim_normal(q, xr, nr);
        wall_velocity_at(q, xr, uw);
        double n[3] = {nr[0], nr[1], nr[2]}, vp[3] = {uw[0], uw[1], uw[2]};
        dem_touch(d, i, -1 - (int64_t)k, n, delta, vp, dt, ocid, ocxi, oncon, &nk, F, T);
    }
    d->ncon[i] = nk;
}

/* DEM:motion rigid: the grains as one rigid body (symplectic Euler as the
 * free grains): its centre (the grains' mean: equal masses) moves by the
 * total force F_i over the total mass; its angular momentum I w grows by the
 * total torque about the centre, sum r_i x F_i + T_i (T_i the contacts'
 * torques on grain i), I = sum m (|r_i|^2 1 - r_i r_i^T) + n I_grain 1 the
 * inertia tensor of the grains as spheres about the centre, at the present
 * positions; then each r_i turns by |w| dt about w (Rodrigues) and v_i = v_c +
 * w x r_i (the bodies: physics/dem.h). Across a periodic axis the body (continuous through the period,
 * as a laterally periodic block) translates only: its rotation is zero by
 * the lateral symmetry, and its grains' wrapped positions have no one
 * centre. */
static void dem_rigid_step(dem_t *d, const double *F, const double *T, double dt)
{
    const long n = (long)d->n;
    const double M = d->m * (double)n;
    double xc[3] = {0, 0, 0}, vc[3] = {0, 0, 0};
    real Tt[3] = {0, 0, 0}, J[9] = {0}, w[3], Ft[3] = {0, 0, 0};
    for (long i = 0; i < n; ++i)
        for (int q = 0; q < 3; ++q) xc[q] += d->x[q][i] / (double)n, vc[q] += d->v[q][i] / (double)n;
    for (int q = 0; q < 3; ++q) w[q] = (real)(n ? d->w[q][0] : 0);
    /* v_c: the grains' mean velocity (their spin's share, sum w x r_i / n, is zero) */
    for (long i = 0; i < n; ++i) {
        const real r[3] = {(real)(d->x[0][i] - xc[0]), (real)(d->x[1][i] - xc[1]), (real)(d->x[2][i] - xc[2])};
        const double *f = &F[3 * i];
        Tt[0] += (real)(r[1] * f[2] - r[2] * f[1] + T[3 * i]);
        Tt[1] += (real)(r[2] * f[0] - r[0] * f[2] + T[3 * i + 1]);
        Tt[2] += (real)(r[0] * f[1] - r[1] * f[0] + T[3 * i + 2]);
        for (int q = 0; q < 3; ++q) Ft[q] += (real)f[q];
        dem_inertia_add((real)d->m, (real)d->I, r, J);
    }
    for (int q = 0; q < 3; ++q) vc[q] += (double)Ft[q] / M * dt;
    if (!d->per) dem_spin_update(J, Tt, (real)dt, w);
    for (long i = 0; i < n; ++i) {
        const real r[3] = {(real)(d->x[0][i] - xc[0]), (real)(d->x[1][i] - xc[1]), (real)(d->x[2][i] - xc[2])};
        real rn[3];
        dem_turn(w, (real)dt, r, rn);
        const real wr[3] = {w[1] * rn[2] - w[2] * rn[1], w[2] * rn[0] - w[0] * rn[2], w[0] * rn[1] - w[1] * rn[0]};
        for (int q = 0; q < 3; ++q) {
            d->x[q][i] = xc[q] + vc[q] * dt + (double)rn[q];
            d->v[q][i] = vc[q] + (double)wr[q];
            d->w[q][i] = (double)w[q];
        }
    }
}

/* One DEM step of length dt from t (symplectic Euler: v, w from the forces
 * at x; then x from the new v). */
static void dem_substep(dem_t *d, const wall_geom *w, double t, double dt, double *F, double *T, double *Fi)
{
    const long n = (long)d->n;
    int64_t *ocid = d->cid; /* last step's lists: the history; this step's go to the spare lists */
    double *ocxi = d->cxi;
    int *oncon = d->ncon;
    d->cid = d->cid2, d->cxi = d->cxi2, d->ncon = d->ncon2;
    d->cid2 = ocid, d->cxi2 = ocxi, d->ncon2 = oncon;
    dem_period(d, w); /* a grain that crossed a period comes in from the other side */
    if (d->motion != DEM_RIGID) dem_grid(d, NULL);
    /* a rigid body's grains meet only walls: too little work a DEM step for a team */
#pragma omp parallel for schedule(static) if (n >= DEM_OMP_MIN && d->motion != DEM_RIGID)
    for (long i = 0; i < n; ++i)
        dem_forces(d, w, (size_t)i, t, dt, ocid, ocxi, oncon, &F[3 * i], &T[3 * i], &Fi[3 * i]);
    for (long i = 0; i < n; ++i)
        for (int q = 0; q < 3; ++q) d->exch[q] += Fi[3 * i + q] * dt;
    if (d->motion == DEM_FIXED) return;
    if (d->motion == DEM_RIGID) {
        dem_rigid_step(d, F, T, dt);
        return;
    }
#pragma omp parallel for schedule(static) if (n >= DEM_OMP_MIN)
    for (long i = 0; i < n; ++i)
        for (int q = 0; q < 3; ++q) {
            d->v[q][i] += F[3 * i + q] / d->m * dt;
            d->w[q][i] += T[3 * i + q] / d->I * dt;
            d->x[q][i] += d->v[q][i] * dt;
        }
}

void dem_advance(dem_t *d, const wall_geom *w, double t, double dt)
{
    dem_period(d, w);
    /* fixed grains: their forces (the interaction force at the held fluid) are
     * the same at each DEM step of the fluid step, so one step of dt gives the
     * same exchange */
    long m = d->motion == DEM_FIXED ? 1 : (long)ceil(dt / d->dt);
    if (m < 1) m = 1;
    double h = dt / (double)m;
    double *F = dem_calloc(3 * d->n, sizeof(double)), *T = dem_calloc(3 * d->n, sizeof(double));
    double *Fi = dem_calloc(3 * d->n, sizeof(double));
    for (long k = 0; k < m; ++k) dem_substep(d, w, t + (double)k * h, h, F, T, Fi);
    dem_period(d, w);
    free(F), free(T), free(Fi);
}

double dem_kinetic_energy(const dem_t *d)
{
    double e = 0;
    for (size_t i = 0; i < d->n; ++i)
        for (int q = 0; q < 3; ++q) e += 0.5 * (d->m * d->v[q][i] * d->v[q][i] + d->I * d->w[q][i] * d->w[q][i]);
    return e;
}

double dem_wall_load(const dem_t *d, const wall_geom *w, size_t i)
{
    const double R = 0.5 * (double)d->c.d;
    double load = 0;
    for (int k = 0; k < w->n; ++k) {
        real xr[3] = {(real)d->x[0][i], (real)d->x[1][i], (real)d->x[2][i]}, nr[3];
        double delta = R + (double)wall_prim_depth(&w->prim[k], xr);
        if (delta <= 0) continue;
        wall_prim_normal(&w->prim[k], xr, nr);
        double vn = d->v[0][i] * nr[0] + d->v[1][i] * nr[1] + d->v[2][i] * nr[2];
        load += fmax((double)d->c.kn * delta + (double)d->c.gn * vn, 0.0);
    }
    return load;
}
