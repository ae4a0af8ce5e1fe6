/* test_position.c — positions held to double precision in the single build
 * (src/core/hd.h: x_n double, x + xr the position). This file compiles
 * the physics bodies as the single build does (SPHSEG_SINGLE), on a store
 * of its own arrays:
 *  - a particle 0.05-0.09 m from the origin creeping at 1e-5 to 3e-5 m/s,
 *    well under ulp(x) / (2 dt) = 0.07-0.15 mm/s at dt = 2.5e-5 s, moves by
 *    v t over 40 000 steps (1 s) of save and advance: x + xr within 1e-11 m
 *    of x0 + v t (xr is a float: each step rounds it by ~1e-16 m, 1.3e-12 m
 *    in all here), and x within half an ulp of it (the float image). A float
 *    position alone would not move at all (each step rounds the
 *    displacement away: the last check);
 *  - a fast particle (0.1 m/s) lands on x0 + v t as closely.
 * Reference: exact arithmetic, x0 + v t. */
#define SPHSEG_SINGLE 1
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>
#include "core/particles.h"
#include "physics/step.h"

enum { NP = 2 };

static void test_creep(void **st)
{
    (void)st;
    static real x[3][NP], xr[3][NP], v[3][NP], v_n[3][NP], acc[3][NP], sig[6][NP], sig_n[6][NP], dsig[6][NP], gd[NP];
    static preal x_n[3][NP];
    static creal C[NP], C_n[NP];
    static uint8_t kind[NP];
    particles_t p;
    memset(&p, 0, sizeof p);
    p.dim = 3, p.n = NP;
    for (int d = 0; d < 3; ++d) p.x[d] = x[d], p.xr[d] = xr[d], p.x_n[d] = x_n[d], p.v[d] = v[d], p.v_n[d] = v_n[d];
    for (int d = 0; d < 3; ++d) p.acc[d] = acc[d];
    for (int q = 0; q < 6; ++q) p.sig[q] = sig[q], p.sig_n[q] = sig_n[q], p.dsig[q] = dsig[q];
    p.gdot = gd, p.C = C, p.C_n = C_n, p.kind = kind;
    const double x0[NP][3] = {{0.05, 0.07, 0.09}, {0.05, -0.07, 0.03}};
    const double u[NP][3] = {{1e-5, -3e-5, 2e-5}, {0.1, 0.05, -0.1}};
    for (int i = 0; i < NP; ++i)
        for (int d = 0; d < 3; ++d) x[d][i] = (real)x0[i][d], v[d][i] = (real)u[i][d];
    flow_ctx c;
    memset(&c, 0, sizeof c);
    c.k.dim = 3;
    c.m.mu_s = (real)0.382, c.m.mu_d = (real)0.682, c.m.I0 = (real)0.279, c.m.rho_s = 2500;
    c.m.lambda = (real)0.001;
    c.sp.d_small = (real)0.25e-3, c.sp.d_large = (real)0.5e-3;
    const real dt = (real)2.5e-5;
    const long steps = 40000;
    for (long k = 0; k < steps; ++k)
        for (int i = 0; i < NP; ++i) {
            step_save((size_t)i, &p, 1, 1);
            step_advance((size_t)i, &p, dt / 2, &c, 1, 0, 0); /* the predictor, then the corrector */
            step_advance((size_t)i, &p, dt, &c, 1, 0, 0);
        }
    const double T = (double)steps * (double)dt;
    for (int i = 0; i < NP; ++i)
        for (int d = 0; d < 3; ++d) {
            double exact = (double)(real)x0[i][d] + (double)(real)u[i][d] * T;
            double held = (double)x[d][i] + (double)xr[d][i];
            assert_true(fabs(held - exact) < 1e-11);
            assert_true(fabs((double)x[d][i] - exact) <= 0.5 * (double)nextafterf(fabsf(x[d][i]), INFINITY) -
                                                              0.5 * (double)fabsf(x[d][i]) + 1e-15);
        }
    /* a float accumulator would have stood still: each step's displacement
     * of the creeping particle rounds to nothing */
    for (int d = 0; d < 3; ++d) {
        float f = (float)x0[0][d];
        assert_true(f + (float)u[0][d] * dt == f);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_creep)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
