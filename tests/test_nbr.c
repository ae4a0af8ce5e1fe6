/* test_nbr.c — the sorted cell-linked list (paper §3.4) finds exactly the
 * neighbours that an all-pairs brute-force search finds (r < 2h), in 2D and
 * 3D, and sorts the store by cell. Reference: O(N^2) brute force. */
#include <stdlib.h>
#include <string.h>
#include "testutil.h"
#ifdef _OPENMP
#include <omp.h>
#endif

static void check_against_brute_force(int dim, size_t n, double L, double h)
{
    particles_t p = {0};
    part_alloc(&p, dim, n);
    srand(12345u + (unsigned)dim);
    for (size_t k = 0; k < n; ++k)
        tu_put(&p, L * rand() / RAND_MAX, L * rand() / RAND_MAX, dim == 3 ? L * rand() / RAND_MAX : 0,
               k % 5 ? KIND_MATERIAL : KIND_DUMMY, 1.0);
    nbr_grid g = {0};
    nbr_build(&g, &p, (real)(2 * h), NULL);
    double s2 = 4 * h * h;
    size_t total = 0;
    char *mark = calloc(n, 1);
    for (size_t i = 0; i < p.n; ++i) {
        size_t found = 0;
        NBR_BEGIN(&g.view, p.x, i, j)
            real xij[3];
            if (grid_pair(dim, p.x, i, j, xij) < s2) {
                assert_int_equal(mark[j], 0); /* no pair visited twice */
                mark[j] = 1;
                found++;
            }
        NBR_END
        size_t brute = 0;
        for (size_t j = 0; j < p.n; ++j) {
            real xij[3];
            if (grid_pair(dim, p.x, i, j, xij) < s2) {
                assert_int_equal(mark[j], 1); /* every brute-force neighbour was found */
                brute++;
                mark[j] = 0;
            }
        }
        assert_int_equal(found, brute);
        total += found;
    }
    assert_true(total > n); /* the test had real neighbours to find */
    for (size_t c = 0; c < g.ncell; ++c)
        for (size_t i = g.start[c]; i < g.end[c]; ++i) {
            int cc[3];
            grid_cell_coords(&g.view, p.x[0], p.x[1], p.x[2], i, cc);
            assert_int_equal(grid_cell_index(&g.view, cc[0], cc[1], cc[2]), c);
        }
    free(mark);
    nbr_free(&g);
    part_free(&p);
}

static void test_nbr_2d(void **st) { (void)st; check_against_brute_force(2, 3000, 1.0, 0.012); }
static void test_nbr_3d(void **st) { (void)st; check_against_brute_force(3, 4000, 1.0, 0.04); }

/* IDs and fields travel with their particle through the sort. */
static void test_nbr_permutes_fields(void **st)
{
    (void)st;
    particles_t p = {0};
    part_alloc(&p, 2, 500);
    srand(7);
    for (size_t k = 0; k < 500; ++k) {
        tu_put(&p, rand() / (double)RAND_MAX, rand() / (double)RAND_MAX, 0, KIND_MATERIAL, 1.0);
        p.C[k] = (real)(p.x[0][k] + 2 * p.x[1][k]);
    }
    nbr_grid g = {0};
    nbr_build(&g, &p, R(0.05), NULL);
    for (size_t i = 0; i < p.n; ++i) assert_true(fabs(p.C[i] - (p.x[0][i] + 2 * p.x[1][i])) < 1e-12);
    nbr_free(&g);
    part_free(&p);
}

/* The neighbour list (grid_list_fill, the GPU backend's) visits the
 * in-support particles of the cell scan in the same order, so sums come out
 * bit-identical; a particle with more neighbours than the capacity falls
 * back to the cell scan; the lanes of a team (NBR_BEGIN_T) share the visits
 * out. Reference: the cell scan itself. */
static void check_list(int dim, unsigned cap)
{
    const size_t n = 2000;
    particles_t p = {0};
    part_alloc(&p, dim, n);
    srand(99u + (unsigned)dim);
    for (size_t k = 0; k < n; ++k)
        tu_put(&p, rand() / (double)RAND_MAX, rand() / (double)RAND_MAX, dim == 3 ? rand() / (double)RAND_MAX : 0,
               KIND_MATERIAL, 1.0);
    double h = dim == 3 ? 0.05 : 0.015;
    real s2 = (real)(4 * h * h);
    nbr_grid g = {0};
    nbr_build(&g, &p, (real)(2 * h), NULL);
    unsigned *nl = calloc(n * cap, sizeof *nl), *cnt = calloc(n, sizeof *cnt);
    for (size_t i = 0; i < n; ++i) cnt[i] = grid_list_fill(&g.view, p.x, i, s2, nl, n, cap);
    grid_view lv = g.view;
    lv.nl = nl, lv.ncnt = cnt, lv.nl_stride = n, lv.nl_cap = cap;
    size_t *seq = malloc(n * sizeof *seq), over = 0;
    for (size_t i = 0; i < n; ++i) {
        size_t m = 0, k = 0;
        NBR_BEGIN(&g.view, p.x, i, j)
            real xij[3];
            if (grid_pair(dim, p.x, i, j, xij) < s2) seq[m++] = j;
        NBR_END
        assert_int_equal(m, cnt[i]);
        over += cnt[i] > cap;
        NBR_BEGIN(&lv, p.x, i, j)
            real xij[3];
            if (grid_pair(dim, p.x, i, j, xij) < s2) {
                assert_true(k < m);
                assert_int_equal(seq[k++], j);
            }
        NBR_END
        assert_int_equal(k, m);
        /* teams (hd.h): lane l of T meets every T-th entry of each segment
         * from the l-th on; between them the lanes meet each neighbour of
         * the scan exactly once, each lane in the scan's order */
        for (int T = 2; T <= 16; T *= 2) {
            char *seen = calloc(m, 1);
            size_t met = 0;
            for (int l = 0; l < T; ++l) {
                size_t last = 0;
                int any = 0;
                NBR_BEGIN_T(&lv, p.x, i, j, l, T)
                    real xij[3];
                    if (grid_pair(dim, p.x, i, j, xij) >= s2) continue;
                    size_t pos = 0;
                    while (pos < m && seq[pos] != j) ++pos;
                    assert_true(pos < m);
                    assert_int_equal(seen[pos], 0);
                    assert_true(!any || pos > last);
                    seen[pos] = 1, last = pos, any = 1, ++met;
                NBR_END
            }
            assert_int_equal(met, m);
            free(seen);
        }
    }
    if (cap < 8) assert_true(over > 0); /* the fallback was exercised */
    free(seq);
    free(nl);
    free(cnt);
    nbr_free(&g);
    part_free(&p);
}

static void test_list_2d(void **st) { (void)st; check_list(2, grid_list_cap(2, 1.5)); check_list(2, 4); }
static void test_list_3d(void **st) { (void)st; check_list(3, grid_list_cap(3, 1.5)); check_list(3, 4); }

/* The parallel sort (per-thread histograms over index chunks) gives the
 * serial stable counting sort's order on any thread count, owned and ghost
 * ranges apart, and part_permute carries every field along. Reference: a
 * stable insertion of each range's indices by cell, here. Large enough
 * (2e4) for nbr_build and part_permute to run threaded. */
static void test_nbr_parallel_order(void **st)
{
    (void)st;
    const size_t n = 20000, no = 14000;
    particles_t q = {0}; /* the positions in their original order */
    part_alloc(&q, 3, n);
    srand(2024);
    for (size_t k = 0; k < n; ++k)
        tu_put(&q, rand() / (double)RAND_MAX, rand() / (double)RAND_MAX, rand() / (double)RAND_MAX, KIND_MATERIAL, 1.0);
    size_t *key = malloc(n * sizeof *key), *ref = malloc(n * sizeof *ref), *cnt = NULL;
    for (int nt = 1; nt <= 4; ++nt) {
#ifdef _OPENMP
        omp_set_num_threads(nt);
#endif
        particles_t r = {0};
        part_alloc(&r, 3, n);
        for (size_t k = 0; k < n; ++k) {
            tu_put(&r, q.x[0][k], q.x[1][k], q.x[2][k], k % 3 ? KIND_MATERIAL : KIND_DUMMY, 1.0);
            r.sig[5][k] = (real)k;
        }
        r.n = no, r.ng = n - no;
        nbr_grid g = {0};
        nbr_build(&g, &r, R(0.1), NULL);
        cnt = realloc(cnt, (g.ncell + 1) * sizeof *cnt);
        for (size_t k = 0; k < n; ++k) {
            int c[3];
            grid_cell_coords(&g.view, q.x[0], q.x[1], q.x[2], k, c);
            key[k] = grid_cell_index(&g.view, c[0], c[1], c[2]);
        }
        for (int rg = 0; rg < 2; ++rg) { /* serial stable counting sort of each range */
            size_t a = rg ? no : 0, b = rg ? n : no;
            memset(cnt, 0, (g.ncell + 1) * sizeof *cnt);
            for (size_t k = a; k < b; ++k) cnt[key[k] + 1]++;
            cnt[0] = a;
            for (size_t c = 0; c < g.ncell; ++c) cnt[c + 1] += cnt[c];
            for (size_t c = 0; c < g.ncell; ++c) {
                assert_int_equal((rg ? g.gstart : g.start)[c], cnt[c]);
                assert_int_equal((rg ? g.gend : g.end)[c], cnt[c + 1]);
            }
            for (size_t k = a; k < b; ++k) ref[cnt[key[k]]++] = k;
        }
        for (size_t k = 0; k < n; ++k) {
            assert_int_equal(g.perm[k], ref[k]);
            assert_int_equal(r.id[k], (int64_t)ref[k]);
            assert_true(r.sig[5][k] == (real)ref[k] && r.x[1][k] == q.x[1][ref[k]]);
            assert_int_equal(r.kind[k], ref[k] % 3 ? KIND_MATERIAL : KIND_DUMMY);
        }
        nbr_free(&g);
        part_free(&r);
    }
    free(key), free(ref), free(cnt);
    part_free(&q);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_nbr_2d), cmocka_unit_test(test_nbr_3d),
                                       cmocka_unit_test(test_nbr_permutes_fields), cmocka_unit_test(test_list_2d),
                                       cmocka_unit_test(test_list_3d), cmocka_unit_test(test_nbr_parallel_order)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
