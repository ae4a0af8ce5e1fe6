/* test_io_ranks.c — snapshots are in global particle-ID order whatever the
 * rank count and however particles are spread over ranks.
 *
 * One fixed set of N particles with sparse IDs (gaps, some above 2^32) is
 * shuffled and dealt to ranks by a rule that depends on the rank count:
 * 1 rank holds all; 2 ranks hold 1/3 and 2/3; 3 or more ranks: rank 0 holds a
 * quarter, the last rank the rest, the others none. Every rank writes
 * DIR/snapshot_<P %05d>.h5 (P = rank count); rank 0 reads it back and checks
 * that ParticleIDs is the sorted ID set and every field matches values
 * computed from the ID. tests/test_io_ranks.sh runs P = 1, 2, 3 into one DIR
 * and checks that the three files are identical field by field.
 *   test_io_ranks [DIR [dup]]      (no DIR: a temporary one, removed after)
 * With "dup", rank 0 also holds a copy of the last rank's first particle: the
 * writer must stop with "is held twice" (exit status 1). */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* mkdtemp */
#endif
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <hdf5.h>
#include <math.h>
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "output/io.h"
#include "core/particles.h"

enum { N = 1001 };
static char g_dir[256];
static int g_rank, g_size, g_dup;

/* The g-th particle's ID: sparse, unique, increasing in g, past 2^32 from g = 600. */
static int64_t id_of(int g) { return 7 * (int64_t)g + g % 3 + (g >= 600 ? INT64_C(5000000000) : 0); }

/* Value of component c of field name for a particle of this ID (before real rounding). */
static double ref_value(const char *name, int c, int64_t id)
{
    double d = (double)(id % 100003) + 1e-3 * (double)(id / 100003);
    if (!strcmp(name, "Kind")) return (double)(id % 2);
    if (!strcmp(name, "BoundaryClass")) return (double)(id % 6);
    if (!strcmp(name, "Wall")) return id % 2 ? (double)(1 + id % 7) : 0.0; /* a dummy's wall id, material 0 */
    if (!strcmp(name, "ParticleIDs")) return (double)id;
    return (double)(real)(sin(d + c) * (1.0 + strlen(name)));
}

/* Which rank holds the particle at position q of the shuffled list. */
static int owner(int q)
{
    if (g_size == 1) return 0;
    if (g_size == 2) return q % 3 == 0 ? 0 : 1;
    return q % 4 == 0 ? 0 : g_size - 1;
}

/* This rank's particles, in shuffled order. */
static void make_particles(particles_t *p)
{
    int perm[N];
    for (int g = 0; g < N; g++)
        perm[g] = g;
    unsigned s = 2024u; /* Fisher-Yates with a fixed LCG: the same list on every rank */
    for (int k = N; k > 1; k--) {
        s = s * 1103515245u + 12345u;
        int r = (int)((s >> 8) % (unsigned)k), t = perm[k - 1];
        perm[k - 1] = perm[r];
        perm[r] = t;
    }
    part_alloc(p, 2, N + 1);
    size_t n = 0;
    for (int q = 0; q < N; q++)
        if (owner(q) == g_rank) p->id[n++] = id_of(perm[q]);
    if (g_dup && g_rank == 0) /* a copy of a particle the last rank holds */
        for (int q = 0; q < N; q++)
            if (owner(q) == g_size - 1) {
                p->id[n++] = id_of(perm[q]);
                break;
            }
    p->n = n;
    for (int i = 0; i < io_nfields; i++) {
        const struct io_field *f = &io_fields[i];
        for (int c = 0; c < f->ncomp; c++) {
            void *a = (void *)f->array(p, c);
            for (size_t k = 0; k < n; k++) {
                double v = ref_value(f->name, c, p->id[k]);
                if (f->type == IO_REAL) ((real *)a)[k] = (real)v;
                else if (f->type == IO_CREAL) ((creal *)a)[k] = (creal)v;
                else if (f->type == IO_UINT8) ((uint8_t *)a)[k] = (uint8_t)v;
            }
        }
    }
}

/* Rank 0: the file holds the N particles in increasing ID order, every field right. */
static void check_file(const char *path)
{
    hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    assert_true(file >= 0);
    for (int i = 0; i < io_nfields; i++) {
        const struct io_field *f = &io_fields[i];
        char name[128];
        snprintf(name, sizeof name, "/Particles/%s", f->name);
        hid_t dset = H5Dopen2(file, name, H5P_DEFAULT), space = H5Dget_space(dset);
        assert_true(dset >= 0);
        assert_int_equal(H5Sget_simple_extent_npoints(space), (hssize_t)N * f->ncomp);
        double *v = malloc((size_t)N * f->ncomp * sizeof *v);
        int64_t *ids = malloc(N * sizeof *ids);
        assert_true(H5Dread(dset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) >= 0);
        hid_t did = H5Dopen2(file, "/Particles/ParticleIDs", H5P_DEFAULT);
        assert_true(H5Dread(did, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, ids) >= 0);
        for (int k = 0; k < N; k++) {
            if (ids[k] != id_of(k)) fail_msg("%s: row %d has ID %lld, want %lld", path, k, (long long)ids[k],
                                             (long long)id_of(k));
            for (int c = 0; c < f->ncomp; c++)
                if (v[k * f->ncomp + c] != ref_value(f->name, c, ids[k]))
                    fail_msg("%s[%d][%d] = %.17g, want %.17g", f->name, k, c, v[k * f->ncomp + c],
                             ref_value(f->name, c, ids[k]));
        }
        free(v);
        free(ids);
        H5Dclose(did);
        H5Sclose(space);
        H5Dclose(dset);
    }
    H5Fclose(file);
}

static void test_snapshot_id_order(void **state)
{
    (void)state;
    particles_t p;
    make_particles(&p);
    int64_t first = p.n > 0 ? p.id[0] : -1;
    io_write_snapshot(g_dir, g_size, &p, 1.5, 42, "scene: test\n", "1 base", "test-io-ranks");
    assert_true(p.n == 0 || p.id[0] == first); /* the store is not reordered */
    part_free(&p);
    if (g_rank != 0) return;
    char path[512];
    snprintf(path, sizeof path, "%s/snapshot_%05d.h5", g_dir, g_size);
    check_file(path);
}

int main(int argc, char **argv)
{
    MPI_Init(&argc, &argv);
    MPI_Comm_rank(MPI_COMM_WORLD, &g_rank);
    MPI_Comm_size(MPI_COMM_WORLD, &g_size);
    int keep = argc > 1;
    g_dup = argc > 2 && !strcmp(argv[2], "dup");
    if (keep)
        snprintf(g_dir, sizeof g_dir, "%s", argv[1]);
    else if (g_rank == 0 && !mkdtemp(strcpy(g_dir, "/tmp/sphseg_test_io_ranks_XXXXXX")))
        MPI_Abort(MPI_COMM_WORLD, 1);
    MPI_Bcast(g_dir, sizeof g_dir, MPI_CHAR, 0, MPI_COMM_WORLD);
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_snapshot_id_order)};
    int failed = cmocka_run_group_tests(tests, NULL, NULL), any = 0;
    MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    if (!keep && !any && g_rank == 0) {
        char path[512];
        snprintf(path, sizeof path, "%s/snapshot_%05d.h5", g_dir, g_size);
        unlink(path);
        rmdir(g_dir);
    }
    MPI_Finalize();
    return any ? 1 : 0;
}
