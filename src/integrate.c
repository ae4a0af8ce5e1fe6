/* integrate.c — predictor–corrector time integration (paper eqs. 3.17–3.18)
 * and the time-step bounds of the concentration solver. */
#include <math.h>
#include "error.h"
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
    s->flow.damping = (real)(s->t < s->sc->flow.damping_until ? s->sc->flow.damping : 0.0);
    be->rates(s);
    be->save_start(s);
    be->advance(s, 0.5 * dt);
    be->prepare(s, s->t + 0.5 * dt, 0);
    be->rates(s);
    be->advance(s, dt);
    be->prepare(s, s->t + dt, 1);
    s->t += dt;
    s->step++;
    s->dt = dt;
    unsigned every = s->sc->flow.shepard_every;
    if (s->flow_on && every > 0 && s->step % (long)every == 0) be->filter(s);
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
 *               the last rate evaluation (0 at the start). */
double integrate_dt(sim_t *s)
{
    const struct scene *sc = s->sc;
    double h = s->seg.k.h, b[STEP_NBOUNDS];
    s->be->bounds(s, b);
    double dmax = comm_max(b[STEP_D]), amax = comm_max(b[STEP_WAVE]), umax = comm_max(b[STEP_SPEED]);
    double dt = sc->run.dt_max;
    if (dmax > 0) dt = fmin(dt, sc->run.cfl_diffusion * h * h / dmax);
    if (amax > 0) dt = fmin(dt, sc->run.cfl_segregation * h / amax);
    if (umax > 0) dt = fmin(dt, sc->run.cfl_kinematic * h / umax);
    if (s->flow_on) /* (3.19); |acc| from the last rate evaluation */
        dt = fmin(dt, stress_dt((real)sc->run.cfl_flow, (real)h, (real)comm_max(b[STEP_ACC]), s->flow.cs));
    return dt;
}
