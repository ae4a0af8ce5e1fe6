/* test_flux.c — segregation flux functions and coefficients (paper §2.2):
 * F of (2.8)–(2.9), dF/dC against a central difference, the equal-maximum
 * property that fixes A = 1.6 for kappa = 0.89 (Gajjar & Gray 2014), V and D
 * of the shear-rate model (2.7), the boundary flux f(C) of (4.5), and
 * Segregation:shear_rate yielded's gate (the static cone sqrt(J2) = k(mu_s) p).
 * References: the closed forms and their derivatives; the cone's geometry. */
#include <string.h>
#include "physics/seg.h"
#include "physics/seg_kern.h"
#include "testutil.h"

static seg_params sym(void)
{
    seg_params s = {1, 0, 0, 2e-4, 3e-7, 0.11, 0.0307, 0.004, 0.008, {0, -1, 0}, 0, 0};
    return s;
}

static void test_symmetric(void **st)
{
    (void)st;
    seg_params s = sym();
    assert_true(fabs(seg_F(&s, 0.5) - 0.25) < RT(1e-15));
    assert_true(seg_F(&s, 0) == 0 && seg_F(&s, 1) == 0);
    assert_true(fabs(seg_F(&s, 0.3) - seg_F(&s, 0.7)) < RT(1e-15)); /* symmetric about 1/2 */
    assert_true(fabs(seg_dFdC(&s, 0.5)) < RT(1e-15));
}

static void test_asymmetric(void **st)
{
    (void)st;
    seg_params s = sym();
    s.A = 1.6, s.kappa = 0.89;
    double fmaxv = 0;
    for (double C = 0; C <= 1; C += 1e-5) fmaxv = fmax(fmaxv, seg_F(&s, C));
    assert_true(fabs(fmaxv - 0.25) < 0.01 * 0.25); /* same maximum as C(1 - C) */
    for (double C = 0.01; C < 1; C += 0.07) {
        double e = FD_STEP;
        double fd = (seg_F(&s, C + e) - seg_F(&s, C - e)) / (2 * e);
        assert_true(fabs(fd - seg_dFdC(&s, C)) < 10 * RT(1e-9) + 3 * e * e); /* O(e^2) */
    }
    assert_true(seg_F(&s, 0.3) > seg_F(&s, 0.7)); /* small grains sink faster */
}

static void test_coefficients(void **st)
{
    (void)st;
    seg_params s = sym();
    assert_true(seg_V(&s, 0.2, 5.0) == s.V && seg_D(&s, 0.9, 0.0) == s.D);
    s.shear_model = 1;
    double C = 0.25, gd = 3.0, d = 0.004 * C + 0.008 * (1 - C);
    assert_true(fabs(seg_V(&s, C, gd) - 0.11 * gd * d) < RT(1e-12) * 0.11 * gd * d);
    assert_true(fabs(seg_D(&s, C, gd) - 0.0307 * gd * d * d) < RT(1e-12) * 0.0307 * gd * d * d);
    double e = FD_STEP;
    double fd = (seg_Q(&s, C + e, gd) - seg_Q(&s, C - e, gd)) / (2 * e);
    assert_true(fabs(fd - seg_wave_speed(&s, C, gd)) < (10 * RT(1e-9) + 3 * e * e) * fabs(fd) + 1e-14);
    real up[3] = {0, 1, 0}, down[3] = {0, -1, 0};
    assert_true(seg_wall_flux(&s, C, gd, up) > 0);   /* base: small grains arrive */
    assert_true(seg_wall_flux(&s, C, gd, down) < 0); /* free surface: they leave */
}

/* yielded: eq. (2.7)'s gdot stays where sqrt(J2) >= k p (on the cone, past
 * it, or p <= 0) and is 0 strictly inside; total (and a window's mean, which
 * was gated as it was summed) passes it as it is; V and D follow the gate. */
static void test_drive_gdot(void **st)
{
    (void)st;
    particles_t p;
    part_alloc(&p, 2, 8);
    const double k = stress_yield_k(YIELD_DRUCKER_PRAGER, 0.382), pr = 100.0, gd = 4.0;
    /* sigma = -p I + tau (e_x e_y + e_y e_x): sqrt(J2) = tau; tau / (k p) = 0.5, 1 + 1e-3, 2; then tension */
    const double tau[3] = {0.5 * k * pr, (1 + 1e-3) * k * pr, 2 * k * pr};
    for (int i = 0; i < 4; ++i) {
        tu_put(&p, i, 0, 0, KIND_MATERIAL, 1);
        for (int q = 0; q < 6; ++q) p.sig[q][i] = 0;
        for (int q = 0; q < 3; ++q) p.sig[q][i] = (real)(i < 3 ? -pr : 10.0);
        p.sig[3][i] = (real)(i < 3 ? tau[i] : 0.0); /* xy */
        p.C[i] = 0.5, p.gdot[i] = (real)gd;
    }
    seg_ctx c;
    memset(&c, 0, sizeof c);
    c.sp = sym();
    c.sp.shear_model = 1, c.sp.k_static = (real)k;
    for (int i = 0; i < 4; ++i) assert_true(seg_drive_gdot(&c.sp, &p, (size_t)i, (real)gd) == (real)gd); /* total */
    c.sp.gdot_yielded = 1;
    const double want[4] = {0, gd, gd, gd};
    for (int i = 0; i < 4; ++i) {
        assert_true(seg_drive_gdot(&c.sp, &p, (size_t)i, (real)gd) == (real)want[i]);
        seg_coeffs((size_t)i, &p, &c);
        assert_true(p.segV[i] == seg_V(&c.sp, p.C[i], (real)want[i]) && p.segD[i] == seg_D(&c.sp, p.C[i], (real)want[i]));
    }
    const seg_ctx m = seg_ctx_mean(c);
    seg_coeffs(0, &p, &m);
    assert_true(m.sp.gdot_yielded == 0 && p.segV[0] == seg_V(&c.sp, p.C[0], (real)gd));
    part_free(&p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_symmetric), cmocka_unit_test(test_asymmetric),
                                       cmocka_unit_test(test_coefficients), cmocka_unit_test(test_drive_gdot)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
