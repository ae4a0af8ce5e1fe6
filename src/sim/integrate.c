/* integrate.c — time integration (Run:integrator: the paper's
 * predictor–corrector 3.17–3.18, or its one-evaluation leapfrog form) and
 * the time-step bounds of the concentration solver. */
#include <math.h>
#include <string.h>
#include "core/error.h"
#include "mpi/comm.h"
#include "sim.h"
#include "stages.h"

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
static void step_pc(sim_t *s, double dt, int win)
{
    const struct backend *be = s->be; /* the state is prepared at t (run start, last step) */
    be->rates(s);
    if (s->dem) be->dem_couple(s, s->t);
    be->save_start(s);
    be->advance(s, 0.5 * dt, 0.0);
    be->prepare(s, s->t + 0.5 * dt, 0);
    be->rates(s);
    if (s->dem) be->dem_couple(s, s->t + 0.5 * dt);
    be->advance(s, dt, win ? dt : 0.0);
    be->prepare(s, s->t + dt, !win); /* windows classify and renormalise at their close */
}

/* Does the leapfrog's step take fresh rates at t^n? At the run's first step
 * (no earlier corrector), and after a Shepard filter (its stage writes the
 * filtered stress into dsig, the stored stress rate). A rule of the step
 * number alone, so that a restart (the stored rates are arrays of the
 * checkpoint) takes the same steps as the run it continues. */
static int lf_fresh(const sim_t *s)
{
    unsigned every = s->sc->flow.shepard_every;
    return s->step == 0 || (s->flow_on && every > 0 && s->step % (long)every == 0);
}

/* Run:integrator leapfrog: the midpoint rule of step_pc with one rate
 * evaluation a step. The predictor takes the rates of the last step's
 * corrector, X^{n+1/2} = X^n + (dt/2) Gamma^{n-1/2}, which differ from
 * Gamma^n by O(dt), so X^{n+1/2} by O(dt^2) and X^{n+1} = X^n + dt
 * Gamma^{n+1/2} by O(dt^3): second order, as the predictor–corrector. The
 * same rule for x (its rate u), u, sigma (return-mapped after each stage)
 * and C, so the bodies, stages and hooks are the predictor–corrector's and
 * the Shepard filter works unchanged; the shift rides in the midpoint flow
 * pass (below). Chosen
 * over kick–drift–kick and Verlet because the one flow pass gives du/dt
 * and dsigma/dt at the same state: a symplectic (staggered) update of the
 * u–sigma wave needs grad u after the kick, a second pass. On the linear
 * wave u' = -w s, s' = w u its growth a step is the predictor–corrector's
 * order at small w dt (1 + 2.6e-5 against 1.2e-5 at w dt = 0.1; tools/studies/integrator_study.py
 * --oscillator), and it is stable where dissipation (stabilisation,
 * return mapping) outweighs it; Run:cfl_flow's limit is measured there.
 * For a diffusion-like rate (-lambda) it is stable for lambda dt <= 1, half
 * the midpoint rule's: integrate_dt halves the diffusion bound.
 * Classification and L are taken at t^{n+1/2}, where the rates are; the
 * end-of-step prepare places, sorts and walls the state at t^{n+1} for the
 * driver (output, load balance, checks) and the next save_start. */
static void step_lf(sim_t *s, double dt, int win)
{
    const struct backend *be = s->be;
    if (lf_fresh(s)) {
        be->prepare(s, s->t, !win); /* as a restart's first prepare (run_start): the same bits */
        be->rates(s);
        if (s->dem) be->dem_couple(s, s->t);
    }
    /* The shift rides in the midpoint flow pass (flow_rates_body: the same
     * pairs, no pass of its own), from the state there; it moves the saved
     * copies, so the corrector starts from the shifted state as in step_pc. */
    s->shift_due = stage_runs(stage_flags(s), ST_SHIFT);
    be->save_start(s);
    be->advance(s, 0.5 * dt, 0.0);
    be->prepare(s, s->t + 0.5 * dt, !win);
    be->rates(s); /* clears shift_due */
    if (s->dem) be->dem_couple(s, s->t + 0.5 * dt);
    be->advance(s, dt, win ? dt : 0.0);
    s->kgc_skip = 1; /* B is made again at the next midpoint (or fresh) prepare, before any rates */
    be->prepare(s, s->t + dt, 0);
    s->kgc_skip = 0;
}

void integrate_step(sim_t *s, double dt)
{
    const int win = s->win.on; /* C in windows: the flow alone here (integrate_conc) */
    s->flow.damping = (real)(s->t < s->sc->flow.damping_until ? s->sc->flow.damping : 0.0);
    s->dt = dt; /* this step's, for the shift in save_start (physics/shift.h) */
    if (s->be->step_begin) s->be->step_begin(s);
    if (s->sc->run.integrator == INTEGRATOR_LEAPFROG) step_lf(s, dt, win);
    else step_pc(s, dt, win);
    if (s->dem) s->be->dem_advance(s, s->t, dt); /* the grains over the step, the coupling's forces */
    s->t += dt;
    s->step++;
    if (win) s->win.k++, s->win.T += dt;
    unsigned every = s->sc->flow.shepard_every;
    if (s->flow_on && every > 0 && s->step % (long)every == 0) s->be->filter(s);
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
static double conc_dt(const sim_t *s, double dmax, double wmax, double fdiff)
{
    const struct scene *sc = s->sc;
    double h = s->seg.k.h, dt = INFINITY;
    if (dmax > 0) dt = fmin(dt, fdiff * sc->run.cfl_diffusion * h * h / dmax);
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
    double tc = conc_dt(s, b[STEP_D], b[STEP_WAVE], 1.0); /* the window's own midpoint steps */
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
 *               stable for cfl_diffusion < 1/7 (the leapfrog, step_lf, for
 *               |lambda dt| <= 1: its bound is halved);
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
    const int lf = sc->run.integrator == INTEGRATOR_LEAPFROG; /* stable for lambda dt <= 1: step_lf */
    double dt = sc->run.dt_max, tc = conc_dt(s, dmax, amax, lf && !s->win.on ? 0.5 : 1.0);
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
