/* test_wall.c — dummy-wall extrapolation (paper eqs. 4.1–4.3) and the
 * Shepard filter (3.12), ahead of the granular solver. References: a
 * hydrostatic column (sigma_yy = -rho g (H - y), linear, so the extrapolated
 * dummy stress must equal the column's stress at the dummy's depth exactly),
 * the no-slip mirror condition (the dummy and material velocities average to
 * the wall's), free slip (tangential velocity passes, normal is mirrored),
 * and the Shepard filter reproducing a constant field. */
#include "physics/kernel.h"
#include "physics/wall.h"
#include <string.h>
#include "testutil.h"

static const double DR = 1e-3, H = 0.02, RHO = 1500, G = 9.81;

/* Gather a dummy at (xd, yd) over a lattice column of material y in (0, H). */
static wall_sums gather(double xd, double yd, const real u[3])
{
    wall_sums ws = {0, {0, 0, 0}, {0, 0, 0, 0, 0, 0}, {0, 0, 0}};
    double h = 1.5 * DR, alpha = kernel_alpha(2, h), V = DR * DR;
    real g[3] = {0, (real)-G, 0};
    for (int i = -10; i <= 10; ++i)
        for (int j = 0; j < (int)(H / DR); ++j) {
            double x = (i + 0.5) * DR, y = (j + 0.5) * DR;
            double r = hypot(xd - x, yd - y);
            real W = kernel_w(r, h, alpha);
            if (W == 0) continue;
            real s[6] = {0, (real)(-RHO * G * (H - y)), 0, 0, 0, 0};
            real rdm[3] = {(real)(xd - x), (real)(yd - y), 0};
            wall_add(&ws, W, V, RHO * V, u, s, g, rdm);
        }
    return ws;
}

static void test_hydrostatic_dummy(void **st)
{
    (void)st;
    real u[3] = {0, 0, 0};
    for (int l = 0; l < 2; ++l) { /* layers whose support reaches material */
        double yd = -(l + 0.5) * DR;
        wall_sums ws = gather(0.3 * DR, yd, u);
        real sd[6];
        wall_stress(&ws, sd);
        double exact = -RHO * G * (H - yd);
        assert_true(ws.w > 0 && fabs(sd[1] - exact) < RT(1e-9) * fabs(exact));
        assert_true(sd[0] == 0 && sd[3] == 0);
    }
    wall_sums far = gather(0, -2.5 * DR, u); /* 3rd layer: 3 dr = 2h away, no material */
    real sd[6];
    wall_stress(&far, sd);
    assert_true(far.w == 0 && sd[1] == 0); /* no division by zero */
}

static void test_velocity(void **st)
{
    (void)st;
    real u[3] = {0.2, -0.05, 0}, uw[3] = {0.1, 0, 0}, n[3] = {0, 1, 0}, ud[3];
    wall_sums ws = gather(0, -0.5 * DR, u);
    wall_velocity(&ws, uw, n, 0, ud); /* no slip: (u_d + u_avg)/2 = u_w */
    for (int a = 0; a < 2; ++a) assert_true(fabs(0.5 * (ud[a] + u[a]) - uw[a]) < RT(1e-12));
    wall_velocity(&ws, uw, n, 1, ud); /* free slip */
    assert_true(fabs(ud[0] - u[0]) < RT(1e-12));           /* tangential passes */
    assert_true(fabs(0.5 * (ud[1] + u[1]) - 0) < RT(1e-12)); /* normal mirrored about u_w.n = 0 */
    /* a piston: the wall moves along its normal at 0.3 m/s and slides at
     * -0.7 m/s; free slip mirrors the normal velocity about the wall's
     * (impermeability: (u_d + u_m).n / 2 = u_w.n) and ignores its sliding */
    real up[3] = {(real)-0.7, (real)0.3, 0};
    wall_velocity(&ws, up, n, 1, ud);
    assert_true(fabs(ud[0] - u[0]) < RT(1e-12));
    assert_true(fabs(0.5 * (ud[1] + u[1]) - 0.3) < RT(1e-12));
    wall_velocity(&ws, up, n, 0, ud); /* no slip follows both components */
    for (int a = 0; a < 2; ++a) assert_true(fabs(0.5 * (ud[a] + u[a]) - up[a]) < RT(1e-12));
}

static void test_shepard_constant(void **st)
{
    (void)st;
    double h = 1.5 * DR, alpha = kernel_alpha(2, h);
    real acc[6] = {0}, ws = 0, s[6] = {-3, -5, -4, 1, 0, 0.5};
    for (int i = -3; i <= 3; ++i)
        for (int j = -1; j <= 3; ++j) /* a cut support, as at a wall */
            shepard_add(acc, &ws, kernel_w(hypot(i * DR, j * DR), h, alpha), s);
    for (int c = 0; c < 6; ++c) assert_true(fabs(acc[c] / ws - s[c]) < RT(1e-12));
}

/* A plane primitive (wall.h) through p with normal n into the material. */
static wall_prim plane(double px, double py, double pz, double nx, double ny, double nz, int slip, int claim)
{
    wall_prim q;
    memset(&q, 0, sizeof q);
    q.shape = WALL_PLANE, q.slip = slip, q.bound = 1, q.claim = claim, q.open_at = -1;
    q.p[0] = (real)px, q.p[1] = (real)py, q.p[2] = (real)pz;
    q.n[0] = (real)nx, q.n[1] = (real)ny, q.n[2] = (real)nz;
    return q;
}

/* Wall ids: a dummy's wall, set once from its reference position
 * (wall_id_at), for every dummy site around a 3D box of 50 x 40 dr with the
 * base claiming first (as setup.c's box), with and without the x walls (a
 * periodic x): below the base (corners included) the base, else the side
 * wall the site lies furthest beyond, x before z on a tie - the rule
 * written out here by coordinates; its normal and slip are that plane's. */
static void test_wall_ids(void **st)
{
    (void)st;
    const double W = 0.05, D = 0.04;
    for (int per = 0; per <= 1; ++per) {
        wall_geom w;
        memset(&w, 0, sizeof w);
        const char *name[5];
        w.prim[w.n] = plane(0, 0, 0, 0, 1, 0, 0, WALL_CLAIM_FIRST), name[w.n++] = "base";
        if (!per) {
            w.prim[w.n] = plane(0, 0, 0, 1, 0, 0, 1, WALL_CLAIM_SIDE), name[w.n++] = "xlo";
            w.prim[w.n] = plane(W, 0, 0, -1, 0, 0, 1, WALL_CLAIM_SIDE), name[w.n++] = "xhi";
        }
        w.prim[w.n] = plane(0, 0, 0, 0, 0, 1, 1, WALL_CLAIM_SIDE), name[w.n++] = "zlo";
        w.prim[w.n] = plane(0, 0, D, 0, 0, -1, 1, WALL_CLAIM_SIDE), name[w.n++] = "zhi";
        int seen[6] = {0};
        for (int i = -3; i < 53; ++i)
            for (int j = -3; j < 8; ++j)
                for (int q = -3; q < 43; ++q) {
                    double xd = (i + 0.5) * 1e-3, yd = (j + 0.5) * 1e-3, zd = (q + 0.5) * 1e-3;
                    real x[3] = {(real)xd, (real)yd, (real)zd};
                    int inside = i >= 0 && i < 50 && j >= 0 && q >= 0 && q < 40;
                    if (inside || (per && j >= 0 && q >= 0 && q < 40)) continue; /* material, or no wall */
                    double ox = per ? -1 : fmax(-xd, xd - W), oz = fmax(-zd, zd - D);
                    const char *want = yd < 0 ? "base" : oz > ox ? (zd < 0 ? "zlo" : "zhi") : (xd < 0 ? "xlo" : "xhi");
                    int id = wall_id_at(&w, x);
                    assert_true(id >= 1 && id <= w.n);
                    assert_string_equal(name[id - 1], want);
                    seen[id]++;
                    real n[3];
                    int slip = wall_normal_of(&w, id, x, n);
                    assert_int_equal(slip, strcmp(want, "base") != 0);
                    for (int a = 0; a < 3; ++a) assert_true(n[a] == w.prim[id - 1].n[a]);
                }
        for (int k = 1; k <= w.n; ++k) assert_true(seen[k] > 0);
        real inside[3] = {(real)0.02, (real)0.01, (real)0.02};
        assert_int_equal(wall_id_at(&w, inside), 0); /* beyond no wall */
    }
    /* a primitive that claims nothing (a gate) takes no site, however far beyond it */
    wall_geom g;
    memset(&g, 0, sizeof g);
    g.prim[g.n++] = plane(0.03, 0, 0, -1, 0, 0, 1, WALL_CLAIM_NONE);
    real far[3] = {(real)0.05, (real)0.01, 0};
    assert_int_equal(wall_id_at(&g, far), 0);
}

/* A cylinder of radius R about (0.05, 0.05) with the material inside (a
 * drum) and the same with the material outside (a post): normals, depths,
 * the claim of a dummy and the "beyond" test change side, the rest not. */
static void test_post(void **st)
{
    (void)st;
    wall_geom w;
    memset(&w, 0, sizeof w);
    w.n = 1;
    wall_prim *q = &w.prim[0];
    q->shape = WALL_CYLINDER, q->bound = 1, q->claim = WALL_CLAIM_SIDE, q->radius = (real)0.01;
    q->p[0] = q->p[1] = (real)0.05;
    const real in[3] = {(real)0.052, (real)0.05, 0}, out[3] = {(real)0.065, (real)0.05, 0};
    const double ind[3] = {0.052, 0.05, 0}, outd[3] = {0.065, 0.05, 0};
    real n[3];
    for (int side = 0; side < 2; ++side) {
        q->outside = side;
        const real *mat = side ? out : in, *dum = side ? in : out; /* a material point and a dummy's */
        const double *matd = side ? outd : ind, *dumd = side ? ind : outd;
        assert_true(wall_prim_depth(q, mat) < 0 && wall_prim_depth(q, dum) > 0);
        assert_true(fabs((double)wall_prim_depth(q, dum) - (side ? 0.008 : 0.005)) < RT(1e-9));
        wall_prim_normal(q, dum, n); /* into the material: towards the axis in a drum, away in a post */
        assert_true(fabs((double)n[0] - (side ? 1.0 : -1.0)) < RT(1e-12) && n[1] == 0);
        assert_true(wall_id_at(&w, dum) == 1 && wall_id_at(&w, mat) == 0);
        assert_true(wall_beyond(&w, dumd, 0, 0.001) && !wall_beyond(&w, matd, 0, 0.001));
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_hydrostatic_dummy), cmocka_unit_test(test_velocity),
                                       cmocka_unit_test(test_shepard_constant), cmocka_unit_test(test_wall_ids),
                                       cmocka_unit_test(test_post)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
