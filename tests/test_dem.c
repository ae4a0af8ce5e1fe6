/* test_dem.c — the DEM grains alone (src/dem/dem.c, src/physics/dem.h), no
 * fluid (rho_f = 0: no drag, no buoyancy). References, each analytic:
 *  - a head-on collision of two equal grains leaves them with the relative
 *    speed e times the one they met with, e the restitution that set the
 *    linear spring-dashpot's damping (dem_damping: the damped oscillator's
 *    half period), within 2 % at e = 0.9 and 0.7. The normal force is not
 *    let pull (F_n >= 0), so contact ends before the overlap returns to 0
 *    and the grains part faster than e says where the damping is strong
 *    (Schwager & Poeschel 2007, Phys. Rev. E 75, 051304): at every e the
 *    test also integrates that clamped oscillator, m* x'' = -max(k x + gamma
 *    x', 0), at 1/2000 of the DEM step, and asks for 2 % against it (the DEM
 *    step, t_c / 50 with symplectic Euler, is first order: 0.7 % at e = 0.7,
 *    1.6 % at t_c / 20; at e = 0.5 the clamp puts e 8 % above the nominal);
 *  - a grain resting on a plane wall carries its weight: the wall's normal
 *    force equals m g to 1e-6 (the damped contact settles; 1 s is over 1000
 *    contact times) and the overlap is m g / kn;
 *  - a stack of 4 grains on a wall: the wall carries the stack's weight,
 *    4 m g to 1e-6, through the grain-grain contacts (each grain keeps its
 *    contacts with its neighbours, the lowest one the wall's too);
 *  - a grain sliding on a wall with friction (the tangential spring with its
 *    Coulomb limit, and the spin) ends rolling at 5/7 of its sliding speed
 *    (a uniform sphere: friction's impulse J slows it by J/m and spins it
 *    by J R / I until v = w R), tolerance 2 %; w R then swings about v by
 *    the tangential spring, which has no damping (the DEM paper's model):
 *    within 5 % of v;
 *  - the wall factor Gamma of eq. (16) for the code's kernel (dem_gamma_wall)
 *    against the kernel summed on a fine grid over the side of a plane at
 *    distance y (2D and 3D, cells of h/40): within 1e-4 in 3D (the
 *    quadrature is exact there; measured 2e-5, the grid's error) and 1e-3 in
 *    2D (acos is not a polynomial: 3e-4); 1/2 on the wall, 1 from 2h on. */
#include "dem/dem.h"
#include <string.h>
#include "testutil.h"

/* n grains of 4 mm, 1200 kg/m^3, kn 1000 N/m, restitution e, friction mu,
 * in no fluid, gravity gy. */
static dem_t *grains(size_t n, double e, double mu, double gy)
{
    dem_t *d = dem_alloc(n);
    d->c.d = (real)0.004, d->c.rho = (real)1200, d->c.kn = (real)1000, d->c.kt = (real)(2.0 / 7.0 * 1000);
    d->c.mu = (real)mu;
    dem_derive(d, e);
    d->h = 0.008, d->rho_f = 0, d->nu = 1e-6, d->K = 0, d->t_damp = 0;
    d->g[1] = gy;
    return d;
}

/* A plane wall y = 0 with its normal +y (a base). */
static wall_geom base(void)
{
    wall_geom w;
    memset(&w, 0, sizeof w);
    w.n = 1;
    wall_prim *q = &w.prim[0];
    q->shape = WALL_PLANE, q->n[1] = 1, q->open_at = -1, q->t_lo = -1, q->t_hi = 1;
    return w;
}

/* The restitution of the clamped linear spring-dashpot of grains like d's,
 * integrated finely (velocity Verlet on the relative motion). */
static double clamped_e(const dem_t *d)
{
    const double ms = 0.5 * d->m, k = (double)d->c.kn, g = (double)d->c.gn, dt = d->dt / 2000;
    double x = 0, v = 1; /* overlap and its rate, closing at 1 m/s */
    do {
        double f = -k * x - g * v;
        if (f > 0 && x > 0) f = 0; /* no pull: -F_n = max(k x + g v, 0) */
        v += f / ms * dt;
        x += v * dt;
    } while (x > 0);
    return -v;
}

static void test_restitution(void **st)
{
    (void)st;
    wall_geom none;
    memset(&none, 0, sizeof none);
    const double es[] = {0.9, 0.7, 0.5};
    for (int k = 0; k < 3; ++k) {
        dem_t *d = grains(2, es[k], 0.3, 0);
        d->x[0][0] = 0, d->x[0][1] = 0.0041; /* 0.1 mm apart */
        d->v[0][0] = 0.05, d->v[0][1] = -0.05;
        for (int s = 0; s < 200; ++s) dem_advance(d, &none, s * 1e-4, 1e-4); /* 20 ms: met and parted */
        double e = (d->v[0][1] - d->v[0][0]) / 0.1;
        double ec = clamped_e(d);
        print_message("head-on, e = %.2f: measured %.4f (%.2f %%); the clamped oscillator's %.4f (%.2f %%)\n", es[k], e,
                      100 * (e - es[k]) / es[k], ec, 100 * (e - ec) / ec);
        if (es[k] >= 0.7) assert_true(fabs(e - es[k]) <= 0.02 * es[k]);
        assert_true(fabs(e - ec) <= 0.02 * ec);
        assert_true(fabs(d->v[0][0] + d->v[0][1]) < 1e-12); /* momentum */
        assert_true(d->x[0][1] - d->x[0][0] > 0.004 && d->ncon[0] == 0);
        dem_free(d);
    }
}

static void test_resting(void **st)
{
    (void)st;
    wall_geom w = base();
    dem_t *d = grains(1, 0.5, 0.3, -9.81);
    d->x[0][0] = 0.01, d->x[1][0] = 0.0025; /* 0.5 mm above the wall */
    for (int s = 0; s < 1000; ++s) dem_advance(d, &w, s * 1e-3, 1e-3);
    double mg = d->m * 9.81, load = dem_wall_load(d, &w, 0), delta = 0.002 - d->x[1][0];
    print_message("resting: wall load %.6e N, m g %.6e N; overlap %.4e m, m g / kn %.4e m\n", load, mg, delta,
                  mg / 1000);
    assert_true(fabs(load - mg) <= 1e-6 * mg);
    assert_true(fabs(delta - mg / 1000) <= 1e-6 * mg / 1000);
    assert_true(d->ncon[0] == 1);
    /* moving into the wall the dashpot adds to the load, moving away it takes
     * from it: the contact's force (dem_contact, -gn vn with vn < 0 closing) */
    const double vz = 1e-3, k0 = 1000 * delta;
    d->v[1][0] = -vz;
    assert_true(fabs(dem_wall_load(d, &w, 0) - (k0 + d->c.gn * vz)) <= 1e-9 * k0);
    d->v[1][0] = vz;
    assert_true(fabs(dem_wall_load(d, &w, 0) - (k0 - d->c.gn * vz)) <= 1e-9 * k0);
    dem_free(d);
}

static void test_stack(void **st)
{
    (void)st;
    wall_geom w = base();
    dem_t *d = grains(4, 0.5, 0.3, -9.81);
    for (size_t i = 0; i < 4; ++i) d->x[0][i] = 0.01, d->x[1][i] = 0.0021 + 0.0041 * (double)i; /* apart */
    for (int s = 0; s < 2000; ++s) dem_advance(d, &w, s * 1e-3, 1e-3);
    double mg = d->m * 9.81, load = dem_wall_load(d, &w, 0);
    print_message("stack of 4: wall load %.6e N, 4 m g %.6e N; contacts %d %d %d %d\n", load, 4 * mg, d->ncon[0],
                  d->ncon[1], d->ncon[2], d->ncon[3]);
    assert_true(fabs(load - 4 * mg) <= 1e-6 * 4 * mg);
    assert_true(d->ncon[0] == 2 && d->ncon[1] == 2 && d->ncon[2] == 2 && d->ncon[3] == 1);
    for (size_t i = 0; i < 4; ++i) assert_true(fabs(d->x[0][i] - 0.01) < 1e-12); /* it stays upright */
    dem_free(d);
}

static void test_rolling(void **st)
{
    (void)st;
    wall_geom w = base();
    dem_t *d = grains(1, 0.5, 0.3, -9.81);
    d->x[1][0] = 0.002 - d->m * 9.81 / 1000; /* resting on the wall */
    d->v[0][0] = 0.1;                         /* sliding along x, no spin */
    for (int s = 0; s < 500; ++s) dem_advance(d, &w, s * 1e-3, 1e-3); /* sliding ends after 5 ms */
    double v = d->v[0][0], wr = -d->w[2][0] * 0.002;
    print_message("rolling: v %.5f m/s (5/7 v0 = %.5f), w R %.5f m/s\n", v, 0.1 * 5 / 7, wr);
    assert_true(fabs(v - 0.1 * 5 / 7) <= 0.02 * 0.1 * 5 / 7);
    assert_true(fabs(wr - v) <= 0.05 * v);
    dem_free(d);
}

/* int of W over the points beyond the plane z = y (z > y), on a grid of h/40. */
static double cap_grid(int dim, double y, double h)
{
    const double c = h / 40, alpha = (double)kernel_alpha(dim, (real)h);
    const int n = 80;
    double s = 0;
    for (int i = -n; i < n; ++i)
        for (int j = -n; j < n; ++j)
            for (int k = dim == 3 ? -n : 0; k < (dim == 3 ? n : 1); ++k) {
                double x = (i + 0.5) * c, z = (j + 0.5) * c, w = dim == 3 ? (k + 0.5) * c : 0;
                if (z <= y) continue;
                s += (double)kernel_w((real)sqrt(x * x + z * z + w * w), (real)h, (real)alpha);
            }
    return s * (dim == 3 ? c * c * c : c * c);
}

static void test_gamma(void **st)
{
    (void)st;
    const double h = 0.008;
    for (int dim = 2; dim <= 3; ++dim) {
        assert_true(fabs((double)dem_gamma_wall(dim, 0, (real)h) - 0.5) < 1e-6);
        assert_true((double)dem_gamma_wall(dim, (real)(2 * h), (real)h) == 1.0);
        for (double q = 0.25; q < 2; q += 0.5) {
            double g = (double)dem_gamma_wall(dim, (real)(q * h), (real)h), ref = 1 - cap_grid(dim, q * h, h);
            print_message("Gamma %dD at y = %.2f h: %.5f, grid %.5f\n", dim, q, g, ref);
            assert_true(fabs(g - ref) < (dim == 3 ? 1e-4 : 1e-3));
        }
    }
}

/* DEM:motion rigid: a dumbbell of two grains 3 d apart along x spinning
 * about z at w, no force: after time t it has turned by w t (Rodrigues'
 * turn is exact for a constant w), its grains 3 d apart, each v = w x r. */
static void test_rigid_spin(void **st)
{
    (void)st;
    wall_geom none;
    memset(&none, 0, sizeof none);
    dem_t *d = grains(2, 0.9, 0.3, 0);
    d->motion = DEM_RIGID;
    const double a = 0.006, w = 10.0; /* half the separation, m; rad/s */
    for (int i = 0; i < 2; ++i) {
        double sx = i ? 1.0 : -1.0;
        d->x[0][i] = 0.05 + sx * a, d->x[1][i] = 0.05, d->w[2][i] = w;
        d->v[1][i] = w * sx * a; /* w z x (sx a) x = w sx a y */
    }
    for (int s = 0; s < 100; ++s) dem_advance(d, &none, s * 1e-3, 1e-3);
    double rx = d->x[0][1] - d->x[0][0], ry = d->x[1][1] - d->x[1][0];
    double ang = atan2(ry, rx), sep = sqrt(rx * rx + ry * ry), turn = fmod(w * 0.1, 2 * M_PI);
    print_message("rigid spin: turned %.9f rad (w t %.9f), separation %.9e m (%.9e)\n", ang, turn, sep, 2 * a);
    assert_true(fabs(ang - turn) < 1e-9);
    assert_true(fabs(sep - 2 * a) < 1e-12);
    assert_true(fabs(d->x[0][0] + d->x[0][1] - 0.1) < 1e-12); /* the centre stays */
    dem_free(d);
}

/* DEM:motion rigid: a tilted dumbbell falls at v0 onto the wall y = 0
 * without friction; grain 0 alone strikes it. The wall's impulse J (along
 * y) changes the momentum by J and the angular momentum about the centre
 * by r_0 x J: dL_z = r_0x dP_y, r_0x the contact's arm (which turns a
 * little during the contact: 1 %). L_z = I_zz w_z, I_zz = 2 m a^2 + 2 I_grain
 * for a dumbbell along x. */
static void test_rigid_impact(void **st)
{
    (void)st;
    wall_geom w = base();
    dem_t *d = grains(2, 0.9, 0.0, 0);
    d->motion = DEM_RIGID;
    const double a = 0.006, tilt = 0.2, v0 = -0.5;
    for (int i = 0; i < 2; ++i) {
        double sx = i ? 1.0 : -1.0;
        d->x[0][i] = 0.05 + sx * a * cos(tilt), d->x[1][i] = 0.0025 + a * sin(tilt) + sx * a * sin(tilt);
        d->v[1][i] = v0;
    }
    const double r0x = d->x[0][0] - 0.5 * (d->x[0][0] + d->x[0][1]);
    /* 4 ms: grain 0 struck and left; the spin it took brings grain 1 down to the wall 2 ms later */
    for (int s = 0; s < 40; ++s) dem_advance(d, &w, s * 1e-4, 1e-4);
    double dP = 2 * d->m * (0.5 * (d->v[1][0] + d->v[1][1]) - v0);
    double Izz = 2 * d->m * a * a + 2 * d->I, dL = Izz * d->w[2][0];
    print_message("rigid impact: dP_y %.6e N s, dL_z %.6e N m s, r_0x dP_y %.6e (arm %.4e m), grain 1 %.4e m "
                  "above the wall\n", dP, dL, r0x * dP, r0x, d->x[1][1]);
    assert_true(dP > 0 && d->x[1][0] > 0.002 && d->v[1][0] > 0 && d->x[1][1] > 0.002); /* struck, and left the wall */
    assert_true(fabs(dL - r0x * dP) <= 0.02 * fabs(r0x * dP));
    dem_free(d);
}

/* A periodic axis (x, period P): two grains on either side of the seam,
 * their centres 0.9 d apart through it, meet there: they push each other
 * apart along x (equal and opposite), and stay inside [0, P). */
static void test_periodic_contact(void **st)
{
    (void)st;
    wall_geom w;
    memset(&w, 0, sizeof w);
    w.periodic = 1, w.period[0] = (real)0.05;
    dem_t *d = grains(2, 0.9, 0.3, 0);
    d->x[0][0] = 0.0018, d->x[0][1] = 0.05 - 0.0018, d->x[1][0] = d->x[1][1] = 0.01;
    dem_advance(d, &w, 0, 1e-3);
    print_message("periodic contact: v_x %.6e, %.6e m/s; x %.6e, %.6e m\n", d->v[0][0], d->v[0][1], d->x[0][0],
                  d->x[0][1]);
    assert_true(d->v[0][0] > 1e-3 && fabs(d->v[0][0] + d->v[0][1]) < 1e-12);
    for (int i = 0; i < 2; ++i) assert_true(d->x[0][i] >= 0 && d->x[0][i] < 0.05);
    dem_free(d);
}

/* A rank that holds no grain (split among many ranks) advances nothing:
 * its grid over nothing is one cell (dem_grid_fit's empty box), not the
 * cell count of an infinite extent. */
static void test_no_grains(void **st)
{
    (void)st;
    wall_geom w = base();
    dem_t *d = grains(0, 0.9, 0.3, -9.81);
    const double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    dem_grid_fit(d, lo, hi);
    for (int a = 0; a < 3; ++a) assert_int_equal(d->nc[a], 1);
    dem_advance(d, &w, 0, 1e-3);
    assert_true(d->steps > 0);
    dem_free(d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_restitution), cmocka_unit_test(test_resting),
                                       cmocka_unit_test(test_stack),
                                       cmocka_unit_test(test_rolling), cmocka_unit_test(test_gamma),
                                       cmocka_unit_test(test_rigid_spin), cmocka_unit_test(test_rigid_impact),
                                       cmocka_unit_test(test_periodic_contact), cmocka_unit_test(test_no_grains)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
