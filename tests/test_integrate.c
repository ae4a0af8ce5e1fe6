/* test_integrate.c — integrate_step (src/sim/integrate.c), the predictor–
 * corrector (3.17–3.18), through a backend whose hooks integrate one ODE,
 * y' = cos(t) y, exact y = exp(sin t):
 *  - the observed order of accuracy: halving dt from 0.02 divides the error at t = 2
 *    by 4 (an explicit midpoint rule is second order; log2 of the ratio
 *    within [1.9, 2.1]), and the error at dt = 0.01 is the midpoint rule's
 *    own (reference: a closed-form step of the same rule on the same ODE,
 *    to round-off); a rate evaluated at t + dt instead of t + dt/2, or a
 *    corrector from the predicted state, is first order;
 *  - the stages: prepare at t + dt/2 without classification, then at t + dt
 *    with it; t, step and dt advanced;
 *  - the Shepard filter every Flow:shepard_every steps with computed flow,
 *    never without it or with shepard_every = 0;
 *  - the settling damping on while t < Flow:damping_until, off after;
 *  - the store's stage update (step_save, step_advance as the CPU backend
 *    calls them): both stages start from the start-of-step C, so after the
 *    predictor (dt/2) and the corrector (dt) C = C_n + dt r, not
 *    C_n + 3/2 dt r;
 *  - integrate_dt (mock bounds): the diffusion step is stable: dt times the
 *    Gershgorin bound of the SPH Laplacian, 4 D sum_j |F_ij| V_j summed here
 *    over a lattice at h = 1.5 dr, stays within the midpoint rule's
 *    stability limit 2; the flow step is (3.19), chi min(sqrt(h/a), h/c_s);
 *  - the shear box's prescribed kinematics (kin_state) are consistent: the
 *    velocity is the time derivative of the position (central differences
 *    over the cycle) and the shear rate is |du_x/dy|; the base stays put. */
#include <mpi.h>
#include <string.h>
#include "sim/sim.h"
#include "testutil.h"

/* The mock backend's state: one ODE variable and its stages. */
static struct {
    double y, y_n, r, t_stage;
    int filters, last_classify;
    double stage_t[2];
    int nprep;
} M;

static void m_prepare(sim_t *s, double t, int classify)
{
    (void)s;
    M.t_stage = t;
    M.last_classify = classify;
    if (M.nprep < 2) M.stage_t[M.nprep] = t;
    M.nprep++;
}
static void m_rates(sim_t *s) { (void)s, M.r = cos(M.t_stage) * M.y; }
static void m_advance(sim_t *s, double a, double w) { (void)s, (void)w, M.y = M.y_n + a * M.r; }
static void m_save(sim_t *s) { (void)s, M.y_n = M.y; }
static void m_filter(sim_t *s) { (void)s, M.filters++; }

static double B[STEP_NBOUNDS]; /* what the mock's bounds hook reports */
static void m_bounds(sim_t *s, double out[STEP_NBOUNDS])
{
    (void)s;
    for (int k = 0; k < STEP_NBOUNDS; ++k) out[k] = B[k];
}

static const struct backend MOCK = {.name = "mock",    .prepare = m_prepare, .rates = m_rates,
                                    .advance = m_advance, .save_start = m_save, .filter = m_filter,
                                    .bounds = m_bounds,   .ghost_depth = 1};

static void start(sim_t *s, struct scene *sc)
{
    memset(s, 0, sizeof *s);
    memset(sc, 0, sizeof *sc);
    memset(&M, 0, sizeof M);
    s->sc = sc;
    s->be = &MOCK;
    M.y = 1;
    MOCK.prepare(s, 0, 1);
}

/* |y(2) - exp(sin 2)| after 2 / dt steps. */
static double error_at_2(double dt)
{
    sim_t s;
    struct scene sc;
    start(&s, &sc);
    int n = (int)(2 / dt + 0.5);
    for (int k = 0; k < n; ++k) integrate_step(&s, dt);
    assert_true(fabs(s.t - 2) < 1e-12 && s.step == n && s.dt == dt);
    return fabs(M.y - exp(sin(2.0)));
}

static void test_order(void **st)
{
    (void)st;
    double e1 = error_at_2(0.02), e2 = error_at_2(0.01), p = log2(e1 / e2);
    print_message("midpoint errors %.3e, %.3e: order %.3f\n", e1, e2, p);
    assert_true(p > 1.9 && p < 2.1);
    double y = 1, t = 0, dt = 0.01; /* the explicit midpoint rule by hand */
    for (int k = 0; k < 200; ++k, t += dt) y += dt * cos(t + dt / 2) * (y + dt / 2 * cos(t) * y);
    assert_true(fabs(e2 - fabs(y - exp(sin(2.0)))) < 1e-12);
}

static void test_stages(void **st)
{
    (void)st;
    sim_t s;
    struct scene sc;
    start(&s, &sc);
    M.nprep = 0;
    integrate_step(&s, 0.25);
    assert_int_equal(M.nprep, 2);
    assert_true(M.stage_t[0] == 0.125 && M.stage_t[1] == 0.25);
    assert_int_equal(M.last_classify, 1);
    assert_true(s.t == 0.25 && s.step == 1 && s.dt == 0.25);
}

static void test_filter_and_damping(void **st)
{
    (void)st;
    sim_t s;
    struct scene sc;
    start(&s, &sc);
    sc.flow.shepard_every = 3, sc.flow.damping = 40, sc.flow.damping_until = 0.35;
    s.flow_on = 1;
    for (int k = 1; k <= 10; ++k) {
        integrate_step(&s, 0.1);
        assert_int_equal(M.filters, k / 3);
        /* the damping of the step that started at t = (k - 1) 0.1 */
        assert_true(s.flow.damping == ((k - 1) * 0.1 < 0.35 ? 40 : 0));
    }
    s.flow_on = 0; /* prescribed kinematics: no stress to filter */
    for (int k = 0; k < 6; ++k) integrate_step(&s, 0.1);
    assert_int_equal(M.filters, 3);
    s.flow_on = 1, sc.flow.shepard_every = 0;
    for (int k = 0; k < 6; ++k) integrate_step(&s, 0.1);
    assert_int_equal(M.filters, 3);
}

static void test_stage_update(void **st)
{
    (void)st;
    particles_t p;
    flow_ctx c;
    memset(&c, 0, sizeof c);
    part_alloc(&p, 2, 1);
    p.n = 1, p.kind[0] = KIND_MATERIAL, p.C[0] = (real)0.25, p.dCdt[0] = 2;
    step_save(0, &p, 0, 1);
    step_advance(0, &p, (real)0.05, &c, 0, 1, R(0.0)); /* predictor, dt = 0.1 */
    assert_true(fabs(p.C[0] - 0.35) < RT(1e-14));
    p.dCdt[0] = 3; /* the midpoint rate */
    step_advance(0, &p, (real)0.1, &c, 0, 1, R(0.0));
    assert_true(fabs(p.C[0] - 0.55) < RT(1e-14));
    part_free(&p);
}

static void test_dt_bounds(void **st)
{
    (void)st;
    sim_t s;
    struct scene sc;
    start(&s, &sc);
    const double dr = 1e-3, h = 1.5 * dr, D = 1e-6;
    sc.run.dt_max = 1e9, sc.run.cfl_diffusion = 0.1, sc.run.cfl_segregation = 0.2, sc.run.cfl_kinematic = 1;
    sc.run.cfl_flow = 0.1;
    s.seg.k = sph_make(2, (real)h, (real)dr);
    memset(B, 0, sizeof B);
    B[STEP_D] = D;
    double dt = integrate_dt(&s), gersh = 0;
    for (int a = -3; a <= 3; ++a)
        for (int b = -3; b <= 3; ++b) {
            double r = hypot(a, b) * dr;
            if (r > 0 && r < 2 * h) gersh += 4 * D * fabs(kernel_f((real)r, s.seg.k.h, s.seg.k.alpha)) * dr * dr;
        }
    print_message("diffusion: dt %.3e s, Gershgorin radius x dt = %.3f (stable <= 2)\n", dt, gersh * dt);
    assert_true(gersh * dt <= 2 && gersh * dt > 0.5); /* stable, and not needlessly short */
    memset(B, 0, sizeof B);
    s.flow_on = 1, s.flow.cs = 10, B[STEP_ACC] = 50;
    dt = integrate_dt(&s);
    assert_true(fabs(dt - 0.1 * fmin(sqrt(h / 50), h / 10)) < RT(1e-12) * dt);
}

static void test_kinematics(void **st)
{
    (void)st;
    kin_params kp = {1, 0.57735, 2 * M_PI / 13.0};
    const double e = 1e-3, y = 0.05, T = 13.0, tol = sizeof(real) == sizeof(float) ? 2e-3 : 1e-6;
    real X0[3] = {(real)0.01, (real)y, 0}, X1[3] = {(real)0.01, (real)(2 * y), 0}, Xb[3] = {0, (real)-0.001, 0};
    for (int k = 0; k < 16; ++k) {
        double t = k * T / 16 + 0.3;
        real xp[3], xm[3], x[3], u[3], u1[3], up[3], gd, g1;
        kin_state(&kp, X0, t + e, xp, up, &gd);
        kin_state(&kp, X0, t - e, xm, up, &gd);
        kin_state(&kp, X0, t, x, u, &gd);
        kin_state(&kp, X1, t, x, u1, &g1);
        double dxdt = (xp[0] - xm[0]) / (2 * e), amp = kp.gamma0 * kp.omega * y;
        assert_true(fabs(u[0] - dxdt) < tol * amp && u[1] == 0); /* truncation (omega e)^2 / 6 = 4e-8 */
        assert_true(fabs(gd - fabs((u1[0] - u[0]) / y)) < RT(1e-9) * amp / y && gd == g1);
        kin_state(&kp, Xb, t, x, u, &gd);
        assert_true(x[0] == Xb[0] && u[0] == 0);
    }
}

int main(int argc, char **argv)
{
    MPI_Init(&argc, &argv);
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_order), cmocka_unit_test(test_stages),
                                       cmocka_unit_test(test_filter_and_damping), cmocka_unit_test(test_stage_update),
                                       cmocka_unit_test(test_dt_bounds), cmocka_unit_test(test_kinematics)};
    int r = cmocka_run_group_tests(tests, NULL, NULL);
    MPI_Finalize();
    return r;
}
