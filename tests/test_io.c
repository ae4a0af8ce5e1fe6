/* test_io.c — particle store (alloc, permute) and snapshot output (HDF5 +
 * XDMF). Runs on any rank count: every rank contributes particles with
 * disjoint IDs; rank 0 reads the file back with the serial HDF5 API and
 * compares every field with values computed independently from the IDs
 * (tests/test_io_ranks.sh runs it on 3 ranks).
 *   mpirun -np 2 ./test_io */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* strdup, mkdtemp */
#endif
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <dirent.h>
#include <hdf5.h>
#include <math.h>
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "output/io.h"
#include "core/particles.h"

static char g_dir[256];
static int g_rank, g_size;
static char *g_scene; /* a large scene text (> 64 KiB, the attribute header limit) */

/* ---- reference values, functions of the particle ID only ---------------- */

/* Expected stored value of component c of field name for particle id, before
 * rounding to real. Independent of io.c's table, so a wrong accessor shows. */
static double ref_value(const char *name, int c, int64_t id)
{
    double d = (double)id;
    if (!strcmp(name, "Coordinates")) return c == 0 ? 0.01 * d + 0.001 : c == 1 ? 0.5 - 0.02 * d : 0;
    if (!strcmp(name, "Velocities")) return c == 0 ? sin(d) : c == 1 ? cos(d) : 0;
    if (!strcmp(name, "Concentration")) return (id % 7) / 7.0;
    if (!strcmp(name, "ShearRate")) return 1.5 + d;
    if (!strcmp(name, "Volume")) return 1e-6 * (1 + id % 3);
    if (!strcmp(name, "Stress")) return -100.0 * (c + 1) - 0.5 * d;
    if (!strcmp(name, "Normal")) return c == 0 ? cos(0.3 * d) : c == 1 ? sin(0.3 * d) : 0;
    if (!strcmp(name, "Psi")) return 0.1 * (id % 11);
    if (!strcmp(name, "Kind")) return (double)(id % 2);
    if (!strcmp(name, "BoundaryClass")) return (double)(id % 6);
    if (!strcmp(name, "Wall")) return id % 2 ? (double)(1 + id % 7) : 0.0; /* a dummy's wall id, material 0 */
    if (!strcmp(name, "ParticleIDs")) return d;
    fail_msg("no reference for field %s", name);
    return 0;
}

/* The value as the file must hold it (real rounding, then double). */
static double ref_stored(const char *name, int c, int64_t id)
{
    double v = ref_value(name, c, id);
    return strcmp(name, "Kind") && strcmp(name, "BoundaryClass") && strcmp(name, "ParticleIDs")
               ? (double)(real)v
               : v;
}

/* Particle k of p gets ID id and the reference values; arrays that are not
 * output get distinct junk so a wrong accessor cannot pass. */
static void fill_particle(particles_t *p, size_t k, int64_t id)
{
    for (int c = 0; c < 3; c++) {
        p->x[c][k] = (real)ref_value("Coordinates", c, id);
        p->v[c][k] = (real)ref_value("Velocities", c, id);
        p->nrm[c][k] = (real)ref_value("Normal", c, id);
        p->X0[c][k] = (real)(-1000.0 - id);
    }
    for (int c = 0; c < 6; c++) {
        p->sig[c][k] = (real)ref_value("Stress", c, id);
        p->sig_n[c][k] = p->dsig[c][k] = (real)(7777.0 + id);
    }
    p->C[k] = (real)ref_value("Concentration", 0, id);
    p->gdot[k] = (real)ref_value("ShearRate", 0, id);
    p->vol[k] = (real)ref_value("Volume", 0, id);
    p->psi[k] = (real)ref_value("Psi", 0, id);
    p->kind[k] = (uint8_t)ref_value("Kind", 0, id);
    p->bclass[k] = (uint8_t)ref_value("BoundaryClass", 0, id);
    p->wall[k] = (uint8_t)ref_value("Wall", 0, id);
    p->id[k] = id;
    p->C_n[k] = (real)(-2000.0 - id);
    p->dCdt[k] = (real)(-3000.0 - id);
}

/* n particles on this rank with IDs rank + size*j (j < n), shuffled. */
static void make_particles(particles_t *p, size_t n)
{
    part_alloc(p, 2, n + 3);
    p->n = n;
    size_t *j = malloc((n ? n : 1) * sizeof *j);
    for (size_t k = 0; k < n; k++)
        j[k] = k;
    unsigned s = 12345u + (unsigned)g_rank;
    for (size_t k = n; k > 1; k--) { /* Fisher-Yates with a fixed LCG */
        s = s * 1103515245u + 12345u;
        size_t r = (s >> 8) % k, t = j[k - 1];
        j[k - 1] = j[r];
        j[r] = t;
    }
    for (size_t k = 0; k < n; k++)
        fill_particle(p, k, g_rank + (int64_t)g_size * (int64_t)j[k]);
    free(j);
}

/* ---- HDF5 read-back helpers ------------------------------------------------ */

static char *read_attr_string(hid_t loc, const char *name)
{
    hid_t attr = H5Aopen(loc, name, H5P_DEFAULT);
    assert_true(attr >= 0);
    hid_t ftype = H5Aget_type(attr);
    assert_true(H5Tis_variable_str(ftype) > 0);
    hid_t mtype = H5Tcopy(H5T_C_S1);
    H5Tset_size(mtype, H5T_VARIABLE);
    H5Tset_cset(mtype, H5T_CSET_UTF8);
    char *s = NULL;
    assert_true(H5Aread(attr, mtype, &s) >= 0);
    char *copy = strdup(s);
    H5free_memory(s);
    H5Tclose(mtype);
    H5Tclose(ftype);
    H5Aclose(attr);
    return copy;
}

static void read_attr(hid_t loc, const char *name, hid_t mtype, void *val)
{
    hid_t attr = H5Aopen(loc, name, H5P_DEFAULT);
    assert_true(attr >= 0);
    assert_true(H5Aread(attr, mtype, val) >= 0);
    H5Aclose(attr);
}

/* Read dataset /Particles/<f->name> as doubles (n rows x ncomp); checks its
 * shape, stored type, and Description/Units attributes. */
static double *read_field(hid_t file, const struct io_field *f, long long n)
{
    char path[128];
    snprintf(path, sizeof path, "/Particles/%s", f->name);
    hid_t dset = H5Dopen2(file, path, H5P_DEFAULT);
    assert_true(dset >= 0);
    hid_t space = H5Dget_space(dset), type = H5Dget_type(dset);
    hsize_t dims[2] = {0, 0};
    assert_int_equal(H5Sget_simple_extent_ndims(space), f->ncomp > 1 ? 2 : 1);
    H5Sget_simple_extent_dims(space, dims, NULL);
    assert_int_equal(dims[0], n);
    if (f->ncomp > 1) assert_int_equal(dims[1], f->ncomp);
    hid_t want = f->type == IO_REAL || f->type == IO_CREAL ? H5T_IEEE_F64LE : f->type == IO_UINT8 ? H5T_STD_U8LE : H5T_STD_I64LE;
    assert_true(H5Tequal(type, want) > 0);
    double *buf = malloc((n > 0 ? n : 1) * (size_t)f->ncomp * sizeof *buf);
    if (n > 0) assert_true(H5Dread(dset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0);
    char *desc = read_attr_string(dset, "Description"), *units = read_attr_string(dset, "Units");
    assert_true(strlen(desc) > 10);
    assert_string_equal(desc, f->description);
    assert_string_equal(units, f->units);
    free(desc);
    free(units);
    H5Tclose(type);
    H5Sclose(space);
    H5Dclose(dset);
    return buf;
}

static void check_no_tmp(void)
{
    DIR *d = opendir(g_dir);
    assert_non_null(d);
    struct dirent *e;
    while ((e = readdir(d))) {
        size_t l = strlen(e->d_name);
        if (l >= 4 && !strcmp(e->d_name + l - 4, ".tmp")) fail_msg("left behind: %s", e->d_name);
    }
    closedir(d);
}

/* ---- snapshot checks ------------------------------------------------------- */

/* Header of snapshot index: Time, Step, Dimension, N, Code, Version, Scene. */
static hid_t open_and_check_header(int index, double time, long step, long long ntot)
{
    char path[512];
    snprintf(path, sizeof path, "%s/snapshot_%05d.h5", g_dir, index);
    hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    assert_true(file >= 0);
    hid_t h = H5Gopen2(file, "Header", H5P_DEFAULT);
    double t;
    int64_t s, n;
    int dim;
    read_attr(h, "Time", H5T_NATIVE_DOUBLE, &t);
    read_attr(h, "Step", H5T_NATIVE_INT64, &s);
    read_attr(h, "NumPart_Total", H5T_NATIVE_INT64, &n);
    read_attr(h, "Dimension", H5T_NATIVE_INT, &dim);
    assert_true(t == time);
    assert_int_equal(s, step);
    assert_int_equal(n, ntot);
    assert_int_equal(dim, 2);
    char *code = read_attr_string(h, "Code"), *ver = read_attr_string(h, "Version");
    char *scene = read_attr_string(h, "Scene");
    assert_string_equal(code, "sphseg");
    assert_string_equal(ver, "test-1.2.3");
    assert_string_equal(scene, g_scene);
    free(code);
    free(ver);
    free(scene);
    H5Gclose(h);
    return file;
}

static int cmp_ll(const void *a, const void *b)
{
    long long x = *(const long long *)a, y = *(const long long *)b;
    return (x > y) - (x < y);
}

/* Rank r held nloc[r] particles with IDs r + size*j: the file lists all of
 * them in increasing ID order whatever the rank count; every field matches. */
static void check_particles(hid_t file, const long long *nloc, long long ntot)
{
    double *ids = read_field(file, &io_fields[io_nfields - 1], ntot);
    assert_string_equal(io_fields[io_nfields - 1].name, "ParticleIDs");
    long long *want = malloc((ntot > 0 ? ntot : 1) * sizeof *want), row = 0;
    for (int r = 0; r < g_size; r++)
        for (long long j = 0; j < nloc[r]; j++)
            want[row++] = r + (long long)g_size * j;
    qsort(want, (size_t)ntot, sizeof *want, cmp_ll);
    for (row = 0; row < ntot; row++)
        if (ids[row] != (double)want[row])
            fail_msg("ParticleIDs[%lld] = %.17g, want %lld", row, ids[row], want[row]);
    free(want);
    for (int i = 0; i < io_nfields; i++) {
        const struct io_field *f = &io_fields[i];
        double *v = read_field(file, f, ntot);
        for (long long k = 0; k < ntot; k++)
            for (int c = 0; c < f->ncomp; c++)
                if (v[k * f->ncomp + c] != ref_stored(f->name, c, (int64_t)ids[k]))
                    fail_msg("%s[%lld][%d] = %.17g, want %.17g", f->name, k, c, v[k * f->ncomp + c],
                             ref_stored(f->name, c, (int64_t)ids[k]));
        free(v);
    }
    free(ids);
}

/* Collective: every rank writes nmine particles into snapshot index; the
 * store must come back untouched. Fills nloc[r] with rank r's count. */
static void write_snapshot(int index, size_t nmine, double time, long step, long long *nloc)
{
    particles_t p;
    make_particles(&p, nmine);
    int64_t *before = malloc((nmine ? nmine : 1) * sizeof *before);
    memcpy(before, p.id, nmine * sizeof *before);
    int rc = io_write_snapshot(g_dir, index, &p, time, step, g_scene, NULL, "test-1.2.3");
    ssize_t open_ids = H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL); /* nothing left open */
    long long n = (long long)nmine;
    MPI_Allgather(&n, 1, MPI_LONG_LONG, nloc, 1, MPI_LONG_LONG, MPI_COMM_WORLD);
    int same = memcmp(before, p.id, nmine * sizeof *before) == 0;
    free(before);
    part_free(&p);
    assert_int_equal(rc, 0);
    assert_true(same); /* the store is not reordered by the writer */
    assert_int_equal(open_ids, 0);
}

/* Rank 0 only (no collectives, so a failed check cannot hang other ranks). */
static void check_snapshot(int index, double time, long step, const long long *nloc)
{
    if (g_rank != 0) return;
    long long ntot = 0;
    for (int r = 0; r < g_size; r++)
        ntot += nloc[r];
    check_no_tmp();
    hid_t file = open_and_check_header(index, time, step, ntot);
    check_particles(file, nloc, ntot);
    H5Fclose(file);
}

static void write_and_check(int index, size_t nmine, double time, long step)
{
    long long *nloc = calloc(g_size, sizeof *nloc);
    write_snapshot(index, nmine, time, step, nloc);
    check_snapshot(index, time, step, nloc);
    free(nloc);
}

static void test_snapshot_roundtrip(void **state)
{
    (void)state;
    write_and_check(0, 50, 0.25, 17);
}

static void test_snapshot_empty_ranks(void **state)
{
    (void)state;
    write_and_check(1, g_rank == 0 ? 30 : 0, 1.0 / 3.0, 123456789012L);
}

static void test_snapshot_no_particles(void **state)
{
    (void)state;
    write_and_check(2, 0, 2.5, 3);
}

/* Overwriting an existing snapshot replaces it whole. */
static void test_snapshot_overwrite(void **state)
{
    (void)state;
    long long *nloc = calloc(g_size, sizeof *nloc);
    write_snapshot(3, 40, 7.0, 70, nloc);
    write_snapshot(3, 20, 8.0, 80, nloc);
    check_snapshot(3, 8.0, 80, nloc);
    free(nloc);
}

static void test_xdmf(void **state)
{
    (void)state;
    double times[4] = {0.25, 1.0 / 3.0, 2.5, 8.0};
    long long npart[4] = {50LL * g_size, 30, 0, 20LL * g_size};
    assert_int_equal(io_write_xdmf(g_dir, 4, times, npart, NULL, 2), 0);
    if (g_rank != 0) return;
    check_no_tmp();
    char path[512];
    snprintf(path, sizeof path, "%s/snapshots.xmf", g_dir);
    FILE *fp = fopen(path, "r");
    assert_non_null(fp);
    static char text[1 << 16];
    size_t len = fread(text, 1, sizeof text - 1, fp);
    text[len] = 0;
    fclose(fp);
    const char *want[] = {"snapshot_00000.h5:/Particles/Coordinates",
                          "snapshot_00001.h5:/Particles/Concentration",
                          "snapshot_00002.h5:/Particles/Kind",
                          "snapshot_00003.h5:/Particles/Normal",
                          "CollectionType=\"Temporal\"",
                          "TopologyType=\"Polyvertex\"",
                          "GeometryType=\"XYZ\"",
                          "<Attribute Name=\"Velocities\" AttributeType=\"Vector\"",
                          "<Attribute Name=\"Normal\" AttributeType=\"Vector\"",
                          "<Attribute Name=\"ShearRate\" AttributeType=\"Scalar\"",
                          "<Attribute Name=\"BoundaryClass\" AttributeType=\"Scalar\"",
                          "<Time Value=\"0.33333333333333331\"/>",
                          "</Xdmf>"};
    for (size_t i = 0; i < sizeof want / sizeof want[0]; i++)
        if (!strstr(text, want[i])) fail_msg("snapshots.xmf lacks %s", want[i]);
    assert_null(strstr(text, "snapshot_00004"));
}

/* ---- particle store ---------------------------------------------------------- */

static void test_part_alloc(void **state)
{
    (void)state;
    particles_t p;
    part_alloc(&p, 2, 64);
    assert_int_equal(p.dim, 2);
    assert_int_equal(p.n, 0);
    assert_int_equal(p.cap, 64);
    for (size_t k = 0; k < 64; k++) {
        assert_true(p.x[2][k] == 0 && p.v[2][k] == 0 && p.nrm[2][k] == 0 && p.X0[2][k] == 0);
        assert_true(p.C[k] == 0 && p.id[k] == 0 && p.kind[k] == 0 && p.bclass[k] == 0);
    }
    part_free(&p);
    assert_null(p.x[0]);
    assert_int_equal(p.cap, 0);
    part_alloc(&p, 3, 0); /* empty store is valid */
    assert_non_null(p.id);
    part_free(&p);
    /* Every row of the field table (core/fields.h), components times element
     * size, summed here from the rows themselves: a new field needs no edit. */
#define ROW_BYTES(member, fld, type, n, trim) +(size_t)(n) * sizeof(type)
    const size_t want = 0 PART_FIELDS(ROW_BYTES);
#undef ROW_BYTES
    assert_int_equal(part_bytes_per_particle(), want);
    assert_true(want >= 58 * sizeof(real)); /* the table as it was at issue 54 is a floor */
}

/* Value of array a (0..56) for a particle originally at index k. */
static double perm_val(int a, size_t k) { return 1000.0 * a + (double)k; }

static void test_part_permute(void **state)
{
    (void)state;
    enum { N = 37 };
    particles_t p;
    part_alloc(&p, 2, N + 5);
    p.n = N;
    real **r[] = {&p.x[0], &p.x[1], &p.x[2], &p.X0[0], &p.X0[1], &p.X0[2],  &p.v[0],   &p.v[1],   &p.v[2],
                  &p.vol,  &p.C,    &p.C_n,  &p.dCdt,  &p.gdot,  &p.nrm[0], &p.nrm[1], &p.nrm[2], &p.psi,
                  &p.segV, &p.segQ, &p.segD, &p.L[0],  &p.L[1],  &p.L[2],   &p.L[3],   &p.L[4],   &p.L[5],
                  &p.sig[0], &p.sig[1], &p.sig[2], &p.sig[3], &p.sig[4], &p.sig[5],
                  &p.sig_n[0], &p.sig_n[1], &p.sig_n[2], &p.sig_n[3], &p.sig_n[4], &p.sig_n[5],
                  &p.dsig[0], &p.dsig[1], &p.dsig[2], &p.dsig[3], &p.dsig[4], &p.dsig[5],
                  &p.x_n[0], &p.x_n[1], &p.x_n[2], &p.v_n[0], &p.v_n[1], &p.v_n[2],
                  &p.acc[0], &p.acc[1], &p.acc[2], &p.xr[0], &p.xr[1],  &p.xr[2]};
    int nr = (int)(sizeof r / sizeof r[0]);
    for (size_t k = 0; k < N; k++) {
        for (int a = 0; a < nr; a++)
            (*r[a])[k] = (real)perm_val(a, k);
        p.id[k] = 5000000000LL + (int64_t)k; /* needs all 8 bytes */
        p.kind[k] = (uint8_t)(k % 2);
        p.bclass[k] = (uint8_t)(k % 251);
    }
    size_t perm[N];
    for (size_t k = 0; k < N; k++)
        perm[k] = (k * 10 + 3) % N; /* 10 coprime to 37 */
    part_permute(&p, perm);
    for (size_t k = 0; k < N; k++) {
        size_t o = perm[k];
        for (int a = 0; a < nr; a++)
            assert_true((*r[a])[k] == (real)perm_val(a, o));
        assert_int_equal(p.id[k], 5000000000LL + (int64_t)o);
        assert_int_equal(p.kind[k], o % 2);
        assert_int_equal(p.bclass[k], o % 251);
    }
    assert_int_equal(p.n, N);
    part_free(&p);
}

/* ---- driver ------------------------------------------------------------------- */

/* After every test, so that a failed check on one rank (which skips the rest
 * of that test) cannot leave ranks out of step in later collectives. */
static int sync_ranks(void **state)
{
    (void)state;
    MPI_Barrier(MPI_COMM_WORLD);
    return 0;
}

static void make_dir_and_scene(void)
{
    if (g_rank == 0) {
        strcpy(g_dir, "/tmp/sphseg_test_io_XXXXXX");
        if (!mkdtemp(g_dir)) {
            perror("mkdtemp");
            MPI_Abort(MPI_COMM_WORLD, 1);
        }
    }
    MPI_Bcast(g_dir, sizeof g_dir, MPI_CHAR, 0, MPI_COMM_WORLD);
    size_t len = 100000, k = 0;
    g_scene = malloc(len + 1);
    const char *line = "# scene key: value  (units) \xc2\xb0 comment\n";
    for (; k + strlen(line) < len; k += strlen(line))
        memcpy(g_scene + k, line, strlen(line));
    g_scene[k] = 0;
}

static void remove_dir(void)
{
    if (g_rank != 0) return;
    DIR *d = opendir(g_dir);
    struct dirent *e;
    char path[600];
    while (d && (e = readdir(d))) {
        if (e->d_name[0] == '.') continue;
        snprintf(path, sizeof path, "%s/%s", g_dir, e->d_name);
        unlink(path);
    }
    if (d) closedir(d);
    rmdir(g_dir);
}

int main(int argc, char **argv)
{
    MPI_Init(&argc, &argv);
    MPI_Comm_rank(MPI_COMM_WORLD, &g_rank);
    MPI_Comm_size(MPI_COMM_WORLD, &g_size);
    make_dir_and_scene();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(test_part_alloc, sync_ranks),
        cmocka_unit_test_teardown(test_part_permute, sync_ranks),
        cmocka_unit_test_teardown(test_snapshot_roundtrip, sync_ranks),
        cmocka_unit_test_teardown(test_snapshot_empty_ranks, sync_ranks),
        cmocka_unit_test_teardown(test_snapshot_no_particles, sync_ranks),
        cmocka_unit_test_teardown(test_snapshot_overwrite, sync_ranks),
        cmocka_unit_test_teardown(test_xdmf, sync_ranks),
    };
    int failed = cmocka_run_group_tests(tests, NULL, NULL), any = 0;
    MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    if (!any) remove_dir(); /* keep the files of a failed run for inspection */
    free(g_scene);
    MPI_Finalize();
    return any ? 1 : 0;
}
