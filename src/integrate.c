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
 * step). On return positions, velocities and classes are those at t^{n+1}. */
void integrate_step(sim_t *s, double dt)
{
    const struct backend *be = s->be; /* the state is prepared at t (run start, last step) */
    be->conc_rates(s);
    be->save_start(s);
    be->advance(s, 0.5 * dt);
    be->prepare(s, s->t + 0.5 * dt, 0);
    be->conc_rates(s);
    be->advance(s, dt);
    be->prepare(s, s->t + dt, 1);
    s->t += dt;
    s->step++;
    s->dt = dt;
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
 *               resolved in time). */
double integrate_dt(const sim_t *s)
{
    const struct scene *sc = s->sc;
    const particles_t *p = &s->p;
    const seg_params *sp = &s->seg.sp;
    double gmax = kin_max_shear_rate(&s->kin), h = s->seg.k.h;
    double dmax = 0, amax = 0, umax = 0;
    for (size_t i = 0; i < p->n; ++i) {
        if (p->kind[i] != KIND_MATERIAL) continue;
        double C = p->C[i];
        double D = seg_D(sp, (real)C, (real)gmax), a = seg_wave_speed(sp, (real)C, (real)gmax);
        real X0[3] = {p->X0[0][i], p->X0[1][i], p->X0[2][i]};
        double u = kin_max_speed(&s->kin, X0);
        dmax = D > dmax ? D : dmax;
        amax = a > amax ? a : amax;
        umax = u > umax ? u : umax;
    }
    dmax = comm_max(dmax), amax = comm_max(amax), umax = comm_max(umax);
    double dt = sc->run.dt_max;
    if (dmax > 0) dt = fmin(dt, sc->run.cfl_diffusion * h * h / dmax);
    if (amax > 0) dt = fmin(dt, sc->run.cfl_segregation * h / amax);
    if (umax > 0) dt = fmin(dt, sc->run.cfl_kinematic * h / umax);
    return dt;
}
