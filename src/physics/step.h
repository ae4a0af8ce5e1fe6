/* step.h — the per-particle quantities the driver reduces every step, shared
 * by the CPU and GPU backends so that both decide the same way:
 *   step_bounds_of  what the time-step bounds need (integrate_dt): the
 *                   diffusivity, the segregation wave speed and the speed;
 *   step_guard      the blow-up conditions of the driver (src/run_guard.c);
 * and the per-particle bodies of the backend hooks that are not neighbour
 * loops (step_place, step_save, step_advance). */
#ifndef SPHSEG_STEP_H
#define SPHSEG_STEP_H
#include <math.h>
#include "../core/particles.h"
#include "flow.h"
#include "kin.h"
#include "seg.h"
#include "wall.h"

typedef struct step_ctx {
    double h;    /* smoothing length, m */
    double gkin; /* largest prescribed shear rate, 1/s (kin_max_shear_rate) */
    int flow_on, seg_on;
    kin_params kin;
    seg_params sp;
    wall_geom w;
    int seg_cap;         /* the donor limiter (seg_flux_donor) is on: the wave speed is at least A V */
    int outlet;          /* Outlet:enabled: material below outlet_below leaves the run */
    double outlet_below; /* Outlet:below, m */
} step_ctx;

/* The local maxima the time step is bounded by (integrate_dt). */
enum { STEP_D = 0, STEP_WAVE = 1, STEP_SPEED = 2, STEP_ACC = 3, STEP_NBOUNDS = 4 };

/* Material particle i: D, |dQ/dC| and |u| (the first three STEP_ slots;
 * |acc| comes from the rate evaluation). With the donor limiter the wave
 * speed is at least A V, the slope of its cap at the bounds (seg_kern.h
 * seg_flux_donor): |dQ/dC| alone vanishes where F' does (C = 1/2 of the
 * symmetric flux), and a uniform C = 1/2 would take its first step from
 * the diffusion bound alone. */
HD_INLINE void step_bounds_of(size_t i, const particles_t *p, const step_ctx *c, double out[3])
{
    double u, gmax = c->gkin;
    if (c->flow_on) {
        gmax = p->gdot[i];
        u = sqrt((double)p->v[0][i] * p->v[0][i] + (double)p->v[1][i] * p->v[1][i] +
                 (double)p->v[2][i] * p->v[2][i]);
    } else {
        real X0[3] = {p->X0[0][i], p->X0[1][i], p->X0[2][i]};
        u = kin_max_speed(&c->kin, X0);
    }
    out[0] = out[1] = 0;
    out[2] = u;
    if (!c->seg_on) return;
    real C = p->C[i];
    out[0] = seg_D(&c->sp, C, (real)gmax);
    out[1] = seg_wave_speed(&c->sp, C, (real)gmax);
    if (c->seg_cap) out[1] = fmax(out[1], (double)(c->sp.A * seg_V(&c->sp, C, (real)gmax)));
}

/* Blow-up conditions, in the order they are tested (DESIGN.md "Errors"). */
enum step_bad {
    STEP_OK = 0,
    STEP_BAD_C = 1,        /* C non-finite or far outside [0, 1] */
    STEP_BAD_STATE = 2,    /* non-finite position, velocity or stress */
    STEP_BAD_OUTSIDE = 3,  /* beyond a wall by more than h */
    STEP_BAD_CFL = 4,      /* moved more than h in one step */
    STEP_OUTLET = 5        /* not a failure: below the outlet, to leave the run (run_guard.c run_drain) */
};

/* Is material particle i outside its container (beyond a bounding wall by
 * more than h, wall_beyond) at time t? */
HD_INLINE int step_outside(size_t i, const particles_t *p, const step_ctx *c, double t)
{
    const double x[3] = {p->x[0][i], p->x[1][i], p->x[2][i]};
    return wall_beyond(&c->w, x, t, c->h);
}

/* Which blow-up condition material particle i meets after a step ending at
 * t (enum step_bad). */
HD_INLINE int step_guard(size_t i, const particles_t *p, const step_ctx *c, double t)
{
    double C = p->C[i];
    if (c->seg_on && !(isfinite(C) && C >= -1.0 && C <= 2.0)) return STEP_BAD_C;
    if (!c->flow_on) return STEP_OK;
    double sum = 0, mv = 0;
    for (int d = 0; d < 3; ++d) {
        sum += (double)p->x[d][i] + (double)p->v[d][i];
        double dx = (double)p->x[d][i] - (double)p->x_n[d][i];
        mv += dx * dx;
    }
    for (int q = 0; q < 6; ++q) sum += (double)p->sig[q][i];
    if (!isfinite(sum)) return STEP_BAD_STATE;
    if (c->outlet && (double)p->x[1][i] < c->outlet_below) return STEP_OUTLET;
    if (step_outside(i, p, c, t)) return STEP_BAD_OUTSIDE;
    return mv > c->h * c->h ? STEP_BAD_CFL : STEP_OK;
}

/* prepare(): particle i at time t. Computed flow: a dummy follows its wall
 * (the material stays where the integrator put it); prescribed velocity:
 * every particle's position, velocity and shear rate from kin_state. */
HD_INLINE void step_place(size_t i, const particles_t *p, int flow_on, const wall_geom *w,
                          const kin_params *kin, double t)
{
    real X0[3] = {p->X0[0][i], p->X0[1][i], p->X0[2][i]}, x[3], u[3], gd;
    if (flow_on) {
        if (p->kind[i] != KIND_DUMMY) return;
        wall_motion(w, p->wall[i], X0, t, x, u);
        for (int d = 0; d < 3; ++d) p->x[d][i] = x[d];
        return;
    }
    kin_state(kin, X0, t, x, u, &gd);
    for (int d = 0; d < 3; ++d) p->x[d][i] = x[d], p->v[d][i] = u[d];
    p->gdot[i] = gd;
}

/* save_start(): the start-of-step copies of particle i: C_n with the
 * concentration equation, x_n, v_n, sig_n with computed flow (the store
 * holds no others: ST_SAVE's rows). */
HD_INLINE void step_save(size_t i, const particles_t *p, int flow_on, int seg_on)
{
    if (seg_on) p->C_n[i] = p->C[i];
    if (!flow_on) return;
    for (int d = 0; d < 3; ++d) {
        p->x_n[d][i] = POS_REMAINDER ? (preal)p->x[d][i] + (preal)p->xr[d][i] : (preal)p->x[d][i];
        p->v_n[d][i] = p->v[d][i];
    }
    for (int q = 0; q < 6; ++q) p->sig_n[q][i] = p->sig[q][i];
}

/* advance(): X = X_n + a dX/dt for material particle i (flow_advance reads
 * C before it moves). With the concentration in windows (seg_on 0 then),
 * the shear rate of the last rate evaluation adds w gdot to the window's
 * integral (w: the corrector's dt, 0 in the predictor): the midpoint rule
 * for the integral of gdot over the window; gdot as eq. (2.7) takes it
 * (seg_drive_gdot: the stress read is that evaluation's). */
HD_INLINE void step_advance(size_t i, particles_t *p, real a, const flow_ctx *c, int flow_on, int seg_on, real w)
{
    if (p->kind[i] != KIND_MATERIAL) return;
    if (w > 0) p->gsum[i] += w * seg_drive_gdot(&c->sp, p, i, p->gdot[i]);
    if (flow_on) flow_advance(i, p, a, c);
    if (seg_on) p->C[i] = p->C_n[i] + (creal)a * p->dCdt[i];
}

/* Concentration windows (integrate_conc): material particle i's mean shear
 * rate over a window of length T, from the integral. */
HD_INLINE void step_shear_mean(size_t i, particles_t *p, real inv_T)
{
    if (p->kind[i] == KIND_MATERIAL) p->gsum[i] *= inv_T;
}

/* Concentration windows: one stage of the window's midpoint step for C
 * alone, C = C_n + a dC/dt (stage 0 first copies C_n = C). */
HD_INLINE void step_conc_advance(size_t i, particles_t *p, real a, int stage)
{
    if (p->kind[i] != KIND_MATERIAL) return;
    if (stage == 0) p->C_n[i] = p->C[i];
    p->C[i] = p->C_n[i] + (creal)a * p->dCdt[i];
}

#endif
