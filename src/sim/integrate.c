/* integrate.c — predictor–corrector time integration (paper eqs. 3.17–3.18)
 * and the time-step bounds of the concentration solver. */
#include <math.h>
#include <string.h>
#include "core/error.h"
#include "mpi/comm.h"
#include "sim.h"

/* Explicit midpoint form of (3.17)–(3.18): the predictor advances half a
 * step, X^{n+1/2} = X^n + (dt/2) Gamma^n, and the corrector takes the full
 * step with the mid-point rate, X^{n+1} = X^n + dt Gamma^{n+1/2}. Positions
 * follow the prescribed kinematics exactly at t^{n+1/2} and t^{n+1}. The
 * HCSR boundary classification runs once per step, at t^{n+1} for the next
 * step's predictor; the corrector reuses it (particles move less than h per
 * step). On return positions, velocities and classes are those at t^{n+1}.
 * With computed flow, x, u and sigma take the same two stages (sigma
 * returned to the yield cone after each), and every Flow:shepard_every
 * steps the Shepard filter (3.12) smooths the stress at t^{n+1}. */
void integrate_step(sim_t *s, double dt)
{
    const struct backend *be = s->be; /* the state is prepared at t (run start, last step) */
    const int win = s->win.on;        /* C in windows: the flow alone here (integrate_conc) */
    s->flow.damping = (real)(s->t < s->sc->flow.damping_until ? s->sc->flow.damping : 0.0);
    s->dt = dt; /* this step's, for the shift in save_start (physics/shift.h) */
    be->rates(s);
    if (s->dem) dem_couple(s->dem, &s->p, &s->flow.w, s->t, (double)s->flow.visc_norm);
    be->save_start(s);
    be->advance(s, 0.5 * dt, 0.0);
    be->prepare(s, s->t + 0.5 * dt, 0);
    be->rates(s);
    if (s->dem) dem_couple(s->dem, &s->p, &s->flow.w, s->t + 0.5 * dt, (double)s->flow.visc_norm);
    be->advance(s, dt, win ? dt : 0.0);
    be->prepare(s, s->t + dt, !win); /* windows classify and renormalise at their close */
    if (s->dem) dem_advance(s->dem, &s->flow.w, s->t, dt); /* the grains over the step, the coupling's forces */
    s->t += dt;
    s->step++;
    if (win) s->win.k++, s->win.T += dt;
    unsigned every = s->sc->flow.shepard_every;
    if (s->flow_on && every > 0 && s->step % (long)every == 0) be->filter(s);
}

/* The largest K that Segregation:every auto gives. The window's
 * concentration step costs about one flow step (two neighbour passes of dC/dt,
 * one of L, the coefficients), so its share of the run is about 1/K: at
 * K = 100 the remaining speed-up is under 1 %, while the error of the
 * window (the geometry and C of its end for the whole window) grows with
 * K. docs/gpu.md "Concentration windows" measures both. */
#define CONC_AUTO_MAX 100

int integrate_conc_auto_max(void) { return CONC_AUTO_MAX; }

void integrate_conc_init(sim_t *s)
{
    unsigned every = s->sc->segregation.every_k;
    memset(&s->win, 0, sizeof s->win);
    s->win.every = every;
    s->win.on = s->flow_on && s->seg_on && every != 1;
}

/* dt bound of the concentration equation alone (docs/numerics.md), from
 * the largest D and |dQ/dC| over all ranks; INFINITY when neither bounds it. */
static double conc_dt(const sim_t *s, double dmax, double wmax)
{
    const struct scene *sc = s->sc;
    double h = s->seg.k.h, dt = INFINITY;
    if (dmax > 0) dt = fmin(dt, sc->run.cfl_diffusion * h * h / dmax);
    if (wmax > 0) dt = fmin(dt, sc->run.cfl_segregation * h / wmax);
    return dt;
}

/* The window's concentration step at its end t: the classes (HCSR schemes)
 * and L of these positions, the window's mean shear rate, and C advanced by
 * the midpoint rule over the window's length T, in as many equal steps as
 * the concentration's own bounds at that shear rate ask (one, normally). */
int integrate_conc(sim_t *s, int force)
{
    conc_window *w = &s->win;
    if (!w->on || w->k == 0 || (!force && w->k < w->K)) return 0;
    const struct backend *be = s->be;
    if (s->hcsr) be->prepare(s, s->t, 1);
    double b[STEP_NBOUNDS];
    be->conc_begin(s, w->T, b);
    comm_max_n(b, STEP_NBOUNDS);
    double tc = conc_dt(s, b[STEP_D], b[STEP_WAVE]);
    long m = tc >= w->T ? 1 : (long)ceil(w->T / tc);
    for (long q = 0; q < m; ++q) be->conc_step(s, w->T / (double)m, q == m - 1);
    w->windows++, w->substeps += m;
    w->k = 0, w->T = 0;
    return 1;
}

/* Time-step bounds (derivation in docs/numerics.md):
 *  diffusion:   dt <= cfl_diffusion h^2 / D_max. Gershgorin on the SPH
 *               Laplacian (3.8) gives a spectral radius <= 4 D int|W'|/r dV
 *               = 14 D / h^2 for the Wendland C2 kernel in 2D and 3D; the
 *               midpoint rule is stable for |lambda dt| <= 2, so the bound is
 *               stable for cfl_diffusion < 1/7;
 *  segregation: dt <= cfl_segregation h / max|dQ/dC| (a kinematic wave of
 *               speed dQ/dC = V F' + F dV/dC must cross less than h per step);
 *  kinematics:  dt <= cfl_kinematic h / |u|_max (particles move less than a
 *               fraction of h per step, so that the neighbour geometry is
 *               resolved in time);
 *  flow:        (3.19), dt <= chi_CFL min(sqrt(h / a_max), h / c_s), with
 *               the elastic sound speed c_s and the largest acceleration of
 *               the last rate evaluation (0 at the start);
 *  viscosity:   a Newtonian fluid (Material:model newtonian), dt <= 0.125
 *               h^2 / nu (Morris et al. 1997, eq. 11: the viscous term is an
 *               SPH Laplacian like the diffusion's). */
double integrate_dt(sim_t *s)
{
    const struct scene *sc = s->sc;
    double h = s->seg.k.h, b[STEP_NBOUNDS];
    s->be->bounds(s, b);
    comm_max_n(b, STEP_NBOUNDS); /* one reduction for every bound */
    double dmax = b[STEP_D], amax = b[STEP_WAVE], umax = b[STEP_SPEED];
    double dt = sc->run.dt_max, tc = conc_dt(s, dmax, amax);
    if (!s->win.on) dt = fmin(dt, tc);
    if (umax > 0) dt = fmin(dt, sc->run.cfl_kinematic * h / umax);
    if (s->flow_on) /* (3.19); |acc| from the last rate evaluation */
        dt = fmin(dt, stress_dt((real)sc->run.cfl_flow, (real)h, (real)b[STEP_ACC], s->flow.cs));
    if (s->flow_on && s->flow.nu > 0) dt = fmin(dt, 0.125 * h * h / (double)s->flow.nu);
    conc_window *w = &s->win;
    if (w->on && w->k == 0) { /* a window opens: its length in steps */
        double k = w->every ? (double)w->every : fmin(floor(tc / dt), (double)CONC_AUTO_MAX);
        w->K = k < 1 ? 1 : (long)k;
    }
    return dt;
}
