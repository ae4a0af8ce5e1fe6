/* dem/dem_body.h — the per-item bodies of the DEM grains (issue 58), written
 * once for the CPU's OpenMP loops (src/dem/dem.c) and the GPU's kernels
 * (gpu/gpu_dem.cu): the coupling's cell grid and its walk, the fluid
 * fraction at a fluid particle, a grain's sums over the fluid, the
 * interaction force, the two-way fluid source, a grain's contacts with
 * grains and walls (with the history and the list it writes), the motion of
 * a free grain and of a rigid body's grains. They read and write through a
 * dem_view, plain data passed by value: host pointers on the CPU (dem_view_of,
 * dem.c), device pointers on the GPU, the scalars (parameters, the grid's
 * extent, the periods) the host's dem_t holds in both. A body neither
 * allocates nor stops the run: a contact list that overflows is returned as
 * 1, and the caller reports it. The formulas are src/physics/dem.h's. */
#ifndef SPHSEG_DEM_BODY_H
#define SPHSEG_DEM_BODY_H
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include "core/particles.h"
#include "dem.h"
#include "physics/dem.h"
#include "physics/grid.h"
#include "physics/kernel.h"
#include "physics/wall.h"

/* The lowest fluid fraction a fluid particle or a grain is given (eq. 15
 * reaches 0 or below where a grain sits on a fluid particle and the kernel
 * is narrower than the grain, h < d; eq. 19 has no meaning there). */
#define DEM_EPS_MIN 0.1

/* What a body reads and writes: the grains' arrays, the fluid fraction at
 * the fluid particles, the cell grid, and the scalars of dem_t. */
typedef struct dem_view {
    dem_params c;
    int coupling, motion; /* enum dem_coupling, enum dem_motion */
    size_t n;             /* grains */
    double *x[3], *v[3], *w[3], *fint[3], *fd[3], *uf[3], *eps, *snorm;
    const int64_t *id;
    int *ncon;            /* this DEM step's contact lists (written by dem_forces) */
    int64_t *cid;
    double *cxi;
    const int *oncon;     /* the last step's (read: the history) */
    const int64_t *ocid;
    const double *ocxi;
    double *eps_f, *deps_f; /* at the fluid particles, owned and ghosts */
    size_t nown;          /* the owned fluid particles [0, nown): a grain's sums take only these */
    double V, m, I, rho_f, nu, K, h, g[3], t_damp;
    double lo[3], cell, plen[3];
    int nc[3], per;
    const size_t *gstart, *gidx, *fstart, *fidx; /* grains and fluid particles by cell */
} dem_view;

/* The view of d's host arrays (dem.c): the lists that a DEM step writes
 * (cid, cxi, ncon) and those it reads as the history (cid2, cxi2, ncon2). */
dem_view dem_view_of(dem_t *d);

/* The scalars of d in a view whose arrays are NULL (the caller points them
 * at the host's arrays or at the device's). */
static inline dem_view dem_view_scalars(const dem_t *d)
{
    dem_view v;
    memset(&v, 0, sizeof v);
    v.c = d->c, v.coupling = d->coupling, v.motion = d->motion, v.n = d->n;
    v.V = d->V, v.m = d->m, v.I = d->I, v.rho_f = d->rho_f, v.nu = d->nu, v.K = d->K, v.h = d->h;
    v.t_damp = d->t_damp, v.cell = d->cell, v.per = d->per, v.nown = d->nown;
    for (int a = 0; a < 3; ++a) v.g[a] = d->g[a], v.lo[a] = d->lo[a], v.plen[a] = d->plen[a], v.nc[a] = d->nc[a];
    return v;
}

/* The view's arrays from src, a dem_t (host arrays, dem.c) or the GPU's
 * mirror (device arrays, gpu_dem.cu), whose arrays have dem_t's names: the
 * lists a DEM step writes (cid, cxi, ncon) and those it reads as the
 * history (cid2, cxi2, ncon2: the last step's, swapped in dem_substep). One
 * list of fields for both, so a new array cannot be missed on one side. */
#define DEM_VIEW_ARRAYS(v, src)                                                                              \
    do {                                                                                                     \
        for (int a_ = 0; a_ < 3; ++a_) {                                                                     \
            (v).x[a_] = (src)->x[a_], (v).v[a_] = (src)->v[a_], (v).w[a_] = (src)->w[a_];                    \
            (v).fint[a_] = (src)->fint[a_], (v).fd[a_] = (src)->fd[a_], (v).uf[a_] = (src)->uf[a_];          \
        }                                                                                                    \
        (v).eps = (src)->eps, (v).snorm = (src)->snorm, (v).id = (src)->id;                                  \
        (v).ncon = (src)->ncon, (v).cid = (src)->cid, (v).cxi = (src)->cxi;                                  \
        (v).oncon = (src)->ncon2, (v).ocid = (src)->cid2, (v).ocxi = (src)->cxi2;                            \
        (v).eps_f = (src)->eps_f, (v).deps_f = (src)->deps_f;                                                \
        (v).gstart = (src)->gstart, (v).gidx = (src)->gidx, (v).fstart = (src)->fstart, (v).fidx = (src)->fidx; \
    } while (0)

HD_INLINE int dem_fluid(const particles_t *p, size_t a) { return p->kind[a] == KIND_MATERIAL; }

/* ---- the cell grid (cells of at least 2h and d) -------------------------------- */

/* Point x brought into the period along the periodic axes where it lies
 * outside it (the GPU's store wraps its particles only at list builds; the
 * CPU's, and the grains, are in the period already: unchanged). */
HD_INLINE void dem_wrap_point(const dem_view *d, double x[3])
{
    for (int a = 0; a < 3; ++a)
        if ((d->per >> a & 1) && (x[a] < 0 || x[a] >= d->plen[a])) x[a] -= d->plen[a] * floor(x[a] / d->plen[a]);
}

/* The cell of point x (in the period), clamped to the grid: c[3] and its key. */
HD_INLINE size_t dem_cell(const dem_view *d, const double x[3], int c[3])
{
    for (int a = 0; a < 3; ++a) {
        int q = (int)floor((x[a] - d->lo[a]) / d->cell);
        c[a] = q < 0 ? 0 : q >= d->nc[a] ? d->nc[a] - 1 : q;
    }
    return ((size_t)c[2] * (size_t)d->nc[1] + (size_t)c[1]) * (size_t)d->nc[0] + (size_t)c[0];
}

/* The cells about cell c along axis a, from lo to hi: c - 1 to c + 1; along a
 * periodic axis of fewer than 3 cells, each of its cells once. */
HD_INLINE void dem_cell_span(const dem_view *d, int a, int c, int *lo, int *hi)
{
    *lo = c - 1, *hi = c + 1;
    if ((d->per >> a & 1) && d->nc[a] < 3) *lo = 0, *hi = d->nc[a] - 1;
}

/* Cell c along axis a wrapped into the grid (a periodic axis), or -1 when
 * it lies outside it. */
HD_INLINE int dem_cell_wrap(const dem_view *d, int a, int c)
{
    if (d->per >> a & 1) return ((c % d->nc[a]) + d->nc[a]) % d->nc[a];
    return c < 0 || c >= d->nc[a] ? -1 : c;
}

/* r = x - y, the minimum image along the periodic axes (the periods are
 * over 4 supports 2h and 2 grains: the scene's check). */
HD_INLINE void dem_sep(const dem_view *d, const double x[3], double y0, double y1, double y2, double r[3])
{
    r[0] = x[0] - y0, r[1] = x[1] - y1, r[2] = x[2] - y2;
    for (int a = 0; a < 3; ++a)
        if (d->per >> a & 1) r[a] -= d->plen[a] * floor(r[a] / d->plen[a] + 0.5);
}

/* Loops over the entries j of the 27 cells about point x (in the period) of
 * a binned set, each cell's in ascending index order (across a periodic
 * axis, the cells of the other side). */
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

/* The squared distance grain i moved from x0 (its centre at the last
 * exchange, src/dem/dem_halo.c), the minimum image across the periods. */
HD_INLINE double dem_shift2(const dem_view *d, size_t i, const double *const x0[3])
{
    const double x[3] = {d->x[0][i], d->x[1][i], d->x[2][i]};
    double r[3];
    dem_sep(d, x, x0[0][i], x0[1][i], x0[2][i], r);
    return r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
}

/* Grain i back into the period along the periodic axes. */
HD_INLINE void dem_wrap_grain(const dem_view *d, size_t i)
{
    for (int a = 0; a < 3; ++a)
        if (d->per >> a & 1) d->x[a][i] -= d->plen[a] * floor(d->x[a][i] / d->plen[a]);
}

/* ---- the coupling with the fluid ------------------------------------------------- */

/* Fluid particle a's position, in the period. */
HD_INLINE void dem_fluid_at(const dem_view *d, const particles_t *p, size_t a, double x[3])
{
    x[0] = p->x[0][a], x[1] = p->x[1][a], x[2] = p->x[2][a];
    dem_wrap_point(d, x);
}

/* Gamma of eq. (16) at x: the nearest wall's (the paper's choice; a corner,
 * where two walls cut the kernel, is not corrected further). */
HD_INLINE double dem_gamma_at(const dem_view *d, const wall_geom *w, const real x[3])
{
    double y = INFINITY;
    for (int k = 0; k < w->n; ++k) y = fmin(y, -(double)wall_prim_depth(&w->prim[k], x));
    return y == INFINITY ? 1.0 : (double)dem_gamma_wall(3, (real)y, (real)d->h);
}

/* Fluid particle a: eps_a (15-16) and d eps_a / dt following a, =
 * -sum_i V_i grad_a W_ai . (u_a - v_i). */
HD_INLINE void dem_fluid_fraction(const dem_view *d, const particles_t *p, const wall_geom *w, size_t a)
{
    double x[3];
    dem_fluid_at(d, p, a, x);
    const double h = d->h, alpha = kernel_alpha(3, (real)h);
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
    const real xr[3] = {(real)x[0], (real)x[1], (real)x[2]};
    d->eps_f[a] = (double)dem_fraction((real)s, (real)dem_gamma_at(d, w, xr), (real)DEM_EPS_MIN);
    d->deps_f[a] = de;
}

/* two_way, fluid particle a (owned or ghost) after its eps_a (dem_fluid_fraction):
 * the space it represents, vol_a = phi_a / eps_a. Locally averaged SPH: its
 * mass of fluid rho_f phi_a is fixed and its density is the superficial
 * eps_a rho_f, whose continuity the source's pressure rate -(K / eps) D eps /
 * Dt is; so every fluid sum (the pressure force, the velocity gradient, the
 * grains' eq. 20, the source's pair term) reads the space the particle
 * holds beside the grains, as its neighbours spread apart where grains come
 * in. phi_a = eps_a vol_a at its first coupling (phi 0 before: the field's
 * allocation), so vol_a keeps its value then and the particle's fluid is
 * what lay outside the grains at the start. m^3. */
HD_INLINE void dem_fluid_volume(const dem_view *d, const particles_t *p, size_t a)
{
    const double e = d->eps_f[a];
    if (!(p->phi[a] > 0)) p->phi[a] = (real)(e * (double)p->vol[a]);
    p->vol[a] = (real)((double)p->phi[a] / e);
}

/* Grain i's sums over the owned fluid particles (eq. 20): s[0] = sum V_a
 * W_ai, s[1] = sum eps_a V_a W_ai, s[2..4] = sum u_a V_a W_ai. On several
 * ranks each rank's are partial (its own particles), summed over the ranks
 * before dem_grain_from_sums (dem.c). */
HD_INLINE void dem_grain_partial(const dem_view *d, const particles_t *p, size_t i, double s[5])
{
    const double x[3] = {d->x[0][i], d->x[1][i], d->x[2][i]}, h = d->h, alpha = kernel_alpha(3, (real)h);
    double S = 0, E = 0, U[3] = {0, 0, 0};
    DEM_CELLS_BEGIN(d, x, d->fstart, d->fidx, a)
        if (a >= d->nown) continue; /* a ghost: its owner's rank sums it */
        double r[3];
        dem_sep(d, x, p->x[0][a], p->x[1][a], p->x[2][a], r);
        double rr = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
        if (rr >= 2.0 * h) continue;
        double vw = (double)p->vol[a] * (double)kernel_w((real)rr, (real)h, (real)alpha);
        S += vw, E += d->eps_f[a] * vw;
        for (int q = 0; q < 3; ++q) U[q] += (double)p->v[q][a] * vw;
    DEM_CELLS_END
    s[0] = S, s[1] = E;
    for (int q = 0; q < 3; ++q) s[2 + q] = U[q];
}

/* Grain i from its sums over all the fluid s[5] (dem_grain_partial): eps_i
 * and u_f,i (eq. 20), the denominator of (14). */
HD_INLINE void dem_grain_from_sums(const dem_view *d, size_t i, const double s[5])
{
    const double S = s[0], E = s[1];
    d->snorm[i] = S;
    d->eps[i] = S > 0 ? fmax(E / S, DEM_EPS_MIN) : 1.0;
    for (int q = 0; q < 3; ++q) d->uf[q][i] = S > 0 ? s[2 + q] / S : 0.0;
}

/* Grain i: eps_i and u_f,i (eq. 20), the denominator of (14), on one rank. */
HD_INLINE void dem_grain_sums(const dem_view *d, const particles_t *p, size_t i)
{
    double s[5];
    dem_grain_partial(d, p, i, s);
    dem_grain_from_sums(d, i, s);
}

/* The interaction force on grain i (eq. 23) at its velocity now, and its
 * drag part F_D (eq. 19) into Fd when Fd is not NULL. */
HD_INLINE void dem_force_int(const dem_view *d, size_t i, double F[3], double *Fd)
{
    real u[3], FD[3], Fi[3], g[3];
    for (int q = 0; q < 3; ++q) u[q] = (real)(d->uf[q][i] - d->v[q][i]), g[q] = (real)d->g[q];
    dem_drag(d->c.d, (real)d->rho_f, (real)d->nu, (real)d->eps[i], u, FD);
    dem_interaction(FD, (real)d->eps[i], (real)d->V, (real)d->rho_f, g, Fi);
    for (int q = 0; q < 3; ++q) F[q] = (double)Fi[q];
    if (Fd)
        for (int q = 0; q < 3; ++q) Fd[q] = (double)FD[q];
}

/* Grain i's interaction force and its drag part at its velocity now into
 * fint, fd (its eps and u_f set). */
HD_INLINE void dem_grain_force(const dem_view *d, size_t i)
{
    double F[3], Fd[3];
    dem_force_int(d, i, F, Fd);
    for (int q = 0; q < 3; ++q) d->fint[q][i] = F[q], d->fd[q][i] = Fd[q];
}

/* Grain i at a coupling on one rank: its sums over the fluid
 * (dem_grain_sums), then the interaction force and its drag part at its
 * velocity now into fint, fd. */
HD_INLINE void dem_grain_couple(const dem_view *d, const particles_t *p, size_t i)
{
    dem_grain_sums(d, p, i);
    dem_grain_force(d, i);
}

/* Whether any grain is binned in the 5^3 cells about point x: every grain
 * within 4h of x is (cells of at least 2h). */
HD_INLINE int dem_grains_near(const dem_view *d, const double x[3])
{
    int c0[3];
    dem_cell(d, x, c0);
    for (int cz = c0[2] - 2; cz <= c0[2] + 2; ++cz)
        for (int cy = c0[1] - 2; cy <= c0[1] + 2; ++cy)
            for (int cx = c0[0] - 2; cx <= c0[0] + 2; ++cx) {
                int wx = dem_cell_wrap(d, 0, cx), wy = dem_cell_wrap(d, 1, cy), wz = dem_cell_wrap(d, 2, cz);
                if (wx < 0 || wy < 0 || wz < 0) continue;
                size_t k = ((size_t)wz * (size_t)d->nc[1] + (size_t)wy) * (size_t)d->nc[0] + (size_t)wx;
                if (d->gstart[k + 1] > d->gstart[k]) return 1;
            }
    return 0;
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
 * dp/dt = -(K / eps_a) D eps_a / Dt to the pressure rate. Added to a's
 * acc and dsig. The pair term's b are a's fluid neighbours in the flow
 * pass's own walk g (its Verlet list or cells, owned and ghosts: a periodic
 * image and another rank's particle as the flow pass meets them), in the
 * flow pass's order on either backend. */
HD_INLINE void dem_fluid_source(const dem_view *d, const particles_t *p, const grid_view *g, size_t a,
                                double visc_norm)
{
    double x[3];
    dem_fluid_at(d, p, a, x);
    /* No grain within 4h: eps is 1 at a and at each of its neighbours (none
     * has a grain within 2h), so the drag's source, the correction (c = 0 for
     * every b) and the pressure rate (d eps / dt = 0) add nothing: the fluid
     * loop of about 27 (max(2h, d) / dr)^3 candidates is skipped. */
    if (!dem_grains_near(d, x)) return;
    const double h = d->h, alpha = kernel_alpha(3, (real)h);
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
    const real xa[3] = {p->x[0][a], p->x[1][a], p->x[2][a]};
    NBR_BEGIN(g, p->x, a, b)
        if (b == a || !dem_fluid(p, b)) continue;
        real xab[3];
        const double rr = sqrt((double)grid_pair_xi(g->dim, xa, p->x, b, xab));
        const double c = 0.5 * (ea + d->eps_f[b]) / ea - 1.0;
        if (rr >= 2.0 * h || c == 0) continue;
        double f = (double)kernel_f((real)rr, (real)h, (real)alpha) * nu2 * (double)p->vol[b] * c;
        for (int q = 0; q < 3; ++q) acc[q] += f * ((double)p->v[q][a] - (double)p->v[q][b]);
    NBR_END
    for (int q = 0; q < 3; ++q) p->acc[q][a] += (real)acc[q];
    const double dp = -d->K / ea * d->deps_f[a]; /* Pa/s; sigma is tension positive */
    for (int q = 0; q < 3; ++q) p->dsig[q][a] -= (real)dp;
}

/* ---- contacts and motion --------------------------------------------------------- */

/* The history of grain i's contact with partner pid in its list before
 * this step (xi[3], zero for a new contact). */
HD_INLINE void dem_history(const dem_view *d, size_t i, int64_t pid, real xi[3])
{
    xi[0] = xi[1] = xi[2] = 0;
    for (int k = 0; k < d->oncon[i]; ++k)
        if (d->ocid[i * DEM_CMAX + (size_t)k] == pid) {
            for (int q = 0; q < 3; ++q) xi[q] = (real)d->ocxi[(i * DEM_CMAX + (size_t)k) * 3 + q];
            return;
        }
}

/* One contact of grain i into its new list and its force and torque sums:
 * n from the partner to i, overlap delta, the partner's contact-point
 * velocity vp (its centre's velocity plus its spin's share; a wall's).
 * Returns 1 when the list is full (DEM_CMAX: the contact is not kept), else 0. */
HD_INLINE int dem_touch(const dem_view *d, size_t i, int64_t pid, const double n[3], double delta, const double vp[3],
                        double dt, int *nk, double F[3], double T[3])
{
    const double R = 0.5 * (double)d->c.d;
    real xi[3], nn[3], vrel[3], Fc[3];
    dem_history(d, i, pid, xi);
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
    if (*nk >= DEM_CMAX) return 1;
    d->cid[i * DEM_CMAX + (size_t)*nk] = pid;
    for (int q = 0; q < 3; ++q) d->cxi[(i * DEM_CMAX + (size_t)*nk) * 3 + q] = (double)xi[q];
    ++*nk;
    return 0;
}

/* The force F and torque T on grain i at time t: gravity (3-4), the
 * interaction force (23) into Fi, and its contacts with grains and walls,
 * whose list and history it rewrites. Returns 1 when its contact list
 * overflowed (DEM_CMAX), else 0. */
HD_INLINE int dem_forces(const dem_view *d, const wall_geom *w, size_t i, double t, double dt, double F[3],
                         double T[3], double Fi[3])
{
    const double D = (double)d->c.d, R = 0.5 * D, x[3] = {d->x[0][i], d->x[1][i], d->x[2][i]};
    real g[3] = {(real)d->g[0], (real)d->g[1], (real)d->g[2]}, Fg[3];
    dem_gravity((real)d->V, g, (real)d->rho_f, d->c.rho, dem_gravity_ramp(t, d->t_damp), Fg);
    dem_force_int(d, i, Fi, NULL);
    for (int q = 0; q < 3; ++q) F[q] = (double)Fg[q] + Fi[q], T[q] = 0;
    int nk = 0, full = 0;
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
        full |= dem_touch(d, i, d->id[j], n, D - rr, vp, dt, &nk, F, T);
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
        full |= dem_touch(d, i, -1 - (int64_t)k, n, delta, vp, dt, &nk, F, T);
    }
    d->ncon[i] = nk;
    return full;
}

/* A free grain over dt (symplectic Euler: v, w from the forces F[3], T[3]
 * at x; then x from the new v). */
HD_INLINE void dem_move_free(const dem_view *d, size_t i, const double *F, const double *T, double dt)
{
    for (int q = 0; q < 3; ++q) {
        d->v[q][i] += F[q] / d->m * dt;
        d->w[q][i] += T[q] / d->I * dt;
        d->x[q][i] += d->v[q][i] * dt;
    }
}

/* DEM:motion rigid (dem.c dem_rigid_step): grain i's share of the body's
 * sums about its centre xc, added to the torque Tt (sum r_i x F_i + T_i),
 * the force Ft and the inertia tensor J (the grain as a sphere at r_i). */
HD_INLINE void dem_rigid_share(const dem_view *d, size_t i, const double xc[3], const double f[3], const double Ti[3],
                               real Tt[3], real Ft[3], real J[9])
{
    const real r[3] = {(real)(d->x[0][i] - xc[0]), (real)(d->x[1][i] - xc[1]), (real)(d->x[2][i] - xc[2])};
    Tt[0] += (real)(r[1] * f[2] - r[2] * f[1] + Ti[0]);
    Tt[1] += (real)(r[2] * f[0] - r[0] * f[2] + Ti[1]);
    Tt[2] += (real)(r[0] * f[1] - r[1] * f[0] + Ti[2]);
    for (int q = 0; q < 3; ++q) Ft[q] += (real)f[q];
    dem_inertia_add((real)d->m, (real)d->I, r, J);
}

/* Grain i of the rigid body over dt: its lever r_i turned by |w| dt about w,
 * its centre at the body's moved centre xc + vc dt plus it, its velocity
 * vc + w x r_i, its spin w. */
HD_INLINE void dem_rigid_move(const dem_view *d, size_t i, const double xc[3], const double vc[3], const real w[3],
                              double dt)
{
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

#endif
