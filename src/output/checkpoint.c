/* checkpoint.c — full-state checkpoints and restarts (see checkpoint.h). */
#include "checkpoint.h"
#include <errno.h>
#include <fcntl.h>
#include <hdf5.h>
/* hdf5.h's H5F_ACC_* flags use its own H5CHECK, which error.h and this file
 * take over: read the flag first (as checkpoint_read.c does). */
static unsigned ckpt_acc_rdonly(void) { return H5F_ACC_RDONLY; }
#include <mpi.h>
#include <signal.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>
#include "diag.h"
#include "core/error.h"
#include "io.h"
#include "mpi/comm.h"
#include "core/version.h"

/* Every HDF5 call here writes the checkpoint: a failure is a failed write
 * (exit status 4, src/output/io.h), checkpoint.h5 stays the last complete one. */
#undef H5CHECK
#define H5CHECK(call)                                                                                        \
    do {                                                                                                     \
        if ((call) < 0) io_write_failed("%s at %s:%d", #call, __FILE__, __LINE__);                           \
    } while (0)

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
    dxpl = io_select_rows(fspace, mspace, start, count);
    char what[80];
    snprintf(what, sizeof what, "the dataset %s", name);
    if (ntot > 0) io_write_rows(dset, mtype, mspace, fspace, dxpl, buf, what);
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
    ckpt_attr_int64(g, "Checkpoint", CKPT_FORMAT);
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
    ckpt_attr_int64(g, "OutflowCount", r->out_n);
    ckpt_attr_double(g, "OutflowSmallVolume", r->out_cv);
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

/* /Particles: RankCounts, then every array of the store, raw; an array
 * this run does not allocate (part_alloc_fields) as zeros, so that the
 * format is the table's whatever the run (a restart reads it or not). */
static void ckpt_write_particles(hid_t file, const particles_t *p, long long ntot, long long offset)
{
    int size = comm_size(), rank = comm_rank();
    long long n = (long long)p->n, *counts = malloc((size_t)size * sizeof *counts);
    if (!counts) error_exit(EXIT_SYSTEM, "out of memory writing a checkpoint");
    MPICHECK(MPI_Allgather(&n, 1, MPI_LONG_LONG, counts, 1, MPI_LONG_LONG, MPI_COMM_WORLD));
    hid_t g, d;
    H5CHECK(g = H5Gcreate2(file, "Particles", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    H5CHECK(d = ckpt_write_rows(g, "RankCounts", H5T_STD_I64LE, H5T_NATIVE_LLONG, counts, rank == 0 ? size : 0,
                                size, 0));
    H5CHECK(H5Dclose(d));
    void *zeros = NULL;
    for (size_t k = 0; k < part_narrays(); ++k) {
        char name[24];
        size_t es = part_array_esize(k);
        snprintf(name, sizeof name, "%02zu", k);
        const void *a = part_array_get(p, k);
        if (!a && !zeros && !(zeros = calloc(n > 0 ? (size_t)n : 1, 8)))
            error_exit(EXIT_SYSTEM, "out of memory writing a checkpoint");
        H5CHECK(d = ckpt_write_rows(g, name, ckpt_raw_file(es), ckpt_raw_mem(es), a ? a : zeros, n, ntot,
                                    offset));
        ckpt_attr_int64(d, "ElementBytes", (long long)es);
        H5CHECK(H5Dclose(d));
    }
    H5CHECK(H5Gclose(g));
    free(zeros);
    free(counts);
}

/* /DEM (a scene with grains): d is the whole store on every rank
 * (dem_whole), so rank 0 writes the rows and the others take part with
 * none, as /Outputs. The arrays of dem_state_get, flat (grain by grain), as
 * doubles or signed integers of their size; the scalars as attributes. */
static void ckpt_write_dem(hid_t file, dem_t *d)
{
    if (!d) return;
    hid_t g, ds;
    const int r0 = comm_rank() == 0;
    H5CHECK(g = H5Gcreate2(file, "DEM", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    ckpt_attr_int64(g, "Count", (long long)d->n);
    ckpt_attr_int64(g, "ContactsMax", DEM_CMAX);
    ckpt_attr_int64(g, "Steps", d->steps);
    ckpt_attr_double(g, "ExchangeX", d->exch[0]);
    ckpt_attr_double(g, "ExchangeY", d->exch[1]);
    ckpt_attr_double(g, "ExchangeZ", d->exch[2]);
    for (size_t k = 0; k < DEM_STATE_NARRAYS; ++k) {
        dem_state_array a = dem_state_get(d, k);
        long long len = (long long)(d->n * a.per);
        hid_t ft = a.is_double ? H5T_IEEE_F64LE : a.esize == 8 ? H5T_STD_I64LE : H5T_STD_I32LE;
        hid_t mt = a.is_double ? H5T_NATIVE_DOUBLE : a.esize == 8 ? H5T_NATIVE_INT64 : H5T_NATIVE_INT32;
        H5CHECK(ds = ckpt_write_rows(g, a.name, ft, mt, a.a, r0 ? len : 0, len, 0));
        H5CHECK(H5Dclose(ds));
    }
    H5CHECK(H5Gclose(g));
}

/* Rank 0 rotates, between barriers: checkpoint.h5 is hard-linked to
 * checkpoint_prev.h5 (through a temporary name, renamed over the old one),
 * then the new file is renamed over checkpoint.h5. checkpoint.h5 names a
 * complete checkpoint at every instant, and so does checkpoint_prev.h5 once
 * there is one; a file system without hard links falls back to two renames
 * (a moment with no checkpoint.h5; --restart OUTDIR still finds _prev).
 * tests/test_outdir.sh kills rank 0 just before the rename over
 * checkpoint.h5 (an LD_PRELOAD shim, tests/shim_kill.c). */
static void ckpt_commit(const char *outdir, const char *tmp)
{
    char path[CKPT_PATH_MAX], prev[CKPT_PATH_MAX], link_tmp[CKPT_PATH_MAX];
    snprintf(path, sizeof path, "%s/checkpoint.h5", outdir);
    snprintf(prev, sizeof prev, "%s/checkpoint_prev.h5", outdir);
    snprintf(link_tmp, sizeof link_tmp, "%s/checkpoint_prev.h5.tmp", outdir);
    MPICHECK(MPI_Barrier(MPI_COMM_WORLD));
    if (comm_rank() == 0) {
        if (unlink(link_tmp) != 0 && errno != ENOENT) io_write_failed("cannot remove %s", link_tmp);
        if (link(path, link_tmp) == 0) {
            if (rename(link_tmp, prev) != 0) io_write_failed("cannot rename %s to %s", link_tmp, prev);
        } else if (errno != ENOENT) {
            static int told;
            if (!told++) warning("cannot hard-link %s (%s): rotating checkpoints by renames", path, strerror(errno));
            if (rename(path, prev) != 0 && errno != ENOENT) io_write_failed("cannot rename %s to %s", path, prev);
        }
        if (rename(tmp, path) != 0) io_write_failed("cannot rename it to %s", path);
    }
    io_forget_tmp();
    MPICHECK(MPI_Barrier(MPI_COMM_WORLD));
}

/* ---- the seal: a checksum of the whole file in its user block ------------------ */

/* splitmix64's finaliser: every bit of the word reaches every bit of the hash. */
static uint64_t ckpt_mix(uint64_t z)
{
    z = (z ^ (z >> 30)) * UINT64_C(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94D049BB133111EB);
    return z ^ (z >> 31);
}

/* Sum over the little-endian 8-byte words w_i (i from 1, zero-padded) of the
 * bytes from CKPT_USERBLOCK to size of mix(w_i + i * golden), words
 * [w0, w1) of them: ranks hash their own parts and add. Returns -1 on a read
 * error. */
static int ckpt_hash_words(int fd, uint64_t w0, uint64_t w1, uint64_t size, uint64_t *sum)
{
    enum { BLOCK = 1 << 17 };
    static unsigned char buf[BLOCK * 8];
    uint64_t h = 0;
    for (uint64_t w = w0; w < w1;) {
        uint64_t m = w1 - w < BLOCK ? w1 - w : BLOCK, off = CKPT_USERBLOCK + 8 * w;
        uint64_t want = off + 8 * m > size ? size - off : 8 * m;
        memset(buf, 0, (size_t)(8 * m));
        for (uint64_t got = 0; got < want;) {
            ssize_t r = pread(fd, buf + got, (size_t)(want - got), (off_t)(off + got));
            if (r <= 0) return -1;
            got += (uint64_t)r;
        }
        for (uint64_t k = 0; k < m; ++k) {
            uint64_t v = 0;
            for (int b = 7; b >= 0; --b) v = v << 8 | buf[8 * k + (uint64_t)b];
            h += ckpt_mix(v + (w + k + 1) * UINT64_C(0x9E3779B97F4A7C15));
        }
        w += m;
    }
    *sum = h;
    return 0;
}

/* Collective: the checksum of path's bytes past the user block (size bytes
 * in all), each rank hashing an even share; -1 if a rank could not read it
 * or it is no longer a regular file (opened non-blocking: a FIFO put in its
 * place never hangs a rank). */
static int ckpt_hash_file(const char *path, uint64_t size, uint64_t *sum)
{
    uint64_t nw = size > CKPT_USERBLOCK ? (size - CKPT_USERBLOCK + 7) / 8 : 0, h = 0;
    uint64_t r = (uint64_t)comm_rank(), P = (uint64_t)comm_size();
    struct stat st;
    int fd = open(path, O_RDONLY | O_NONBLOCK), bad = fd < 0 || fstat(fd, &st) != 0 || !S_ISREG(st.st_mode);
    if (!bad) bad = ckpt_hash_words(fd, nw * r / P, nw * (r + 1) / P, size, &h) != 0;
    if (fd >= 0) close(fd);
    MPICHECK(MPI_Allreduce(MPI_IN_PLACE, &bad, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD));
    MPICHECK(MPI_Allreduce(MPI_IN_PLACE, &h, 1, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD));
    *sum = h;
    return bad ? -1 : 0;
}

static void ckpt_put64(unsigned char *b, uint64_t v)
{
    for (int k = 0; k < 8; ++k) b[k] = (unsigned char)(v >> (8 * k));
}

static uint64_t ckpt_get64(const unsigned char *b)
{
    uint64_t v = 0;
    for (int k = 7; k >= 0; --k) v = v << 8 | b[k];
    return v;
}

/* The check word of a seal (bytes 48..55): a chained splitmix64 hash of its
 * first six words (magic, format, size, sum, step, time bits), never 0 (0
 * marks a legacy seal, checkpoint.h). Every change to one word changes it:
 * each step is a bijection of the running hash. */
static uint64_t ckpt_seal_check(const unsigned char *b)
{
    uint64_t h = 0;
    for (int k = 0; k < 6; ++k)
        h = ckpt_mix(h ^ (ckpt_get64(b + 8 * k) + (uint64_t)(k + 1) * UINT64_C(0x9E3779B97F4A7C15)));
    return h ? h : 1;
}

/* Rank 0: the seal into tmp's user block, flushed to the disk; 0 or -1
 * (errno says why). */
static int ckpt_write_seal(const char *tmp, const sim_t *s, uint64_t size, uint64_t sum)
{
    unsigned char b[64] = "SPHSEGCK";
    double t = s->t;
    uint64_t tbits;
    memcpy(&tbits, &t, 8);
    ckpt_put64(b + 8, CKPT_FORMAT), ckpt_put64(b + 16, size), ckpt_put64(b + 24, sum);
    ckpt_put64(b + 32, (uint64_t)s->step), ckpt_put64(b + 40, tbits);
    ckpt_put64(b + 48, ckpt_seal_check(b));
    int fd = open(tmp, O_WRONLY), bad = fd < 0 || pwrite(fd, b, sizeof b, 0) != (ssize_t)sizeof b || fsync(fd) != 0;
    int err = errno;
    if (fd >= 0 && close(fd) != 0 && !bad) bad = 1, err = errno;
    errno = err;
    return bad ? -1 : 0;
}

/* Collective, after the file is closed: hash it and write the seal into its
 * user block (rank 0), then flush it to the disk. */
static void ckpt_seal_file(const char *tmp, const sim_t *s)
{
    struct stat st;
    uint64_t size = 0, sum;
    int bad = comm_rank() == 0 && stat(tmp, &st) != 0;
    if (comm_rank() == 0 && !bad) size = (uint64_t)st.st_size;
    io_write_agree(bad, "cannot stat it");
    MPICHECK(MPI_Bcast(&size, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD));
    io_write_agree(ckpt_hash_file(tmp, size, &sum) != 0, "cannot read it back to checksum it"); /* agreed already */
    if (comm_rank() == 0) bad = ckpt_write_seal(tmp, s, size, sum);
    io_write_agree(bad, "cannot write its checksum");
}

/* Rank 0: read path's seal into b (64 bytes) without blocking on a FIFO or
 * a device: the type is looked at before the open (stat), the open is
 * non-blocking and its fstat is checked again (the name may have been
 * replaced in between). 0, or why it cannot be read (1: errno says, 2: not
 * a regular file, 3: no seal, 5: the user block past the seal is not zero,
 * as the writer leaves it: neither the seal's check nor the checksum covers
 * those bytes, so a flip there is caught here). */
static int ckpt_read_seal(const char *path, unsigned char *b, struct stat *st)
{
    if (stat(path, st) != 0) return 1;
    if (!S_ISREG(st->st_mode)) return 2;
    int fd = open(path, O_RDONLY | O_NONBLOCK), bad = 0;
    unsigned char ub[CKPT_USERBLOCK];
    ssize_t got = 0;
    if (fd < 0 || fstat(fd, st) != 0) bad = 1;
    else if (!S_ISREG(st->st_mode)) bad = 2;
    else if ((got = pread(fd, ub, sizeof ub, 0)) < 64 || memcmp(ub, "SPHSEGCK", 8) != 0) bad = 3;
    else {
        memcpy(b, ub, 64);
        for (ssize_t k = 64; k < got && !bad; ++k) bad = ub[k] != 0 ? 5 : 0;
    }
    int err = errno;
    if (fd >= 0) close(fd);
    errno = err;
    return bad;
}

/* The seal's own words: their check (a legacy seal's is 0: accepted, its
 * step and time are checked against /Header by ckpt_read), the reserved
 * word, the size. 0, or 1 with why. */
static int ckpt_check_seal(const unsigned char *b, const struct stat *st, char *why, size_t n)
{
    uint64_t check = ckpt_get64(b + 48);
    if ((check != 0 && check != ckpt_seal_check(b)) || ckpt_get64(b + 56) != 0)
        return snprintf(why, n, "damaged: its checksum block is corrupted (the seal's words do not match their "
                        "check)"), 1;
    if (ckpt_get64(b + 16) != (uint64_t)st->st_size)
        return snprintf(why, n, "damaged: %llu bytes long, written as %llu (cut short or extended)",
                        (unsigned long long)st->st_size, (unsigned long long)ckpt_get64(b + 16)), 1;
    if (ckpt_get64(b + 8) != CKPT_FORMAT)
        return snprintf(why, n, "checkpoint format %llu; this sphseg reads format %d",
                        (unsigned long long)ckpt_get64(b + 8), CKPT_FORMAT), 1;
    return 0;
}

/* A string attribute of loc (variable or fixed length) into v; 0 if absent
 * or not a string. */
static int ckpt_peek_string(hid_t loc, const char *name, char *v, size_t n)
{
    if (H5Aexists(loc, name) <= 0) return 0;
    hid_t a = H5Aopen(loc, name, H5P_DEFAULT), ft = a < 0 ? -1 : H5Aget_type(a), mt = H5Tcopy(H5T_C_S1);
    int ok = ft >= 0 && H5Tget_class(ft) == H5T_STRING;
    if (ok) H5Tset_cset(mt, H5Tget_cset(ft)); /* sphseg writes UTF-8: HDF5 converts no other way */
    if (ok && H5Tis_variable_str(ft) > 0) {
        char *str = NULL;
        H5Tset_size(mt, H5T_VARIABLE);
        ok = H5Aread(a, mt, &str) >= 0 && str;
        if (ok) snprintf(v, n, "%.40s", str);
        if (str) H5free_memory(str);
    } else if (ok) {
        char buf[64] = "";
        size_t size = H5Tget_size(ft);
        H5Tset_size(mt, sizeof buf);
        ok = size < sizeof buf && H5Aread(a, mt, buf) >= 0;
        if (ok) snprintf(v, n, "%.40s", buf);
    }
    if (ft >= 0) H5Tclose(ft);
    H5Tclose(mt);
    if (a >= 0) H5Aclose(a);
    return ok;
}

/* A numeric attribute of loc as a double into v; 0 if absent or not a number. */
static int ckpt_peek_number(hid_t loc, const char *name, double *v)
{
    if (H5Aexists(loc, name) <= 0) return 0;
    hid_t a = H5Aopen(loc, name, H5P_DEFAULT), ft = a < 0 ? -1 : H5Aget_type(a);
    H5T_class_t c = ft < 0 ? H5T_NO_CLASS : H5Tget_class(ft);
    int ok = (c == H5T_FLOAT || c == H5T_INTEGER) && H5Aread(a, H5T_NATIVE_DOUBLE, v) >= 0;
    if (ft >= 0) H5Tclose(ft);
    if (a >= 0) H5Aclose(a);
    return ok;
}

/* Rank 0: what a regular file without a seal is, into why: a snapshot (its
 * /Header has Code sphseg, no Checkpoint attribute), a checkpoint written
 * before checkpoints were sealed, another HDF5 file, a checkpoint whose seal
 * is overwritten, or no HDF5 file at all. Opened with HDF5 only when its
 * first bytes are HDF5's signature (a file without a user block: snapshots,
 * unsealed checkpoints); one with its HDF5 part after a user block, as a
 * sealed checkpoint has, is damaged, and HDF5 reads none of it. */
static void ckpt_unsealed_why(const char *path, char *why, size_t n)
{
    static const unsigned char sig[8] = {0x89, 'H', 'D', 'F', '\r', '\n', 0x1a, '\n'};
    unsigned char b[8] = {0}, ub[8] = {0};
    FILE *f = fopen(path, "rb");
    int hdf5 = f && fread(b, 1, 8, f) == 8 && !memcmp(b, sig, 8);
    int after_ub = f && !hdf5 && fseek(f, CKPT_USERBLOCK, SEEK_SET) == 0 && fread(ub, 1, 8, f) == 8 &&
                   !memcmp(ub, sig, 8);
    if (f) fclose(f);
    snprintf(why, n, after_ub ? "damaged: its checksum block is missing or overwritten (an HDF5 file after a "
                                "user block, as a checkpoint is, but its first bytes are not the seal's)"
                              : "not a sphseg checkpoint (no checksum block, and not an HDF5 file)");
    if (!hdf5) return;
    H5E_auto2_t fn;
    void *data;
    H5Eget_auto2(H5E_DEFAULT, &fn, &data);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL); /* our message, not HDF5's stack */
    hid_t file = H5Fopen(path, ckpt_acc_rdonly(), H5P_DEFAULT), g = -1;
    char code[48] = "", version[48] = "?";
    double t = 0, step = 0, format = 0;
    snprintf(why, n, "not a sphseg checkpoint (no checksum block; an HDF5 file%s)",
             file < 0 ? " HDF5 cannot open" : " without a sphseg /Header");
    if (file >= 0 && H5Lexists(file, "Header", H5P_DEFAULT) > 0 && (g = H5Gopen2(file, "Header", H5P_DEFAULT)) >= 0 &&
        ckpt_peek_string(g, "Code", code, sizeof code) && !strcmp(code, "sphseg")) {
        ckpt_peek_string(g, "Version", version, sizeof version);
        int is_ckpt = ckpt_peek_number(g, "Checkpoint", &format);
        ckpt_peek_number(g, "Time", &t), ckpt_peek_number(g, "Step", &step);
        if (is_ckpt)
            snprintf(why, n, "not a sealed sphseg checkpoint: a checkpoint of sphseg %s (format %.0f, step %.0f, "
                     "t = %.9g s) without its checksum block (written before checkpoints were sealed, or copied "
                     "without its first %d bytes); sphseg %s reads sealed checkpoints only", version, format, step,
                     t, CKPT_USERBLOCK, SPHSEG_VERSION);
        else
            snprintf(why, n, "not a sphseg checkpoint: a snapshot of sphseg %s (step %.0f, t = %.9g s), which holds "
                     "no run state; restart from a checkpoint (OUTDIR/checkpoint.h5: written every "
                     "Output:checkpoint_dt, at Run:max_wall_time and on a stop signal)", version, step, t);
    }
    if (g >= 0) H5Gclose(g);
    if (file >= 0) H5Fclose(file);
    H5Eset_auto2(H5E_DEFAULT, fn, data);
}

int ckpt_verify(const char *path, ckpt_seal *seal, char *why, size_t n)
{
    unsigned char b[64] = {0};
    int bad = 0;
    struct stat st = {0};
    if (comm_rank() == 0) {
        bad = ckpt_read_seal(path, b, &st);
        if (bad == 1) snprintf(why, n, "cannot read it: %s", strerror(errno));
        if (bad == 2) snprintf(why, n, "not a regular file");
        if (bad == 3) ckpt_unsealed_why(path, why, n);
        if (bad == 5) snprintf(why, n, "damaged: its user block past the checksum block is not blank (bytes 64 to "
                               "%d are written as zero)", CKPT_USERBLOCK - 1);
        if (!bad) bad = 4 * ckpt_check_seal(b, &st, why, n);
    }
    MPICHECK(MPI_Bcast(&bad, 1, MPI_INT, 0, MPI_COMM_WORLD));
    if (bad) { /* rank 0's reason, on every rank */
        MPICHECK(MPI_Bcast(why, (int)n, MPI_CHAR, 0, MPI_COMM_WORLD));
        return bad == 1 ? -1 : 1;
    }
    MPICHECK(MPI_Bcast(b, sizeof b, MPI_UNSIGNED_CHAR, 0, MPI_COMM_WORLD));
    seal->size = ckpt_get64(b + 16), seal->sum = ckpt_get64(b + 24), seal->step = (long long)ckpt_get64(b + 32);
    uint64_t tbits = ckpt_get64(b + 40), sum = 0;
    memcpy(&seal->time, &tbits, 8);
    seal->legacy = ckpt_get64(b + 48) == 0;
    if (ckpt_hash_file(path, seal->size, &sum) != 0) return snprintf(why, n, "cannot read it through"), 1;
    if (sum != seal->sum)
        return snprintf(why, n, "damaged: its checksum does not match its contents (the file changed after "
                        "it was written)"), 1;
    return 0;
}

/* The bytes of a checkpoint's datasets, their object headers (1 kB each:
 * one dataset per particle array and per array of the grains: 684 bytes a
 * grain) and scene text; io_create_file adds a margin for the rest of
 * HDF5's metadata. */
static double ckpt_bytes(const sim_t *s, const ckpt_run *r, long long ntot, const char *scene_text)
{
    const halo_t *h = s->halo;
    double nv = h && h->method == HALO_METIS ? (double)h->cg_n[0] * h->cg_n[1] * h->cg_n[2] : 0;
    double grains =
        s->dem ? (double)s->dem->ntot * (DEM_CMAX * 32 + 21 * 8 + 4) + 1024.0 * DEM_STATE_NARRAYS : 0;
    return (double)ntot * (double)part_bytes_per_particle() + 16.0 * r->nsnap + 4 * nv +
           8.0 * (2 * comm_size() + 1) + 1024.0 * (double)part_narrays() + grains +
           (double)strlen(scene_text ? scene_text : "");
}

double ckpt_write(const char *outdir, const sim_t *s, const ckpt_run *r, const char *scene_text)
{
    double w0 = diag_wall();
    char tmp[CKPT_PATH_MAX];
    if (snprintf(tmp, sizeof tmp, "%s/checkpoint.h5.tmp", outdir) >= (int)sizeof tmp)
        error_exit(EXIT_SYSTEM, "output path too long: %s", outdir);
    long long n = (long long)s->p.n, ntot = 0, offset = 0;
    MPICHECK(MPI_Allreduce(&n, &ntot, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD));
    MPICHECK(MPI_Exscan(&n, &offset, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD));
    if (comm_rank() == 0) offset = 0; /* MPI_Exscan leaves rank 0's result undefined */
    hid_t file = io_create_file(tmp, CKPT_USERBLOCK, ckpt_bytes(s, r, ntot, scene_text));
    ckpt_write_header(file, s, ntot, scene_text);
    ckpt_write_run(file, r);
    ckpt_write_decomp(file, s->halo);
    ckpt_write_particles(file, &s->p, ntot, offset);
    dem_t *whole = dem_whole(s->dem); /* collective: every grain, on every rank */
    ckpt_write_dem(file, whole);
    dem_whole_free(s->dem, whole);
    if (s->dem) s->dem->due = 1; /* the next coupling exchanges, as a restart from this file does */
    io_close_file(file);
    ckpt_seal_file(tmp, s);
    ckpt_commit(outdir, tmp);
    return diag_wall() - w0;
}

/* ---- when to stop ------------------------------------------------------------- */

static volatile sig_atomic_t ckpt_sig, ckpt_stepping;
static struct timespec ckpt_sig_at; /* when the first signal came */

/* The first signal asks for a stop after the step; a second SIGTERM, SIGINT
 * or SIGHUP ends the process at once (the default action), and so does one
 * before the first step (nothing to save yet; a SIGUSR1 then waits for the
 * first step: it is a warning that the end is near). A second signal within
 * CKPT_SIGNAL_ECHO_S of the first is the same event delivered twice (SLURM
 * signals every task, and srun forwards its own copy) and is ignored. */
static void ckpt_on_signal(int sig)
{
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now); /* async-signal-safe */
    if (ckpt_sig && (double)(now.tv_sec - ckpt_sig_at.tv_sec) +
                            1e-9 * (double)(now.tv_nsec - ckpt_sig_at.tv_nsec) < CKPT_SIGNAL_ECHO_S)
        return;
    if ((ckpt_sig || !ckpt_stepping) && sig != SIGUSR1) {
        signal(sig, SIG_DFL);
        raise(sig);
        return;
    }
    if (!ckpt_sig) ckpt_sig = sig, ckpt_sig_at = now;
}

void ckpt_signals_install(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = ckpt_on_signal;
    sa.sa_flags = SA_RESTART;
    sigemptyset(&sa.sa_mask);
    const int sigs[] = {SIGTERM, SIGUSR1, SIGINT, SIGHUP};
    for (size_t k = 0; k < sizeof sigs / sizeof sigs[0]; ++k) sigaction(sigs[k], &sa, NULL);
}

void ckpt_signals_stepping(void) { ckpt_stepping = 1; }

void ckpt_clock_start(ckpt_clock *c, double wall0, double max_wall, const char *outdir)
{
    c->wall0 = wall0;
    c->loop0 = diag_wall();
    c->last_check = -1e300;
    c->write_s = 0;
    c->max_wall = max_wall;
    c->signal = 0;
    snprintf(c->stop, sizeof c->stop, "%s/STOP", outdir);
}

enum ckpt_stop ckpt_poll(ckpt_clock *c, long steps_done)
{
    int why[2] = {CKPT_GO, ckpt_sig}; /* rank 0's wall/STOP decision; a signal any rank received */
    if (comm_rank() == 0) {
        double now = diag_wall(), mean = steps_done > 0 ? (now - c->loop0) / (double)steps_done : 0;
        if (c->max_wall > 0 && now - c->wall0 + mean + c->write_s > c->max_wall) why[0] = CKPT_WALL;
        if (now - c->last_check >= CKPT_STOP_EVERY_S) {
            c->last_check = now;
            if (access(c->stop, F_OK) == 0) why[0] = CKPT_STOPFILE;
        }
    }
    MPICHECK(MPI_Allreduce(MPI_IN_PLACE, why, 2, MPI_INT, MPI_MAX, MPI_COMM_WORLD));
    if (why[1]) c->signal = why[1];
    return why[1] ? CKPT_SIGNAL : (enum ckpt_stop)why[0];
}
void ckpt_clear_stop(const ckpt_clock *c)
{
    if (comm_rank() == 0 && unlink(c->stop) != 0 && errno != ENOENT)
        warning("cannot remove %s: %s", c->stop, strerror(errno));
}
