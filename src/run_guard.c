/* run_guard.c — after each step: a particle in a blow-up state ends the run
 * (exit 3), and particles leave the run through an outlet or with a lifted
 * gate (run_drain); src/run.h. */
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include "core/error.h"
#include "mpi/comm.h"
#include "run.h"

/* A blow-up stops the run with exit status 3 (DESIGN.md "Errors"), naming
 * the step, time and particle; the last snapshot written stays intact:
 *  - a non-finite concentration, or one far outside [0, 1] (below -1 or
 *    above 2; small overshoots of an explicit scheme are tolerated and show
 *    in diagnostics.csv as C_min, C_max);
 *  - computed flow: a non-finite position, velocity or stress; a particle
 *    outside its container (beyond a wall by more than h); a particle that
 *    moved more than h in one step (the CFL condition violated: the
 *    neighbour geometry was not resolved in time). */
static void blowup(const sim_t *s, diag *d, size_t i, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static void blowup(const sim_t *s, diag *d, size_t i, const char *fmt, ...)
{
    const particles_t *p = &s->p;
    char why[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(why, sizeof why, fmt, ap);
    va_end(ap);
    diag_close(d);
    error_exit(EXIT_NUMERICAL, "step %ld, t = %.9g s: particle %lld at (%.6g, %.6g) m %s (dt = %.3g s)", s->step,
               s->t, (long long)p->id[i], (double)p->x[0][i], (double)p->x[1][i], why, s->dt);
}

/* Particles leave the run (collective: every rank drops its own, here_host
 * when this rank's host copy is up to date): gate 0, the material below the
 * outlet, whose count and sum C_i V_i are kept for the diagnostics; else
 * the dummies of the gates of bit mask `gate` (bit k: wall primitive k).
 * The store shrinks, the backend
 * takes it over, and the state is prepared again at t (as after a load
 * balance). */
void run_drain(sim_t *s, int here_host, unsigned gate)
{
    if (!here_host) s->be->to_host(s);
    particles_t *p = &s->p;
    size_t *keep = malloc((p->n + 1) * sizeof *keep), m = 0;
    if (!keep) error_exit(1, "out of memory");
    for (size_t i = 0; i < p->n; ++i) {
        if (gate && p->wall[i] && (gate >> (p->wall[i] - 1) & 1)) continue;
        if (!gate && p->kind[i] == KIND_MATERIAL && (double)p->x[1][i] < s->step_c.outlet_below) {
            s->out_n++;
            s->out_cv += (double)p->C[i] * (double)p->vol[i];
        } else {
            keep[m++] = i;
        }
    }
    p->ng = 0;
    if (m < p->n) part_compact(p, keep, m);
    free(keep);
    s->be->from_host(s);
    s->be->prepare(s, s->t, !s->win.on);
}

/* Particle i is in a blow-up state, or below the outlet (returns 1). */
static int check_failed(sim_t *s, diag *d, size_t i)
{
    s->be->to_host(s);
    const particles_t *p = &s->p;
    double mv = 0;
    for (int c = 0; c < 3; ++c) mv += pow((double)p->x[c][i] - (double)p->x_n[c][i], 2);
    switch (step_guard(i, p, &s->step_c, s->t)) {
    case STEP_BAD_C:
        blowup(s, d, i, "has concentration %g: the scheme went unstable (see docs/shearbox.md for where "
               "each scheme is stable)", (double)p->C[i]);
        break;
    case STEP_BAD_STATE:
        blowup(s, d, i, "has a non-finite position, velocity or stress: the flow went unstable "
               "(see docs/granular.md, stability limits)");
        break;
    case STEP_BAD_OUTSIDE:
        blowup(s, d, i, "left its container through a wall");
        break;
    case STEP_OUTLET:
        return 1;
    default:
        blowup(s, d, i, "moved %.3g m > h = %.3g m in one step: CFL condition violated (lower Run:cfl_flow)",
               sqrt(mv), (double)s->seg.k.h);
    }
    return 0;
}

/* The backend finds the lowest-index material particle in a blow-up state
 * (step_guard, physics/step.h); the host copy names it. A particle below an
 * outlet is no failure: every rank drains its outlet (run_drain). */
void run_check_finite(sim_t *s, diag *d)
{
    long first = s->be->check(s);
    int out = 0;
    if (first >= 0) out = check_failed(s, d, (size_t)first);
    if (s->step_c.outlet && comm_max(out) > 0) run_drain(s, first >= 0, 0);
}
