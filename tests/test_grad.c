/* test_grad.c — the C1-consistent gradient of paper App. E (E2, E9–E14) is
 * exact for linear fields at boundary particles (corners, edges, walls),
 * where the standard SPH difference gradient (3.13) is not. Reference: the
 * exact gradient of the linear field. */
#include "cpu/bound.h"
#include "physics/seg_kern.h"
#include "testutil.h"

static void grads_at(const particles_t *p, const grid_view *g, const sph_ctx *k, size_t i,
                     const real ghat[3], double c1[2], double std_[2])
{
    seg_c1 s = {{0}, {0}};
    double sg[2] = {0, 0};
    NBR_BEGIN(g, p->x, i, j)
        if (p->kind[j] != KIND_MATERIAL) continue;
        real xij[3];
        real r2 = grid_pair(k->dim, p->x, i, j, xij);
        if (r2 >= k->support2) continue;
        real r = (real)sqrt((double)r2);
        real f = kernel_f(r, k->h, k->alpha) * p->vol[j];
        real grad[3] = {f * xij[0], f * xij[1], f * xij[2]};
        seg_c1_add(&s, k->dim, kernel_w(r, k->h, k->alpha) * p->vol[j], grad, xij, p->C[j], p->gdot[j]);
        real gg = grad[0] * ghat[0] + grad[1] * ghat[1];
        sg[0] += (p->C[j] - p->C[i]) * gg;
        sg[1] += (p->gdot[j] - p->gdot[i]) * gg;
    NBR_END
    real out[2];
    assert_int_equal(seg_c1_solve(&s, k->dim, ghat, out), 0);
    c1[0] = out[0], c1[1] = out[1], std_[0] = sg[0], std_[1] = sg[1];
}

static void test_c1_linear(void **st)
{
    (void)st;
    int N = 14;
    double dr = 0.01;
    particles_t p = {0};
    tu_block2d(&p, N, N, dr, 3, 0); /* base wall, free sides and top */
    for (size_t i = 0; i < p.n; ++i) { /* two linear fields (C and a second one) */
        p.C[i] = (real)(0.3 + 2.0 * p.x[0][i] - 5.0 * p.x[1][i]);
        p.gdot[i] = (real)(-1.0 + 7.0 * p.x[0][i] + 3.0 * p.x[1][i]);
    }
    nbr_grid g = {0};
    bound_work w = {0};
    sph_ctx k = sph_make(2, (real)(1.5 * dr), (real)dr);
    nbr_build(&g, &p, R(2.0) * k.h, NULL);
    bound_classify(&w, &p, &g, &k);
    const real ghat[3] = {R(0.6), R(-0.8), 0}; /* a tilted gravity direction */
    double exact[2] = {0.6 * 2.0 + 0.8 * 5.0, 0.6 * 7.0 - 0.8 * 3.0};
    int nb = 0;
    double worst_std = 0;
    for (size_t i = 0; i < p.n; ++i) {
        if (p.kind[i] != KIND_MATERIAL || p.bclass[i] == BC_INTERIOR) continue;
        double c1[2], sd[2];
        grads_at(&p, &g.view, &k, i, ghat, c1, sd);
        for (int f = 0; f < 2; ++f) {
            assert_true(fabs(c1[f] - exact[f]) < (sizeof(real) == sizeof(float) ? 2e-3 : 1e-9) * fabs(exact[f])); /* single: cancellation in the solve */
            worst_std = fmax(worst_std, fabs(sd[f] - exact[f]) / fabs(exact[f]));
        }
        nb++;
    }
    assert_true(nb > 4 * N);         /* many boundary particles were checked */
    assert_true(worst_std > 0.2);    /* and the standard gradient fails there */
    bound_free(&w);
    nbr_free(&g);
    part_free(&p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_c1_linear)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
