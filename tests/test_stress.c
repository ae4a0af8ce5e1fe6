/* test_stress.c — the mu(I) elastoplastic pieces (paper §2.3–2.4, App. C)
 * and the momentum pair terms (3.9, 3.10, 3.14–3.15), ahead of the granular
 * solver. References: linear elasticity (E, nu -> G, K), the closed forms of
 * (2.12)–(2.14) and their limits, the geometry of the Drucker–Prager cone,
 * the invariance of p and J2 under the Jaumann spin terms, Newton's third
 * law for the pair force, and exact velocity gradients of linear fields on
 * a lattice (up to the 0.3 % lattice moment at h = 1.5 dr). */
#include <string.h>
#include "physics/kernel.h"
#include "physics/momentum.h"
#include "physics/stress.h"
#include "testutil.h"

static mat_params table1(void)
{
    mat_params m;
    memset(&m, 0, sizeof m); /* pr_IN1 = 0: Material:mu_law regularized */
    stress_moduli(10e6, 0.3, &m.G, &m.K); /* paper Table 1 */
    m.rho_s = 2500, m.mu_s = 0.382, m.mu_d = 0.682, m.I0 = 0.279, m.lambda = 0.001;
    return m;
}

static void test_moduli(void **st)
{
    (void)st;
    mat_params m = table1();
    assert_true(fabs(m.G - 10e6 / 2.6) < RT(1e-12) * m.G && fabs(m.K - 10e6 / 1.2) < RT(1e-12) * m.K);
    double c = stress_sound_speed(m.G, m.K, 1500);
    assert_true(fabs(c * c * 1500 - (m.K + 4.0 / 3.0 * m.G)) < RT(1e-12) * m.K);
    assert_true(fabs(stress_dt(0.1, 1e-3, 0, c) - 0.1 * 1e-3 / c) < RT(1e-12) * 1e-4 / c);
    assert_true(fabs(stress_dt(0.1, 1e-3, 1e9, c) - 0.1 * sqrt(1e-3 / 1e9)) < RT(1e-12) * 1e-7); /* acceleration-bound */
}

static void test_mu(void **st)
{
    (void)st;
    mat_params m = table1();
    assert_true(fabs(stress_kmu(0.382) - 3 * 0.382 / sqrt(9 + 12 * 0.382 * 0.382)) < RT(1e-15));
    assert_true(stress_mu(&m, 0, 1000, 3.75e-4) == m.mu_s);               /* no shear: mu_s */
    assert_true(fabs(stress_mu(&m, 1e9, 1000, 3.75e-4) - m.mu_d) < 1e-5); /* fast shear: mu_d */
    double prev = m.mu_s;
    for (double g = 0.01; g < 1000; g *= 3) { /* monotone in the shear rate */
        double mu = stress_mu(&m, g, 1000, 3.75e-4);
        assert_true(mu > prev && mu < m.mu_d);
        prev = mu;
    }
    double p0 = stress_mu(&m, 1.0, 0, 3.75e-4); /* free surface: finite */
    assert_true(isfinite(p0) && p0 > m.mu_s && p0 < m.mu_d);
    /* far from the regularization (gdot >> lambda), (2.14) is (2.13) with
     * I = gdot d / sqrt(p / rho_s) */
    double g = 5, p = 800, d = 3.75e-4, I = g * d / sqrt(p / m.rho_s);
    double mu13 = m.mu_s + (m.mu_d - m.mu_s) / (m.I0 / I + 1);
    assert_true(fabs(stress_mu(&m, g, p, d) - mu13) < RT(1e-6));
}

/* Material:mu_law partial (Barker & Gray 2017) for Table 1's mu(I). The
 * reference values are tools/analysis/inertial_range.py's (`window --pr-alpha
 * 1.9`: I_N1 0.01656, A 2554, mu(1e-4) 0.3338, a layer at 20 deg flows at I =
 * 0.00151), an independent implementation (numpy, a different scan). */
static void test_mu_partial(void **st)
{
    (void)st;
    double IN1 = 0, A = 0;
    assert_int_equal(stress_partial_law(0.382, 0.682, 0.279, 1.9, &IN1, &A), 0);
    assert_true(fabs(IN1 - 0.01656) < 0.00001 && fabs(A - 2554) < 1);
    /* I_N1 is where the criterion changes sign, ill posed (C > 0) below */
    assert_true(stress_wellposed_C(IN1 * (1 - 1e-6), 0.382, 0.682, 0.279) > 0);
    assert_true(stress_wellposed_C(IN1 * (1 + 1e-6), 0.382, 0.682, 0.279) < 0);
    mat_params m = table1();
    m.pr_alpha = (real)1.9, m.pr_A = (real)A, m.pr_IN1 = (real)IN1;
    const double p = 800, d = 3.75e-4, gI = sqrt(p / m.rho_s) / d; /* gdot = I gI */
    /* no static yield: at gdot = 0, mu at I = lambda d / sqrt(p / rho_s) (lambda's regularisation) */
    double Il = 0.001 / gI, mu0 = sqrt(1.9 / log(A / Il));
    assert_true(fabs(stress_mu(&m, 0, p, d) - mu0) < RT(1e-6) && mu0 < 0.32);
    assert_true(fabs(stress_mu(&m, (real)(1e-4 * gI), p, d) - 0.3338) < 1e-4);
    double mu20 = tan(20 * M_PI / 180); /* the inverse: I = A exp(-alpha / mu^2) */
    assert_true(fabs(A * exp(-1.9 / (mu20 * mu20)) - 0.00151) < 0.000005);
    assert_true(fabs(stress_mu(&m, (real)(0.00151 * gI), p, d) - mu20) < RT(1e-4));
    /* continuous at I_N1, and monotone through it */
    double below = stress_mu(&m, (real)(IN1 * (1 - 1e-5) * gI), p, d);
    double above = stress_mu(&m, (real)(IN1 * (1 + 1e-5) * gI), p, d);
    assert_true(fabs(above - below) < RT(1e-5) && below <= above);
    double prev = 0;
    for (double I = 1e-9; I < 10; I *= 1.7) {
        double mu = stress_mu(&m, (real)(I * gI), p, d);
        assert_true(mu > prev - RT(1e-7) && mu < m.mu_d);
        prev = mu;
    }
    /* above I_N1, and at p = 0, the paper's (2.14) */
    mat_params r = table1();
    assert_true(stress_mu(&m, (real)(0.1 * gI), p, d) == stress_mu(&r, (real)(0.1 * gI), p, d));
    assert_true(stress_mu(&m, 1, 0, d) == stress_mu(&r, 1, 0, d));
    /* nothing to regularise: mu_s = 0 is well posed at 1e-8 already */
    assert_int_equal(stress_partial_law(0, 0.682, 0.279, 1.9, &IN1, &A), -1);
}

static void test_return_map(void **st)
{
    (void)st;
    real k = stress_kmu(0.5);
    real in[6] = {-1000, -1200, -1100, 50, 0, 20}; /* inside the cone */
    real s[6];
    for (int c = 0; c < 6; ++c) s[c] = in[c];
    assert_int_equal(stress_return_map(s, k), 0);
    for (int c = 0; c < 6; ++c) assert_true(s[c] == in[c]);
    real out[6] = {-1000, -3000, -500, 900, 100, -300}; /* far outside */
    for (int c = 0; c < 6; ++c) s[c] = out[c];
    real p = stress_pressure(out), tau = sqrt(stress_J2(out));
    assert_true(tau > k * p);
    assert_int_equal(stress_return_map(s, k), 1);
    assert_true(fabs(stress_pressure(s) - p) < RT(1e-9) * p);          /* pressure kept */
    assert_true(fabs(sqrt(stress_J2(s)) - k * p) < RT(1e-9) * k * p);   /* on the cone */
    assert_true(fabs(s[3] / out[3] - s[5] / out[5]) < RT(1e-12));       /* same deviator direction */
    real ten[6] = {100, -20, 10, 5, 0, 0}; /* mean tension: apex */
    assert_int_equal(stress_return_map(ten, k), 2);
    for (int c = 0; c < 6; ++c) assert_true(ten[c] == 0);
}

/* |tau| = sqrt(tau_ij tau_ij / 2) over the full 3x3 deviator tau = sigma + p I
 * (Jop, Forterre & Pouliquen 2006's second invariant), written out
 * independently of stress_J2. */
static double jfp_tau(const real s[6])
{
    double p = -((double)s[0] + s[1] + s[2]) / 3;
    double T[3][3] = {{s[0] + p, s[3], s[4]}, {s[3], s[1] + p, s[5]}, {s[4], s[5], s[2] + p}}, sum = 0;
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) sum += T[a][b] * T[a][b];
    return sqrt(sum / 2);
}

/* Simple shear u_x = gdot y (plane strain) from an initial stress s, in
 * small elastic trial increments (Jaumann rate C1, spin included), each
 * returned onto the surface of `yield` at mu_s (the quasi-static limit);
 * the stress after n increments of shear strain dg each. */
static void shear_path(real s[6], int yield, int n, double dg)
{
    mat_params m = table1();
    real eps[6] = {0, 0, 0, (real)(dg / 2), 0, 0}, w[3] = {(real)(dg / 2), 0, 0}, r[6];
    for (int k = 0; k < n; ++k) {
        stress_rate_elastic(s, eps, w, m.G, m.K, r); /* the rate times dt: eps, w are increments */
        for (int c = 0; c < 6; ++c) s[c] += r[c];
        stress_return_yield(s, yield, m.mu_s);
    }
}

/* Material:yield in simple shear: the layer's shear stress at yield is
 * tau_xy / p = mu_s with mu_I (tan 20.9 deg for Table 1's beads, Pouliquen
 * 1999's onset) and k_mu(mu_s) with drucker_prager (the paper's, tan 19.3
 * deg): the factor between sqrt(J2) and tau_xy is 1 once the flow rule has
 * driven the normal stress differences to O(tau^2 / G), whatever the start
 * (isotropic, or the geostatic K0 = nu / (1 - nu) state of setup.c). */
static void test_yield_simple_shear(void **st)
{
    (void)st;
    const double p = 1000, mu_s = 0.382, K0 = 0.3 / 0.7;
    for (int start = 0; start < 2; ++start)
        for (int yield = 0; yield < 2; ++yield) {
            /* start 1: sigma_yy = -P, sigma_xx = sigma_zz = K0 sigma_yy, p = 1000 */
            double P = start ? 3 * p / (1 + 2 * K0) : p;
            real s[6] = {(real)(-(start ? K0 : 1) * P), (real)-P, (real)(-(start ? K0 : 1) * P), 0, 0, 0};
            shear_path(s, yield, 4000, 2e-5); /* shear strain 0.08, 800 times the yield strain 1e-4 */
            double ratio = s[3] / stress_pressure(s), want = yield == YIELD_MU_I ? mu_s : stress_kmu(mu_s);
            assert_true(fabs(stress_pressure(s) - p) < RT(1e-9) * p); /* isochoric: p kept */
            assert_true(fabs(ratio - want) < RT(1e-6));
            /* the normal stresses equal again */
            assert_true(fabs(s[0] - s[1]) < 1e-3 * p && fabs(s[2] + p) < 1e-3 * p);
        }
    /* the onset angles of the two surfaces: atan mu_s = 20.9 deg, atan k_mu(mu_s) = 19.3 deg */
    assert_true(fabs(atan(stress_yield_k(YIELD_MU_I, mu_s)) * 180 / M_PI - 20.90) < 0.01);
    assert_true(fabs(atan(stress_yield_k(YIELD_DRUCKER_PRAGER, mu_s)) * 180 / M_PI - 19.27) < 0.01);
}

/* The mu_I return mapping on 2D plane-strain and 3D states: the code's
 * sqrt(J2) is JFP's |tau| (an independent sum over the 3x3 deviator); a
 * state inside |tau| <= mu p is left bit for bit; one outside lands on the
 * surface with its pressure and deviator direction kept; mapping it again
 * changes nothing beyond round-off; tension goes to the apex. */
static void test_return_map_mu_i(void **st)
{
    (void)st;
    const real mu = (real)0.5;
    const real states[][6] = {
        {-1000, -1200, -1100, 50, 0, 0},      /* 2D plane strain, inside */
        {-1000, -1200, -1100, 50, 30, -40},   /* 3D, inside */
        {-1000, -3000, -500, 900, 0, 0},      /* 2D plane strain, outside */
        {-1000, -3000, -500, 900, 100, -300}, /* 3D, outside */
        {-800, -800, -800, 0, 0, 700},        /* pure shear in y-z, outside */
    };
    for (size_t k = 0; k < sizeof states / sizeof states[0]; ++k) {
        real s[6];
        for (int c = 0; c < 6; ++c) s[c] = states[k][c];
        double p = stress_pressure(s), tau = jfp_tau(s);
        assert_true(fabs(tau - sqrt(stress_J2(s))) < RT(1e-12) * tau); /* sqrt(J2) = |tau| */
        int inside = tau <= mu * p;
        assert_int_equal(stress_return_yield(s, YIELD_MU_I, mu), inside ? 0 : 1);
        if (inside) {
            for (int c = 0; c < 6; ++c) assert_true(s[c] == states[k][c]);
            continue;
        }
        assert_true(fabs(stress_pressure(s) - p) < RT(1e-12) * p);   /* p kept */
        assert_true(fabs(jfp_tau(s) - mu * p) < RT(1e-12) * mu * p); /* on |tau| = mu p */
        double r = (s[3] != 0 ? s[3] / states[k][3] : s[5] / states[k][5]);
        for (int c = 0; c < 6; ++c) /* the deviator scaled by one factor */
            assert_true(fabs((s[c] + (c < 3 ? p : 0)) - r * (states[k][c] + (c < 3 ? p : 0))) < RT(1e-12) * p);
        real again[6];
        for (int c = 0; c < 6; ++c) again[c] = s[c];
        stress_return_yield(again, YIELD_MU_I, mu); /* idempotent */
        for (int c = 0; c < 6; ++c) assert_true(fabs(again[c] - s[c]) < RT(1e-14) * p);
        /* the drucker_prager surface of the same mu is the narrower cone k_mu(mu) < mu */
        for (int c = 0; c < 6; ++c) again[c] = states[k][c];
        assert_int_equal(stress_return_yield(again, YIELD_DRUCKER_PRAGER, mu), 1);
        assert_true(fabs(sqrt(stress_J2(again)) - stress_kmu(mu) * p) < RT(1e-12) * p);
        assert_true(stress_kmu(mu) < mu);
    }
    real in_mu_out_dp[6] = {-1000, -1000, -1000, 450, 0, 0}; /* k_mu(0.5) p = 433 < 450 < 500 = mu p */
    real t[6];
    for (int c = 0; c < 6; ++c) t[c] = in_mu_out_dp[c];
    assert_int_equal(stress_return_yield(t, YIELD_MU_I, mu), 0);
    assert_int_equal(stress_return_yield(in_mu_out_dp, YIELD_DRUCKER_PRAGER, mu), 1);
    real ten[6] = {100, -20, 10, 5, 0, 3}; /* mean tension: the apex, as drucker_prager */
    assert_int_equal(stress_return_yield(ten, YIELD_MU_I, mu), 2);
    for (int c = 0; c < 6; ++c) assert_true(ten[c] == 0);
}

static void test_elastic_rate(void **st)
{
    (void)st;
    mat_params m = table1();
    real s[6] = {-1000, -3000, -500, 900, 100, -300}, zero[6] = {0}, w[3] = {0.7, -0.2, 0.4}, r[6];
    stress_rate_elastic(s, zero, w, m.G, m.K, r); /* spin only: p and J2 unchanged */
    real p = stress_pressure(s), dd[3] = {s[0] + p, s[1] + p, s[2] + p};
    double sdot = dd[0] * r[0] + dd[1] * r[1] + dd[2] * r[2] + 2 * (s[3] * r[3] + s[4] * r[4] + s[5] * r[5]);
    assert_true(fabs(r[0] + r[1] + r[2]) < RT(1e-12) * 3000 && fabs(sdot) < RT(1e-12) * 3000 * 3000);
    real comp[6] = {-1e-3, -1e-3, -1e-3, 0, 0, 0}, nw[3] = {0, 0, 0}; /* isotropic compression */
    stress_rate_elastic(zero, comp, nw, m.G, m.K, r);
    assert_true(fabs(stress_pressure(r) - m.K * 3e-3) < RT(1e-12) * m.K * 3e-3 && fabs(r[0] - r[1]) < RT(1e-12) * m.K * 3e-3);
    real shear[6] = {0, 0, 0, 0.5, 0, 0}; /* simple shear, gdot = 1 */
    stress_rate_elastic(zero, shear, nw, m.G, m.K, r);
    assert_true(fabs(r[3] - m.G) < RT(1e-12) * m.G && fabs(stress_pressure(r)) < RT(1e-12) * m.G);
    assert_true(fabs(stress_shear_rate(shear) - 1) < RT(1e-12));
}

static void test_pair_terms(void **st)
{
    (void)st;
    real si[6] = {-900, -1500, -1000, 200, 0, 30}, sj[6] = {-1200, -700, -800, -50, 10, 0};
    real xij[3] = {0.3e-3, -0.2e-3, 0}, uij[3] = {-0.01, 0.02, 0}; /* approaching */
    real h = 0.75e-3, alpha = kernel_alpha(2, h), r = sqrt(xij[0] * xij[0] + xij[1] * xij[1]);
    real g[3] = {kernel_f(r, h, alpha) * xij[0], kernel_f(r, h, alpha) * xij[1], 0};
    real gm[3] = {-g[0], -g[1], 0}, xji[3] = {-xij[0], -xij[1], 0}, uji[3] = {-uij[0], -uij[1], 0};
    real Pij = mom_av(0.1, 100, h, 1500, 1510, uij, xij), Pji = mom_av(0.1, 100, h, 1510, 1500, uji, xji);
    assert_true(Pij < 0 && Pij == Pji);
    real ai[3] = {0, 0, 0}, aj[3] = {0, 0, 0}, mi = 2e-4, mj = 3e-4;
    mom_accel_add(ai, mj, si, 1500, sj, 1510, Pij, g);
    mom_accel_add(aj, mi, sj, 1510, si, 1500, Pji, gm);
    for (int d = 0; d < 2; ++d) assert_true(fabs(mi * ai[d] + mj * aj[d]) < RT(1e-12) * fabs(mi * ai[d]));
    real sep[3] = {-uij[0], -uij[1], 0};
    assert_true(mom_av(0.1, 100, h, 1500, 1500, sep, xij) == 0); /* separating pairs: none */
}

/* Velocity gradient of u = A x on a 2D lattice (interior particle). */
static void test_velgrad_lattice(void **st)
{
    (void)st;
    double dr = 1e-3, h = 1.5 * dr, alpha = kernel_alpha(2, h);
    real A[2][2] = {{0.3, 1.1}, {-0.4, -0.2}}, L[9] = {0};
    for (int i = -3; i <= 3; ++i)
        for (int j = -3; j <= 3; ++j) {
            real xj[3] = {i * dr, j * dr, 0}, xij[3] = {-xj[0], -xj[1], 0};
            real r = sqrt(xij[0] * xij[0] + xij[1] * xij[1]);
            real f = kernel_f(r, h, alpha), g[3] = {f * xij[0], f * xij[1], 0};
            real uij[3] = {-(A[0][0] * xj[0] + A[0][1] * xj[1]), -(A[1][0] * xj[0] + A[1][1] * xj[1]), 0};
            mom_velgrad_add(L, dr * dr, uij, g);
        }
    for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b) assert_true(fabs(L[3 * a + b] - A[a][b]) < 0.005 * 1.1);
    real eps[6], w[3];
    mom_strain_spin(L, eps, w);
    assert_true(fabs(eps[3] - 0.5 * (1.1 - 0.4)) < 0.005 && fabs(w[0] - 0.5 * (1.1 + 0.4)) < 0.005);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_moduli),       cmocka_unit_test(test_mu), cmocka_unit_test(test_mu_partial),
        cmocka_unit_test(test_return_map),   cmocka_unit_test(test_yield_simple_shear),
        cmocka_unit_test(test_return_map_mu_i), cmocka_unit_test(test_elastic_rate),
        cmocka_unit_test(test_pair_terms),   cmocka_unit_test(test_velgrad_lattice)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
