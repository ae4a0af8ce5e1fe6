/* checkpoint.c — full-state checkpoints and restarts (see checkpoint.h). */
#include "checkpoint.h"
#include <errno.h>
#include <hdf5.h>
#include <mpi.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
/* hdf5.h's H5F_ACC_* flags use its own H5CHECK, whose name error.h takes over
 * (error.h): read the flag before error.h comes in. */
static unsigned ckpt_acc_rdonly(void) { return H5F_ACC_RDONLY; }
#include "diag.h"
#include "error.h"
#include "io.h"
#include "mpi/comm.h"
#include "version.h"

#define CKPT_PATH_MAX 4200

static const char *ckpt_precision(void) { return sizeof(real) == sizeof(float) ? "single" : "double"; }

/* Raw element types by size: the bytes go to the file unconverted. */
static hid_t ckpt_raw_file(size_t esize)
{
    return esize == 1 ? H5T_STD_U8LE : esize == 2 ? H5T_STD_U16LE : esize == 4 ? H5T_STD_U32LE : H5T_STD_U64LE;
}

static hid_t ckpt_raw_mem(size_t esize)
{
    return esize == 1   ? H5T_NATIVE_UINT8
           : esize == 2 ? H5T_NATIVE_UINT16
           : esize == 4 ? H5T_NATIVE_UINT32
                        : H5T_NATIVE_UINT64;
}

static void ckpt_attr_double(hid_t loc, const char *name, double v)
{
    io_attr_scalar(loc, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &v);
}

static void ckpt_attr_int64(hid_t loc, const char *name, long long v)
{
    int64_t w = v;
    io_attr_scalar(loc, name, H5T_STD_I64LE, H5T_NATIVE_INT64, &w);
}

/* Rows [start, start + count) of fspace (none when count is 0, mspace too:
 * the rank still takes part); returns a collective transfer list. */
static hid_t ckpt_select_rows(hid_t fspace, hid_t mspace, hsize_t start, hsize_t count)
{
    hid_t dxpl;
    H5CHECK(dxpl = H5Pcreate(H5P_DATASET_XFER));
    H5CHECK(H5Pset_dxpl_mpio(dxpl, H5FD_MPIO_COLLECTIVE));
    if (count > 0) {
        H5CHECK(H5Sselect_hyperslab(fspace, H5S_SELECT_SET, &start, NULL, &count, NULL));
    } else {
        H5CHECK(H5Sselect_none(fspace));
        H5CHECK(H5Sselect_none(mspace));
    }
    return dxpl;
}

/* ---- writing ---------------------------------------------------------------- */

/* A 1D dataset of ntot rows of mtype (file type ftype); this rank writes its n
 * rows at offset collectively (n = 0: takes part with an empty selection). */
static hid_t ckpt_write_rows(hid_t loc, const char *name, hid_t ftype, hid_t mtype, const void *buf,
                             long long n, long long ntot, long long offset)
{
    hsize_t dims = (hsize_t)ntot, mdims = n > 0 ? (hsize_t)n : 1, start = (hsize_t)offset, count = (hsize_t)n;
    hid_t fspace, mspace, dset, dxpl;
    H5CHECK(fspace = H5Screate_simple(1, &dims, NULL));
    H5CHECK(mspace = H5Screate_simple(1, &mdims, NULL));
    H5CHECK(dset = H5Dcreate2(loc, name, ftype, fspace, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    dxpl = ckpt_select_rows(fspace, mspace, start, count);
    if (ntot > 0) H5CHECK(H5Dwrite(dset, mtype, mspace, fspace, dxpl, buf));
    H5CHECK(H5Pclose(dxpl));
    H5CHECK(H5Sclose(mspace));
    H5CHECK(H5Sclose(fspace));
    return dset;
}

static void ckpt_write_header(hid_t file, const sim_t *s, long long ntot, const char *scene_text)
{
    hid_t g;
    H5CHECK(g = H5Gcreate2(file, "Header", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    io_attr_string(g, "Code", "sphseg");
    io_attr_string(g, "Version", SPHSEG_VERSION);
    ckpt_attr_int64(g, "Checkpoint", 1);
    io_attr_string(g, "Precision", ckpt_precision());
    ckpt_attr_int64(g, "RealBytes", (long long)sizeof(real));
    ckpt_attr_int64(g, "Dimension", s->p.dim);
    ckpt_attr_int64(g, "NumRanks", comm_size());
    ckpt_attr_int64(g, "NumPart_Total", ntot);
    ckpt_attr_int64(g, "NumArrays", (long long)part_narrays());
    ckpt_attr_double(g, "Time", s->t);
    ckpt_attr_int64(g, "Step", s->step);
    ckpt_attr_double(g, "Dt", s->dt);
    ckpt_attr_double(g, "Amax", s->amax);
    ckpt_attr_int64(g, "WindowSteps", s->win.k); /* the open concentration window (sim.h) */
    ckpt_attr_int64(g, "WindowTarget", s->win.K);
    ckpt_attr_double(g, "WindowLength", s->win.T);
    io_attr_string(g, "Scene", scene_text);
    H5CHECK(H5Gclose(g));
}

/* /Diagnostics and /Outputs: the same on every rank; rank 0 writes the rows. */
static void ckpt_write_run(hid_t file, const ckpt_run *r)
{
    hid_t g, d;
    H5CHECK(g = H5Gcreate2(file, "Diagnostics", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    ckpt_attr_double(g, "SmallVolume0", r->small0);
    ckpt_attr_double(g, "MaxDrift", r->max_drift);
    ckpt_attr_int64(g, "Warned", r->warned);
    H5CHECK(H5Gclose(g));
    H5CHECK(g = H5Gcreate2(file, "Outputs", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    ckpt_attr_int64(g, "Count", r->nsnap);
    long long n0 = comm_rank() == 0 ? r->nsnap : 0;
    H5CHECK(d = ckpt_write_rows(g, "Times", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, r->times, n0, r->nsnap, 0));
    H5CHECK(H5Dclose(d));
    H5CHECK(d = ckpt_write_rows(g, "NumPart", H5T_STD_I64LE, H5T_NATIVE_LLONG, r->npart, n0, r->nsnap, 0));
    H5CHECK(H5Dclose(d));
    H5CHECK(H5Gclose(g));
}

/* /Decomposition: the cut of a multi-rank run; rank 0 writes the rows. */
static void ckpt_write_decomp(hid_t file, const halo_t *h)
{
    if (!h) return;
    hid_t g, d;
    long long nv = h->method == HALO_METIS ? (long long)h->cg_n[0] * h->cg_n[1] * h->cg_n[2] : 0;
    int r0 = comm_rank() == 0;
    H5CHECK(g = H5Gcreate2(file, "Decomposition", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    ckpt_attr_int64(g, "Method", h->method);
    ckpt_attr_int64(g, "Axis", h->axis);
    ckpt_attr_int64(g, "CoarseCellWidth", h->blk);
    for (int k = 0; k < 3; ++k) {
        char name[16];
        snprintf(name, sizeof name, "CoarseCells%d", k);
        ckpt_attr_int64(g, name, h->cg_n[k]);
    }
    H5CHECK(d = ckpt_write_rows(g, "Bounds", H5T_STD_I64LE, H5T_NATIVE_LONG, h->bound, r0 ? h->size + 1 : 0,
                                h->size + 1, 0));
    H5CHECK(H5Dclose(d));
    H5CHECK(d = ckpt_write_rows(g, "Owners", H5T_STD_I32LE, H5T_NATIVE_INT, h->part, r0 ? nv : 0, nv, 0));
    H5CHECK(H5Dclose(d));
    H5CHECK(H5Gclose(g));
}

/* /Particles: RankCounts, then every array of the store, raw. */
static void ckpt_write_particles(hid_t file, const particles_t *p, long long ntot, long long offset)
{
    int size = comm_size(), rank = comm_rank();
    long long n = (long long)p->n, *counts = malloc((size_t)size * sizeof *counts);
    if (!counts) error_exit(1, "out of memory writing a checkpoint");
    MPICHECK(MPI_Allgather(&n, 1, MPI_LONG_LONG, counts, 1, MPI_LONG_LONG, MPI_COMM_WORLD));
    hid_t g, d;
    H5CHECK(g = H5Gcreate2(file, "Particles", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    H5CHECK(d = ckpt_write_rows(g, "RankCounts", H5T_STD_I64LE, H5T_NATIVE_LLONG, counts, rank == 0 ? size : 0,
                                size, 0));
    H5CHECK(H5Dclose(d));
    for (size_t k = 0; k < part_narrays(); ++k) {
        char name[24];
        size_t es = part_array_esize(k);
        snprintf(name, sizeof name, "%02zu", k);
        H5CHECK(d = ckpt_write_rows(g, name, ckpt_raw_file(es), ckpt_raw_mem(es), part_array_get(p, k), n, ntot,
                                    offset));
        ckpt_attr_int64(d, "ElementBytes", (long long)es);
        H5CHECK(H5Dclose(d));
    }
    H5CHECK(H5Gclose(g));
    free(counts);
}

/* Rank 0: checkpoint.h5 -> checkpoint_prev.h5, tmp -> checkpoint.h5, between
 * barriers; at every moment one complete checkpoint exists under a final name
 * (DESIGN.md "Errors": no half-written file under a final name). */
static void ckpt_commit(const char *outdir, const char *tmp)
{
    char path[CKPT_PATH_MAX], prev[CKPT_PATH_MAX];
    snprintf(path, sizeof path, "%s/checkpoint.h5", outdir);
    snprintf(prev, sizeof prev, "%s/checkpoint_prev.h5", outdir);
    MPICHECK(MPI_Barrier(MPI_COMM_WORLD));
    if (comm_rank() == 0) {
        if (rename(path, prev) != 0 && errno != ENOENT)
            error_exit(1, "cannot rename %s to %s: %s", path, prev, strerror(errno));
        if (rename(tmp, path) != 0) error_exit(1, "cannot rename %s to %s: %s", tmp, path, strerror(errno));
    }
    MPICHECK(MPI_Barrier(MPI_COMM_WORLD));
}

double ckpt_write(const char *outdir, const sim_t *s, const ckpt_run *r, const char *scene_text)
{
    double w0 = diag_wall();
    char tmp[CKPT_PATH_MAX];
    if (snprintf(tmp, sizeof tmp, "%s/checkpoint.h5.tmp", outdir) >= (int)sizeof tmp)
        error_exit(1, "output path too long: %s", outdir);
    long long n = (long long)s->p.n, ntot = 0, offset = 0;
    MPICHECK(MPI_Allreduce(&n, &ntot, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD));
    MPICHECK(MPI_Exscan(&n, &offset, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD));
    if (comm_rank() == 0) offset = 0; /* MPI_Exscan leaves rank 0's result undefined */
    hid_t file = io_create_file(tmp);
    ckpt_write_header(file, s, ntot, scene_text);
    ckpt_write_run(file, r);
    ckpt_write_decomp(file, s->halo);
    ckpt_write_particles(file, &s->p, ntot, offset);
    H5CHECK(H5Fclose(file));
    ckpt_commit(outdir, tmp);
    return diag_wall() - w0;
}

/* ---- reading ---------------------------------------------------------------- */

/* Bad restart files are bad input: exit 2 on every rank, one line naming the
 * file (every rank reads the same file and finds the same problem). */
static void ckpt_bad(const char *file, const char *fmt, ...) __attribute__((format(printf, 2, 3), noreturn));
static void ckpt_bad(const char *file, const char *fmt, ...)
{
    char why[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(why, sizeof why, fmt, ap);
    va_end(ap);
    input_error("--restart %s: %s", file, why);
}

/* A header attribute that must exist (else the file is not a checkpoint). */
static void ckpt_need(const char *file, hid_t g, const char *name)
{
    htri_t e;
    H5CHECK(e = H5Aexists(g, name));
    if (!e) ckpt_bad(file, "not a sphseg checkpoint (no attribute %s; a snapshot?)", name);
}

/* A scalar attribute read as type (H5T_NATIVE_DOUBLE or H5T_NATIVE_INT64) into out. */
static void ckpt_get_attr(const char *file, hid_t g, const char *name, hid_t type, void *out)
{
    hid_t a;
    ckpt_need(file, g, name);
    H5CHECK(a = H5Aopen(g, name, H5P_DEFAULT));
    H5CHECK(H5Aread(a, type, out));
    H5CHECK(H5Aclose(a));
}

static double ckpt_get_double(const char *file, hid_t g, const char *name)
{
    double v;
    ckpt_get_attr(file, g, name, H5T_NATIVE_DOUBLE, &v);
    return v;
}

static long long ckpt_get_int(const char *file, hid_t g, const char *name)
{
    int64_t v;
    ckpt_get_attr(file, g, name, H5T_NATIVE_INT64, &v);
    return v;
}

/* A variable-length string attribute, malloc'd. */
static char *ckpt_get_string(const char *file, hid_t g, const char *name)
{
    hid_t a, type;
    char *v = NULL;
    ckpt_need(file, g, name);
    H5CHECK(type = H5Tcopy(H5T_C_S1));
    H5CHECK(H5Tset_size(type, H5T_VARIABLE));
    H5CHECK(H5Tset_cset(type, H5T_CSET_UTF8));
    H5CHECK(a = H5Aopen(g, name, H5P_DEFAULT));
    H5CHECK(H5Aread(a, type, &v));
    char *copy = strdup(v ? v : "");
    H5CHECK(H5free_memory(v));
    H5CHECK(H5Aclose(a));
    H5CHECK(H5Tclose(type));
    if (!copy) error_exit(1, "out of memory reading %s", file);
    return copy;
}

/* Open file read-only with MPI-IO; a missing or non-HDF5 file is bad input. */
static hid_t ckpt_open(const char *file)
{
    if (access(file, R_OK) != 0) ckpt_bad(file, "cannot read it: %s", strerror(errno));
    hid_t fapl, f;
    H5CHECK(fapl = H5Pcreate(H5P_FILE_ACCESS));
    H5CHECK(H5Pset_fapl_mpio(fapl, MPI_COMM_WORLD, MPI_INFO_NULL));
    H5CHECK(H5Pset_all_coll_metadata_ops(fapl, 1));
    H5E_auto2_t fn;
    void *data;
    H5CHECK(H5Eget_auto2(H5E_DEFAULT, &fn, &data));
    H5CHECK(H5Eset_auto2(H5E_DEFAULT, NULL, NULL)); /* our message, not HDF5's stack */
    f = H5Fopen(file, ckpt_acc_rdonly(), fapl);
    H5CHECK(H5Eset_auto2(H5E_DEFAULT, fn, data));
    H5CHECK(H5Pclose(fapl));
    if (f < 0) ckpt_bad(file, "not an HDF5 file (or a damaged one)");
    htri_t e;
    H5CHECK(e = H5Lexists(f, "Header", H5P_DEFAULT));
    if (!e) ckpt_bad(file, "not a sphseg checkpoint (no /Header group)");
    return f;
}

/* The first line where the stored scene and this run's differ, into buf. */
static int ckpt_scene_diff(const char *a, const char *b, char *buf, size_t n)
{
    while (*a || *b) {
        size_t la = strcspn(a, "\n"), lb = strcspn(b, "\n");
        if (la != lb || strncmp(a, b, la)) {
            snprintf(buf, n, "'%.*s' (checkpoint) vs '%.*s' (now)", (int)la, a, (int)lb, b);
            return 1;
        }
        a += la + (a[la] != 0);
        b += lb + (b[lb] != 0);
    }
    return 0;
}

/* Check what must match this build and scene (exit 2), warn on a new scene. */
static void ckpt_check_header(const char *file, hid_t g, const sim_t *s)
{
    ckpt_need(file, g, "Checkpoint");
    char *prec = ckpt_get_string(file, g, "Precision");
    if (strcmp(prec, ckpt_precision()) != 0 || ckpt_get_int(file, g, "RealBytes") != (long long)sizeof(real))
        ckpt_bad(file, "written by a %s-precision build; this build is %s precision (rebuild with "
                 "PRECISION=%s)", prec, ckpt_precision(), prec);
    free(prec);
    long long dim = ckpt_get_int(file, g, "Dimension");
    if (dim != (long long)s->sc->geometry.dim)
        ckpt_bad(file, "holds a %lldD run; the scene %s is %uD", dim, s->sc->path, s->sc->geometry.dim);
    if (ckpt_get_int(file, g, "NumArrays") != (long long)part_narrays())
        ckpt_bad(file, "its particle store has %lld arrays, this build's %zu: written by another version "
                 "of sphseg", ckpt_get_int(file, g, "NumArrays"), part_narrays());
    char *stored = ckpt_get_string(file, g, "Scene"), *now = scene_used_text(s->sc), diff[600];
    if (ckpt_scene_diff(stored, now, diff, sizeof diff) && comm_rank() == 0)
        warning("--restart %s: the scene differs from the checkpoint's, first at %s; continuing with "
                "the scene as it is now", file, diff);
    free(stored);
    free(now);
}

/* Read rows [offset, offset + n) of the 1D dataset name into buf (mtype),
 * collectively; returns the dataset's length. */
static long long ckpt_read_rows(const char *file, hid_t loc, const char *name, hid_t mtype, void *buf,
                                long long n, long long offset)
{
    htri_t e;
    H5CHECK(e = H5Lexists(loc, name, H5P_DEFAULT));
    if (!e) ckpt_bad(file, "not a sphseg checkpoint (dataset %s missing)", name);
    hid_t dset, fspace, mspace, dxpl;
    hsize_t len, mdims = n > 0 ? (hsize_t)n : 1, start = (hsize_t)offset, count = (hsize_t)n;
    H5CHECK(dset = H5Dopen2(loc, name, H5P_DEFAULT));
    H5CHECK(fspace = H5Dget_space(dset));
    H5CHECK(H5Sget_simple_extent_dims(fspace, &len, NULL));
    if (offset + n > (long long)len) ckpt_bad(file, "dataset %s is too short", name);
    H5CHECK(mspace = H5Screate_simple(1, &mdims, NULL));
    dxpl = ckpt_select_rows(fspace, mspace, start, count);
    if (len > 0) H5CHECK(H5Dread(dset, mtype, mspace, fspace, dxpl, buf));
    H5CHECK(H5Pclose(dxpl));
    H5CHECK(H5Sclose(mspace));
    H5CHECK(H5Sclose(fspace));
    H5CHECK(H5Dclose(dset));
    return (long long)len;
}

/* This rank's rows: its own block on the same rank count, else an even
 * contiguous share of all rows. */
static void ckpt_my_rows(const char *file, hid_t g, int nranks_file, long long ntot, long long *n,
                         long long *offset)
{
    int size = comm_size(), rank = comm_rank();
    if (nranks_file == size) {
        long long *counts = malloc((size_t)size * sizeof *counts), sum = 0;
        if (!counts) error_exit(1, "out of memory reading %s", file);
        if (ckpt_read_rows(file, g, "RankCounts", H5T_NATIVE_LLONG, counts, size, 0) != size)
            ckpt_bad(file, "RankCounts does not have NumRanks = %d entries", size);
        for (int r = 0; r < size; ++r) sum += counts[r];
        if (sum != ntot) ckpt_bad(file, "RankCounts sum to %lld, NumPart_Total is %lld", sum, ntot);
        *offset = 0;
        for (int r = 0; r < rank; ++r) *offset += counts[r];
        *n = counts[rank];
        free(counts);
        return;
    }
    long long q = ntot / size, rem = ntot % size;
    *n = q + (rank < rem);
    *offset = rank * q + (rank < rem ? rank : rem);
}

/* Every array of the store, raw, this rank's rows. */
static void ckpt_read_particles(const char *file, hid_t f, sim_t *s, int dim, long long ntot, int nranks_file)
{
    hid_t g;
    long long n, offset;
    H5CHECK(g = H5Gopen2(f, "Particles", H5P_DEFAULT));
    ckpt_my_rows(file, g, nranks_file, ntot, &n, &offset);
    part_alloc(&s->p, dim, (size_t)n);
    s->p.n = (size_t)n;
    for (size_t k = 0; k < part_narrays(); ++k) {
        char name[24];
        size_t es = part_array_esize(k);
        snprintf(name, sizeof name, "%02zu", k);
        hid_t d;
        H5CHECK(d = H5Dopen2(g, name, H5P_DEFAULT));
        if (ckpt_get_int(file, d, "ElementBytes") != (long long)es)
            ckpt_bad(file, "particle array %s has %lld-byte elements, this build's %zu: written by another "
                     "version of sphseg", name, ckpt_get_int(file, d, "ElementBytes"), es);
        H5CHECK(H5Dclose(d));
        if (ckpt_read_rows(file, g, name, ckpt_raw_mem(es), part_array_get(&s->p, k), n, offset) != ntot)
            ckpt_bad(file, "particle array %s does not have NumPart_Total = %lld rows", name, ntot);
    }
    H5CHECK(H5Gclose(g));
    long long nm = 0;
    for (size_t i = 0; i < s->p.n; ++i) nm += s->p.kind[i] == KIND_MATERIAL;
    s->n_material = (size_t)comm_sum_ll(nm);
}

static void ckpt_read_run(const char *file, hid_t f, ckpt_run *r)
{
    hid_t g;
    H5CHECK(g = H5Gopen2(f, "Diagnostics", H5P_DEFAULT));
    r->small0 = ckpt_get_double(file, g, "SmallVolume0");
    r->max_drift = ckpt_get_double(file, g, "MaxDrift");
    r->warned = (int)ckpt_get_int(file, g, "Warned");
    H5CHECK(H5Gclose(g));
    H5CHECK(g = H5Gopen2(f, "Outputs", H5P_DEFAULT));
    r->nsnap = (int)ckpt_get_int(file, g, "Count");
    size_t m = (size_t)(r->nsnap > 0 ? r->nsnap : 1);
    r->times = malloc(m * sizeof *r->times);
    r->npart = malloc(m * sizeof *r->npart);
    if (!r->times || !r->npart) error_exit(1, "out of memory reading %s", file);
    if (ckpt_read_rows(file, g, "Times", H5T_NATIVE_DOUBLE, r->times, r->nsnap, 0) != r->nsnap ||
        ckpt_read_rows(file, g, "NumPart", H5T_NATIVE_LLONG, r->npart, r->nsnap, 0) != r->nsnap)
        ckpt_bad(file, "/Outputs does not have Count = %d rows", r->nsnap);
    H5CHECK(H5Gclose(g));
}

/* The decomposition, when the checkpoint has one and this run has its
 * rank count. */
static void ckpt_read_decomp(const char *file, hid_t f, int nranks, ckpt_run *r)
{
    htri_t e;
    H5CHECK(e = H5Lexists(f, "Decomposition", H5P_DEFAULT));
    if (!e || nranks != comm_size()) return;
    hid_t g;
    H5CHECK(g = H5Gopen2(f, "Decomposition", H5P_DEFAULT));
    r->dec_method = (int)ckpt_get_int(file, g, "Method");
    r->dec_axis = (int)ckpt_get_int(file, g, "Axis");
    htri_t has_blk;
    H5CHECK(has_blk = H5Aexists(g, "CoarseCellWidth"));
    r->dec_blk = has_blk ? (int)ckpt_get_int(file, g, "CoarseCellWidth") : HALO_DEPTH;
    long long nv = 1;
    for (int k = 0; k < 3; ++k) {
        char name[16];
        snprintf(name, sizeof name, "CoarseCells%d", k);
        r->dec_cg[k] = (int)ckpt_get_int(file, g, name);
        nv *= r->dec_cg[k];
    }
    if (r->dec_method != HALO_METIS) nv = 0;
    r->dec_bound = malloc(((size_t)nranks + 1) * sizeof(long));
    r->dec_part = malloc(((size_t)nv + 1) * sizeof(int));
    if (!r->dec_bound || !r->dec_part) error_exit(1, "out of memory reading %s", file);
    if (ckpt_read_rows(file, g, "Bounds", H5T_NATIVE_LONG, r->dec_bound, nranks + 1, 0) != nranks + 1 ||
        ckpt_read_rows(file, g, "Owners", H5T_NATIVE_INT, r->dec_part, nv, 0) != nv)
        ckpt_bad(file, "/Decomposition does not match NumRanks and CoarseCells");
    H5CHECK(H5Gclose(g));
    r->dec_present = 1;
}

void ckpt_read(const char *file, sim_t *s, ckpt_run *r)
{
    hid_t f = ckpt_open(file), g;
    H5CHECK(g = H5Gopen2(f, "Header", H5P_DEFAULT));
    ckpt_check_header(file, g, s);
    long long ntot = ckpt_get_int(file, g, "NumPart_Total");
    int nranks = (int)ckpt_get_int(file, g, "NumRanks");
    s->t = ckpt_get_double(file, g, "Time");
    s->step = (long)ckpt_get_int(file, g, "Step");
    s->dt = ckpt_get_double(file, g, "Dt");
    s->amax = ckpt_get_double(file, g, "Amax");
    s->win.k = (long)ckpt_get_int(file, g, "WindowSteps");
    s->win.K = (long)ckpt_get_int(file, g, "WindowTarget");
    s->win.T = ckpt_get_double(file, g, "WindowLength");
    H5CHECK(H5Gclose(g));
    ckpt_read_run(file, f, r);
    ckpt_read_particles(file, f, s, (int)s->sc->geometry.dim, ntot, nranks);
    ckpt_read_decomp(file, f, nranks, r);
    H5CHECK(H5Fclose(f));
    if (nranks != comm_size())
        message("restart: the checkpoint was written by %d rank(s), this run has %d: each rank read an even "
                "share of the %lld particles", nranks, comm_size(), ntot);
}

void ckpt_run_free(ckpt_run *r)
{
    free(r->times);
    free(r->npart);
    free(r->dec_bound);
    free(r->dec_part);
    *r = (ckpt_run){0};
}

/* ---- when to stop ------------------------------------------------------------- */

void ckpt_clock_start(ckpt_clock *c, double wall0, double max_wall, const char *outdir)
{
    c->wall0 = wall0;
    c->loop0 = diag_wall();
    c->last_check = -1e300;
    c->write_s = 0;
    c->max_wall = max_wall;
    snprintf(c->stop, sizeof c->stop, "%s/STOP", outdir);
}

enum ckpt_stop ckpt_poll(ckpt_clock *c, long steps_done)
{
    int why = CKPT_GO;
    if (comm_rank() == 0) {
        double now = diag_wall(), mean = steps_done > 0 ? (now - c->loop0) / (double)steps_done : 0;
        if (c->max_wall > 0 && now - c->wall0 + mean + c->write_s > c->max_wall) why = CKPT_WALL;
        if (now - c->last_check >= CKPT_STOP_EVERY_S) {
            c->last_check = now;
            if (access(c->stop, F_OK) == 0) why = CKPT_STOPFILE;
        }
    }
    MPICHECK(MPI_Bcast(&why, 1, MPI_INT, 0, MPI_COMM_WORLD));
    return (enum ckpt_stop)why;
}

void ckpt_clear_stop(const ckpt_clock *c)
{
    if (comm_rank() == 0 && unlink(c->stop) != 0 && errno != ENOENT)
        warning("cannot remove %s: %s", c->stop, strerror(errno));
}
