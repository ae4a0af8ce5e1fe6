/* test_nbr.c — the sorted cell-linked list (paper §3.4) finds exactly the
 * neighbours that an all-pairs brute-force search finds (r < 2h), in 2D and
 * 3D, and sorts the store by cell. Reference: O(N^2) brute force. */
#include <stdlib.h>
#include <string.h>
#include "testutil.h"
#include "cpu/nlist.h"
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
/* The pairs within sqrt(s2) of particle i that view ref meets, into seq, and
 * that view v meets the same ones in the same order; returns their count. */
static size_t same_pairs(const grid_view *ref, const grid_view *v, real *const *x, int dim, size_t i, real s2,
                         size_t *seq)
{
    size_t m = 0, k = 0;
    NBR_BEGIN(ref, x, i, j)
        real xij[3];
        if (grid_pair(dim, x, i, j, xij) < s2) seq[m++] = j;
    NBR_END
    NBR_BEGIN(v, x, i, j)
        real xij[3];
        if (grid_pair(dim, x, i, j, xij) < s2) {
            assert_true(k < m);
            assert_int_equal(seq[k++], j);
        }
    NBR_END
    assert_int_equal(k, m);
    return m;
}

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
        const size_t m = same_pairs(&g.view, &lv, p.x, dim, i, s2, seq);
        assert_int_equal(m, cnt[i]);
        over += cnt[i] > cap;
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

/* The canonical order (DESIGN.md "Parallel model": results do not depend on
 * the rank count; issue 55): the same cloud held as one rank holds it and as
 * a rank of two holds it gives every particle its neighbours in the same
 * order. The cloud (IDs shuffled) is periodic along x over [0, 0.8): the
 * points beyond are images. Store A, one rank: the points inside the period
 * owned, the images ghosts. Store B, a cut along y on a lattice line: the
 * points inside the period below it owned, the rest ghosts (the other
 * rank's and the images). Each store in another shuffled order. The cells
 * at the period's end hold owned points and images in both. Reference: the
 * neighbour IDs of each particle met by the cell scan of store A. Then the
 * GPU's list build over a cut off the lattice (store C). */
static void nbr_fill_shuffled(particles_t *q, const double (*pt)[2], const int64_t *id, const int *own,
                              size_t n, unsigned seed)
{
    size_t *ord = malloc(n * sizeof *ord), no = 0;
    for (size_t k = 0; k < n; ++k) ord[k] = k;
    srand(seed);
    for (size_t k = n - 1; k > 0; --k) { /* Fisher-Yates */
        size_t m = (size_t)rand() % (k + 1), t = ord[k];
        ord[k] = ord[m], ord[m] = t;
    }
    for (int pass = 0; pass < 2; ++pass) /* owned first, then ghosts */
        for (size_t k = 0; k < n; ++k)
            if (own[ord[k]] == !pass) {
                tu_put(q, pt[ord[k]][0], pt[ord[k]][1], 0, KIND_MATERIAL, 1.0);
                q->id[q->n - 1] = id[ord[k]];
                no += !pass;
            }
    q->ng = q->n - no;
    q->n = no;
    free(ord);
}

static void test_nbr_canonical_order(void **st)
{
    (void)st;
    const size_t n = 4000;
    const real plo[3] = {0, 0, 0}, plen[3] = {R(0.8), 0, 0};
    double (*pt)[2] = malloc(n * sizeof *pt);
    int64_t *id = malloc(n * sizeof *id);
    int *ownA = malloc(n * sizeof *ownA), *ownB = malloc(n * sizeof *ownB);
    srand(55);
    for (size_t k = 0; k < n; ++k) {
        pt[k][0] = rand() / (double)RAND_MAX, pt[k][1] = rand() / (double)RAND_MAX;
        id[k] = (int64_t)((k * 7919u) % n); /* a permutation: 7919 is prime, not a factor of n */
    }
    const real support = R(0.05);
    particles_t A = {0}, B = {0};
    part_alloc(&A, 2, n), part_alloc(&B, 2, n);
    for (size_t k = 0; k < n; ++k) ownA[k] = pt[k][0] < 0.8;
    nbr_fill_shuffled(&A, (const double(*)[2])pt, id, ownA, n, 1);
    nbr_grid ga = {0}, gb = {0};
    nbr_set_period(&ga, 1, plo, plen);
    nbr_build(&ga, &A, support, NULL);
    const real ycut = ga.view.lo[1] + R(9.0) * support; /* a lattice line */
    for (size_t k = 0; k < n; ++k) ownB[k] = pt[k][0] < 0.8 && pt[k][1] < ycut;
    nbr_fill_shuffled(&B, (const double(*)[2])pt, id, ownB, n, 2);
    nbr_set_period(&gb, 1, plo, plen);
    nbr_build(&gb, &B, support, NULL);
    assert_true(A.ng > 0 && B.ng > A.ng && B.n > 0);
    size_t mixed = 0; /* cells of A with owned points and images */
    for (size_t c = 0; c < ga.ncell; ++c) mixed += ga.end[c] > ga.start[c] && ga.gend[c] > ga.gstart[c];
    assert_true(mixed > 0);
    /* where each ID sits in store B */
    size_t *atB = malloc(n * sizeof *atB);
    for (size_t k = 0; k < n; ++k) atB[B.id[k]] = k;
    int64_t *seq = malloc(n * sizeof *seq);
    size_t checked = 0;
    for (size_t i = 0; i < A.n + A.ng; ++i) {
        size_t m = 0, k = 0;
        NBR_BEGIN(&ga.view, A.x, i, j)
            seq[m++] = A.id[j];
        NBR_END
        const size_t ib = atB[A.id[i]]; /* B's grid is A's: the same box */
        NBR_BEGIN(&gb.view, B.x, ib, j)
            assert_true(k < m);
            assert_true(B.id[j] == seq[k]);
            ++k;
        NBR_END
        assert_int_equal(k, m);
        ++checked;
    }
    assert_int_equal(checked, n);
    /* The GPU's lists (grid_list_fill_ranked) over a cut that is no lattice
     * line (its cells of 2h + skin are not the slabs'): cells hold owned
     * particles and the other rank's ghosts; merged by rank (images last,
     * then ID), a particle's list is store A's in-support cell scan. */
    particles_t C = {0};
    part_alloc(&C, 2, n);
    int *ownC = malloc(n * sizeof *ownC);
    for (size_t k = 0; k < n; ++k) ownC[k] = pt[k][0] < 0.8 && pt[k][1] < ycut + R(0.3) * support;
    nbr_fill_shuffled(&C, (const double(*)[2])pt, id, ownC, n, 3);
    nbr_grid gc = {0};
    nbr_set_period(&gc, 1, plo, plen);
    nbr_build(&gc, &C, support, NULL);
    size_t cut = 0; /* cells of C with owned particles and other ghosts than images */
    for (size_t c = 0; c < gc.ncell; ++c)
        for (size_t k = gc.gstart[c]; k < gc.gend[c] && gc.end[c] > gc.start[c]; ++k) cut += C.x[0][k] < R(0.8);
    assert_true(cut > 0);
    unsigned *rk = malloc(n * sizeof *rk), *nl = malloc(n * 64 * sizeof *nl), *cnt = malloc(n * sizeof *cnt);
    for (size_t k = 0; k < n; ++k) rk[k] = (unsigned)C.id[k] | (unsigned)(C.x[0][k] >= R(0.8)) << 31;
    const real s2 = support * support;
    for (size_t k = 0; k < n; ++k) cnt[k] = grid_list_fill_ranked(&gc.view, C.x, k, s2, nl, n, 64, rk);
    size_t *atC = malloc(n * sizeof *atC);
    for (size_t k = 0; k < n; ++k) atC[C.id[k]] = k;
    size_t differ = 0;
    for (size_t i = 0; i < A.n + A.ng; ++i) {
        size_t m = 0;
        NBR_BEGIN(&ga.view, A.x, i, j)
            real xij[3];
            if (grid_pair(2, A.x, i, j, xij) < s2) seq[m++] = A.id[j];
        NBR_END
        const size_t ic = atC[A.id[i]];
        assert_true(cnt[ic] <= 64);
        assert_int_equal(cnt[ic], m);
        for (size_t q = 0; q < m; ++q) assert_true(C.id[nl[q * n + ic]] == seq[q]);
    }
    /* the plain cell scan of C (owned, then ghosts) is not that order: the check has teeth */
    for (size_t i = 0; i < A.n + A.ng; ++i) {
        size_t m = 0, k = 0, bad = 0;
        NBR_BEGIN(&ga.view, A.x, i, j)
            seq[m++] = A.id[j];
        NBR_END
        NBR_BEGIN(&gc.view, C.x, atC[A.id[i]], j)
            bad |= k >= m || C.id[j] != seq[k];
            ++k;
        NBR_END
        differ += bad;
    }
    assert_true(differ > 0);
    free(rk), free(nl), free(cnt), free(atC), free(ownC);
    nbr_free(&gc);
    part_free(&C);
    free(seq), free(atB), free(pt), free(id), free(ownA), free(ownB);
    nbr_free(&ga), nbr_free(&gb);
    part_free(&A), part_free(&B);
}

/* The list's other forms (grid.h form: the GPU's SPHSEG_GPU_NBR): the
 * 16-bit list (grid_enc16) and the cells form (no list: the build's cells,
 * owned and ghost runs merged by rank, counted within the list's radius at
 * the build's positions) hand every lane of a team of T (1 to 16) the same
 * particles in the same order as the plain list, in 2D and 3D, with cells
 * that hold owned particles and ghosts, after the particles moved (under
 * half the skin) from where the build put them. Reference: the 32-bit list
 * (grid_list_fill_ranked). */
static void check_forms(int dim)
{
    const size_t n = dim == 3 ? 6000 : 3000;
    const double sup = dim == 3 ? 0.1 : 0.04, skin = 0.1 * sup; /* cell edge = the list's radius */
    particles_t p = {0};
    part_alloc(&p, dim, n);
    srand(31u + (unsigned)dim);
    size_t no = 0;
    for (int pass = 0; pass < 2; ++pass) /* owned (x < 0.6, and some beyond) first, then ghosts */
        for (size_t k = 0; k < n; ++k) {
            srand(1000u * (unsigned)dim + (unsigned)k); /* the same point in both passes */
            double x = rand() / (double)RAND_MAX, y = rand() / (double)RAND_MAX, z = rand() / (double)RAND_MAX;
            int own = x < 0.6 || rand() % 5 == 0;
            if (own != !pass) continue;
            tu_put(&p, x, y, dim == 3 ? z : 0, KIND_MATERIAL, 1.0);
            p.id[p.n - 1] = (int64_t)((k * 7919u) % n);
            no += !pass;
        }
    p.ng = p.n - no, p.n = no;
    nbr_grid g = {0};
    nbr_build(&g, &p, (real)sup, NULL);
    const size_t nt = p.n + p.ng;
    size_t mixed = 0;
    for (size_t c = 0; c < g.ncell; ++c) mixed += g.end[c] > g.start[c] && g.gend[c] > g.gstart[c];
    assert_true(mixed > 10); /* cells where the merge by rank matters */
    const unsigned cap = dim == 3 ? 64 : 32;
    const real l2 = (real)(sup * sup);
    unsigned *rk = malloc(nt * sizeof *rk), *nl = malloc(nt * cap * sizeof *nl), *cnt = malloc(nt * sizeof *cnt);
    unsigned short *nl16 = malloc(nt * cap * sizeof *nl16);
    real *xb[3];
    for (int d = 0; d < 3; ++d) xb[d] = malloc(nt * sizeof(real)), memcpy(xb[d], p.x[d], nt * sizeof(real));
    for (size_t k = 0; k < nt; ++k) rk[k] = (unsigned)p.id[k];
    for (size_t i = 0; i < nt; ++i) {
        cnt[i] = grid_list_fill_ranked(&g.view, p.x, i, l2, nl, nt, cap, rk);
        assert_true(cnt[i] <= cap);
        assert_int_equal(grid_list_fill_form(&g.view, p.x, i, l2, NULL, nl16, nt, cap, rk), cnt[i]);
    }
    size_t moved = 0; /* then the particles move, under half the skin along each axis */
    for (size_t k = 0; k < nt; ++k) {
        int c0[3], c1[3];
        grid_cell_coords(&g.view, p.x[0], p.x[1], p.x[2], k, c0);
        for (int d = 0; d < dim; ++d) p.x[d][k] += (real)(skin * 0.45 * (2.0 * rand() / RAND_MAX - 1));
        grid_cell_coords(&g.view, p.x[0], p.x[1], p.x[2], k, c1);
        moved += c0[0] != c1[0] || c0[1] != c1[1] || c0[2] != c1[2];
    }
    assert_true(moved > 0); /* some particles left the cell they were sorted into */
    grid_view v[3] = {g.view, g.view, g.view};
    v[0].nl = nl, v[0].ncnt = cnt, v[0].nl_stride = nt, v[0].nl_cap = cap;
    v[1].form = GRID_NBR_LIST16, v[1].nl16 = nl16, v[1].ncnt = cnt, v[1].nl_stride = nt, v[1].nl_cap = cap;
    v[2].form = GRID_NBR_CELLS;
    for (int f = 1; f < 3; ++f) {
        for (int d = 0; d < 3; ++d) v[f].xb[d] = xb[d];
        v[f].rk = rk, v[f].list2 = l2;
    }
    size_t *ref = malloc(cap * sizeof *ref), met = 0;
    for (size_t i = 0; i < nt; ++i)
        for (int T = 1; T <= 16; T *= 2)
            for (int l = 0; l < T; ++l) {
                size_t m = 0;
                NBR_BEGIN_T(&v[0], p.x, i, j, l, T)
                    ref[m++] = j;
                NBR_END
                for (int f = 1; f < 3; ++f) {
                    size_t k = 0;
                    NBR_BEGIN_T(&v[f], p.x, i, j, l, T)
                        assert_true(k < m);
                        assert_int_equal(j, ref[k]);
                        ++k;
                    NBR_END
                    assert_int_equal(k, m);
                }
                met += m;
            }
    assert_true(met > 5 * nt); /* real neighbours were compared */
    /* The tile (grid_tile: the GPU's staged flow pass, SPHSEG_GPU_NBR=tile):
     * for each cell, the 3^d cells around it copied into a stage in the
     * tile's order; every owned particle of the cell meets, through
     * NBR_BEGIN_TJ, the list16's neighbours in its order, each at a slot of
     * the stage that holds that neighbour's copy. */
    grid_view vt = v[1];
    grid_tile tb;
    particles_t st = {0};
    size_t tiles = 0, via = 0;
    for (size_t c = 0; c < g.ncell; ++c) {
        if (g.end[c] == g.start[c]) continue;
        const int c0[3] = {(int)(c % (size_t)g.view.nc[0]), (int)((c / (size_t)g.view.nc[0]) % (size_t)g.view.nc[1]),
                           (int)(c / ((size_t)g.view.nc[0] * (size_t)g.view.nc[1]))};
        unsigned ng[27];
        for (int k = 0; k < (dim == 3 ? 27 : 9); ++k) ng[k] = grid_tile_slot(&g.view, c0, k, &tb);
        grid_tile_bases(&tb, ng, dim);
        const unsigned tot = tb.base[27];
        for (int d = 0; d < 3; ++d) st.x[d] = malloc((tot + 1) * sizeof(real));
        st.id = malloc((tot + 1) * sizeof *st.id);
        for (unsigned k = 0; k < tot; ++k) {
            const size_t j = grid_tile_at(&tb, k, dim);
            for (int d = 0; d < 3; ++d) st.x[d][k] = p.x[d][j];
            st.id[k] = p.id[j];
        }
        vt.tiled = 1, vt.tile = &tb, vt.tp = &st;
        for (size_t i = g.start[c]; i < g.end[c]; ++i)
            for (int T = 1; T <= 16; T *= 4)
                for (int l = 0; l < T; ++l) {
                    size_t m = 0, k = 0;
                    NBR_BEGIN_T(&v[0], p.x, i, j, l, T)
                        ref[m++] = j;
                    NBR_END
                    NBR_BEGIN_TJ(&vt, &p, i, j, jj, jp, l, T)
                        assert_true(k < m);
                        assert_int_equal(j, ref[k]);
                        assert_true(jp == &st && jj < tot);
                        assert_true(jp->id[jj] == p.id[j] && jp->x[0][jj] == p.x[0][j] && jp->x[1][jj] == p.x[1][j]);
                        ++k, ++via;
                    NBR_END
                    assert_int_equal(k, m);
                }
        for (int d = 0; d < 3; ++d) free(st.x[d]);
        free(st.id);
        ++tiles;
    }
    assert_true(tiles > 10 && via > 5 * p.n); /* the tiles were walked */
    free(ref), free(rk), free(nl), free(cnt), free(nl16);
    for (int d = 0; d < 3; ++d) free(xb[d]);
    nbr_free(&g);
    part_free(&p);
}

static void test_forms_2d(void **st) { (void)st; check_forms(2); }
static void test_forms_3d(void **st) { (void)st; check_forms(3); }

/* A cell past the 16-bit offsets (more than GRID_ENC16_OFF + 1 candidates)
 * is reported, not wrapped: the GPU then takes the cells form. */
static void test_forms_overflow(void **st)
{
    (void)st;
    const size_t n = 2100;
    particles_t p = {0};
    part_alloc(&p, 2, n);
    srand(5);
    for (size_t k = 0; k < n; ++k) tu_put(&p, 0.01 * rand() / RAND_MAX, 0.01 * rand() / RAND_MAX, 0, KIND_MATERIAL, 1.0);
    nbr_grid g = {0};
    nbr_build(&g, &p, R(0.1), NULL);
    unsigned *rk = malloc(n * sizeof *rk);
    unsigned short *nl16 = malloc(n * n * sizeof *nl16);
    for (size_t k = 0; k < n; ++k) rk[k] = (unsigned)p.id[k];
    size_t over = 0;
    for (size_t i = 0; i < n; ++i)
        over += grid_list_fill_form(&g.view, p.x, i, R(0.01), NULL, nl16, n, (unsigned)n, rk) == GRID_ENC16_OVER;
    assert_true(over > 0);
    free(rk), free(nl16);
    nbr_free(&g);
    part_free(&p);
}

/* The CPU's Verlet list (src/cpu/nlist.h, GRID_NBR_ROWS) against the cell
 * scan it replaces: after each sort of the store (nbr_build), with the
 * rows built from the cells or following the sort (renamed through its
 * permutation and put back in index order), every particle meets the same
 * neighbours within the support, in the same order, as the plain cell scan
 * of that sort; particles move under half the skin between sorts (the rows
 * follow) and then past it (they are built again). ghosts: a part of the
 * store is ghosts (several ranks), whose rows are built at every sort.
 * lattice: the particles a hair off a lattice of dr = h / 1.5 (the scenes'),
 * where pairs lie 2h apart across cell faces: a pair within the list's
 * radius at a build but two cells apart, which the later scan meets,
 * must be in the rows.
 * Reference: the cell scan (NBR_BEGIN without a list). */
static void check_rows(int dim, int ghosts, int lattice)
{
    const size_t side = dim == 3 ? 17 : 55, n = dim == 3 ? side * side * side : side * side;
    const double dr = 1.0 / (double)side, h = lattice ? 1.5 * dr : dim == 3 ? 0.04 : 0.012, skin = 0.1 * h;
    particles_t p = {0};
    part_alloc(&p, dim, n);
    srand(77u + (unsigned)dim);
    for (size_t k = 0; k < n; ++k) {
        double x[3];
        for (int d = 0; d < 3; ++d) { /* on the lattice, a hair off (pairs 2h apart, cells' faces), or anywhere */
            const size_t m = d == 0 ? k % side : d == 1 ? k / side % side : k / (side * side);
            x[d] = lattice ? ((double)m + 0.5) * dr + 0.02 * dr * (2.0 * rand() / RAND_MAX - 1) : rand() / (double)RAND_MAX;
        }
        /* dummies: every fourth, and a slab x < 0.3 of them alone (out of the material's reach) */
        tu_put(&p, x[0], x[1], dim == 3 ? x[2] : 0, k % 4 && x[0] >= 0.3 ? KIND_MATERIAL : KIND_DUMMY, 1.0);
        p.id[k] = (int64_t)((k * 7919u) % n);
    }
    if (ghosts) p.ng = n / 3, p.n = n - p.ng; /* the last third: ghosts */
    const size_t nt = p.n + p.ng;
    const real s2 = (real)(4 * h * h);
    nbr_grid g = {0};
    nlist L;
    nbr_build(&g, &p, (real)(2 * h), NULL);
    nlist_init(&L, &p, h, h / 1.5, 0.1);
    assert_true(L.on);
    nlist_update(&L, &g, &p, 0);
    size_t *seq = malloc(nt * sizeof *seq), resorted = 0, met = 0, skipped = 0;
    for (int round = 0; round < 12; ++round) {
        /* rounds 0-4 and 6-10: a step of skin/12 at most along each axis; round 5: past the skin */
        const double step = round == 5 ? 2 * skin : skin / 12;
        for (size_t k = 0; k < nt; ++k)
            for (int d = 0; d < dim; ++d) p.x[d][k] += (real)(step * (2.0 * rand() / RAND_MAX - 1));
        nbr_build(&g, &p, (real)(2 * h), NULL);
        for (size_t k = 0; k < nt; ++k) resorted += g.perm[k] != k;
        nlist_update(&L, &g, &p, 0);
        assert_int_equal(g.view.form, GRID_NBR_ROWS);
        grid_view cv = g.view;
        cv.form = GRID_NBR_LIST, cv.nl = cv.ncnt = NULL;
        for (size_t i = 0; i < nt; ++i) {
            met += same_pairs(&cv, &g.view, p.x, dim, i, s2, seq);
            /* the wall skip (nlist_wall_due): a dummy that the scan finds material within 2h of
             * is due; one not due meets none (ST_WALLS gives it flow_wall_none's result) */
            int reach = 0;
            NBR_BEGIN(&cv, p.x, i, j)
                real xij[3];
                reach |= p.kind[j] == KIND_MATERIAL && grid_pair(dim, p.x, i, j, xij) < s2;
            NBR_END
            if (p.kind[i] == KIND_DUMMY && reach) assert_true(nlist_wall_due(&L, i));
            skipped += p.kind[i] == KIND_DUMMY && !nlist_wall_due(&L, i);
        }
    }
    assert_true(met > 10 * nt); /* real neighbours to meet */
    assert_true(skipped > nt / 20); /* the slab's dummies out of reach skip their loop */
    assert_true(resorted > 0);  /* the sorts moved particles in the store */
    if (ghosts) {
        assert_int_equal(L.follows, 0); /* ghosts are made afresh: every sort builds */
    } else {
        assert_true(L.follows >= 8); /* the rows followed the sorts between builds */
        assert_true(L.builds >= 2 && L.builds <= 4); /* and were built again past the skin */
    }
    free(seq);
    nlist_free(&L);
    nbr_free(&g);
    part_free(&p);
}

static void test_rows_2d(void **st) { (void)st; check_rows(2, 0, 0); check_rows(2, 1, 0); check_rows(2, 0, 1); }
static void test_rows_3d(void **st) { (void)st; check_rows(3, 0, 0); check_rows(3, 1, 0); check_rows(3, 0, 1); }

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_nbr_2d), cmocka_unit_test(test_nbr_3d),
                                       cmocka_unit_test(test_nbr_permutes_fields), cmocka_unit_test(test_list_2d),
                                       cmocka_unit_test(test_list_3d), cmocka_unit_test(test_nbr_parallel_order),
                                       cmocka_unit_test(test_nbr_canonical_order), cmocka_unit_test(test_forms_2d),
                                       cmocka_unit_test(test_forms_3d), cmocka_unit_test(test_forms_overflow),
                                       cmocka_unit_test(test_rows_2d), cmocka_unit_test(test_rows_3d)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
