/* test_checkpoint.c — checkpoint round trip (src/output/checkpoint.c): every array of
 * the particle store, filled with bytes that are a function of (array, rank,
 * index) only, and every scalar and list of the run state are written with
 * ckpt_write and must come back bit-identical from ckpt_read, each rank its
 * own block (same rank count); a second write keeps the first as
 * checkpoint_prev.h5. A checkpoint whose NumRanks differs gives each rank an
 * even contiguous share of the global rows (the restart on another rank
 * count, before the distribution step); the directory gives its newest
 * checkpoint. Every one-bit flip in the seal is refused, a legacy seal
 * (check 0) is taken, a FIFO is refused at once. DEM grains (every rank
 * holding the same ones): every array of dem_state_get and the scalars
 * exch and steps come back bit-identical on every rank. Runs on any rank count:
 *   mpirun -np 2 ./test_checkpoint */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* mkdtemp */
#endif
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <hdf5.h>
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "output/checkpoint.h"
#include "mpi/comm.h"
#include "sim/stages.h"

static char g_dir[64];
static int g_rank, g_size;
/* The wall primitives of the container the rows refer to (setup_contexts
 * builds them in a run; ckpt_read refuses a wall id past them). */
enum { NWALLS = 7 };

/* Byte b of element i of array k on rank r: never the same pattern twice. */
static uint8_t ref_byte(size_t k, int r, size_t i, size_t b)
{
    return (uint8_t)(31 * k + 17 * (size_t)r + 7 * i + 3 * b + ((i * b) >> 2));
}

static void fill_store(particles_t *p, size_t n)
{
    part_alloc(p, 2, n);
    p->n = n;
    for (size_t k = 0; k < part_narrays(); ++k) {
        size_t es = part_array_esize(k);
        uint8_t *a = part_array_get(p, k);
        for (size_t i = 0; i < n; ++i)
            for (size_t b = 0; b < es; ++b) a[i * es + b] = ref_byte(k, g_rank, i, b);
    }
    for (size_t i = 0; i < n; ++i) { /* the arrays ckpt_read checks for range hold valid values */
        p->kind[i] = (uint8_t)(i % 3 == 0);
        p->wall[i] = (uint8_t)(p->kind[i] ? 1 + i % NWALLS : 0); /* a dummy has a wall, material none */
        p->bclass[i] = (uint8_t)(i % 6);
        p->id[i] = (int64_t)(1000 * g_rank + (int)i);
        p->vol[i] = (real)(1e-6 * (1 + (double)i));
        p->C[i] = (real)((double)(i % 11) / 10);
        for (int d = 0; d < 3; ++d) p->x[d][i] = p->X0[d][i] = p->v[d][i] = (real)(0.01 * (double)(i + d) - g_rank);
        for (int q = 0; q < 6; ++q) p->sig[q][i] = (real)(-100.0 * (double)(i + q));
    }
}

/* Array k is one fill_store sets to valid values (not ref_byte's pattern). */
static int is_checked(const particles_t *p, size_t k)
{
    const void *a = part_array_get(p, k);
    if (a == p->kind || a == p->bclass || a == p->wall || a == p->id || a == p->vol || a == p->C) return 1;
    for (int d = 0; d < 3; ++d)
        if (a == p->x[d] || a == p->X0[d] || a == p->v[d]) return 1;
    for (int q = 0; q < 6; ++q)
        if (a == p->sig[q]) return 1;
    return 0;
}

/* The seal of a sphseg checkpoint (src/output/checkpoint.h): sum of
 * mix(w_i + i * golden) over the little-endian words past the user block,
 * and the check of the seal's first six words, written again after the file
 * was changed on purpose. */
static uint64_t mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * UINT64_C(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94D049BB133111EB);
    return z ^ (z >> 31);
}

static void reseal(const char *path)
{
    FILE *f = fopen(path, "r+b");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long size = ftell(f);
    uint64_t h = 0, i = 0;
    unsigned char w[8], le[8];
    fseek(f, CKPT_USERBLOCK, SEEK_SET);
    for (size_t got; memset(w, 0, 8), (got = fread(w, 1, 8, f)) > 0;) {
        uint64_t v = 0;
        for (int b = 7; b >= 0; --b) v = v << 8 | w[b];
        h += mix64(v + ++i * UINT64_C(0x9E3779B97F4A7C15));
    }
    for (int b = 0; b < 8; ++b) le[b] = (unsigned char)((uint64_t)size >> (8 * b));
    fseek(f, 16, SEEK_SET);
    fwrite(le, 1, 8, f);
    for (int b = 0; b < 8; ++b) le[b] = (unsigned char)(h >> (8 * b));
    fwrite(le, 1, 8, f);
    unsigned char head[48];
    fseek(f, 0, SEEK_SET);
    assert_int_equal(fread(head, 1, 48, f), 48);
    uint64_t c = 0;
    for (int k = 0; k < 6; ++k) {
        uint64_t v = 0;
        for (int b = 7; b >= 0; --b) v = v << 8 | head[8 * k + b];
        c = mix64(c ^ (v + (uint64_t)(k + 1) * UINT64_C(0x9E3779B97F4A7C15)));
    }
    c = c ? c : 1;
    for (int b = 0; b < 8; ++b) le[b] = (unsigned char)(c >> (8 * b));
    fseek(f, 48, SEEK_SET);
    fwrite(le, 1, 8, f);
    fclose(f);
}

static void load_scene(struct scene *sc)
{
    char path[128], err[SCENE_ERRLEN];
    snprintf(path, sizeof path, "%s/scene.yml", g_dir);
    if (g_rank == 0) {
        FILE *f = fopen(path, "w");
        assert_non_null(f);
        fputs("Run:\n  t_end: 2.5\nGeometry:\n  dr: 0.002\nOutput:\n  dt: 0.5\nSegregation:\n"
              "  V: 1.0e-4\n  D: 1.0e-6\n", f);
        fclose(f);
    }
    MPI_Barrier(MPI_COMM_WORLD);
    assert_int_equal(scene_parse(sc, path, 0, NULL, err, sizeof err), 0);
}

/* The fixture of each test (cmocka setup and teardown): the scene, its
 * text as a checkpoint stores it, and two runs of it, a to write and b to
 * read back, freed after the test whether it passed or not. */
typedef struct ckpt_fx {
    struct scene sc;
    char *text;
    sim_t a, b;
} ckpt_fx;

static int fx_setup(void **state)
{
    ckpt_fx *f = calloc(1, sizeof *f);
    *state = f;
    if (!f) return -1;
    load_scene(&f->sc);
    f->a.sc = f->b.sc = &f->sc;
    f->a.flow.w.n = f->b.flow.w.n = NWALLS;
    f->text = scene_used_text(&f->sc);
    return 0;
}

static int fx_teardown(void **state)
{
    ckpt_fx *f = *state;
    part_free(&f->a.p);
    part_free(&f->b.p);
    dem_free(f->a.dem);
    dem_free(f->b.dem);
    free(f->text);
    scene_free(&f->sc);
    free(f);
    return 0;
}

static void test_round_trip(void **state)
{
    ckpt_fx *f = *state;
    size_t n = 50 + 13 * (size_t)g_rank; /* unequal blocks */
    fill_store(&f->a.p, n);
    f->a.t = 1.2345678901234567, f->a.step = 4242, f->a.dt = 3.3e-5, f->a.amax = 98.765;
    double times[3] = {0, 0.5, 1.0};
    long long npart[3] = {100, 101, 102};
    ckpt_run ra = {.small0 = 1.5e-3, .max_drift = 2.5e-15, .warned = 1, .nsnap = 3, .times = times, .npart = npart};
    ckpt_run rb = {0};
    ckpt_write(g_dir, &f->a, &ra, f->text);
    f->a.step = 4243;
    ckpt_write(g_dir, &f->a, &ra, f->text); /* the first becomes checkpoint_prev.h5 */
    char prev[128], cur[128];
    snprintf(prev, sizeof prev, "%s/checkpoint_prev.h5", g_dir);
    snprintf(cur, sizeof cur, "%s/checkpoint.h5", g_dir);
    assert_int_equal(access(prev, R_OK), 0);

    char chosen[256];
    ckpt_read(cur, &f->b, &rb, chosen, sizeof chosen);
    assert_int_equal(f->b.p.n, n);
    /* the reader holds its run's fields (stage_store_fields), each restored exactly; the others NULL */
    const uint32_t held = stage_store_fields(stage_flags(&f->b));
    assert_int_equal(f->b.p.fields, held);
    for (size_t k = 0; k < part_narrays(); ++k) {
        if (!(held >> part_array_field(k) & 1)) {
            assert_null(part_array_get(&f->b.p, k));
            continue;
        }
        assert_memory_equal(part_array_get(&f->b.p, k), part_array_get(&f->a.p, k), n * part_array_esize(k));
    }
    assert_memory_equal(&f->b.t, &f->a.t, sizeof f->a.t);
    assert_memory_equal(&f->b.dt, &f->a.dt, sizeof f->a.dt);
    assert_memory_equal(&f->b.amax, &f->a.amax, sizeof f->a.amax);
    assert_int_equal(f->b.step, 4243);
    /* kind 1 (dummy) at i % 3 == 0; n_material counts all ranks */
    assert_int_equal(f->b.n_material, comm_sum_ll((long long)(n - (n + 2) / 3)));
    assert_memory_equal(&rb.small0, &ra.small0, sizeof ra.small0);
    assert_memory_equal(&rb.max_drift, &ra.max_drift, sizeof ra.max_drift);
    assert_int_equal(rb.warned, 1);
    assert_int_equal(rb.nsnap, 3);
    assert_memory_equal(rb.times, times, sizeof times);
    assert_memory_equal(rb.npart, npart, sizeof npart);

    sim_t c = {0};
    ckpt_run rc = {0};
    c.sc = &f->sc;
    c.flow.w.n = NWALLS;
    ckpt_read(prev, &c, &rc, chosen, sizeof chosen);
    assert_int_equal(c.step, 4242);
    sim_t e = {0}; /* the directory: its newest valid checkpoint */
    ckpt_run re = {0};
    e.sc = &f->sc;
    e.flow.w.n = NWALLS;
    ckpt_read(g_dir, &e, &re, chosen, sizeof chosen);
    assert_int_equal(e.step, 4243);
    assert_string_equal(chosen, cur);
    ckpt_run_free(&re);
    part_free(&e.p);
    ckpt_run_free(&rb);
    ckpt_run_free(&rc);
    part_free(&c.p);
}

/* DEM grains (src/dem/dem.h): n of them, the same on every rank (they are
 * replicated), every array of the state filled with values of (array,
 * index) that the reader's checks take: IDs 0..n-1, contact counts within
 * DEM_CMAX, partners another grain or one of the NWALLS walls; the entries
 * past a grain's count (never read) hold anything. */
static void fill_grains(dem_t *d)
{
    const size_t n = d->n;
    for (size_t k = 0; k < DEM_STATE_NARRAYS; ++k) {
        dem_state_array a = dem_state_get(d, k);
        for (size_t i = 0; i < n * a.per; ++i) {
            if (a.is_double) ((double *)a.a)[i] = (double)(k + 1) * 1e-3 * (double)i - 0.5 / (double)(k + 1);
            else if (a.esize == 8) ((int64_t *)a.a)[i] = (int64_t)(1000 * k + i);
        }
    }
    for (size_t i = 0; i < n; ++i) {
        d->id[i] = (int64_t)i;
        d->ncon[i] = (int)(i % (DEM_CMAX + 1));
        for (int c = 0; c < d->ncon[i]; ++c) /* a wall, then the other grains */
            d->cid[i * DEM_CMAX + (size_t)c] =
                c == 0 ? -1 - (int64_t)(i % NWALLS) : (int64_t)((i + (size_t)c) % n);
    }
    d->exch[0] = 1.25e-3, d->exch[1] = -7.5e-4, d->exch[2] = 3.0e-17;
    d->steps = 123456789;
}

static void test_dem_round_trip(void **state)
{
    ckpt_fx *f = *state;
    const size_t n = 37;
    fill_store(&f->a.p, 10 + (size_t)g_rank);
    f->a.t = 0.5, f->a.step = 77;
    f->a.dem = dem_alloc(n);
    fill_grains(f->a.dem);
    f->b.dem = dem_alloc(n); /* as setup_contexts makes it from the scene: at rest */
    ckpt_run ra = {0}, rb = {0};
    ckpt_write(g_dir, &f->a, &ra, f->text);
    char path[128], chosen[256];
    snprintf(path, sizeof path, "%s/checkpoint.h5", g_dir);
    ckpt_read(path, &f->b, &rb, chosen, sizeof chosen);
    for (size_t k = 0; k < DEM_STATE_NARRAYS; ++k) {
        dem_state_array a = dem_state_get(f->a.dem, k), b = dem_state_get(f->b.dem, k);
        assert_string_equal(a.name, b.name);
        assert_memory_equal(b.a, a.a, n * a.per * a.esize);
    }
    assert_memory_equal(f->b.dem->exch, f->a.dem->exch, sizeof f->a.dem->exch);
    assert_int_equal(f->b.dem->steps, 123456789);
    ckpt_run_free(&rb);
}

/* Rank 0 xors byte k of path with x (then all ranks meet). */
static void xor_byte(const char *path, long k, unsigned char x)
{
    if (g_rank == 0) {
        FILE *f = fopen(path, "r+b");
        assert_non_null(f);
        fseek(f, k, SEEK_SET);
        int c = fgetc(f);
        assert_true(c != EOF);
        fseek(f, k, SEEK_SET);
        fputc(c ^ x, f);
        fclose(f);
    }
    MPI_Barrier(MPI_COMM_WORLD);
}

/* The seal checks itself (issue 33): every one-bit flip in its 64 bytes is
 * refused (a flipped step chose the wrong checkpoint); a legacy seal (check
 * word 0) is taken; a FIFO is refused at once, not opened for a read that
 * waits for a writer. */
static void test_seal_bits(void **state)
{
    ckpt_fx *f = *state;
    fill_store(&f->a.p, 5 + (size_t)g_rank);
    f->a.t = 0.75, f->a.step = 10;
    ckpt_run ra = {0};
    char path[128], why[600], fifo[128];
    ckpt_write(g_dir, &f->a, &ra, f->text);
    snprintf(path, sizeof path, "%s/checkpoint.h5", g_dir);
    ckpt_seal seal;
    assert_int_equal(ckpt_verify(path, &seal, why, sizeof why), 0);
    assert_int_equal(seal.step, 10);
    int taken = 0;
    for (long bit = 0; bit < 64 * 8; ++bit) {
        xor_byte(path, bit / 8, (unsigned char)(1u << (bit % 8)));
        if (ckpt_verify(path, &seal, why, sizeof why) == 0) ++taken, print_message("bit %ld taken\n", bit);
        else if (bit >= 64) assert_non_null(strstr(why, "checksum block is corrupted")); /* past the magic */
        xor_byte(path, bit / 8, (unsigned char)(1u << (bit % 8)));
    }
    assert_int_equal(taken, 0);
    if (g_rank == 0) { /* a legacy seal: check word 0 */
        FILE *f = fopen(path, "r+b");
        assert_non_null(f);
        fseek(f, 48, SEEK_SET);
        for (int k = 0; k < 8; ++k) fputc(0, f);
        fclose(f);
    }
    MPI_Barrier(MPI_COMM_WORLD);
    assert_int_equal(ckpt_verify(path, &seal, why, sizeof why), 0);
    assert_int_equal(seal.step, 10);
    snprintf(fifo, sizeof fifo, "%s/fifo.h5", g_dir);
    if (g_rank == 0) assert_int_equal(mkfifo(fifo, 0600), 0);
    MPI_Barrier(MPI_COMM_WORLD);
    assert_int_equal(ckpt_verify(fifo, &seal, why, sizeof why), 1);
    assert_string_equal(why, "not a regular file");
    if (g_rank == 0) unlink(fifo);
}

/* Rank 0 sets the Header attribute NumRanks of path to nranks, gives
 * /Particles/RankCounts nranks entries (the blocks of 20 + 7 r particles
 * this test writes, then empty ones) and seals the file again. */
static void set_nranks(const char *path, long long nranks)
{
    if (g_rank == 0) {
        hid_t f = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
        assert_true(f >= 0);
        hid_t g = H5Gopen2(f, "Header", H5P_DEFAULT), sp = H5Screate(H5S_SCALAR);
        assert_true(H5Adelete(g, "NumRanks") >= 0); /* H5Awrite in place fails here (HDF5 1.10.8) */
        hid_t a = H5Acreate2(g, "NumRanks", H5T_STD_I64LE, sp, H5P_DEFAULT, H5P_DEFAULT);
        int64_t v = nranks;
        assert_true(H5Awrite(a, H5T_NATIVE_INT64, &v) >= 0);
        H5Aclose(a);
        H5Sclose(sp);
        H5Gclose(g);
        g = H5Gopen2(f, "Particles", H5P_DEFAULT);
        assert_true(H5Ldelete(g, "RankCounts", H5P_DEFAULT) >= 0);
        hsize_t len = (hsize_t)nranks;
        int64_t *counts = calloc(len, sizeof *counts);
        for (int r = 0; r < g_size && r < nranks; ++r) counts[r] = 20 + 7 * r;
        hid_t sp1 = H5Screate_simple(1, &len, NULL);
        hid_t d = H5Dcreate2(g, "RankCounts", H5T_STD_I64LE, sp1, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
        assert_true(H5Dwrite(d, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, counts) >= 0);
        free(counts);
        H5Dclose(d);
        H5Sclose(sp1);
        H5Gclose(g);
        H5Fclose(f);
        reseal(path);
    }
    MPI_Barrier(MPI_COMM_WORLD);
}

static void test_other_rank_count(void **state)
{
    ckpt_fx *f = *state;
    fill_store(&f->a.p, 20 + 7 * (size_t)g_rank);
    ckpt_run ra = {0}, rb = {0};
    char path[128];
    ckpt_write(g_dir, &f->a, &ra, f->text);
    snprintf(path, sizeof path, "%s/checkpoint.h5", g_dir);
    set_nranks(path, g_size + 1);
    char chosen[256];
    ckpt_read(path, &f->b, &rb, chosen, sizeof chosen);
    long long ntot = 0, share = 0;
    for (int r = 0; r < g_size; ++r) ntot += 20 + 7 * r;
    long long q = ntot / g_size, rem = ntot % g_size, first = g_rank * q + (g_rank < rem ? g_rank : rem);
    share = q + (g_rank < rem);
    assert_int_equal(f->b.p.n, share);
    for (long long j = 0; j < share; ++j) { /* global row first + j: which rank wrote it, where */
        long long row = first + j;
        int r = 0;
        while (row >= 20 + 7 * r) row -= 20 + 7 * r++;
        for (size_t k = 0; k < part_narrays(); ++k) {
            size_t es = part_array_esize(k);
            if (!part_array_get(&f->b.p, k)) continue; /* a field the reader's run does not hold */
            const uint8_t *got = (const uint8_t *)part_array_get(&f->b.p, k) + (size_t)j * es;
            if (is_checked(&f->b.p, k)) continue; /* set apart by fill_store */
            for (size_t by = 0; by < es; ++by) assert_int_equal(got[by], ref_byte(k, r, (size_t)row, by));
        }
    }
    ckpt_run_free(&rb);
}

int main(int argc, char **argv)
{
    MPI_Init(&argc, &argv);
    MPI_Comm_rank(MPI_COMM_WORLD, &g_rank);
    MPI_Comm_size(MPI_COMM_WORLD, &g_size);
    if (g_rank == 0) {
        snprintf(g_dir, sizeof g_dir, "/tmp/sphseg_ckpt_XXXXXX");
        if (!mkdtemp(g_dir)) MPI_Abort(MPI_COMM_WORLD, 1);
    }
    MPI_Bcast(g_dir, sizeof g_dir, MPI_CHAR, 0, MPI_COMM_WORLD);
    const struct CMUnitTest tests[] = {cmocka_unit_test_setup_teardown(test_round_trip, fx_setup, fx_teardown),
                                       cmocka_unit_test_setup_teardown(test_other_rank_count, fx_setup, fx_teardown),
                                       cmocka_unit_test_setup_teardown(test_seal_bits, fx_setup, fx_teardown),
                                       cmocka_unit_test_setup_teardown(test_dem_round_trip, fx_setup,
                                                                       fx_teardown)};
    int failed = cmocka_run_group_tests(tests, NULL, NULL), any = 0;
    MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    if (!any && g_rank == 0) {
        char cmd[128];
        snprintf(cmd, sizeof cmd, "rm -rf %s", g_dir);
        if (system(cmd) != 0) fprintf(stderr, "cannot remove %s\n", g_dir);
    }
    MPI_Finalize();
    return any;
}
