/* test_stages.c — what src/sim/stages.c derives from the stage table, against
 * the lists the backends carried by hand before it (issue 15, "Shape":
 * parallel_ghost_arrays in src/run.c, the refreshes of backend_cpu.c,
 * moving_fields in gpu/gpu_halo.cu), worked out from the bodies' reads:
 *  - the hooks' stage order (prepare: place, exchange, classify, renorm,
 *    walls; rates: flow, coefficients, dC/dt; filter: Shepard, store,
 *    walls), with the stages a run does not solve left out;
 *  - the ghosts' fields for the drum (flow, conservative renormalised C),
 *    the drum in windows (the window's mean shear rate gsum instead of
 *    gdot), the shear box (prescribed flow, paper scheme: no v, sig, wall, L)
 *    and the column (flow only: no C, gdot, L);
 *  - the refresh after each stage: classes, normals and psi after the
 *    classification (from the owners), gdot after the flow rates only
 *    when the coefficients read it in the same step (not in windows), sig
 *    after the Shepard store, gsum after the window mean, C after a
 *    window's midpoint stage; nothing after advance on a backend that
 *    makes its ghosts afresh in every prepare;
 *  - the GPU's moving fields (ghosts kept between list builds): x, v, sig
 *    and C for the drum, x, v, sig in windows, x, gdot and C for the
 *    shear box (its GPU list carried v too, which no stage reads of a ghost
 *    without computed flow);
 *  - stage_arrays: the z components and the xz, yz stresses left out of a
 *    trimmed 2D list; every field's bit together gives the whole store in
 *    its order (the field table, src/core/fields.h, makes both); FLD_SEGC
 *    is segV, segQ, segD;
 *  - every field refreshed is one the ghosts carry;
 *  - the DEM grains' coupling: its own hook; two ways phi held and carried
 *    by ghosts, the ghosts' vol (and, kept, phi) refreshed after it where a
 *    stage reads them before an exchange; nothing else changed. */
#include "testutil.h"
#include "sim/stages.h"

#define DRUM (SF_FLOW | SF_SEG | SF_RENORM)
#define SHEARBOX (SF_SEG | SF_HCSR)
#define COLUMN (SF_FLOW)

static void expect_plan(int hook, unsigned f, const int *ids, int n)
{
    const stage *rows[ST_N];
    int m = stage_plan(hook, f, rows);
    assert_int_equal(m, n);
    for (int k = 0; k < n; ++k) assert_int_equal(rows[k]->id, ids[k]);
}

static void test_plans(void **st)
{
    (void)st;
    int prep[] = {ST_PLACE, ST_EXCHANGE, ST_CLASSIFY, ST_RENORM, ST_WALLS};
    expect_plan(HOOK_PREPARE, DRUM, prep, 5);
    int prep_col[] = {ST_PLACE, ST_EXCHANGE, ST_CLASSIFY, ST_WALLS};
    expect_plan(HOOK_PREPARE, COLUMN, prep_col, 4);
    int prep_box[] = {ST_PLACE, ST_EXCHANGE, ST_CLASSIFY};
    expect_plan(HOOK_PREPARE, SHEARBOX, prep_box, 3);
    int rates[] = {ST_FLOW, ST_SEG_COEFFS, ST_DCDT};
    expect_plan(HOOK_RATES, DRUM, rates, 3);
    expect_plan(HOOK_RATES, DRUM | SF_WIN, rates, 1);
    expect_plan(HOOK_RATES, SHEARBOX, rates + 1, 2);
    int filt[] = {ST_SHEPARD, ST_SHEPARD_STORE, ST_WALLS};
    expect_plan(HOOK_FILTER, DRUM, filt, 3);
    int adv[] = {ST_ADVANCE, ST_ADVANCE_C};
    expect_plan(HOOK_ADVANCE, DRUM, adv, 2);
    int advw[] = {ST_ADVANCE, ST_ADVANCE_GSUM};
    expect_plan(HOOK_ADVANCE, DRUM | SF_WIN, advw, 2);
    int cb[] = {ST_SHEAR_MEAN, ST_WIN_RENORM, ST_WIN_BOUNDS};
    expect_plan(HOOK_CONC_BEGIN, DRUM | SF_WIN, cb, 3);
    expect_plan(HOOK_CONC_BEGIN, DRUM, cb, 0);
    int cs[] = {ST_WIN_COEFFS, ST_WIN_DCDT, ST_WIN_ADVANCE};
    expect_plan(HOOK_CONC_STEP, DRUM | SF_WIN, cs, 3);
    /* Flow:shifting: after the save, with computed flow only; it reads what the flow rates read of
     * ghosts and writes the start-of-step copies, which no ghost carries: no refresh, no new ghost field */
    int save[] = {ST_SAVE, ST_SHIFT};
    expect_plan(HOOK_SAVE, DRUM, save, 1);
    expect_plan(HOOK_SAVE, DRUM | SF_SHIFT, save, 2);
    expect_plan(HOOK_SAVE, SHEARBOX | SF_SHIFT, save, 1);
    assert_int_equal(stage_ghost_fields(DRUM | SF_SHIFT), stage_ghost_fields(DRUM));
    assert_int_equal(stage_refresh_after(ST_SHIFT, DRUM | SF_SHIFT, 0), 0);
    assert_int_equal(stage_refresh_after(ST_SHIFT, DRUM | SF_SHIFT, 1), 0);
    assert_int_equal(stage_moving_fields(DRUM | SF_SHIFT | SF_WIN), stage_moving_fields(DRUM | SF_WIN));
    /* Flow:gradient_correction: B in every prepare, before the walls, owned and ghosts from their own
     * support (no refresh); the flow rates read the neighbours' B, so a ghost carries it */
    int prep_kgc[] = {ST_PLACE, ST_EXCHANGE, ST_CLASSIFY, ST_RENORM, ST_KGC, ST_WALLS};
    expect_plan(HOOK_PREPARE, DRUM | SF_KGC, prep_kgc, 6);
    expect_plan(HOOK_PREPARE, SHEARBOX | SF_KGC, prep_box, 3); /* prescribed flow: none */
    for (int keep = 0; keep < 2; ++keep) assert_int_equal(stage_refresh_after(ST_KGC, DRUM | SF_KGC, keep), 0);
    assert_int_equal(stage_ghost_fields(DRUM | SF_KGC), stage_ghost_fields(DRUM) | FLD_B);
    assert_int_equal(stage_moving_fields(DRUM | SF_KGC), stage_moving_fields(DRUM));
    /* DEM grains: the coupling, its own hook after each rates; two ways it writes the owned fluid particles'
     * volume phi / eps (and the binned ghosts', from the phi they carry: a ghost field); the other ghosts
     * take their owners' where a stage reads them before an exchange: the shift in the save, and on a
     * backend that keeps its ghosts the next prepare (vol) and coupling (phi) */
    int dem[] = {ST_DEM_COUPLE};
    expect_plan(HOOK_DEM, COLUMN | SF_DEM, dem, 1);
    expect_plan(HOOK_DEM, COLUMN | SF_DEM | SF_DEM2, dem, 1);
    expect_plan(HOOK_DEM, COLUMN, dem, 0);
    expect_plan(HOOK_DEM, DRUM | SF_WIN, dem, 0);
    const unsigned two = COLUMN | SF_DEM | SF_DEM2;
    for (int h = 0; h < HOOK_N; ++h) {
        const stage *rows[ST_N];
        if (h != HOOK_DEM) assert_int_equal(stage_plan(h, two, rows), stage_plan(h, COLUMN, rows));
    }
    assert_int_equal(stage_ghost_fields(COLUMN | SF_DEM), stage_ghost_fields(COLUMN));
    assert_int_equal(stage_ghost_fields(two), stage_ghost_fields(COLUMN) | FLD_PHI);
    assert_int_equal(stage_store_fields(COLUMN | SF_DEM), stage_store_fields(COLUMN));
    assert_int_equal(stage_store_fields(two), stage_store_fields(COLUMN) | FLD_PHI);
    assert_int_equal(stage_moving_fields(two), stage_moving_fields(COLUMN));
    for (int id = 0; id < ST_N; ++id)
        for (int keep = 0; keep < 2; ++keep)
            if (id != ST_DEM_COUPLE)
                assert_int_equal(stage_refresh_after(id, two, keep), stage_refresh_after(id, COLUMN, keep));
    assert_int_equal(stage_refresh_after(ST_DEM_COUPLE, two, 0), 0);
    assert_int_equal(stage_refresh_after(ST_DEM_COUPLE, two | SF_SHIFT, 0), FLD_VOL);
    assert_int_equal(stage_refresh_after(ST_DEM_COUPLE, two, 1), FLD_VOL | FLD_PHI);
    for (int keep = 0; keep < 2; ++keep)
        assert_int_equal(stage_refresh_after(ST_DEM_COUPLE, COLUMN | SF_DEM, keep), 0);
    for (unsigned f = 0; f <= SF_ALL; ++f)
        if (!(f & SF_DEM2)) assert_int_equal(stage_store_fields(f) & FLD_PHI, 0);
}

static void test_ghost_fields(void **st)
{
    (void)st;
    const uint32_t base = FLD_X | FLD_VOL | FLD_ID | FLD_KIND | FLD_BCLASS | FLD_NRM | FLD_PSI;
    assert_int_equal(stage_ghost_fields(DRUM), base | FLD_WALL | FLD_V | FLD_SIG | FLD_C | FLD_GDOT | FLD_L);
    assert_int_equal(stage_ghost_fields(DRUM | SF_WIN), base | FLD_WALL | FLD_V | FLD_SIG | FLD_C | FLD_GSUM | FLD_L);
    assert_int_equal(stage_ghost_fields(SHEARBOX), base | FLD_C | FLD_GDOT);
    assert_int_equal(stage_ghost_fields(COLUMN), base | FLD_WALL | FLD_V | FLD_SIG);
}

static void test_refreshes(void **st)
{
    (void)st;
    for (int keep = 0; keep < 2; ++keep) {
        assert_int_equal(stage_refresh_after(ST_CLASSIFY, DRUM, keep), FLD_BCLASS | FLD_NRM | FLD_PSI);
        assert_int_equal(stage_refresh_after(ST_FLOW, DRUM, keep), FLD_GDOT);
        assert_int_equal(stage_refresh_after(ST_FLOW, DRUM | SF_WIN, keep), 0);
        assert_int_equal(stage_refresh_after(ST_SHEPARD_STORE, DRUM, keep), FLD_SIG);
        assert_int_equal(stage_refresh_after(ST_SHEPARD, DRUM, keep), 0); /* dsig: read of i only */
        assert_int_equal(stage_refresh_after(ST_SHEAR_MEAN, DRUM | SF_WIN, keep), FLD_GSUM);
        assert_int_equal(stage_refresh_after(ST_WIN_ADVANCE, DRUM | SF_WIN, keep), FLD_C);
        assert_int_equal(stage_refresh_after(ST_WALLS, DRUM, keep), 0);       /* each ghost its own */
        assert_int_equal(stage_refresh_after(ST_SEG_COEFFS, DRUM, keep), 0);
        assert_int_equal(stage_refresh_after(ST_SAVE, DRUM, keep), 0);
    }
    /* made afresh in the next prepare: no refresh after advance or place */
    assert_int_equal(stage_refresh_after(ST_ADVANCE, DRUM, 0), 0);
    assert_int_equal(stage_refresh_after(ST_ADVANCE_C, DRUM, 0), 0);
    assert_int_equal(stage_refresh_after(ST_PLACE, SHEARBOX, 0), 0);
    /* kept: the place writes x, v again, so advance owes only sig (and C) */
    assert_int_equal(stage_refresh_after(ST_ADVANCE, DRUM, 1), FLD_SIG);
    assert_int_equal(stage_refresh_after(ST_PLACE, DRUM, 1), FLD_X | FLD_V);
    assert_int_equal(stage_moving_fields(DRUM), FLD_X | FLD_V | FLD_SIG | FLD_C);
    assert_int_equal(stage_moving_fields(DRUM | SF_WIN), FLD_X | FLD_V | FLD_SIG);
    assert_int_equal(stage_moving_fields(SHEARBOX), FLD_X | FLD_GDOT | FLD_C); /* nothing reads a ghost's v */
    assert_int_equal(stage_moving_fields(COLUMN), FLD_X | FLD_V | FLD_SIG);
    /* whatever is refreshed, the ghosts carry */
    const unsigned runs[] = {DRUM, DRUM | SF_WIN, SHEARBOX, COLUMN, SF_SEG | SF_RENORM, DRUM | SF_HCSR};
    for (size_t r = 0; r < sizeof runs / sizeof runs[0]; ++r) {
        uint32_t g = stage_ghost_fields(runs[r]);
        assert_int_equal(stage_moving_fields(runs[r]) & ~g, 0);
        for (int id = 0; id < ST_N; ++id)
            for (int keep = 0; keep < 2; ++keep) assert_int_equal(stage_refresh_after(id, runs[r], keep) & ~g, 0);
    }
}

/* The schedule holds the same as the functions it memoises. */
static void test_schedule(void **st)
{
    (void)st;
    const unsigned runs[] = {DRUM, DRUM | SF_WIN, SHEARBOX, COLUMN};
    for (size_t r = 0; r < sizeof runs / sizeof runs[0]; ++r) {
        const stage_sched *m = stage_schedule(runs[r]);
        assert_ptr_equal(m, stage_schedule(runs[r]));
        for (int h = 0; h < HOOK_N; ++h) {
            const stage *rows[ST_N];
            assert_int_equal(m->n[h], stage_plan(h, runs[r], rows));
            for (int k = 0; k < m->n[h]; ++k) assert_int_equal(m->ids[h][k], rows[k]->id);
        }
        for (int id = 0; id < ST_N; ++id)
            for (int keep = 0; keep < 2; ++keep)
                assert_int_equal(m->refresh[keep][id], stage_refresh_after(id, runs[r], keep));
        assert_int_equal(m->moving, stage_moving_fields(runs[r]));
        assert_int_equal(m->ghost, stage_ghost_fields(runs[r]));
    }
}

static void test_arrays(void **st)
{
    (void)st;
    particles_t p;
    part_alloc(&p, 2, 4);
    void *a[PART_NARRAYS];
    assert_int_equal(stage_arrays(&p, FLD_X | FLD_SIG, 1, a), 2 + 4);
    assert_ptr_equal(a[1], p.x[1]);
    assert_ptr_equal(a[2 + 3], p.sig[3]);
    assert_int_equal(stage_arrays(&p, FLD_X | FLD_SIG, 0, a), 3 + 6);
    assert_int_equal(stage_arrays(&p, FLD_SEGC | FLD_L | FLD_KIND, 0, a), 3 + 6 + 1);
    assert_ptr_equal(a[9], p.kind);
    assert_ptr_equal(a[0], p.segV);
    assert_ptr_equal(a[1], p.segQ);
    assert_ptr_equal(a[2], p.segD);
    char buf[512];
    assert_string_equal(stage_fields_str(FLD_X | FLD_GDOT | FLD_BCLASS, buf, sizeof buf), "x, gdot, bclass");
    assert_string_equal(stage_fields_str(FLD_SEGC | FLD_SIGN, buf, sizeof buf), "segV, segQ, segD, sig_n");
    /* all the fields: the store's arrays in order, and 2D trims only x, v,
     * nrm, x_n, xr, v_n, acc (z) and sig, sig_n, dsig (xz, yz) */
    const uint32_t all = (1u << FLD_NFIELDS) - 1;
    assert_int_equal(stage_arrays(&p, all, 0, a), (int)part_narrays());
    for (size_t k = 0; k < part_narrays(); ++k) assert_ptr_equal(a[k], part_array_get(&p, k));
    assert_int_equal(stage_arrays(&p, all, 1, a), (int)part_narrays() - 7 - 3 * 2);
    assert_int_equal(stage_arrays(&p, FLD_X0 | FLD_L, 1, a), 3 + 6);
    assert_ptr_equal(a[2], p.X0[2]);
    assert_ptr_equal(a[8], p.L[5]);
    assert_int_equal(stage_arrays(&p, FLD_XR | FLD_DSIG, 1, a), 4 + 2); /* in the store's order */
    assert_ptr_equal(a[0], p.dsig[0]);
    assert_ptr_equal(a[3], p.dsig[3]);
    assert_ptr_equal(a[4], p.xr[0]);
    assert_ptr_equal(a[5], p.xr[1]);
    part_free(&p);
}

/* What the rows name under flags: their halo, writes and own reads (all
 * rows, or only those whose `when` holds bit `need`). */
static uint32_t named(unsigned flags, unsigned need)
{
    uint32_t m = 0;
    for (int k = 0; k < stage_table_n; ++k) {
        const stage *r = &stage_table[k];
        if ((r->when & flags) != r->when || (r->unless & flags)) continue;
        if (need && !(r->when & need)) continue;
        m |= r->halo | r->writes | r->reads;
    }
    return m;
}

/* Issue 56: a run allocates every field a running row names (no body
 * meets a NULL array) and no field that only rows of a module it does not
 * run name. The module's own fields come from the table (the rows that need
 * SF_SEG or SF_WIN, SF_FLOW), not from a list here: a scene without
 * segregation holds no dC/dt, C_n, V, Q, D, gsum, L; a scene with
 * prescribed flow no stress rate, acceleration or start-of-step v, sigma. */
static void test_store_fields(void **st)
{
    (void)st;
    const uint32_t xr = POS_REMAINDER ? 0 : FLD_XR; /* double: x is the position, xr never read */
    for (unsigned f = 0; f <= SF_ALL; ++f) {
        const uint32_t have = stage_store_fields(f);
        assert_int_equal(named(f, 0) & ~xr & ~have, 0);                /* every named field held */
        assert_int_equal(have & ~(named(f, 0) | STAGE_STORE_BASE | stage_ghost_fields(f)), 0); /* and no other */
        assert_int_equal(have & xr, 0);
    }
    /* the modules' own fields: named by their rows, by no row that runs without them, not in the base */
    const unsigned flow = SF_FLOW | SF_KGC | SF_SHIFT, seg = SF_SEG | SF_WIN | SF_RENORM | SF_HCSR;
    const uint32_t seg_own = named(flow | seg, SF_SEG | SF_WIN) & ~named(flow, 0) & ~STAGE_STORE_BASE;
    const uint32_t flow_own = named(flow | seg, SF_FLOW) & ~named(seg, 0) & ~STAGE_STORE_BASE;
    const uint32_t want_seg = FLD_DCDT | FLD_CN | FLD_SEGC | FLD_GSUM | FLD_L;
    const uint32_t want_flow = FLD_DSIG | FLD_ACC | FLD_VN | FLD_SIGN | FLD_B;
    assert_int_equal(seg_own & want_seg, want_seg); /* the table names them as the segregation's own */
    assert_int_equal(flow_own & want_flow, want_flow);
    for (unsigned f = 0; f <= SF_ALL; ++f) {
        if (!(f & SF_SEG) && !(f & SF_WIN)) assert_int_equal(stage_store_fields(f) & seg_own, 0);
        if (!(f & SF_FLOW)) assert_int_equal(stage_store_fields(f) & flow_own, 0);
        if (!(f & SF_KGC)) assert_int_equal(stage_store_fields(f) & FLD_B, 0);
        if (!(f & SF_RENORM)) assert_int_equal(stage_store_fields(f) & FLD_L, 0);
        if (!(f & SF_WIN)) assert_int_equal(stage_store_fields(f) & FLD_GSUM, 0);
    }
    /* a store of some fields: the others NULL, and the loops over the arrays skip them */
    particles_t p;
    const uint32_t some = stage_store_fields(SF_FLOW);
    part_alloc_fields(&p, 2, 8, some);
    assert_null(p.dCdt);
    assert_null(p.C_n);
    assert_null(p.segV);
    assert_non_null(p.acc[0]);
    assert_non_null(p.C);
    assert_int_equal(part_store_bytes(&p), part_fields_bytes(some));
    assert_true(part_store_bytes(&p) < part_bytes_per_particle());
    p.n = 8;
    for (size_t i = 0; i < 8; ++i) p.id[i] = (int64_t)i, p.x[0][i] = (real)i;
    size_t perm[8] = {7, 6, 5, 4, 3, 2, 1, 0};
    part_permute(&p, perm);
    part_reserve(&p, 20);
    assert_null(p.dCdt);
    for (size_t i = 0; i < 8; ++i) assert_true(p.id[i] == (int64_t)(7 - i) && p.x[0][i] == (real)(7 - i));
    assert_int_equal(part_array_find(&p, NULL), -1);
    part_free(&p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_plans), cmocka_unit_test(test_ghost_fields),
                                       cmocka_unit_test(test_refreshes), cmocka_unit_test(test_schedule),
                                       cmocka_unit_test(test_arrays), cmocka_unit_test(test_store_fields)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
