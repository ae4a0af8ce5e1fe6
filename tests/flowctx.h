/* flowctx.h — the granular flow context of the unit tests that call the flow
 * bodies (test_flow.c, test_stab.c): Table 1's material at modulus E, the
 * bed density 1500 kg/m^3, gravity -9.81 m/s^2 along y, the kernel at
 * h = 1.5 dr in 2D, the EV drum's grains; no walls, no stabilisation term
 * (alpha_av 0, STAB_MONAGHAN): the callers add theirs. */
#ifndef SPHSEG_FLOWCTX_H
#define SPHSEG_FLOWCTX_H
#include <string.h>
#include "physics/flow.h"

static inline flow_ctx tu_flow_ctx(double E, double dr)
{
    flow_ctx c;
    memset(&c, 0, sizeof c);
    c.k = sph_make(2, (real)(1.5 * dr), (real)dr);
    stress_moduli((real)E, (real)0.3, &c.m.G, &c.m.K);
    c.m.rho_s = 2500, c.m.mu_s = (real)0.382, c.m.mu_d = (real)0.682, c.m.I0 = (real)0.279;
    c.m.lambda = (real)0.001;
    c.rho = 1500;
    c.cs = stress_sound_speed(c.m.G, c.m.K, c.rho);
    c.g[1] = (real)-9.81;
    c.sp.d_small = (real)0.25e-3, c.sp.d_large = (real)0.5e-3;
    return c;
}
#endif
