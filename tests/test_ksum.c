/* test_ksum.c — the compensated sum behind the conservation check
 * (src/core/ksum.h, src/output/diag.c, mpi/comm.c comm_sum_compensated).
 *
 * 400 000 terms C_i V_i as a drum's particles give them (C in (0, 1), V near
 * 1e-9 m^3), summed in three orders (as built, reversed, shuffled: a list
 * build reorders the particles). Reference: a pairwise sum in long double
 * (64-bit mantissa; its own error about log2(n) * 5e-20 relative). Checked:
 *  - each order's compensated sum lies within one unit round-off (2.2e-16)
 *    of the reference, so the orders agree with one another to 4.4e-16;
 *  - the plain sum of the same terms misses the reference by more than 3e-15
 *    in at least one order (so the data do exercise the round-off the
 *    compensated sum is there to remove: the plain sum's 1e-13-1e-12
 *    "drift" of the R35 drum in docs/gpu.md);
 *  - comm_sum_compensated on one rank returns hi + lo compensated: exact
 *    for a pair whose plain sum would round; and a cancelling sum exactly. */
#include <float.h>
#include <math.h>
#include <mpi.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <cmocka.h>
#include "core/ksum.h"
#include "mpi/comm.h"

enum { N = 400000 };
static double term[N];

static uint64_t lcg(uint64_t *s) { return *s = *s * 6364136223846793005ULL + 1442695040888963407ULL; }
static double unit(uint64_t *s) { return (double)(lcg(s) >> 11) * 0x1.0p-53; }

static long double pairwise(const double *x, size_t n)
{
    if (n <= 8) {
        long double s = 0;
        for (size_t i = 0; i < n; ++i) s += x[i];
        return s;
    }
    return pairwise(x, n / 2) + pairwise(x + n / 2, n - n / 2);
}

static void fill(int order, double *x)
{
    for (size_t i = 0; i < N; ++i) x[i] = term[order == 1 ? N - 1 - i : i];
    if (order == 2) {
        uint64_t s = 99;
        for (size_t i = N - 1; i > 0; --i) {
            size_t j = (size_t)(lcg(&s) >> 33) % (i + 1);
            double t = x[i];
            x[i] = x[j], x[j] = t;
        }
    }
}

static void test_orders(void **st)
{
    (void)st;
    uint64_t s = 7;
    for (size_t i = 0; i < N; ++i) term[i] = unit(&s) * 1e-9 * (1 + 0.01 * unit(&s));
    static double x[N];
    double worst_plain = 0;
    for (int order = 0; order < 3; ++order) {
        fill(order, x);
        long double ref = pairwise(x, N);
        ksum k = {0, 0};
        double plain = 0;
        for (size_t i = 0; i < N; ++i) ksum_add(&k, x[i]), plain += x[i];
        double err = fabs((double)((ksum_value(k) - ref) / ref));
        print_message("order %d: compensated %.3e, plain %.3e relative to the long-double sum\n", order, err,
                      fabs((double)((plain - ref) / ref)));
        assert_true(err <= DBL_EPSILON);
        worst_plain = fmax(worst_plain, fabs((double)((plain - ref) / ref)));
    }
    assert_true(worst_plain > 3e-15);
}

static void test_ranks(void **st)
{
    (void)st;
    /* hi = 1, lo = 2^-60: their exact sum's nearest double, either way round;
     * and a sum whose plain form loses the 1 to the 1e16 beside it */
    assert_true(comm_sum_compensated(1.0, 0x1.0p-60) == 1.0);
    assert_true(comm_sum_compensated(0x1.0p-60, 1.0) == 1.0);
    ksum k = {0, 0};
    ksum_add(&k, 1e16), ksum_add(&k, 1.0), ksum_add(&k, -1e16);
    assert_true(ksum_value(k) == 1.0); /* the plain sum gives 0 */
}

int main(int argc, char **argv)
{
    MPI_Init(&argc, &argv);
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_orders), cmocka_unit_test(test_ranks)};
    int r = cmocka_run_group_tests(tests, NULL, NULL);
    MPI_Finalize();
    return r;
}
