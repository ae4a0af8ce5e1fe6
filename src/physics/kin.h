/* kin.h — prescribed kinematics: the velocity field a scene may impose so
 * that only the concentration equation runs. Oscillatory shear of the shear
 * box (paper §5, van der Vaart et al. 2015): the side walls pivot about the
 * base with shear gamma(t) = gamma0 sin(omega t), omega = 2 pi / T, so
 *   x(t) = X0 + gamma(t) max(Y0, 0),  y = Y0,
 *   u_x = gamma0 omega cos(omega t) max(Y0, 0),  gdot = |gamma0 omega cos(omega t)|,
 * exact positions (no time-integration error); the base (Y0 < 0) stays put. */
#ifndef SPHSEG_KIN_H
#define SPHSEG_KIN_H
#include <math.h>
#include "../core/hd.h"
#include "options.h"

typedef struct kin_params {
    int type;      /* enum kin_type (options.h): KIN_REST, KIN_OSCILLATORY_SHEAR */
    double gamma0; /* shear amplitude */
    double omega;  /* 2 pi / T, 1/s */
} kin_params;

/* Position, velocity and shear rate at time t of the particle whose
 * reference position is X0 (3 components). */
HD_INLINE void kin_state(const kin_params *kp, const real X0[3], double t, real x[3],
                         real v[3], real *gdot)
{
    x[0] = X0[0], x[1] = X0[1], x[2] = X0[2];
    v[0] = v[1] = v[2] = 0;
    *gdot = 0;
    if (kp->type != 1) return;
    double y = X0[1] > 0 ? (double)X0[1] : 0.0; /* the base stays put */
    double rate = kp->gamma0 * kp->omega * cos(kp->omega * t);
    x[0] = (real)((double)X0[0] + kp->gamma0 * sin(kp->omega * t) * y);
    v[0] = (real)(rate * y);
    *gdot = (real)fabs(rate);
}

/* Largest speed over a cycle of the particle at X0, m/s (time-step bound). */
HD_INLINE double kin_max_speed(const kin_params *kp, const real X0[3])
{
    return kp->type == 1 && X0[1] > 0 ? kp->gamma0 * kp->omega * (double)X0[1] : 0.0;
}

/* Largest shear rate over a cycle, 1/s (time-step bound, shear-rate model). */
HD_INLINE double kin_max_shear_rate(const kin_params *kp)
{
    return kp->type == 1 ? kp->gamma0 * kp->omega : 0.0;
}

#endif
