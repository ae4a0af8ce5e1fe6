/* test_stab.c — Flow:stabilization riemann and delta (src/physics/momentum.h
 * mom_riemann, mom_pdiff; flow.h flow_rates_team), against exact answers:
 *  - the Riemann pair term (Zhang, Hu & Adams 2017 with their limiter):
 *    none for separating pairs, -eta dU^2 / rho below the cap (so quadratic
 *    in the closing speed dU), -c dU / rho above it and against a wall, to
 *    round-off;
 *  - the pressure diffusion leaves a hydrostatic column at rest untouched,
 *    free surface included, where the support is cut: the pair differences
 *    less rho g.x_ji vanish pair by pair (a wrong sign of the hydrostatic part
 *    doubles them: the top row's pressure would grow at ~rho g c_s);
 *  - it conserves sum V_i p_i (equal volumes, no walls, no gravity) to
 *    round-off, and moves a pressure bump down: the bump's rate is negative,
 *    its neighbours' positive;
 *  - it is isotropic: the deviatoric stress rate is the elastic one (zero
 *    at rest);
 *  - riemann's bed damping (Flow:bed_damping, stress.h stress_static_q): a particle
 *    moving through a bed far inside the yield cone is slowed by it (its
 *    acceleration against the motion grows), not at all when the stress is
 *    on the cone (the flowing layer) or where p <= 0; a rigid rotation of the
 *    bed feels none of it (to round-off against the moving particle's). */
#include "physics/flow.h"
#include <string.h>
#include "testutil.h"
#include "flowctx.h"

#define DR 1e-3

static flow_ctx ctx(int stab)
{
    flow_ctx c = tu_flow_ctx(1e5, DR);
    c.stab = stab;
    c.eta_r = 3;
    c.pdiff = flow_pdiff_coef(stab, 1, R(0.1), c.m.K, c.rho, c.cs, c.k.h); /* riemann with its diffusion on */
    return c;
}

static void test_riemann_pair(void **st)
{
    (void)st;
    const real rho = 1500, c = 3, eta = 3;
    real x[3] = {(real)DR, 0, 0}, r2 = (real)(DR * DR);
    real sep[3] = {R(0.01), 0, 0}; /* u_ij . x_ij > 0: separating */
    assert_true(mom_riemann(eta, c, rho, sep, x, r2, 0) == 0);
    real slow[3] = {R(-0.02), R(0.05), 0}; /* closing at dU = 0.02 m/s, a shear part that does not count */
    double want = -3.0 * 0.02 * 0.02 / 1500;
    assert_true(fabs(mom_riemann(eta, c, rho, slow, x, r2, 0) - want) <= RT(1e-12) * fabs(want));
    real fast[3] = {R(-2.0), 0, 0}; /* eta dU = 6 > c: the cap */
    want = -3.0 * 2.0 / 1500;
    assert_true(fabs(mom_riemann(eta, c, rho, fast, x, r2, 0) - want) <= RT(1e-12) * fabs(want));
    want = -3.0 * 0.02 / 1500; /* a wall dummy: unlimited, beta = c at any closing speed */
    assert_true(fabs(mom_riemann(eta, c, rho, slow, x, r2, 1) - want) <= RT(1e-12) * fabs(want));
}

/* Hydrostatic stress -p I, p = rho |g| (H - y), on a block with dummy rows
 * below and at the sides; velocities zero. */
static void hydrostatic(particles_t *p, const flow_ctx *c, int nx, int ny)
{
    tu_block2d(p, nx, ny, DR, 3, 3);
    double H = ny * DR;
    for (size_t i = 0; i < p->n; ++i) {
        double pr = c->rho * 9.81 * (H - p->x[1][i]);
        for (int q = 0; q < 3; ++q) p->sig[q][i] = (real)-pr;
    }
}

/* A hydrostatic column at rest under stabilisation stab: no stress rate anywhere. */
static void hydrostatic_at_rest(tu_fx *f, int stab)
{
    flow_ctx c = ctx(stab);
    hydrostatic(&f->p, &c, 10, 8);
    tu_fx_list(f, c.k.h);
    /* the rate of a pressure change the size of one row's weight per acoustic time h / c_s */
    double scale = c.rho * 9.81 * DR * c.cs / c.k.h;
    for (size_t i = 0; i < f->p.n; ++i) {
        if (f->p.kind[i] != KIND_MATERIAL) continue;
        flow_rates(i, &f->p, &f->g.view, &c);
        for (int q = 0; q < 6; ++q) assert_true(fabs((double)f->p.dsig[q][i]) <= RT(1e-9) * scale);
    }
}

static void test_hydrostatic_riemann(void **st) { hydrostatic_at_rest(*st, STAB_RIEMANN); }
static void test_hydrostatic_delta(void **st) { hydrostatic_at_rest(*st, STAB_DELTA); }

/* A rough pressure field with a bump, no walls, no gravity: sum V dp/dt = 0, the bump's
 * rate negative and its neighbour's positive, the rate isotropic. */
static void conservation_and_sign(tu_fx *f, int stab)
{
    particles_t *p = &f->p;
    flow_ctx c = ctx(stab);
    c.g[1] = 0;
    int n = 9;
    tu_block2d(p, n, n, DR, 0, 0);
    unsigned s = 12345u;
    for (size_t i = 0; i < p->n; ++i) {
        s = s * 1103515245u + 12345u;
        double pr = 1000 + 300 * ((s >> 8) & 1023) / 1023.0;
        for (int q = 0; q < 3; ++q) p->sig[q][i] = (real)-pr;
    }
    size_t b = tu_find(p, (int64_t)((n / 2) * n + n / 2));
    for (int q = 0; q < 3; ++q) p->sig[q][b] -= 5000;
    tu_fx_list(f, c.k.h);
    double sum = 0, mag = 0;
    for (size_t i = 0; i < p->n; ++i) {
        flow_rates(i, p, &f->g.view, &c);
        double dp = -(double)p->dsig[0][i]; /* dp/dt; the normal rates all equal, the shear ones zero */
        assert_true(fabs((double)p->dsig[1][i] - p->dsig[0][i]) <= RT(1e-12) * (fabs(dp) + 1));
        assert_true(fabs((double)p->dsig[3][i]) <= RT(1e-12) * (fabs(dp) + 1));
        sum += (double)p->vol[i] * dp, mag += (double)p->vol[i] * fabs(dp);
    }
    assert_true(fabs(sum) <= RT(1e-12) * mag);
    flow_rates(b, p, &f->g.view, &c);
    assert_true(p->dsig[0][b] > 0); /* dp/dt < 0 at the bump */
    size_t nb = tu_find(p, (int64_t)((n / 2) * n + n / 2 + 1));
    flow_rates(nb, p, &f->g.view, &c);
    assert_true(p->dsig[0][nb] < 0); /* and > 0 beside it */
}

static void test_conservation_riemann(void **st) { conservation_and_sign(*st, STAB_RIEMANN); }
static void test_conservation_delta(void **st) { conservation_and_sign(*st, STAB_DELTA); }

/* A 9 x 9 block, no walls, no gravity, p = 1000 Pa with deviator q of the
 * static cone (sig_xy = q k p); velocities from vel(x, y). Returns the
 * x-acceleration of the centre particle with the bed damping at alpha. */
static double bed_accel(tu_fx *f, double q, double alpha, void (*vel)(double, double, double *))
{
    particles_t *p = &f->p;
    flow_ctx c = ctx(STAB_RIEMANN);
    c.g[1] = 0, c.pdiff = 0;
    c.bed_alpha = (real)alpha, c.bed_k = stress_yield_k(YIELD_DRUCKER_PRAGER, c.m.mu_s);
    int n = 9;
    part_free(p); /* a fresh block each call (tu_block2d allocates) */
    tu_block2d(p, n, n, DR, 0, 0);
    for (size_t i = 0; i < p->n; ++i) {
        for (int k = 0; k < 6; ++k) p->sig[k][i] = 0;
        for (int k = 0; k < 3; ++k) p->sig[k][i] = -1000;
        p->sig[3][i] = (real)(q * c.bed_k * 1000); /* sqrt(J2) = |sig_xy| */
        double u[2];
        vel(p->x[0][i], p->x[1][i], u);
        p->v[0][i] = (real)u[0], p->v[1][i] = (real)u[1], p->v[2][i] = 0;
    }
    tu_fx_list(f, c.k.h);
    size_t b = tu_find(p, (int64_t)((n / 2) * n + n / 2));
    flow_rates(b, p, &f->g.view, &c);
    return (double)p->acc[0][b];
}

static double xc_(void) { return 4.5 * DR; } /* the centre particle's x and y on tu_block2d's lattice */
static void one_moving(double x, double y, double *u)
{
    u[0] = fabs(x - xc_()) < 0.1 * DR && fabs(y - xc_()) < 0.1 * DR ? 0.01 : 0, u[1] = 0;
}
static void rigid(double x, double y, double *u) { u[0] = -0.5 * (y - xc_()), u[1] = 0.5 * (x - xc_()); }

static void test_bed_damping(void **st)
{
    tu_fx *f = *st;
    double a0 = bed_accel(f, 0, 0, one_moving), a1 = bed_accel(f, 0, 1, one_moving);
    double damp = a1 - a0; /* the damping's own acceleration of the moving particle */
    assert_true(damp < 0 && fabs(damp) > 1e-3 * fabs(a0) + 1e-6);
    /* half way to the cone: weight 1 - 0.5 */
    double half = bed_accel(f, 0.5, 1, one_moving) - bed_accel(f, 0.5, 0, one_moving);
    assert_true(fabs(half - 0.5 * damp) <= 1e-9 * fabs(damp));
    /* on the cone (yielded): none */
    assert_true(bed_accel(f, 1, 1, one_moving) == bed_accel(f, 1, 0, one_moving));
    /* a rigid rotation: u_ij . x_ij = 0, none to round-off */
    double r0 = bed_accel(f, 0, 0, rigid), r1 = bed_accel(f, 0, 1, rigid);
    assert_true(fabs(r1 - r0) <= RT(1e-9) * fabs(damp));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_riemann_pair),
        TU_FX_TEST(test_hydrostatic_riemann),
        TU_FX_TEST(test_hydrostatic_delta),
        TU_FX_TEST(test_conservation_riemann),
        TU_FX_TEST(test_conservation_delta),
        TU_FX_TEST(test_bed_damping),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
