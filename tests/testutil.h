/* testutil.h — small particle sets for the unit tests. */
#ifndef SPHSEG_TESTUTIL_H
#define SPHSEG_TESTUTIL_H
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdlib.h>
#include <cmocka.h>
#include "cpu/bound.h"
#include "cpu/nbr.h"
#include "core/particles.h"

/* Tolerances for both precisions. RT(x): a check that holds to round-off,
 * with x chosen for double precision; in single precision it becomes
 * max(x, 2e-5), about 170 float epsilons. FD_STEP: the step of a central
 * finite-difference check (1e-6 in double, 1e-3 in single, where a smaller
 * step drowns in round-off). */
#define RT(x) (sizeof(real) == sizeof(float) && (x) < 2e-5 ? 2e-5 : (x))
#define FD_STEP (sizeof(real) == sizeof(float) ? 1e-3 : 1e-6)

/* Append one particle. */
static inline void tu_put(particles_t *p, double x, double y, double z, int kind, double vol)
{
    size_t k = p->n++;
    assert_true(k < p->cap);
    p->x[0][k] = p->X0[0][k] = (real)x;
    p->x[1][k] = p->X0[1][k] = (real)y;
    p->x[2][k] = p->X0[2][k] = (real)z;
    p->kind[k] = (uint8_t)kind;
    p->vol[k] = (real)vol;
    p->id[k] = (int64_t)k;
    p->psi[k] = 1;
}

/* A 2D lattice block of nx x ny material particles of spacing dr with its
 * lower-left particle at (dr/2, dr/2); optional dummy layers below (nl_base)
 * and at both sides (nl_side), as in the shear box. */
static inline void tu_block2d(particles_t *p, int nx, int ny, double dr, int nl_base, int nl_side)
{
    size_t cap = (size_t)(nx + 2 * nl_side) * (size_t)(ny + nl_base + nl_side + 1) + 16;
    part_alloc(p, 2, cap);
    double v = dr * dr;
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) tu_put(p, (i + 0.5) * dr, (j + 0.5) * dr, 0, KIND_MATERIAL, v);
    for (int l = 0; l < nl_base; ++l)
        for (int i = -nl_side; i < nx + nl_side; ++i) tu_put(p, (i + 0.5) * dr, -(l + 0.5) * dr, 0, KIND_DUMMY, v);
    for (int j = 0; j < ny + nl_side; ++j) /* walls reach nl_side layers above */
        for (int l = 0; l < nl_side; ++l) {
            tu_put(p, -(l + 0.5) * dr, (j + 0.5) * dr, 0, KIND_DUMMY, v);
            tu_put(p, (nx + l + 0.5) * dr, (j + 0.5) * dr, 0, KIND_DUMMY, v);
        }
}

/* Index of the particle with the given id (the store is sorted by cell). */
static inline size_t tu_find(const particles_t *p, int64_t id)
{
    for (size_t i = 0; i < p->n; ++i)
        if (p->id[i] == id) return i;
    fail_msg("no particle with id %lld", (long long)id);
    return 0;
}

/* The fixture of a test on a particle set (cmocka_unit_test_setup_teardown
 * with tu_fx_setup, tu_fx_teardown; the test reads it as *state): the
 * store, its cell list and the boundary classification's work arrays, all
 * empty before the test and freed after it, whether it passed or not. */
typedef struct tu_fx {
    particles_t p;
    nbr_grid g;
    bound_work w;
} tu_fx;

static inline int tu_fx_setup(void **state)
{
    tu_fx *f = calloc(1, sizeof *f);
    *state = f;
    return f ? 0 : -1;
}

static inline int tu_fx_teardown(void **state)
{
    tu_fx *f = *state;
    bound_free(&f->w);
    nbr_free(&f->g);
    part_free(&f->p);
    free(f);
    return 0;
}

/* The fixture's cell list: cells of edge 2h. */
static inline void tu_fx_list(tu_fx *f, real h) { nbr_build(&f->g, &f->p, R(2.0) * h, NULL); }

/* A cmocka test entry with the fixture. */
#define TU_FX_TEST(t) cmocka_unit_test_setup_teardown(t, tu_fx_setup, tu_fx_teardown)

#endif
