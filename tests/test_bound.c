/* test_bound.c — HCSR boundary-particle search and normals (paper §4.2.2) on
 * known shapes: a free square (the outer ring is the free surface, normals
 * are the inward axis directions), a free disc (surface on the rim, normals
 * radial), and a box with dummy walls at the base and sides (wall classes,
 * wall normals from the colour function 4.10). Reference: the geometry. */
#include <stdlib.h>
#include "cpu/bound.h"
#include "testutil.h"

static const double DR = 1.0, HF = 1.5;

/* The cell list of the fixture's particles and their classes (h = HF dr). */
static void classify(tu_fx *f)
{
    sph_ctx k = sph_make(2, (real)(HF * DR), (real)DR);
    tu_fx_list(f, k.h);
    bound_classify(&f->w, &f->p, &f->g, &k);
}

/* An N x N block with nl dummy layers at the base and the sides, classified. */
static void classify_block(tu_fx *f, int N, int nl)
{
    tu_block2d(&f->p, N, N, DR, nl, nl);
    classify(f);
}

static void test_square(void **st)
{
    tu_fx *f = *st;
    int N = 20;
    classify_block(f, N, 0);
    for (size_t i = 0; i < f->p.n; ++i) {
        int ci = (int)floor(f->p.x[0][i] / DR), cj = (int)floor(f->p.x[1][i] / DR);
        int edge = ci == 0 || cj == 0 || ci == N - 1 || cj == N - 1;
        int depth = ci < cj ? ci : cj;
        depth = depth < N - 1 - ci ? depth : N - 1 - ci;
        depth = depth < N - 1 - cj ? depth : N - 1 - cj;
        if (edge) assert_int_equal(f->p.bclass[i], BC_FREE_SURFACE);
        else if (depth * DR < 2 * HF * DR - DR) assert_int_equal(f->p.bclass[i], BC_FREE_VICINITY);
        else assert_int_equal(f->p.bclass[i], BC_INTERIOR);
        if (edge && ci == 0 && cj > 2 && cj < N - 3) { /* left edge: normal +x */
            assert_true(fabs(f->p.nrm[0][i] - 1) < RT(1e-9) && fabs(f->p.nrm[1][i]) < RT(1e-9));
        }
        if (edge && ci == N - 1 && cj == N - 1) { /* corner: along the diagonal, inward */
            assert_true(fabs(f->p.nrm[0][i] + 0.70710678118654752) < RT(1e-9) && fabs(f->p.nrm[1][i] + 0.70710678118654752) < RT(1e-9));
        }
        if (f->p.bclass[i] == BC_FREE_VICINITY && ci == 1 && cj > 3 && cj < N - 4) {
            assert_true(f->p.nrm[0][i] > 0.99); /* vicinity normal (4.17) points inward too */
        }
    }
}

static void test_disc(void **st)
{
    tu_fx *f = *st;
    double Rd = 15.0;
    part_alloc(&f->p, 2, 1200);
    for (int i = -16; i <= 16; ++i)
        for (int j = -16; j <= 16; ++j)
            if (hypot(i, j) <= Rd) tu_put(&f->p, i * DR, j * DR, 0, KIND_MATERIAL, DR * DR);
    classify(f);
    int hit[36] = {0};
    for (size_t i = 0; i < f->p.n; ++i) {
        double r = hypot(f->p.x[0][i], f->p.x[1][i]);
        if (r < Rd - 2 * HF * DR) assert_int_equal(f->p.bclass[i], BC_INTERIOR);
        if (f->p.bclass[i] != BC_FREE_SURFACE) continue;
        assert_true(r > Rd - 1.5 * DR); /* the surface is on the rim */
        double cosang = -(f->p.nrm[0][i] * f->p.x[0][i] + f->p.nrm[1][i] * f->p.x[1][i]) / r;
        assert_true(cosang > cos(25.0 * M_PI / 180)); /* normal points to the centre */
        int b = (int)((atan2(f->p.x[1][i], f->p.x[0][i]) + M_PI) / (2 * M_PI) * 36) % 36;
        hit[b] = 1;
    }
    for (int b = 0; b < 36; ++b) assert_int_equal(hit[b], 1); /* the whole rim is found */
}

static void test_walls(void **st)
{
    tu_fx *f = *st;
    int N = 16;
    classify_block(f, N, 3);
    for (size_t i = 0; i < f->p.n; ++i) {
        if (f->p.kind[i] == KIND_DUMMY) {
            assert_int_equal(f->p.bclass[i], BC_DUMMY);
            continue;
        }
        int ci = (int)floor(f->p.x[0][i] / DR), cj = (int)floor(f->p.x[1][i] / DR);
        int near_wall = ci < 2 || ci > N - 3 || cj < 2; /* a dummy closer than 2h = 3 dr */
        if (cj == N - 1) { /* free surface up to the walls, normal straight down */
            assert_int_equal(f->p.bclass[i], BC_FREE_SURFACE);
            assert_true(f->p.nrm[1][i] < -0.9);
            if (ci >= 3 && ci <= N - 4) assert_true(fabs(f->p.nrm[1][i] + 1) < RT(1e-9));
        }
        else if (cj == 0 && ci > 3 && ci < N - 4) {
            assert_int_equal(f->p.bclass[i], BC_WALL_SURFACE);
            assert_true(fabs(f->p.nrm[1][i] - 1) < RT(1e-9) && fabs(f->p.nrm[0][i]) < RT(1e-9));
        } else if (cj < N - 3 && near_wall) {
            assert_true(f->p.bclass[i] == BC_WALL_SURFACE || f->p.bclass[i] == BC_WALL_VICINITY);
            if (cj > 3 && ci == 0) assert_true(fabs(f->p.nrm[0][i] - 1) < RT(1e-9)); /* left wall: +x */
        } else if (cj < N - 3) {
            assert_int_equal(f->p.bclass[i], BC_INTERIOR);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {TU_FX_TEST(test_square),
                                       TU_FX_TEST(test_disc),
                                       TU_FX_TEST(test_walls)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
