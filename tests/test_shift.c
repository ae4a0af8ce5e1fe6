/* test_shift.c — particle shifting (src/physics/shift.h, Flow:shifting
 * fickian) and the Newtonian viscous term's lattice normalisation
 * (mom_visc_lattice, src/physics/momentum.h), on lattice blocks against
 * exact answers:
 *  - the lattice moment S = -(1/d) sum_j V_j f r^2 of the Wendland C2
 *    kernel at h = 1.5 dr: 0.997399 in 2D (an independent sum in numpy,
 *    tools/studies/poiseuille_study.py lattice_laplacian: 0.9973992684); 3D near 1;
 *  - the normalised viscous term on u = (y^2, 0, 0) gives an interior
 *    particle the acceleration nu Laplacian u = (2 nu, 0, 0) to round-off
 *    (Morris's sum alone gives 2 nu S, 0.26 % low);
 *  - an interior particle of a perfect lattice moving at a uniform velocity
 *    is not shifted (to round-off): sum_j V_j grad W_ij = 0 by symmetry;
 *  - a particle displaced from its site by (0.2, 0.1) dr is shifted back
 *    towards it, by D |grad C| with D = A h |u| dt; the other particles'
 *    copies and every C and volume are left alone;
 *  - in a linear velocity field u = G x the Taylor step adds G dr to the
 *    shifted particle's saved velocity, and a linear stress field likewise
 *    (within 3 %: the plain SPH gradient's moment at a particle 0.2 dr off
 *    its site, 2.0 % measured);
 *  - at a free surface (the top row of a block with nothing above) a
 *    particle displaced along the surface is not shifted; three rows down
 *    the same displacement is shifted back; with Flow:shift_surface_rule
 *    tangential the top row's is shifted back too, along the surface (its
 *    normal part under a fifth of the tangential), and three rows down as
 *    before; with the rule fade the top row's shift is the rule
 *    tangential's plus a share w of its normal part, outwards (the same w
 *    along x and y to 1e-6, between 0.1 and 0.5: 0.23 measured, 2 div r / d
 *    - 1 of this displaced top-row particle; the whole normal part is the
 *    rule none's shift with the threshold under its div r), and three rows
 *    down, a whole support, its shift is within 3 % of the rule none's;
 *  - Flow:background_pressure excluded: a uniform background pressure p0
 *    on a perturbed block exerts no force (flow_ctx.p_back = 2 p0 / rho^2
 *    cancels it in the pair term to round-off), where the pair term alone
 *    pushes a displaced particle by (2 p0 / rho) |grad C|;
 *  - off: the stage is not in the plan (src/sim/stages.c): tests/test_stages.c
 *    holds the plans of the scenes without it. */
#include "physics/flow.h"
#include "physics/shift.h"
#include <string.h>
#include "testutil.h"

static const double DR = 1e-3;

static size_t centre(const particles_t *p, int n)
{
    return tu_find(p, (int64_t)((n / 2) * n + n / 2));
}

/* step_save for all: the copies the shift adds to. */
static void save_all(particles_t *p)
{
    for (size_t i = 0; i < p->n; ++i) {
        p->C_n[i] = p->C[i];
        for (int d = 0; d < 3; ++d) p->x_n[d][i] = (preal)p->x[d][i], p->v_n[d][i] = p->v[d][i];
        for (int q = 0; q < 6; ++q) p->sig_n[q][i] = p->sig[q][i];
    }
}

/* Fickian shifting at its default coefficient on the 2D kernel at h = 1.5 dr. */
static shift_ctx fickian(void)
{
    sph_ctx k = sph_make(2, (real)(1.5 * DR), (real)DR);
    return shift_make(&k, SHIFT_FICKIAN, 2, R(0.5), SHIFT_SURFACE_NONE);
}

static void test_lattice_moment(void **st)
{
    (void)st;
    double s2 = (double)mom_visc_lattice(2, (real)(1.5 * DR), (real)DR);
    assert_true(fabs(s2 - 0.9973992684438948) < RT(1e-12));
    double s3 = (double)mom_visc_lattice(3, (real)(1.5 * DR), (real)DR);
    assert_true(s3 > 0.99 && s3 < 1.01);
}

static void test_visc_quadratic(void **st)
{
    tu_fx *f = *st;
    flow_ctx c;
    memset(&c, 0, sizeof c);
    c.k = sph_make(2, (real)(1.5 * DR), (real)DR);
    c.rho = 1000, c.nu = (real)1e-3;
    c.visc_norm = R(1.0) / mom_visc_lattice(2, c.k.h, c.k.dr);
    int n = 12;
    tu_block2d(&f->p, n, n, DR, 0, 0);
    for (size_t i = 0; i < f->p.n; ++i) f->p.v[0][i] = f->p.x[1][i] * f->p.x[1][i];
    nbr_build(&f->g, &f->p, R(2.0) * c.k.h, NULL);
    size_t i = centre(&f->p, n);
    flow_rates(i, &f->p, &f->g.view, &c);
    assert_true(fabs(f->p.acc[0][i] - 2 * c.nu) < RT(1e-9) * 2 * c.nu);
    assert_true(fabs(f->p.acc[1][i]) < RT(1e-9) * 2 * c.nu);
}

/* A 14 x 14 block moving at u0 along x, particle `moved` displaced by d
 * (in dr), saved; returns the index of the centre particle. */
static size_t shifted_block(particles_t *p, nbr_grid *g, const shift_ctx *c, double dx, double dy, double dt)
{
    int n = 14;
    tu_block2d(p, n, n, DR, 0, 0);
    for (size_t i = 0; i < p->n; ++i) p->v[0][i] = (real)0.1, p->C[i] = 0.25 + 0.5 * (double)(i % 2);
    size_t i = (size_t)((n / 2) * n + n / 2); /* before the sort: index = id */
    p->x[0][i] += (real)(dx * DR), p->x[1][i] += (real)(dy * DR);
    nbr_build(g, p, R(2.0) * c->k.h, NULL);
    save_all(p);
    i = centre(p, n);
    shift_team(i, p, &g->view, c, (real)dt, 0, 1);
    return i;
}

static void test_shift_lattice(void **st)
{
    tu_fx *f = *st;
    shift_ctx c = fickian();
    size_t i = shifted_block(&f->p, &f->g, &c, 0, 0, 1e-4);
    for (int a = 0; a < 2; ++a) assert_true(fabs((double)(f->p.x_n[a][i] - (preal)f->p.x[a][i])) < RT(1e-12) * DR);
}

static void test_shift_back(void **st)
{
    tu_fx *f = *st;
    shift_ctx c = fickian();
    const double dt = 1e-4, dx = 0.2, dy = 0.1;
    size_t i = shifted_block(&f->p, &f->g, &c, dx, dy, dt);
    double s[2] = {(double)(f->p.x_n[0][i] - (preal)f->p.x[0][i]), (double)(f->p.x_n[1][i] - (preal)f->p.x[1][i])};
    /* back towards the site: against the displacement, not along it */
    double along = (s[0] * dx + s[1] * dy) / hypot(dx, dy), len = hypot(s[0], s[1]);
    assert_true(along < -0.9 * len);
    /* of the size D |grad C|: D = A h |u| dt, |grad C| of order (displacement) / h^2 */
    double D = 2 * 1.5 * DR * 0.1 * dt;
    assert_true(len > 0.1 * D * hypot(dx, dy) * DR / (1.5 * DR * 1.5 * DR));
    assert_true(len < 10 * D * hypot(dx, dy) * DR / (1.5 * DR * 1.5 * DR));
    /* nothing else changed: the others' copies, every C and volume */
    for (size_t j = 0; j < f->p.n; ++j) {
        assert_true(f->p.C_n[j] == f->p.C[j]);
        assert_true(f->p.vol[j] == (real)(DR * DR));
        if (j == i) continue;
        for (int a = 0; a < 3; ++a) assert_true(f->p.x_n[a][j] == (preal)f->p.x[a][j]);
    }
    /* uniform velocity: the Taylor step adds nothing */
    assert_true(fabs(f->p.v_n[0][i] - (real)0.1) < RT(1e-12));
}

static void test_shift_taylor(void **st)
{
    tu_fx *f = *st;
    shift_ctx c = fickian();
    int n = 14;
    tu_block2d(&f->p, n, n, DR, 0, 0);
    const double G[2][2] = {{3, 1}, {-2, 0.5}}, S = 1e5; /* 1/s; Pa/m */
    size_t i0 = (size_t)((n / 2) * n + n / 2);
    f->p.x[0][i0] += (real)(0.2 * DR), f->p.x[1][i0] += (real)(0.1 * DR);
    for (size_t i = 0; i < f->p.n; ++i) {
        for (int a = 0; a < 2; ++a) f->p.v[a][i] = (real)(0.1 * (a == 0) + G[a][0] * f->p.x[0][i] + G[a][1] * f->p.x[1][i]);
        f->p.sig[3][i] = (real)(S * f->p.x[0][i]);
    }
    nbr_build(&f->g, &f->p, R(2.0) * c.k.h, NULL);
    save_all(&f->p);
    size_t i = centre(&f->p, n);
    shift_team(i, &f->p, &f->g.view, &c, (real)1e-3, 0, 1);
    double s[2] = {(double)(f->p.x_n[0][i] - (preal)f->p.x[0][i]), (double)(f->p.x_n[1][i] - (preal)f->p.x[1][i])};
    assert_true(hypot(s[0], s[1]) > 0);
    for (int a = 0; a < 2; ++a) {
        double want = G[a][0] * s[0] + G[a][1] * s[1], got = f->p.v_n[a][i] - f->p.v[a][i];
        assert_true(fabs(got - want) < 0.03 * (fabs(G[a][0] * s[0]) + fabs(G[a][1] * s[1])));
    }
    assert_true(fabs((f->p.sig_n[3][i] - f->p.sig[3][i]) - S * s[0]) < 0.03 * fabs(S * s[0]));
    assert_true(f->p.sig_n[0][i] == f->p.sig[0][i]);
}

/* The shift of the particle `row` rows below the top of a 14 x 14 block, moved 0.2 dr along the surface,
 * under the free-surface rule `rule` with s = Flow:shift_surface (m). */
static void surface_shift(int rule, double s_free, int row, double out[2])
{
    particles_t p;
    nbr_grid g = {0};
    sph_ctx k = sph_make(2, (real)(1.5 * DR), (real)DR);
    shift_ctx c = shift_make(&k, SHIFT_FICKIAN, 2, (real)s_free, rule);
    int n = 14;
    tu_block2d(&p, n, n, DR, 0, 0);
    size_t id = (size_t)((n - row) * n + n / 2); /* mid-width, moved along the surface */
    p.x[0][id] += (real)(0.2 * DR);
    for (size_t i = 0; i < p.n; ++i) p.v[0][i] = (real)0.1;
    nbr_build(&g, &p, R(2.0) * c.k.h, NULL);
    save_all(&p);
    size_t i = tu_find(&p, (int64_t)id);
    shift_team(i, &p, &g.view, &c, (real)1e-4, 0, 1);
    out[0] = (double)(p.x_n[0][i] - (preal)p.x[0][i]), out[1] = (double)(p.x_n[1][i] - (preal)p.x[1][i]);
    print_message("rule %d, s %.2f, row %d: shift (%.3e, %.3e) m\n", rule, s_free, row, out[0], out[1]);
    nbr_free(&g);
    part_free(&p);
}

static void test_shift_surface(void **st)
{
    (void)st;
    double sh[3][5][2]; /* [rule][row]: the shift along the surface, and across */
    for (int rule = SHIFT_SURFACE_NONE; rule <= SHIFT_SURFACE_FADE; ++rule)
        for (int row = 1; row <= 4; row += 3) { /* the top row, then three rows down */
            double *s = sh[rule][row];
            surface_shift(rule, 0.5, row, s);
            if (row == 1 && rule == SHIFT_SURFACE_NONE) {
                assert_true(s[0] == 0 && s[1] == 0);
            } else if (row == 1 && rule == SHIFT_SURFACE_FADE) {
                assert_true(s[0] < 0 && s[1] > 0); /* back along the surface, and a share outwards */
            } else {
                assert_true(s[0] < 0);
                assert_true(fabs(s[1]) < 0.2 * fabs(s[0]));
            }
        }
    /* fade: the top row's shift is the tangential rule's plus a share w of the normal part, which the rule
     * none with a threshold under the row's div r (s = 1: d - 1 = 1 < 1.24) keeps whole */
    double full[2];
    surface_shift(SHIFT_SURFACE_NONE, 1.0, 1, full);
    const double *tg = sh[SHIFT_SURFACE_TANGENTIAL][1], *fd = sh[SHIFT_SURFACE_FADE][1];
    const double wx = (fd[0] - tg[0]) / (full[0] - tg[0]), wy = (fd[1] - tg[1]) / (full[1] - tg[1]);
    print_message("fade's share of the normal part at the top row: %.4f (x), %.4f (y)\n", wx, wy);
    assert_true(wx > 0.1 && wx < 0.5 && fabs(wx - wy) < 1e-6);
    /* a whole support three rows down: within 3 % of the rule none's (the displaced particle's div r < d) */
    assert_true(fabs(sh[SHIFT_SURFACE_FADE][4][0] / sh[SHIFT_SURFACE_NONE][4][0] - 1) < 0.03);
}

static void test_background_excluded(void **st)
{
    tu_fx *f = *st;
    flow_ctx c;
    memset(&c, 0, sizeof c);
    c.k = sph_make(2, (real)(1.5 * DR), (real)DR);
    c.rho = 1500, c.nu = (real)1e-3, c.visc_norm = 1;
    const double p0 = 300;
    int n = 12;
    tu_block2d(&f->p, n, n, DR, 0, 0);
    size_t i0 = (size_t)((n / 2) * n + n / 2);
    f->p.x[0][i0] += (real)(0.2 * DR), f->p.x[1][i0] -= (real)(0.1 * DR);
    for (size_t i = 0; i < f->p.n; ++i)
        for (int q = 0; q < 3; ++q) f->p.sig[q][i] = (real)-p0;
    nbr_build(&f->g, &f->p, R(2.0) * c.k.h, NULL);
    size_t i = tu_find(&f->p, (int64_t)i0);
    flow_rates(i, &f->p, &f->g.view, &c);
    const double push = hypot(f->p.acc[0][i], f->p.acc[1][i]), scale = 2 * p0 / (c.rho * DR);
    assert_true(push > 0.01 * scale); /* in the pair term: a force */
    c.p_back = (real)(2 * p0 / (c.rho * c.rho));
    flow_rates(i, &f->p, &f->g.view, &c);
    assert_true(hypot(f->p.acc[0][i], f->p.acc[1][i]) < RT(1e-12) * scale); /* left out: none */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lattice_moment), TU_FX_TEST(test_visc_quadratic),
        TU_FX_TEST(test_shift_lattice),  TU_FX_TEST(test_shift_back),
        TU_FX_TEST(test_shift_taylor),   cmocka_unit_test(test_shift_surface),
        TU_FX_TEST(test_background_excluded),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
