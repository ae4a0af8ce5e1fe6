/* test_rates.c — the concentration rate (paper eqs. 2.10, 3.13, 3.8) on a
 * lattice block with a dummy base and side walls and a free top:
 *  - interior rates match the PDE C_t = d/dy(V F(C) + D dC/dy) for a linear
 *    field (segregation term) and a quadratic field (diffusion term), for the
 *    paper scheme and the conservative scheme (reference: the closed form);
 *  - the conservative scheme's sum V_i dC_i/dt is zero to round-off for an
 *    arbitrary field (reference: exact antisymmetry);
 *  - a uniform field in the paper scheme gives zero in the interior, a gain
 *    at the base and a loss at the free surface (CSR sources 4.9, 4.16);
 *  - magnitudes (issue 20): the Laplacian against a hand lattice sum with
 *    and without eta, the segregation term at boundary particles exact for
 *    a linear field (C1 gradients), variable V and D conserving, the CSR
 *    sources of a uniform field integrating to the flux Q W;
 *  - the donor limiter (issue 30): its pair flux against the central one
 *    over a grid of (C_u, C_d), and on the lattice an explicit step at the
 *    default time-step bounds from a field with steep fronts at 0 and 1:
 *    C leaves [0, 1] by more than 1e-3 without the limiter and stays in it
 *    with it, sum V_i dC_i/dt still zero to round-off. */
#include <stdlib.h>
#include "cpu/bound.h"
#include "physics/seg_kern.h"
#include "testutil.h"

static const double DR = 0.002;
static const int N = 24;

typedef struct fixture {
    particles_t p;
    nbr_grid g;
    bound_work w;
    seg_ctx c;
} fixture;

static void setup_fixture(fixture *f, int scheme, double V, double D)
{
    *f = (fixture){0};
    tu_block2d(&f->p, N, N, DR, 3, 3);
    f->c.k = sph_make(2, (real)(1.5 * DR), (real)DR);
    seg_params sp = {1, 0, 0, (real)V, (real)D, 0, 0, 0.004, 0.008, {0, -1, 0}, 0, 0};
    f->c.sp = sp;
    f->c.scheme = scheme;
    nbr_build(&f->g, &f->p, R(2.0) * f->c.k.h, NULL);
    bound_classify(&f->w, &f->p, &f->g, &f->c.k);
}

/* V, Q, D of every particle for the current C (as the backends do). */
static void coeffs(fixture *f)
{
    for (size_t i = 0; i < f->p.n; ++i) seg_coeffs(i, &f->p, &f->c);
}

/* The conservative scheme with variable coefficients (2.7: V and D from
 * each particle's own shear rate, random in [0, 20) 1/s) and
 * renormalisation on; C random in [0, 1], or with fronts: 0 where the
 * random draw is below 0.3, 1 above 0.7. The coefficients computed. */
static void setup_variable(fixture *f, unsigned seed, int fronts)
{
    setup_fixture(f, 2, 0, 0);
    f->c.sp.shear_model = 1, f->c.sp.chi_V = (real)0.3, f->c.sp.chi_D = (real)0.05, f->c.renorm = 1;
    srand(seed);
    for (size_t i = 0; i < f->p.n; ++i) {
        double u = rand() / (double)RAND_MAX;
        f->p.C[i] = (real)(fronts && u < 0.3 ? 0.0 : fronts && u > 0.7 ? 1.0 : u);
        f->p.gdot[i] = (real)(20.0 * rand() / (double)RAND_MAX);
    }
    coeffs(f);
}

static double rate(const fixture *f, size_t i)
{
    seg_rate r = f->c.scheme == 2 ? seg_rate_conservative(i, &f->p, &f->g.view, &f->c, 0, 1)
                                  : seg_rate_hcsr(i, &f->p, &f->g.view, &f->c, 0, 1);
    return r.seg + r.diff + r.src;
}

static int deep_inside(const fixture *f, size_t i)
{
    double x = f->p.x[0][i], y = f->p.x[1][i], m = 3.1 * f->c.k.h;
    return f->p.kind[i] == KIND_MATERIAL && x > m && x < N * DR - m && y > m && y < N * DR - m;
}

/* The rate of C = (y/L)^2 with constant D at a full-support lattice
 * particle, summed by hand over the lattice offsets (b dr in y): the odd
 * part of C_i - C_j cancels, leaving 2 D sum -(b dr / L)^2 F_ij V r^2 /
 * (r^2 + eta2), F = (1/r) dW/dr (eq. 3.8; eta2 = (0.1 h)^2 in the paper
 * scheme, 0 in the conservative one, whose Lbar = I without renorm). An
 * independent reference for the exact value the scheme must give, eta's
 * 1.5 % included, to round-off. */
static double lattice_laplacian(const sph_ctx *k, double eta2, double D, double L)
{
    double sum = 0, h = k->h;
    for (int a = -4; a <= 4; ++a)
        for (int b = -4; b <= 4; ++b) {
            double r2 = (a * a + b * b) * DR * DR;
            if ((a == 0 && b == 0) || r2 >= 4 * h * h) continue;
            double F = kernel_f((real)sqrt(r2), k->h, k->alpha);
            sum += -2 * D * (b * DR / L) * (b * DR / L) * F * DR * DR * r2 / (r2 + eta2);
        }
    return sum;
}

/* Tolerances: the lattice moment -sum V x (x) grad W is 0.9974 at h = 1.5 dr,
 * and the paper's clipping eta = 0.1 h (3.8) lowers the Laplacian by 1.5 %. */
static void check_interior(int scheme)
{
    double tol_seg = 0.005, tol_lap = scheme == 2 ? 0.005 : 0.02;
    double V = 1e-3, D = 1e-7, b = 20.0;
    fixture f;
    setup_fixture(&f, scheme, V, 0.0);
    for (size_t i = 0; i < f.p.n; ++i) f.p.C[i] = (real)(0.2 + b * f.p.x[1][i]); /* C in (0.2, 1.2) */
    coeffs(&f);
    for (size_t i = 0; i < f.p.n; ++i)
        if (deep_inside(&f, i)) {
            double C = f.p.C[i], exact = V * (1 - 2 * C) * b; /* d/dy(V C(1 - C)) */
            assert_true(fabs(rate(&f, i) - exact) < tol_seg * V * b);
        }
    f.c.sp.V = 0, f.c.sp.D = (real)D;
    for (size_t i = 0; i < f.p.n; ++i) f.p.C[i] = (real)(f.p.x[1][i] * f.p.x[1][i] / (N * N * DR * DR));
    coeffs(&f);
    double lap = 2.0 * D / (N * N * DR * DR);
    double eta2 = scheme == 2 ? 0 : (double)f.c.k.eta2, ref = lattice_laplacian(&f.c.k, eta2, D, N * DR);
    for (size_t i = 0; i < f.p.n; ++i)
        if (deep_inside(&f, i)) {
            assert_true(fabs(rate(&f, i) - lap) < tol_lap * lap);
            assert_true(fabs(rate(&f, i) - ref) < RT(1e-10) * lap);
        }
    bound_free(&f.w), nbr_free(&f.g), part_free(&f.p);
}

/* The paper scheme's segregation term at boundary particles (walls and
 * free surface, cut supports): the C1-consistent gradients (App. E) are
 * exact for a linear field, so seg = V (1 - 2C) b exactly (to the solve's
 * round-off), where plain difference gradients are off by tens of percent. */
static void test_boundary_c1(void **st)
{
    (void)st;
    double V = 1e-3, b = 20.0;
    fixture f;
    setup_fixture(&f, 0, V, 0.0);
    for (size_t i = 0; i < f.p.n; ++i) f.p.C[i] = (real)(0.2 + b * f.p.x[1][i]);
    coeffs(&f);
    int nb = 0;
    for (size_t i = 0; i < f.p.n; ++i) {
        if (f.p.kind[i] != KIND_MATERIAL || f.p.bclass[i] == BC_INTERIOR) continue;
        seg_rate r = seg_rate_hcsr(i, &f.p, &f.g.view, &f.c, 0, 1);
        double C = f.p.C[i];
        assert_true(fabs(r.seg - V * (1 - 2 * C) * b) < RT(1e-9) * V * b);
        nb++;
    }
    assert_true(nb > 4 * N);
    bound_free(&f.w), nbr_free(&f.g), part_free(&f.p);
}

static void test_interior_paper(void **st) { (void)st; check_interior(0); }
static void test_interior_conservative(void **st) { (void)st; check_interior(2); }

static void test_conservative_sum(void **st)
{
    (void)st;
    fixture f;
    setup_fixture(&f, 2, 1e-3, 1e-7);
    srand(3);
    double sum = 0, mag = 0;
    for (size_t i = 0; i < f.p.n; ++i) f.p.C[i] = (real)(rand() / (double)RAND_MAX);
    coeffs(&f);
    for (size_t i = 0; i < f.p.n; ++i)
        if (f.p.kind[i] == KIND_MATERIAL) {
            double r = rate(&f, i) * f.p.vol[i];
            sum += r;
            mag += fabs(r);
        }
    assert_true(mag > 0);
    assert_true(fabs(sum) < RT(1e-12) * mag);
    bound_free(&f.w), nbr_free(&f.g), part_free(&f.p);
}

/* Variable coefficients (eq. 2.7: V and D from each particle's own shear
 * rate, random here) with renormalisation on: the pair fluxes stay
 * antisymmetric only when they use (Q_i + Q_j), (D_i + D_j) and (L_i +
 * L_j)/2; sum V_i dC_i/dt = 0 to round-off (a constant D cannot tell
 * D_i + D_j from 2 D_i). */
static void test_conservative_sum_variable(void **st)
{
    (void)st;
    fixture f;
    setup_variable(&f, 5, 0);
    int bent = 0;
    for (size_t i = 0; i < f.p.n; ++i)
        if (f.p.kind[i] == KIND_MATERIAL) {
            seg_renorm(i, &f.p, &f.g.view, &f.c);
            bent += fabs(f.p.L[0][i] - 1) > 1e-3;
        }
    double sum = 0, mag = 0, dmin = INFINITY, dmax = 0;
    for (size_t i = 0; i < f.p.n; ++i)
        if (f.p.kind[i] == KIND_MATERIAL) {
            double r = rate(&f, i) * f.p.vol[i];
            sum += r, mag += fabs(r);
            dmin = fmin(dmin, f.p.segD[i]), dmax = fmax(dmax, f.p.segD[i]);
        }
    assert_true(bent > 0 && dmax > 2 * dmin && mag > 0); /* L and D do vary */
    assert_true(fabs(sum) < RT(1e-12) * mag);
    bound_free(&f.w), nbr_free(&f.g), part_free(&f.p);
}

static void test_uniform_sources(void **st)
{
    (void)st;
    fixture f;
    setup_fixture(&f, 0, 1e-3, 1e-7);
    for (size_t i = 0; i < f.p.n; ++i) f.p.C[i] = R(0.5);
    coeffs(&f);
    int base = 0, top = 0;
    for (size_t i = 0; i < f.p.n; ++i) {
        if (f.p.kind[i] != KIND_MATERIAL) continue;
        double r = rate(&f, i), x = f.p.x[0][i], y = f.p.x[1][i];
        int mid = x > 3 * DR && x < (N - 3) * DR;
        if (deep_inside(&f, i)) assert_true(fabs(r) < RT(1e-12) * 1e-3 / DR); /* scale V / dr */
        if (mid && y < DR) assert_true(r > 0), base++;          /* base gains small grains */
        if (mid && y > (N - 1) * DR) assert_true(r < 0), top++; /* free surface loses them */
    }
    assert_true(base > 10 && top > 10);
    bound_free(&f.w), nbr_free(&f.g), part_free(&f.p);
}

/* The CSR sources of a uniform field in the paper scheme, integrated: the
 * segregation flux Q = V F(C) down through the box (eq. 2.6) meets the
 * impermeable base, so the base region gains small grains at Q W per unit
 * depth (W the base width) and the free surface loses as much; the side
 * walls, parallel to gravity, take no flux (f = -V F n.ghat = 0, eq. 4.5).
 * sum V_i dC_i/dt over the lower and the upper half against +-Q W:
 * measured -0.7 % and -2.5 % at h = 1.5 dr, 24 x 24; tolerances 1.5 % and
 * 5 %. At the corner particle (diagonal n_i) the source is (4.9) with each
 * dummy's own normal, -sum_j f(C_i; n_j) (n_i + n_j).grad_i W_ij V_j,
 * summed here by hand over the store: f(C_i; n_i) would push flux through
 * the vertical wall (+13 %). */
static void test_wall_flux_total(void **st)
{
    (void)st;
    fixture f;
    double V = 1e-3, C = 0.5, Q = V * C * (1 - C), W = N * DR;
    setup_fixture(&f, 0, V, 0);
    for (size_t i = 0; i < f.p.n; ++i) f.p.C[i] = (real)C;
    coeffs(&f);
    double low = 0, high = 0;
    for (size_t i = 0; i < f.p.n; ++i) {
        if (f.p.kind[i] != KIND_MATERIAL) continue;
        double r = rate(&f, i) * f.p.vol[i];
        if (f.p.x[1][i] < 0.5 * N * DR) low += r;
        else high += r;
    }
    assert_true(fabs(low / (Q * W) - 1) < 0.015 && fabs(high / (Q * W) + 1) < 0.05);
    size_t c = tu_find(&f.p, 0); /* the lower-left corner particle */
    assert_true(f.p.bclass[c] == BC_WALL_SURFACE && fabs(f.p.nrm[0][c] - f.p.nrm[1][c]) < 1e-6);
    double q = 0, h = f.c.k.h;
    for (size_t j = 0; j < f.p.n; ++j) {
        double dx = f.p.x[0][c] - f.p.x[0][j], dy = f.p.x[1][c] - f.p.x[1][j], r2 = dx * dx + dy * dy;
        if (f.p.kind[j] != KIND_DUMMY || r2 >= 4 * h * h) continue;
        double F = kernel_f((real)sqrt(r2), f.c.k.h, f.c.k.alpha) * f.p.vol[j];
        double fj = V * C * (1 - C) * f.p.nrm[1][j]; /* -V F n_j.ghat, ghat = -y */
        q -= fj * ((f.p.nrm[0][c] + f.p.nrm[0][j]) * F * dx + (f.p.nrm[1][c] + f.p.nrm[1][j]) * F * dy);
    }
    assert_true(q > 0 && fabs(rate(&f, c) - q) < RT(1e-10) * q);
    bound_free(&f.w), nbr_free(&f.g), part_free(&f.p);
}

/* seg_flux_donor against the central pair flux Q_u + Q_d on a grid of
 * (C_u, C_d) in [0, 1] and just outside, symmetric (2.8) and asymmetric
 * (2.9) F, V from (2.7) with the particle's own C: never negative, never
 * above the central flux, equal to it (exactly) for equal C, zero from a
 * donor without small grains and into a receiver full of them. */
static void test_donor_flux(void **st)
{
    (void)st;
    seg_params sps[2] = {{1, 0, 1, 0, 0, (real)0.11, (real)0.0307, (real)0.004, (real)0.008, {0, -1, 0}, 0, 0},
                         {(real)1.6, (real)0.89, 1, 0, 0, (real)0.11, (real)0.0307, (real)0.004, (real)0.008,
                          {0, -1, 0}, 0, 0}};
    int capped = 0;
    for (int s = 0; s < 2; ++s)
        for (int a = -1; a <= 21; ++a)
            for (int b = -1; b <= 21; ++b) {
                const seg_params *sp = &sps[s];
                real Cu = (real)(a / 20.0), Cd = (real)(b / 20.0), gd = (real)7.0;
                real Vu = seg_V(sp, Cu, gd), Vd = seg_V(sp, Cd, gd);
                real Qsum = Vu * seg_F(sp, Cu) + Vd * seg_F(sp, Cd);
                real q = seg_flux_donor(Qsum, Vu + Vd, Cu, Cd, sp->A);
                assert_true(q >= 0);
                assert_true(q <= Qsum || Qsum < 0);
                if (a == b && a >= 0 && a <= 20) assert_true(q == Qsum);
                if (a <= 0 || b >= 20) assert_true(q == 0);
                capped += q < Qsum;
            }
    assert_true(capped > 40); /* it does act, off the diagonal */
}

/* A lattice field with steep fronts at both bounds (V h / D = 6): rows of
 * C = 0 above rows in (0.3, 0.7), rows of C = 1 below, a few 0 and 1 among
 * them. One explicit step of the default time-step bounds (dt = min(0.2 h
 * / max|dQ/dC|, 0.1 h^2 / D), here at C = 0: A V) with renormalisation on.
 * Without the limiter C leaves [0, 1] by more than 1e-3 (the undershoot of
 * the R35 drum, in one step); with it C stays within [0, 1] to round-off,
 * and sum V_i dC_i/dt is zero to round-off. Symmetric and asymmetric F. */
static void check_donor_step(double A, double kappa)
{
    double V = 1e-3, h = 1.5 * DR, D = V * h / 6;
    fixture f;
    setup_fixture(&f, 2, V, D);
    f.c.sp.A = (real)A, f.c.sp.kappa = (real)kappa, f.c.renorm = 1;
    srand(11);
    for (size_t i = 0; i < f.p.n; ++i) {
        int row = (int)floor(f.p.x[1][i] / DR);
        double u = rand() / (double)RAND_MAX;
        f.p.C[i] = (real)(row >= 16 ? 0.0 : row < 6 ? 1.0 : u < 0.1 ? 0.0 : u > 0.9 ? 1.0 : 0.3 + 0.4 * u);
    }
    coeffs(&f);
    for (size_t i = 0; i < f.p.n; ++i)
        if (f.p.kind[i] == KIND_MATERIAL) seg_renorm(i, &f.p, &f.g.view, &f.c);
    double dt = fmin(0.2 * h / (A * V), 0.1 * h * h / D), lo[2], hi[2], sum = 0, mag = 0;
    for (int lim = 0; lim < 2; ++lim) {
        f.c.limiter = lim;
        lo[lim] = INFINITY, hi[lim] = -INFINITY;
        for (size_t i = 0; i < f.p.n; ++i) {
            if (f.p.kind[i] != KIND_MATERIAL) continue;
            double r = rate(&f, i), C = f.p.C[i] + dt * r;
            lo[lim] = fmin(lo[lim], C), hi[lim] = fmax(hi[lim], C);
            if (lim) sum += r * f.p.vol[i], mag += fabs(r * f.p.vol[i]);
        }
    }
    print_message("    A %.2f kappa %.2f: one step, C in [%.5f, %.5f] without the limiter, [%.3g, 1 + %.3g] with it\n",
                  A, kappa, lo[0], hi[0], lo[1], hi[1] - 1);
    assert_true(lo[0] < -1e-3 && hi[0] > 1 + 1e-3);
    assert_true(lo[1] > -RT(1e-12) && hi[1] < 1 + RT(1e-12));
    assert_true(mag > 0 && fabs(sum) < RT(1e-12) * mag);
    bound_free(&f.w), nbr_free(&f.g), part_free(&f.p);
}

static void test_donor_step_sym(void **st) { (void)st; check_donor_step(1.0, 0.0); }
static void test_donor_step_asym(void **st) { (void)st; check_donor_step(1.6, 0.89); }

/* Variable V and D (2.7, random shear rates) and renormalisation with the
 * limiter on a field with fronts: the capped pair flux is still evaluated
 * alike from both sides, so sum V_i dC_i/dt = 0 to round-off; and the cap
 * acts (the rates differ from the unlimited ones). */
static void test_donor_sum_variable(void **st)
{
    (void)st;
    fixture f;
    setup_variable(&f, 7, 1);
    for (size_t i = 0; i < f.p.n; ++i)
        if (f.p.kind[i] == KIND_MATERIAL) seg_renorm(i, &f.p, &f.g.view, &f.c);
    double sum = 0, mag = 0;
    int differ = 0;
    for (size_t i = 0; i < f.p.n; ++i) {
        if (f.p.kind[i] != KIND_MATERIAL) continue;
        f.c.limiter = 0;
        double r0 = rate(&f, i);
        f.c.limiter = 1;
        double r = rate(&f, i) * f.p.vol[i];
        sum += r, mag += fabs(r);
        differ += fabs(r / f.p.vol[i] - r0) > 1e-6 * fabs(r0);
    }
    assert_true(differ > 10 && mag > 0);
    assert_true(fabs(sum) < RT(1e-12) * mag);
    bound_free(&f.w), nbr_free(&f.g), part_free(&f.p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_interior_paper), cmocka_unit_test(test_interior_conservative),
        cmocka_unit_test(test_boundary_c1),
        cmocka_unit_test(test_conservative_sum), cmocka_unit_test(test_conservative_sum_variable),
        cmocka_unit_test(test_uniform_sources), cmocka_unit_test(test_wall_flux_total),
        cmocka_unit_test(test_donor_flux), cmocka_unit_test(test_donor_step_sym),
        cmocka_unit_test(test_donor_step_asym), cmocka_unit_test(test_donor_sum_variable)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
