/* checkpoint_read.c — restarts: choose, verify and read a checkpoint (see
 * checkpoint.h). A bad checkpoint is bad input (exit 2, one line from rank
 * 0): the seal is verified before HDF5 opens the file; then every group,
 * attribute and dataset is checked for existence, type and shape before it
 * is read, and every value for range; a problem only one rank sees (its own
 * rows) reaches all ranks through input_error_agree, so no rank waits in a
 * collective read for one that has left. */
#include <errno.h>
#include <hdf5.h>
#include <limits.h>
#include <math.h>
#include <mpi.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
/* hdf5.h's H5F_ACC_* flags use its own H5CHECK, whose name error.h takes over
 * (error.h): read the flag before error.h comes in. */
static unsigned ckpt_acc_rdonly(void) { return H5F_ACC_RDONLY; }
#include "checkpoint.h"
#include "core/error.h"
#include "io.h"
#include "mpi/comm.h"
#include "sim/stages.h"

#define CKPT_PATH_MAX 4200

/* Bounds on what a checkpoint may claim before anything is allocated. */
#define CKPT_MAX_RANKS 1000000LL
#define CKPT_MAX_PART 1000000000000LL
#define CKPT_MAX_SNAP 1000000LL
#define CKPT_MAX_CELLS 1000000000LL
#define CKPT_MAX_WINDOW 1000000000LL

static const char *ckpt_file; /* the checkpoint being read, for messages */

static const char *ckpt_precision(void) { return sizeof(real) == sizeof(float) ? "single" : "double"; }

/* Bad restart files are bad input: exit 2, one line naming the file. Every
 * rank reads the same bytes and finds the same problem at the same point. */
static void ckpt_bad(const char *fmt, ...) __attribute__((format(printf, 1, 2), noreturn));
static void ckpt_bad(const char *fmt, ...)
{
    char why[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(why, sizeof why, fmt, ap);
    va_end(ap);
    input_error("--restart %s: %s", ckpt_file, why);
}

/* While reading, an HDF5 call that fails means a damaged file (HDF5's own
 * error stack is silenced: the one line is ours). */
#undef H5CHECK
#define H5CHECK(call)                                                                                        \
    do {                                                                                                     \
        if ((call) < 0) ckpt_bad("damaged: HDF5 could not read it (%s)", #call);                            \
    } while (0)

static hid_t ckpt_raw_mem(size_t esize)
{
    return esize == 1   ? H5T_NATIVE_UINT8
           : esize == 2 ? H5T_NATIVE_UINT16
           : esize == 4 ? H5T_NATIVE_UINT32
                        : H5T_NATIVE_UINT64;
}

/* ---- checked access ------------------------------------------------------------- */

static hid_t ckpt_group(hid_t loc, const char *name)
{
    htri_t e;
    hid_t g;
    H5CHECK(e = H5Lexists(loc, name, H5P_DEFAULT));
    if (!e) ckpt_bad("not a sphseg checkpoint (no group /%s)", name);
    if ((g = H5Gopen2(loc, name, H5P_DEFAULT)) < 0) ckpt_bad("/%s is not a group", name);
    return g;
}

/* A scalar attribute of type class cls (H5T_INTEGER, H5T_FLOAT, H5T_STRING). */
static hid_t ckpt_attr(hid_t g, const char *name, H5T_class_t cls)
{
    htri_t e;
    hid_t a, t, sp;
    H5CHECK(e = H5Aexists(g, name));
    if (!e) ckpt_bad("not a sphseg checkpoint (no attribute %s)", name);
    H5CHECK(a = H5Aopen(g, name, H5P_DEFAULT));
    H5CHECK(t = H5Aget_type(a));
    H5CHECK(sp = H5Aget_space(a));
    int ok = H5Tget_class(t) == cls && H5Sget_simple_extent_type(sp) == H5S_SCALAR;
    if (ok && cls != H5T_STRING) ok = H5Tget_size(t) == 8;
    H5CHECK(H5Tclose(t));
    H5CHECK(H5Sclose(sp));
    if (!ok) ckpt_bad("attribute %s is not a scalar of the type sphseg writes", name);
    return a;
}

static double ckpt_get_double(hid_t g, const char *name, double lo, double hi)
{
    double v;
    hid_t a = ckpt_attr(g, name, H5T_FLOAT);
    H5CHECK(H5Aread(a, H5T_NATIVE_DOUBLE, &v));
    H5CHECK(H5Aclose(a));
    if (!(v >= lo && v <= hi)) ckpt_bad("attribute %s = %g is out of range [%g, %g]", name, v, lo, hi);
    return v;
}

static long long ckpt_get_int(hid_t g, const char *name, long long lo, long long hi)
{
    int64_t v;
    hid_t a = ckpt_attr(g, name, H5T_INTEGER);
    H5CHECK(H5Aread(a, H5T_NATIVE_INT64, &v));
    H5CHECK(H5Aclose(a));
    if (v < lo || v > hi) ckpt_bad("attribute %s = %lld is out of range [%lld, %lld]", name, (long long)v, lo, hi);
    return v;
}

/* A variable-length string attribute, malloc'd. */
static char *ckpt_get_string(hid_t g, const char *name)
{
    hid_t a = ckpt_attr(g, name, H5T_STRING), type;
    char *v = NULL;
    H5CHECK(type = H5Tcopy(H5T_C_S1));
    H5CHECK(H5Tset_size(type, H5T_VARIABLE));
    H5CHECK(H5Tset_cset(type, H5T_CSET_UTF8));
    H5CHECK(H5Aread(a, type, &v));
    char *copy = strdup(v ? v : "");
    H5free_memory(v);
    H5CHECK(H5Aclose(a));
    H5CHECK(H5Tclose(type));
    if (!copy) error_exit(EXIT_SYSTEM, "out of memory reading %s", ckpt_file);
    return copy;
}

/* Open the 1D dataset name of len rows of integers (cls H5T_INTEGER) or
 * floats of esize bytes, after checking all of that. */
static hid_t ckpt_dataset(hid_t loc, const char *name, H5T_class_t cls, size_t esize, long long len)
{
    htri_t e;
    hid_t d, t, sp;
    hsize_t dims[2] = {0, 0};
    H5CHECK(e = H5Lexists(loc, name, H5P_DEFAULT));
    if (!e) ckpt_bad("not a sphseg checkpoint (dataset %s missing)", name);
    if ((d = H5Dopen2(loc, name, H5P_DEFAULT)) < 0) ckpt_bad("%s is not a dataset", name);
    H5CHECK(t = H5Dget_type(d));
    H5CHECK(sp = H5Dget_space(d));
    int ok = H5Tget_class(t) == cls && H5Tget_size(t) == esize;
    int rank = H5Sget_simple_extent_ndims(sp);
    if (rank == 1) H5CHECK(H5Sget_simple_extent_dims(sp, dims, NULL));
    H5CHECK(H5Tclose(t));
    H5CHECK(H5Sclose(sp));
    if (!ok) ckpt_bad("dataset %s does not hold the %zu-byte %s sphseg writes", name, esize,
                      cls == H5T_FLOAT ? "floats" : "integers");
    if (rank != 1 || (long long)dims[0] != len)
        ckpt_bad("dataset %s has the wrong shape (%d dimension(s), %llu rows; %lld rows expected)", name, rank,
                 (unsigned long long)dims[0], len);
    return d;
}

/* Rows [offset, offset + n) of the checked dataset d into buf, collectively. */
static void ckpt_read_rows(hid_t d, hid_t mtype, void *buf, long long n, long long offset)
{
    hid_t fspace, mspace, dxpl;
    hsize_t mdims = n > 0 ? (hsize_t)n : 1;
    H5CHECK(fspace = H5Dget_space(d));
    H5CHECK(mspace = H5Screate_simple(1, &mdims, NULL));
    dxpl = io_select_rows(fspace, mspace, (uint64_t)offset, (uint64_t)n);
    H5CHECK(H5Dread(d, mtype, mspace, fspace, dxpl, buf));
    H5CHECK(H5Pclose(dxpl));
    H5CHECK(H5Sclose(mspace));
    H5CHECK(H5Sclose(fspace));
}

/* All len rows of a small dataset, on every rank (malloc'd, at least one). */
static void *ckpt_read_all(hid_t loc, const char *name, H5T_class_t cls, hid_t mtype, size_t esize, long long len)
{
    void *buf = malloc((size_t)(len > 0 ? len : 1) * esize);
    if (!buf) error_exit(EXIT_SYSTEM, "out of memory reading %s", ckpt_file);
    hid_t d = ckpt_dataset(loc, name, cls, esize, len);
    ckpt_read_rows(d, mtype, buf, len, 0);
    H5CHECK(H5Dclose(d));
    return buf;
}

/* ---- choosing and opening ---------------------------------------------------------- */

/* In directory dir, the valid checkpoint of the later step (checkpoint.h5
 * on a tie). A warning (rank 0) says why the other was passed over whenever
 * it is there and not merely the older one: damaged, unreadable, not a
 * checkpoint, or checkpoint.h5 with the earlier step. */
static void ckpt_choose_dir(const char *dir, char *chosen, size_t n, ckpt_seal *seal)
{
    static const char *name[2] = {"checkpoint.h5", "checkpoint_prev.h5"};
    char why[2][600], path[2][CKPT_PATH_MAX];
    ckpt_seal sl[2];
    int rc[2];
    for (int k = 0; k < 2; ++k) {
        snprintf(path[k], sizeof path[k], "%s/%s", dir, name[k]);
        rc[k] = ckpt_verify(path[k], &sl[k], why[k], sizeof why[k]);
    }
    if (rc[0] && rc[1])
        ckpt_bad("no valid checkpoint in it: checkpoint.h5: %s; checkpoint_prev.h5: %s", why[0], why[1]);
    int best = rc[0] ? 1 : rc[1] ? 0 : sl[1].step > sl[0].step, other = 1 - best;
    if (!rc[0] && !rc[1] && best == 1)
        snprintf(why[0], sizeof why[0], "step %lld, older than checkpoint_prev.h5 (step %lld)", sl[0].step,
                 sl[1].step);
    int tell = best == 1; /* checkpoint.h5 passed over: always said */
    struct stat st;       /* checkpoint_prev.h5 not there (the run's first checkpoint) is no news */
    if (best == 0 && rc[1] != 0) tell = lstat(path[1], &st) == 0 || errno != ENOENT;
    if (tell && comm_rank() == 0)
        warning("--restart %s: %s: %s; taking %s (step %lld)", dir, name[other], why[other], name[best],
                sl[best].step);
    snprintf(chosen, n, "%s", path[best]);
    *seal = sl[best];
}

/* file, or in a directory the valid checkpoint with the latest step; its
 * seal. */
static void ckpt_choose(const char *arg, char *chosen, size_t n, ckpt_seal *seal)
{
    struct stat st;
    int dir = stat(arg, &st) == 0 && S_ISDIR(st.st_mode);
    MPICHECK(MPI_Bcast(&dir, 1, MPI_INT, 0, MPI_COMM_WORLD));
    if (dir) {
        ckpt_choose_dir(arg, chosen, n, seal);
        return;
    }
    char why[600], prev_path[CKPT_PATH_MAX];
    snprintf(chosen, n, "%s", arg);
    if (ckpt_verify(arg, seal, why, sizeof why) == 0) return;
    const char *slash = strrchr(arg, '/');
    int dlen = slash ? (int)(slash - arg) : 1;
    snprintf(prev_path, sizeof prev_path, "%.*s/checkpoint_prev.h5", dlen, slash ? arg : ".");
    int prev = strcmp(prev_path, arg) != 0 && access(prev_path, F_OK) == 0;
    MPICHECK(MPI_Bcast(&prev, 1, MPI_INT, 0, MPI_COMM_WORLD));
    if (prev)
        ckpt_bad("%s (%s is beside it: --restart %.*s takes the newest valid checkpoint there)", why,
                 prev_path, dlen, slash ? arg : ".");
    ckpt_bad("%s", why);
}

/* Open file read-only with MPI-IO, HDF5's error printing off until ckpt_close. */
static hid_t ckpt_open(const char *file)
{
    hid_t fapl, f;
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL); /* our message, not HDF5's stack */
    H5CHECK(fapl = H5Pcreate(H5P_FILE_ACCESS));
    H5CHECK(H5Pset_fapl_mpio(fapl, MPI_COMM_WORLD, MPI_INFO_NULL));
    H5CHECK(H5Pset_all_coll_metadata_ops(fapl, 1));
    f = H5Fopen(file, ckpt_acc_rdonly(), fapl);
    H5CHECK(H5Pclose(fapl));
    if (f < 0) ckpt_bad("not an HDF5 file (or a damaged one)");
    return f;
}

/* ---- the header: this build, this scene ------------------------------------------- */

/* The seal's step and time chose this file (ckpt_choose_dir): they must be
 * /Header's (s->step, s->t), which the checksum covers. Only a legacy seal,
 * whose own words have no check, or a crafted one can differ. */
static void ckpt_check_seal_header(const ckpt_seal *seal, const sim_t *s)
{
    if (seal->step == (long long)s->step && seal->time == s->t) return;
    ckpt_bad("damaged: its checksum block says step %lld, t = %.17g; its /Header says step %ld, t = %.17g%s",
             seal->step, seal->time, s->step, s->t,
             seal->legacy ? " (a seal without its own check, from an earlier sphseg: give the other checkpoint "
                            "by name)" : "");
}

/* The particle arrays the checkpoint holds (its /Header NumArrays): fewer
 * than this build's where it was written before the field table's last
 * rows were added (phi, issue 58); those rows are read only where this
 * run holds them (ckpt_read_particles). */
static size_t ckpt_file_arrays;

/* Check what must match this build (exit 2) and the scene (checkpoint_keys.c). */
static void ckpt_check_header(hid_t g, const sim_t *s)
{
    char *code = ckpt_get_string(g, "Code");
    if (strcmp(code, "sphseg") != 0) ckpt_bad("not a sphseg checkpoint (Code is '%.40s')", code);
    free(code);
    ckpt_get_int(g, "Checkpoint", CKPT_FORMAT, CKPT_FORMAT);
    char *prec = ckpt_get_string(g, "Precision");
    if (strcmp(prec, ckpt_precision()) != 0 || ckpt_get_int(g, "RealBytes", 4, 8) != (long long)sizeof(real))
        ckpt_bad("written by a %.20s-precision build; this build is %s precision (rebuild with "
                 "PRECISION=%.20s)", prec, ckpt_precision(), prec);
    free(prec);
    long long dim = ckpt_get_int(g, "Dimension", 2, 3);
    if (dim != (long long)s->sc->geometry.dim)
        ckpt_bad("holds a %lldD run; the scene %s is %uD: Geometry:dim (%lld in the checkpoint, %u now)", dim,
                 s->sc->path, s->sc->geometry.dim, dim, s->sc->geometry.dim);
    long long na = ckpt_get_int(g, "NumArrays", 1, 1000);
    if (na > (long long)part_narrays())
        ckpt_bad("its particle store has %lld arrays, this build's %zu: written by a later version of sphseg",
                 na, part_narrays());
    ckpt_file_arrays = (size_t)na;
    char *stored = ckpt_get_string(g, "Scene");
    ckpt_check_scene(ckpt_file, stored, s->sc);
    free(stored);
}

/* ---- particles ------------------------------------------------------------------ */

/* This rank's rows: its own block on the same rank count, else an even
 * contiguous share of all rows. */
static void ckpt_my_rows(hid_t g, int nranks_file, long long ntot, long long *n, long long *offset)
{
    int size = comm_size(), rank = comm_rank();
    long long *counts = ckpt_read_all(g, "RankCounts", H5T_INTEGER, H5T_NATIVE_LLONG, 8, nranks_file), sum = 0;
    for (int r = 0; r < nranks_file; ++r) {
        if (counts[r] < 0 || counts[r] > ntot) ckpt_bad("RankCounts[%d] = %lld is out of range", r, counts[r]);
        sum += counts[r];
    }
    if (sum != ntot) ckpt_bad("RankCounts sum to %lld, NumPart_Total is %lld", sum, ntot);
    if (nranks_file == size) {
        *offset = 0;
        for (int r = 0; r < rank; ++r) *offset += counts[r];
        *n = counts[rank];
    } else {
        long long q = ntot / size, rem = ntot % size;
        *n = q + (rank < rem);
        *offset = rank * q + (rank < rem ? rank : rem);
    }
    free(counts);
}

static int ckpt_finite(const real *a, size_t n)
{
    for (size_t i = 0; i < n; ++i)
        if (!isfinite((double)a[i])) return 0;
    return 1;
}

/* This rank's rows in range (kind, class, finite positions, velocities,
 * stresses, volumes > 0, C within the blow-up bounds, a dummy's wall one of the
 * container's nwalls); NULL or the problem. */
static const char *ckpt_check_rows(const particles_t *p, int nwalls, char *why, size_t len)
{
    for (size_t i = 0; i < p->n; ++i) {
        if (p->kind[i] > KIND_DUMMY || p->bclass[i] > BC_DUMMY || p->wall[i] > nwalls ||
            (p->kind[i] == KIND_DUMMY) != (p->wall[i] != 0) || p->id[i] < 0 ||
            !(p->vol[i] > 0 && isfinite((double)p->vol[i])) ||
            (p->kind[i] == KIND_MATERIAL && !((double)p->C[i] >= -1 && (double)p->C[i] <= 2))) {
            snprintf(why, len, "--restart %s: particle row %zu of this rank is out of range (kind %u, class %u, "
                     "wall %u, ID %lld, volume %g, C %g)", ckpt_file, i, p->kind[i], p->bclass[i], p->wall[i], (long long)p->id[i],
                     (double)p->vol[i], (double)p->C[i]);
            return why;
        }
    }
    for (int d = 0; d < 3; ++d)
        if (!ckpt_finite(p->x[d], p->n) || !ckpt_finite(p->X0[d], p->n) || !ckpt_finite(p->v[d], p->n)) {
            snprintf(why, len, "--restart %s: a non-finite position or velocity", ckpt_file);
            return why;
        }
    for (int q = 0; q < 6; ++q)
        if (!ckpt_finite(p->sig[q], p->n)) {
            snprintf(why, len, "--restart %s: a non-finite stress", ckpt_file);
            return why;
        }
    return NULL;
}

/* Every array of the store, raw, this rank's rows; then every rank's rows
 * checked and the verdict agreed. */
static void ckpt_read_particles(hid_t f, sim_t *s, int dim, long long ntot, int nranks_file)
{
    hid_t g = ckpt_group(f, "Particles");
    long long n, offset;
    ckpt_my_rows(g, nranks_file, ntot, &n, &offset);
    hid_t d[256];
    if (part_narrays() > 256) error_exit(EXIT_SYSTEM, "ckpt_read_particles: more than 256 arrays");
    const uint32_t fields = stage_store_fields(stage_flags(s)); /* this run's: the others are not read */
    for (size_t k = ckpt_file_arrays; k < part_narrays(); ++k)   /* an earlier version's file */
        if (fields >> part_array_field(k) & 1u)
            ckpt_bad("its particle store has %zu arrays, this build's %zu, and this run needs array %zu: written "
                     "by an earlier version of sphseg", ckpt_file_arrays, part_narrays(), k);
    for (size_t k = 0; k < ckpt_file_arrays; ++k) { /* every shape before any allocation */
        char name[24];
        snprintf(name, sizeof name, "%02zu", k);
        d[k] = ckpt_dataset(g, name, H5T_INTEGER, part_array_esize(k), ntot);
        if (ckpt_get_int(d[k], "ElementBytes", 1, 8) != (long long)part_array_esize(k))
            ckpt_bad("particle array %s has elements of another size: written by another version", name);
    }
    double need = (double)n * (double)(part_fields_bytes(fields) + 64);
    double have = (double)sysconf(_SC_PHYS_PAGES) * (double)sysconf(_SC_PAGESIZE);
    if (need > 0.8 * have)
        ckpt_bad("%lld particles, %lld on this rank, need %.1f GiB per rank; this machine has %.1f GiB", ntot, n,
                 need / 1073741824.0, have / 1073741824.0);
    part_alloc_fields(&s->p, dim, (size_t)n, fields);
    s->p.n = (size_t)n;
    for (size_t k = 0; k < ckpt_file_arrays; ++k) {
        if (part_array_get(&s->p, k))
            ckpt_read_rows(d[k], ckpt_raw_mem(part_array_esize(k)), part_array_get(&s->p, k), n, offset);
        H5CHECK(H5Dclose(d[k]));
    }
    H5CHECK(H5Gclose(g));
    char why[600];
    input_error_agree(ckpt_check_rows(&s->p, s->flow.w.n, why, sizeof why));
    long long nm = 0;
    for (size_t i = 0; i < s->p.n; ++i) nm += s->p.kind[i] == KIND_MATERIAL;
    s->n_material = (size_t)comm_sum_ll(nm);
    if (s->n_material == 0) ckpt_bad("holds no material particles");
}

/* ---- DEM grains -------------------------------------------------------------------- */

/* /DEM into s->dem (made by setup_contexts from the scene, whose DEM keys
 * ckpt_check_scene has compared): every rank reads every grain, whatever
 * the rank count that wrote them; the first coupling divides them
 * (dem_exchange, src/dem/dem_halo.c).
 * Every rank reads the same bytes, so a problem stops all ranks alike. */
static void ckpt_read_dem(hid_t f, sim_t *s)
{
    htri_t e;
    H5CHECK(e = H5Lexists(f, "DEM", H5P_DEFAULT));
    dem_t *d = s->dem;
    if (!d && !e) return;
    if (!d) ckpt_bad("holds DEM grains, but the scene %s has none (DEM:d = 0)", s->sc->path);
    if (!e) ckpt_bad("holds no DEM grains (no group /DEM), but the scene %s has %zu", s->sc->path, d->n);
    hid_t g = ckpt_group(f, "DEM");
    long long n = ckpt_get_int(g, "Count", 0, CKPT_MAX_PART);
    if (n != (long long)d->n) ckpt_bad("holds %lld DEM grains; the scene %s makes %zu", n, s->sc->path, d->n);
    if (ckpt_get_int(g, "ContactsMax", 1, 1000) != DEM_CMAX)
        ckpt_bad("its DEM contact lists are not %d long: written by another version of sphseg", DEM_CMAX);
    d->steps = (long)ckpt_get_int(g, "Steps", 0, 1LL << 62);
    d->exch[0] = ckpt_get_double(g, "ExchangeX", -HUGE_VAL, HUGE_VAL);
    d->exch[1] = ckpt_get_double(g, "ExchangeY", -HUGE_VAL, HUGE_VAL);
    d->exch[2] = ckpt_get_double(g, "ExchangeZ", -HUGE_VAL, HUGE_VAL);
    for (size_t k = 0; k < DEM_STATE_NARRAYS; ++k) {
        dem_state_array a = dem_state_get(d, k);
        long long len = (long long)(d->n * a.per);
        hid_t ds = ckpt_dataset(g, a.name, a.is_double ? H5T_FLOAT : H5T_INTEGER, a.esize, len);
        hid_t mt = a.is_double ? H5T_NATIVE_DOUBLE : a.esize == 8 ? H5T_NATIVE_INT64 : H5T_NATIVE_INT32;
        ckpt_read_rows(ds, mt, a.a, len, 0);
        H5CHECK(H5Dclose(ds));
    }
    H5CHECK(H5Gclose(g));
    char why[300];
    if (dem_state_check(d, s->flow.w.n, why, sizeof why)) ckpt_bad("%s", why);
}

/* ---- run state, decomposition -------------------------------------------------------- */

static void ckpt_read_run(hid_t f, double t, ckpt_run *r)
{
    hid_t g = ckpt_group(f, "Diagnostics");
    r->small0 = ckpt_get_double(g, "SmallVolume0", -HUGE_VAL, HUGE_VAL);
    r->max_drift = ckpt_get_double(g, "MaxDrift", 0, HUGE_VAL);
    r->warned = (int)ckpt_get_int(g, "Warned", 0, 1);
    r->out_n = ckpt_get_int(g, "OutflowCount", 0, LLONG_MAX);
    r->out_cv = ckpt_get_double(g, "OutflowSmallVolume", -HUGE_VAL, HUGE_VAL);
    H5CHECK(H5Gclose(g));
    g = ckpt_group(f, "Outputs");
    r->nsnap = (int)ckpt_get_int(g, "Count", 0, CKPT_MAX_SNAP);
    r->times = ckpt_read_all(g, "Times", H5T_FLOAT, H5T_NATIVE_DOUBLE, 8, r->nsnap);
    r->npart = ckpt_read_all(g, "NumPart", H5T_INTEGER, H5T_NATIVE_LLONG, 8, r->nsnap);
    for (int i = 0; i < r->nsnap; ++i)
        if (!(r->times[i] >= (i ? r->times[i - 1] : 0) && r->times[i] <= t) || r->npart[i] < 1 ||
            r->npart[i] > CKPT_MAX_PART)
            ckpt_bad("/Outputs row %d (time %g, %lld particles) is out of range", i, r->times[i], r->npart[i]);
    H5CHECK(H5Gclose(g));
}

static void ckpt_check_decomp(const ckpt_run *r, int nranks, long long nv)
{
    for (int k = 0; k < nranks; ++k)
        if (r->dec_method == 0 && r->dec_bound[k + 1] < r->dec_bound[k])
            ckpt_bad("/Decomposition/Bounds decrease at rank %d", k);
    for (long long k = 0; k < nv; ++k)
        if (r->dec_part[k] < 0 || r->dec_part[k] >= nranks)
            ckpt_bad("/Decomposition/Owners[%lld] = %d is not a rank", k, r->dec_part[k]);
}

/* The decomposition, when the checkpoint has one and this run has its
 * rank count. */
static void ckpt_read_decomp(hid_t f, int nranks, ckpt_run *r)
{
    htri_t e;
    H5CHECK(e = H5Lexists(f, "Decomposition", H5P_DEFAULT));
    if (!e || nranks != comm_size()) return;
    hid_t g = ckpt_group(f, "Decomposition");
    r->dec_method = (int)ckpt_get_int(g, "Method", 0, 1);
    r->dec_axis = (int)ckpt_get_int(g, "Axis", -1, 2);
    htri_t has_blk;
    H5CHECK(has_blk = H5Aexists(g, "CoarseCellWidth"));
    r->dec_blk = has_blk ? (int)ckpt_get_int(g, "CoarseCellWidth", 1, 16) : HALO_DEPTH;
    long long nv = 1;
    for (int k = 0; k < 3; ++k) {
        char name[16];
        snprintf(name, sizeof name, "CoarseCells%d", k);
        r->dec_cg[k] = (int)ckpt_get_int(g, name, 0, CKPT_MAX_CELLS);
        nv = nv * r->dec_cg[k] > CKPT_MAX_CELLS ? CKPT_MAX_CELLS + 1 : nv * r->dec_cg[k];
    }
    if (r->dec_method != 1) nv = 0;
    if (nv > CKPT_MAX_CELLS) ckpt_bad("/Decomposition has more than %lld coarse cells", CKPT_MAX_CELLS);
    r->dec_bound = ckpt_read_all(g, "Bounds", H5T_INTEGER, H5T_NATIVE_LONG, 8, nranks + 1);
    r->dec_part = ckpt_read_all(g, "Owners", H5T_INTEGER, H5T_NATIVE_INT, 4, nv);
    ckpt_check_decomp(r, nranks, nv);
    H5CHECK(H5Gclose(g));
    r->dec_present = 1;
}

void ckpt_read(const char *arg, sim_t *s, ckpt_run *r, char *chosen, size_t n)
{
    ckpt_seal seal;
    ckpt_file = arg;
    ckpt_choose(arg, chosen, n, &seal);
    ckpt_file = chosen;
    hid_t f = ckpt_open(chosen), g = ckpt_group(f, "Header");
    s->t = ckpt_get_double(g, "Time", 0, 1e300);
    s->step = (long)ckpt_get_int(g, "Step", 0, 1LL << 62);
    ckpt_check_seal_header(&seal, s);
    ckpt_check_header(g, s);
    long long ntot = ckpt_get_int(g, "NumPart_Total", 1, CKPT_MAX_PART);
    int nranks = (int)ckpt_get_int(g, "NumRanks", 1, CKPT_MAX_RANKS);
    s->dt = ckpt_get_double(g, "Dt", 0, 1e300);
    s->amax = ckpt_get_double(g, "Amax", 0, HUGE_VAL);
    s->win.k = (long)ckpt_get_int(g, "WindowSteps", 0, CKPT_MAX_WINDOW); /* the open concentration window */
    s->win.K = (long)ckpt_get_int(g, "WindowTarget", 0, CKPT_MAX_WINDOW);
    s->win.T = ckpt_get_double(g, "WindowLength", 0, 1e300);
    H5CHECK(H5Gclose(g));
    ckpt_read_run(f, s->t, r);
    ckpt_read_particles(f, s, (int)s->sc->geometry.dim, ntot, nranks);
    ckpt_read_dem(f, s);
    ckpt_read_decomp(f, nranks, r);
    H5CHECK(H5Fclose(f));
    H5Eset_auto2(H5E_DEFAULT, (H5E_auto2_t)H5Eprint2, stderr);
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
