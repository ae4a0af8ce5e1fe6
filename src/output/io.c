/* io.c — parallel HDF5 snapshots and their XDMF index (see io.h). */
#include "io.h"
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <hdf5.h>
#include <mpi.h>
/* hdf5.h's H5F_ACC_* flags expand to its own H5CHECK macro, whose name
 * error.h takes over: read the flag here, before error.h comes in (with
 * error.h first, hdf5.h's H5CHECK replaced ours and no call was checked). */
static unsigned io_acc_trunc(void) { return H5F_ACC_TRUNC; }
#include "core/error.h"
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/statvfs.h>
#include <unistd.h>

#define IO_PATH_MAX 4096
#define IO_LINE_MAX 4800 /* a failed write's line: a path and a reason */
#define IO_SPACE_MARGIN 65536.0 /* bytes of HDF5 metadata and block rounding beyond the data */

/* ---- failed writes ---------------------------------------------------------- */

static int io_rank(void);

/* The file being written (one at a time) and its temporary name: a failed
 * write closes it and removes the temporary before the run ends, so that
 * MPI_Finalize never meets an open HDF5 file and the disk gets its space
 * back; the final names keep the last complete files. agreed: every rank
 * ends together (io_write_agree), so closing, which is collective, is safe. */
static struct {
    hid_t file;
    char tmp[IO_PATH_MAX];
    int agreed;
} io_open = {-1, "", 0};

static int io_abandon(void)
{
    int stuck = 0, size = 1, together = 0;
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    together = size == 1 || io_open.agreed;
    if (io_open.tmp[0]) (void)truncate(io_open.tmp, 0); /* gives the space back, so HDF5 can close it */
    if (io_open.file >= 0 && together) { /* a rank failing alone aborts instead: closing is collective */
        if (size > 1) MPI_Barrier(MPI_COMM_WORLD); /* every rank's truncation before anyone's close writes */
        H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
        stuck = H5Fclose(io_open.file) < 0;
        io_open.file = -1;
        if (size > 1) MPI_Allreduce(MPI_IN_PLACE, &stuck, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD); /* all or none */
    }
    if (io_open.tmp[0]) unlink(io_open.tmp);
    io_open.tmp[0] = 0;
    return stuck;
}

/* An errno that means a write lost data: no space, a quota, a file too
 * large, an I/O error. */
static int io_write_errno(int e) { return e == ENOSPC || e == EDQUOT || e == EFBIG || e == EIO; }

/* Bytes free on the file system of the file path (its directory), or
 * HUGE_VAL when that cannot be read. */
static double io_free_bytes(const char *path)
{
    char dir[IO_PATH_MAX];
    snprintf(dir, sizeof dir, "%s", path);
    char *slash = strrchr(dir, '/');
    if (slash) *slash = 0;
    struct statvfs v;
    return statvfs(slash ? dir : ".", &v) == 0 ? (double)v.f_bavail * (double)v.f_frsize : HUGE_VAL;
}

/* The one line of a failed write: the file, what failed, why (err), and the
 * space left on its file system. */
static void io_fail_line(char *line, size_t n, int err, const char *what)
{
    char space[160] = "";
    double mb = 1e-6 * io_free_bytes(io_open.tmp[0] ? io_open.tmp : "./output");
    if (mb < HUGE_VAL)
        snprintf(space, sizeof space, "; %.4g MB free on its file system%s", mb, mb < 1 ? ": the disk is full" : "");
    snprintf(line, n, "cannot write %s: %s (%s%s); the last complete snapshot and checkpoint are kept",
             io_open.tmp[0] ? io_open.tmp : "output", what, io_write_errno(err) ? strerror(err) : "write failed",
             space);
}

void io_write_failed(const char *fmt, ...)
{
    int err = errno;
    char what[600], line[IO_LINE_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    io_fail_line(line, sizeof line, err, what);
    error_on_exit(io_abandon);
    error_exit(EXIT_WRITE, "%s", line);
}

void io_write_agree(int failed, const char *fmt, ...)
{
    int err = errno;
    char what[600], line[IO_LINE_MAX];
    if (failed) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(what, sizeof what, fmt, ap);
        va_end(ap);
        io_fail_line(line, sizeof line, err, what);
    }
    io_open.agreed = 1;
    error_on_exit(io_abandon);
    error_agree(EXIT_WRITE, failed ? line : NULL); /* returns only when no rank failed */
    error_on_exit(NULL);
    io_open.agreed = 0;
}

/* Collective, before a file of about need bytes is written to path (rank
 * 0 looks): a file system with less room than that (and a margin for
 * HDF5's metadata) ends the run on every rank before anything is written.
 * A collective write that fills the disk part-way can fail on one rank
 * only, inside HDF5 (its close then waits in different collectives on
 * different ranks); this keeps a full disk from ever getting there. */
static void io_check_space(const char *path, double need)
{
    double avail = io_rank() == 0 ? io_free_bytes(path) : HUGE_VAL;
    MPICHECK(MPI_Bcast(&avail, 1, MPI_DOUBLE, 0, MPI_COMM_WORLD));
    double want = need + need / 64 + IO_SPACE_MARGIN;
    char line[IO_LINE_MAX];
    if (avail < want)
        snprintf(line, sizeof line, "cannot write %s: it needs about %.4g MB and its file system has %.4g MB free%s; "
                 "the last complete snapshot and checkpoint are kept", path, 1e-6 * want, 1e-6 * avail,
                 avail < 1e6 ? ": the disk is full" : "");
    error_agree(EXIT_WRITE, io_rank() == 0 && avail < want ? line : NULL);
}

/* In this file every HDF5 call writes an output file: a failure is a failed
 * write (exit status 4), not a system failure. */
#undef H5CHECK
#define H5CHECK(call)                                                                                        \
    do {                                                                                                     \
        if ((call) < 0) io_write_failed("%s at %s:%d", #call, __FILE__, __LINE__);                           \
    } while (0)

/* ---- the field table ---------------------------------------------------- */

#define IO_ARRAY(fn, expr)                                                                                   \
    static const void *fn(const particles_t *p, int c)                                                       \
    {                                                                                                        \
        (void)c;                                                                                             \
        return (expr);                                                                                       \
    }
IO_ARRAY(io_x, p->x[c])
IO_ARRAY(io_v, p->v[c])
IO_ARRAY(io_c, p->C)
IO_ARRAY(io_gdot, p->gdot)
IO_ARRAY(io_sig, p->sig[c])
IO_ARRAY(io_vol, p->vol)
IO_ARRAY(io_nrm, p->nrm[c])
IO_ARRAY(io_psi, p->psi)
IO_ARRAY(io_kind, p->kind)
IO_ARRAY(io_bclass, p->bclass)
IO_ARRAY(io_wall, p->wall)
IO_ARRAY(io_id, p->id)
#undef IO_ARRAY

const struct io_field io_fields[] = {
    {"Coordinates", IO_REAL, 3, "m", "Particle position (x, y, z); z = 0 in 2D", io_x},
    {"Velocities", IO_REAL, 3, "m/s", "Particle velocity (vx, vy, vz); vz = 0 in 2D", io_v},
    {"Concentration", IO_CREAL, 1, "-",
     "Small-grain volume concentration C (eq. 2.10); meaningful for Kind = 0 (material) only", io_c},
    {"ShearRate", IO_REAL, 1, "1/s", "Shear-rate magnitude gdot", io_gdot},
    {"Stress", IO_REAL, 6, "Pa",
     "Cauchy stress, tension positive, (xx, yy, zz, xy, xz, yz); 2D is plane strain (zz from the "
     "model); dummies carry the extrapolated wall stress (eq. 4.3); zero with prescribed velocity",
     io_sig},
    {"Volume", IO_REAL, 1, "m^d", "Particle volume m_i/rho_i (m^2 per unit depth in 2D, m^3 in 3D)", io_vol},
    {"Normal", IO_REAL, 3, "-", "HCSR boundary normal, pointing into the material (paper section 4.2)",
     io_nrm},
    {"Psi", IO_REAL, 1, "-", "Smoothed degenerate function psi~ (eqs. 4.14, 4.18)", io_psi},
    {"Kind", IO_UINT8, 1, "-", "Particle kind: 0 material, 1 dummy (wall)", io_kind},
    {"BoundaryClass", IO_UINT8, 1, "-",
     "HCSR boundary class (paper section 4.2.2): 0 interior, 1 free surface, "
     "2 free-surface vicinity, 3 wall surface, 4 wall vicinity, 5 dummy",
     io_bclass},
    {"Wall", IO_UINT8, 1, "-",
     "A dummy's wall: the 1-based index of its wall primitive, named in the header attribute Walls; 0 material",
     io_wall},
    {"ParticleIDs", IO_INT64, 1, "-", "Global particle ID, unique and constant in a run", io_id},
};
const int io_nfields = (int)(sizeof io_fields / sizeof io_fields[0]);

static hid_t io_mem_type(enum io_type t)
{
    return t == IO_REAL || t == IO_CREAL ? H5T_NATIVE_DOUBLE : t == IO_UINT8 ? H5T_NATIVE_UINT8 : H5T_NATIVE_INT64;
}

static hid_t io_file_type(enum io_type t)
{
    return t == IO_REAL || t == IO_CREAL ? H5T_IEEE_F64LE : t == IO_UINT8 ? H5T_STD_U8LE : H5T_STD_I64LE;
}

/* Bytes of one /Topology/Vertices entry for a snapshot of n particles. */
static int io_vertex_bytes(long long n) { return n <= INT32_MAX ? 4 : 8; }

/* ---- small helpers -------------------------------------------------------- */

static void io_join(char *buf, const char *outdir, const char *name, const char *suffix)
{
    int len = snprintf(buf, IO_PATH_MAX, "%s/%s%s", outdir, name, suffix);
    if (len < 0 || len >= IO_PATH_MAX) error_exit(1, "output path too long: %s/%s", outdir, name);
}

static int io_rank(void)
{
    int rank = 0;
    MPICHECK(MPI_Comm_rank(MPI_COMM_WORLD, &rank));
    return rank;
}

/* Barrier, rank 0 renames tmp to path, barrier: the final name appears only
 * once every rank has finished writing, and exists when this returns. */
static void io_commit(const char *tmp, const char *path, int collective)
{
    if (collective) MPICHECK(MPI_Barrier(MPI_COMM_WORLD));
    if (io_rank() == 0 && rename(tmp, path) != 0) io_write_failed("cannot rename it to %s", path);
    if (collective) MPICHECK(MPI_Barrier(MPI_COMM_WORLD));
}

/* Variable-length UTF-8 string attribute (any length; h5py reads a str). */
void io_attr_string(hid_t loc, const char *name, const char *value)
{
    hid_t type, space, attr;
    const char *v = value ? value : "";
    H5CHECK(type = H5Tcopy(H5T_C_S1));
    H5CHECK(H5Tset_size(type, H5T_VARIABLE));
    H5CHECK(H5Tset_cset(type, H5T_CSET_UTF8));
    H5CHECK(space = H5Screate(H5S_SCALAR));
    H5CHECK(attr = H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT));
    H5CHECK(H5Awrite(attr, type, &v));
    H5CHECK(H5Aclose(attr));
    H5CHECK(H5Sclose(space));
    H5CHECK(H5Tclose(type));
}

void io_attr_scalar(hid_t loc, const char *name, hid_t ftype, hid_t mtype, const void *val)
{
    hid_t space, attr;
    H5CHECK(space = H5Screate(H5S_SCALAR));
    H5CHECK(attr = H5Acreate2(loc, name, ftype, space, H5P_DEFAULT, H5P_DEFAULT));
    H5CHECK(H5Awrite(attr, mtype, val));
    H5CHECK(H5Aclose(attr));
    H5CHECK(H5Sclose(space));
}

/* ---- snapshot: rows in global particle-ID order ---------------------------- */

/* The file holds the N particles in increasing ParticleIDs order whatever the
 * rank count and however particles are spread over ranks (IDs need not be
 * dense, only unique). Rank r writes file rows [r N/P, (r+1) N/P): the
 * particles whose ID has that global rank among all IDs. The boundaries are
 * ID values found by bisection over the ID range (one MPI_Allreduce of P-1
 * counts per halving, at most 64), rows move by MPI_Alltoallv one field at a
 * time and are merged by a local sort. Memory per rank: O(local rows + P). */

struct io_key {
    uint64_t key;
    size_t i;
};

static int io_key_cmp(const void *a, const void *b)
{
    const struct io_key *ka = a, *kb = b;
    return (ka->key > kb->key) - (ka->key < kb->key);
}

/* Order-preserving map of int64 IDs onto uint64 (so bisection cannot overflow). */
static uint64_t io_ukey(int64_t id) { return (uint64_t)id ^ (UINT64_C(1) << 63); }

/* Sorts key[0..n) by key; returns the original indices in that order
 * (malloc'd, >= 1 element) and leaves the sorted keys in ukey (n elements). */
static size_t *io_sort_keys(struct io_key *key, size_t n, uint64_t *ukey)
{
    size_t *order = malloc((n > 0 ? n : 1) * sizeof *order);
    if (!order) error_exit(1, "out of memory sorting %zu particles for output", n);
    qsort(key, n, sizeof *key, io_key_cmp);
    for (size_t k = 0; k < n; k++) {
        order[k] = key[k].i;
        if (ukey) ukey[k] = key[k].key;
    }
    return order;
}

/* How many of the sorted keys key[0..n) are <= v. */
static size_t io_count_le(const uint64_t *key, size_t n, uint64_t v)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (key[mid] <= v)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

/* The first file row of rank r: floor(r N / P), without overflow. */
static long long io_first_row(int r, long long ntot, int size)
{
    return r * (ntot / size) + r * (ntot % size) / size;
}

/* cnt[d] = how many of this rank's ID-sorted rows (sorted keys key[0..n))
 * go to rank d: those whose global rank lies in [d N/P, (d+1) N/P).
 * Collective. */
static void io_plan(const uint64_t *key, size_t n, long long ntot, int size, int *cnt)
{
    int ns = size - 1;
    uint64_t umin = n > 0 ? key[0] : UINT64_MAX, umax = n > 0 ? key[n - 1] : 0, gmin, gmax;
    MPICHECK(MPI_Allreduce(&umin, &gmin, 1, MPI_UINT64_T, MPI_MIN, MPI_COMM_WORLD));
    MPICHECK(MPI_Allreduce(&umax, &gmax, 1, MPI_UINT64_T, MPI_MAX, MPI_COMM_WORLD));
    uint64_t *lo = malloc((ns + 1) * sizeof *lo), *hi = malloc((ns + 1) * sizeof *hi);
    long long *c = malloc((ns + 1) * sizeof *c), *cg = malloc((ns + 1) * sizeof *cg);
    if (!lo || !hi || !c || !cg) error_exit(1, "out of memory planning output over %d ranks", size);
    for (int k = 0; k < ns; k++)
        lo[k] = gmin, hi[k] = gmax;
    /* Splitter k: the smallest ID value v with #{IDs <= v} >= (k+1) N/P.
     * lo and hi are the same on every rank, so all ranks loop alike. */
    for (int busy = ntot > 0 && ns > 0; busy;) {
        for (int k = 0; k < ns; k++)
            c[k] = (long long)io_count_le(key, n, lo[k] + (hi[k] - lo[k]) / 2);
        MPICHECK(MPI_Allreduce(c, cg, ns, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD));
        busy = 0;
        for (int k = 0; k < ns; k++) {
            uint64_t mid = lo[k] + (hi[k] - lo[k]) / 2;
            if (cg[k] >= io_first_row(k + 1, ntot, size))
                hi[k] = mid;
            else
                lo[k] = mid + 1;
            busy |= lo[k] < hi[k];
        }
    }
    size_t prev = 0;
    for (int d = 0; d < size; d++) {
        size_t upto = d == ns ? n : io_first_row(d + 1, ntot, size) == 0 ? 0 : io_count_le(key, n, lo[d]);
        cnt[d] = (int)(upto - prev);
        prev = upto;
    }
    free(lo);
    free(hi);
    free(c);
    free(cg);
}

/* The exchange of one snapshot: this rank's n rows leave in ID order
 * (send_order), m rows arrive and are written in ID order (recv_order). */
struct io_xchg {
    int size;
    size_t n, m;
    size_t *send_order, *recv_order;
    int *scnt, *sdsp, *rcnt, *rdsp; /* in rows */
};

/* Plans the exchange of p's rows (collective); fails on a duplicate ID. */
static void io_xchg_plan(struct io_xchg *x, const particles_t *p, long long ntot)
{
    MPICHECK(MPI_Comm_size(MPI_COMM_WORLD, &x->size));
    size_t n = p->n, sz = (size_t)x->size;
    x->n = n;
    struct io_key *key = malloc((n > 0 ? n : 1) * sizeof *key);
    uint64_t *ukey = malloc((n > 0 ? n : 1) * sizeof *ukey);
    x->scnt = malloc(4 * sz * sizeof(int));
    if (!key || !ukey || !x->scnt) error_exit(1, "out of memory sorting %zu particles for output", n);
    if (n > INT_MAX)
        error_exit(1, "%zu particles on one rank: snapshot output handles at most %d", n, INT_MAX);
    x->sdsp = x->scnt + sz, x->rcnt = x->sdsp + sz, x->rdsp = x->rcnt + sz;
    for (size_t k = 0; k < n; k++)
        key[k] = (struct io_key){io_ukey(p->id[k]), k};
    x->send_order = io_sort_keys(key, n, ukey);
    io_plan(ukey, n, ntot, x->size, x->scnt);
    MPICHECK(MPI_Alltoall(x->scnt, 1, MPI_INT, x->rcnt, 1, MPI_INT, MPI_COMM_WORLD));
    long long m = 0, s = 0;
    for (int d = 0; d < x->size; d++) {
        x->sdsp[d] = (int)s, s += x->scnt[d];
        x->rdsp[d] = (int)(m < INT_MAX ? m : INT_MAX), m += x->rcnt[d];
    }
    if (m > INT_MAX)
        error_exit(1, "%lld particles for one rank: snapshot output handles at most %d", m, INT_MAX);
    x->m = (size_t)m;
    uint64_t *rkey = malloc((x->m > 0 ? x->m : 1) * sizeof *rkey);
    struct io_key *rk = x->m > n ? realloc(key, x->m * sizeof *key) : key;
    if (!rkey || !rk) error_exit(1, "out of memory receiving %zu particles for output", x->m);
    MPICHECK(MPI_Alltoallv(ukey, x->scnt, x->sdsp, MPI_UINT64_T, rkey, x->rcnt, x->rdsp, MPI_UINT64_T,
                           MPI_COMM_WORLD));
    for (size_t k = 0; k < x->m; k++)
        rk[k] = (struct io_key){rkey[k], k};
    x->recv_order = io_sort_keys(rk, x->m, rkey);
    for (size_t k = 1; k < x->m; k++) /* equal IDs always meet on one rank */
        if (rkey[k] == rkey[k - 1])
            error_exit(1, "snapshot output: particle ID %lld is held twice",
                       (long long)io_ukey((int64_t)rkey[k]));
    free(rk);
    free(rkey);
    free(ukey);
}

static void io_xchg_free(struct io_xchg *x)
{
    free(x->send_order);
    free(x->recv_order);
    free(x->scnt);
}

/* buf[k*ncomp + c] = component c of particle order[k], in the stored type. */
static void io_gather(const struct io_field *f, const particles_t *p, const size_t *order, void *buf)
{
    size_t n = p->n, nc = (size_t)f->ncomp;
    for (int c = 0; c < f->ncomp; c++) {
        const void *a = f->array(p, c);
        if (f->type == IO_REAL) {
            const real *s = a;
            double *d = (double *)buf + c;
            for (size_t k = 0; k < n; k++)
                d[k * nc] = (double)s[order[k]];
        } else if (f->type == IO_CREAL) {
            const creal *s = a;
            double *d = (double *)buf + c;
            for (size_t k = 0; k < n; k++)
                d[k * nc] = (double)s[order[k]];
        } else if (f->type == IO_UINT8) {
            const uint8_t *s = a;
            uint8_t *d = (uint8_t *)buf + c;
            for (size_t k = 0; k < n; k++)
                d[k * nc] = s[order[k]];
        } else {
            const int64_t *s = a;
            int64_t *d = (int64_t *)buf + c;
            for (size_t k = 0; k < n; k++)
                d[k * nc] = s[order[k]];
        }
    }
}

static size_t io_type_size(enum io_type t) { return t == IO_REAL || t == IO_CREAL ? 8 : t == IO_UINT8 ? 1 : 8; }

/* Field f of this rank's file rows, in ID order, into out (x->m rows); tmp
 * holds max(n, m) rows of the widest field. Collective. */
static void io_xchg_field(const struct io_xchg *x, const struct io_field *f, const particles_t *p, void *tmp,
                          void *out)
{
    size_t row = io_type_size(f->type) * (size_t)f->ncomp;
    MPI_Datatype t;
    MPI_Datatype base = f->type == IO_REAL || f->type == IO_CREAL ? MPI_DOUBLE : f->type == IO_UINT8 ? MPI_UINT8_T : MPI_INT64_T;
    MPICHECK(MPI_Type_contiguous(f->ncomp, base, &t));
    MPICHECK(MPI_Type_commit(&t));
    io_gather(f, p, x->send_order, tmp);
    MPICHECK(MPI_Alltoallv(tmp, x->scnt, x->sdsp, t, out, x->rcnt, x->rdsp, t, MPI_COMM_WORLD));
    MPICHECK(MPI_Type_free(&t));
    for (size_t k = 0; k < x->m; k++) /* received runs, merged into ID order */
        memcpy((char *)tmp + k * row, (const char *)out + x->recv_order[k] * row, row);
    if (x->m > 0) memcpy(out, tmp, x->m * row);
}

/* Create grp/<f->name> (ntot rows of file type ftype) and write this rank's
 * n rows (memory type mtype) at row offset, collectively; buf holds the
 * gathered rows. */
static void io_write_field_as(hid_t grp, hid_t dxpl, const struct io_field *f, hid_t mtype, hid_t ftype,
                              const void *buf, size_t n, long long ntot, long long offset)
{
    int rank = f->ncomp > 1 ? 2 : 1;
    hsize_t dims[2] = {(hsize_t)ntot, (hsize_t)f->ncomp};
    hsize_t mdims[2] = {n > 0 ? (hsize_t)n : 1, (hsize_t)f->ncomp};
    hsize_t start[2] = {(hsize_t)offset, 0}, count[2] = {(hsize_t)n, (hsize_t)f->ncomp};
    hid_t fspace, mspace, dset;
    H5CHECK(fspace = H5Screate_simple(rank, dims, NULL));
    H5CHECK(mspace = H5Screate_simple(rank, mdims, NULL));
    H5CHECK(dset = H5Dcreate2(grp, f->name, ftype, fspace, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    if (n > 0) {
        H5CHECK(H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start, NULL, count, NULL));
    } else { /* this rank takes part in the collective write with nothing */
        H5CHECK(H5Sselect_none(fspace));
        H5CHECK(H5Sselect_none(mspace));
    }
    char name[80];
    snprintf(name, sizeof name, "the dataset %s", f->name);
    if (ntot > 0) io_write_rows(dset, mtype, mspace, fspace, dxpl, buf, name);
    io_attr_string(dset, "Description", f->description);
    io_attr_string(dset, "Units", f->units);
    H5CHECK(H5Dclose(dset));
    H5CHECK(H5Sclose(mspace));
    H5CHECK(H5Sclose(fspace));
}

/* /Particles/<f->name> in the types of the field table. */
static void io_write_field(hid_t grp, hid_t dxpl, const struct io_field *f, const void *buf, size_t n,
                           long long ntot, long long offset)
{
    io_write_field_as(grp, dxpl, f, io_mem_type(f->type), io_file_type(f->type), buf, n, ntot, offset);
}

/* /Topology/Vertices: 0 .. N-1, the XDMF Polyvertex connectivity (one cell
 * per particle). XDMF readers that build cells from a topology's own data
 * (ParaView's Xdmf3 readers, its default) find no cells without it. Stored
 * as 32-bit integers while N fits (4 bytes a particle, 2-3 % of a snapshot),
 * else 64-bit (io_vertex_bytes). buf holds at least m 8-byte rows. */
static void io_write_vertices(hid_t file, hid_t dxpl, void *buf, size_t m, long long ntot, long long offset)
{
    int wide = io_vertex_bytes(ntot) == 8;
    for (size_t k = 0; k < m; k++) {
        if (wide) ((int64_t *)buf)[k] = offset + (long long)k;
        else ((int32_t *)buf)[k] = (int32_t)(offset + (long long)k);
    }
    static const struct io_field vertices = {"Vertices", IO_INT64, 1, "-",
                                             "XDMF Polyvertex connectivity: row k holds k (one cell per particle)",
                                             NULL};
    hid_t grp;
    H5CHECK(grp = H5Gcreate2(file, "Topology", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    io_write_field_as(grp, dxpl, &vertices, wide ? H5T_NATIVE_INT64 : H5T_NATIVE_INT32,
                      wide ? H5T_STD_I64LE : H5T_STD_I32LE, buf, m, ntot, offset);
    H5CHECK(H5Gclose(grp));
}

/* /Particles: every field of the table, all N rows in global particle-ID
 * order (the DESIGN.md contract) whatever the rank count: this rank writes
 * its x->m rows, the IDs of global rank [offset, offset + m), as one
 * hyperslab. */
static void io_write_particles(hid_t file, const particles_t *p, long long ntot)
{
    struct io_xchg x;
    io_xchg_plan(&x, p, ntot);
    long long m = (long long)x.m, offset = 0;
    MPICHECK(MPI_Exscan(&m, &offset, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD));
    if (io_rank() == 0) offset = 0; /* MPI_Exscan leaves rank 0's result undefined */
    int ncmax = 1;
    for (int k = 0; k < io_nfields; ++k)
        ncmax = io_fields[k].ncomp > ncmax ? io_fields[k].ncomp : ncmax;
    size_t rows = x.m > x.n ? x.m : x.n;
    void *tmp = malloc((rows > 0 ? rows : 1) * (size_t)ncmax * sizeof(double)); /* largest row */
    void *buf = malloc((x.m > 0 ? x.m : 1) * (size_t)ncmax * sizeof(double));
    if (!tmp || !buf) error_exit(1, "out of memory gathering %zu particles for output", rows);
    hid_t grp, dxpl;
    H5CHECK(grp = H5Gcreate2(file, "Particles", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    H5CHECK(dxpl = H5Pcreate(H5P_DATASET_XFER));
    H5CHECK(H5Pset_dxpl_mpio(dxpl, H5FD_MPIO_COLLECTIVE));
    for (int i = 0; i < io_nfields; i++) {
        io_xchg_field(&x, &io_fields[i], p, tmp, buf);
        io_write_field(grp, dxpl, &io_fields[i], buf, x.m, ntot, offset);
    }
    H5CHECK(H5Gclose(grp));
    io_write_vertices(file, dxpl, buf, x.m, ntot, offset);
    H5CHECK(H5Pclose(dxpl));
    free(tmp);
    free(buf);
    io_xchg_free(&x);
}

static void io_write_header(hid_t file, int dim, double time, long step, long long ntot,
                            const char *scene_text, const char *walls, const char *code_version)
{
    hid_t g;
    int64_t step64 = step, ntot64 = ntot;
    H5CHECK(g = H5Gcreate2(file, "Header", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    io_attr_scalar(g, "Time", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &time);
    io_attr_scalar(g, "Step", H5T_STD_I64LE, H5T_NATIVE_INT64, &step64);
    io_attr_scalar(g, "Dimension", H5T_STD_I32LE, H5T_NATIVE_INT, &dim);
    io_attr_scalar(g, "NumPart_Total", H5T_STD_I64LE, H5T_NATIVE_INT64, &ntot64);
    io_attr_string(g, "Code", "sphseg");
    io_attr_string(g, "Version", code_version);
    io_attr_string(g, "Precision", sizeof(real) == sizeof(float) ? "single" : "double");
    io_attr_string(g, "Scene", scene_text);
    io_attr_string(g, "Walls", walls ? walls : "");
    H5CHECK(H5Gclose(g));
}

hid_t io_create_file(const char *path, size_t userblock, double need)
{
    hid_t fapl, fcpl, file;
    io_check_space(path, need + (double)userblock);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL); /* a failed write is one line (io_write_failed), not HDF5's stack */
    H5CHECK(fcpl = H5Pcreate(H5P_FILE_CREATE));
    if (userblock) H5CHECK(H5Pset_userblock(fcpl, (hsize_t)userblock));
    H5CHECK(fapl = H5Pcreate(H5P_FILE_ACCESS));
    H5CHECK(H5Pset_fapl_mpio(fapl, MPI_COMM_WORLD, MPI_INFO_NULL));
    H5CHECK(H5Pset_coll_metadata_write(fapl, 1));
    H5CHECK(H5Pset_all_coll_metadata_ops(fapl, 1));
    snprintf(io_open.tmp, sizeof io_open.tmp, "%s", path);
    errno = 0;
    file = H5Fcreate(path, io_acc_trunc(), fcpl, fapl);
    io_write_agree(file < 0, "cannot create it (does the output directory exist?)");
    io_open.file = file;
    H5CHECK(H5Pclose(fapl));
    H5CHECK(H5Pclose(fcpl));
    return file;
}


void io_close_file(hid_t file)
{
    errno = 0;
    herr_t rc = H5Fclose(file);
    io_open.file = -1; /* closed, or beyond closing: never closed twice */
    io_write_agree(rc < 0 || io_write_errno(errno), "closing it (HDF5 could not flush it)");
}

/* A write failed when HDF5 says so, or when it leaves errno at a lost
 * write's: Open MPI 4.1's OMPIO collective writes on three ranks report
 * success to HDF5 after one aggregator's pwritev failed
 * (tests/test_fulldisk.sh). */
void io_write_rows(hid_t dset, hid_t mtype, hid_t mspace, hid_t fspace, hid_t dxpl, const void *buf,
                   const char *name)
{
    errno = 0;
    herr_t rc = H5Dwrite(dset, mtype, mspace, fspace, dxpl, buf);
    io_write_agree(rc < 0 || io_write_errno(errno), "writing %s", name);
}

void io_forget_tmp(void) { io_open.tmp[0] = 0; }

hid_t io_select_rows(hid_t fspace, hid_t mspace, uint64_t start, uint64_t count)
{
    hid_t dxpl;
    hsize_t s0 = (hsize_t)start, c0 = (hsize_t)count;
    H5CHECK(dxpl = H5Pcreate(H5P_DATASET_XFER));
    H5CHECK(H5Pset_dxpl_mpio(dxpl, H5FD_MPIO_COLLECTIVE));
    if (c0 > 0) {
        H5CHECK(H5Sselect_hyperslab(fspace, H5S_SELECT_SET, &s0, NULL, &c0, NULL));
    } else {
        H5CHECK(H5Sselect_none(fspace));
        H5CHECK(H5Sselect_none(mspace));
    }
    return dxpl;
}

/* ---- DEM grains (issue 58) -------------------------------------------------------- */

static const dem_t *io_grains; /* io_set_grains: the run's grains, or NULL */

void io_set_grains(const dem_t *d) { io_grains = d; }

/* grp/name, n rows of nc values: every rank holds every grain (the whole
 * store, dem_whole), so rank 0 writes them all and the others take part in
 * the collective write with nothing. */
static void io_dem_dataset(hid_t grp, const char *name, hid_t ftype, hid_t mtype, const void *buf, size_t n, int nc,
                           const char *desc, const char *units)
{
    hsize_t dims[2] = {(hsize_t)n, (hsize_t)nc}, mdims[2] = {n ? (hsize_t)n : 1, (hsize_t)nc};
    hid_t sp, msp, ds, dxpl;
    H5CHECK(sp = H5Screate_simple(nc > 1 ? 2 : 1, dims, NULL));
    H5CHECK(msp = H5Screate_simple(nc > 1 ? 2 : 1, mdims, NULL));
    H5CHECK(ds = H5Dcreate2(grp, name, ftype, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    H5CHECK(dxpl = H5Pcreate(H5P_DATASET_XFER));
    H5CHECK(H5Pset_dxpl_mpio(dxpl, H5FD_MPIO_COLLECTIVE));
    if (io_rank() != 0) {
        H5CHECK(H5Sselect_none(sp));
        H5CHECK(H5Sselect_none(msp));
    }
    char what[80];
    snprintf(what, sizeof what, "the dataset /DEM/%s", name);
    if (n > 0) io_write_rows(ds, mtype, msp, sp, dxpl, buf, what);
    io_attr_string(ds, "Description", desc);
    io_attr_string(ds, "Units", units);
    H5CHECK(H5Pclose(dxpl));
    H5CHECK(H5Dclose(ds));
    H5CHECK(H5Sclose(msp));
    H5CHECK(H5Sclose(sp));
}

/* The group /DEM: the grains in ID order (their store's order). */
static void io_write_dem(hid_t file, const dem_t *d)
{
    hid_t g;
    size_t n = d->n;
    double *buf = malloc((n ? n : 1) * 3 * sizeof(double));
    int *ib = malloc((n ? n : 1) * sizeof(int));
    if (!buf || !ib) error_exit(1, "out of memory writing %zu grains", n);
    H5CHECK(g = H5Gcreate2(file, "DEM", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    double *const *vec[3] = {d->x, d->v, d->w};
    static const char *const vname[3] = {"Coordinates", "Velocities", "AngularVelocities"};
    static const char *const vdesc[3] = {"grain centre", "grain velocity", "grain angular velocity"};
    static const char *const vunit[3] = {"m", "m/s", "rad/s"};
    for (int k = 0; k < 3; ++k) {
        for (size_t i = 0; i < n; ++i)
            for (int a = 0; a < 3; ++a) buf[3 * i + (size_t)a] = vec[k][a][i];
        io_dem_dataset(g, vname[k], H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, buf, n, 3, vdesc[k], vunit[k]);
    }
    for (size_t i = 0; i < n; ++i) buf[i] = (double)d->c.d;
    io_dem_dataset(g, "Diameter", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, buf, n, 1, "grain diameter", "m");
    for (size_t i = 0; i < n; ++i) ib[i] = d->ncon[i];
    io_dem_dataset(g, "Contacts", H5T_STD_I32LE, H5T_NATIVE_INT, ib, n, 1,
                   "contacts of the grain (with grains and walls) at the last DEM step", "1");
    io_dem_dataset(g, "FluidFraction", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, d->eps, n, 1,
                   "fluid fraction at the grain, eq. (20) of Markauskas et al. 2016", "1");
    for (size_t i = 0; i < n; ++i)
        for (int a = 0; a < 3; ++a) buf[3 * i + (size_t)a] = d->uf[a][i];
    io_dem_dataset(g, "FluidVelocity", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, buf, n, 3,
                   "fluid velocity at the grain, eq. (20)'s interpolation", "m/s");
    io_dem_dataset(g, "ParticleIDs", H5T_STD_I64LE, H5T_NATIVE_INT64, d->id, n, 1, "grain ID", "1");
    for (size_t i = 0; i < n; ++i) ib[i] = (int)i; /* the XDMF's Polyvertex connectivity (issue 33: without it the
                                                     * Xdmf3 readers show no cells) */
    io_dem_dataset(g, "Vertices", H5T_STD_I32LE, H5T_NATIVE_INT, ib, n, 1, "grain k is vertex k", "1");
    H5CHECK(H5Gclose(g));
    free(buf), free(ib);
}

int io_write_snapshot(const char *outdir, int index, const particles_t *p, double time, long step,
                      const char *scene_text, const char *walls, const char *code_version)
{
    char name[32], path[IO_PATH_MAX], tmp[IO_PATH_MAX];
    snprintf(name, sizeof name, "snapshot_%05d.h5", index);
    io_join(path, outdir, name, "");
    io_join(tmp, outdir, name, ".tmp");

    long long n = (long long)p->n, ntot = 0;
    MPICHECK(MPI_Allreduce(&n, &ntot, 1, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD));

    double row = io_vertex_bytes(ntot);
    for (int i = 0; i < io_nfields; i++) row += (double)(io_type_size(io_fields[i].type) * (size_t)io_fields[i].ncomp);
    double text = (scene_text ? (double)strlen(scene_text) : 0) + (walls ? (double)strlen(walls) : 0);
    hid_t file = io_create_file(tmp, 0, (double)ntot * row + text);
    io_write_header(file, p->dim, time, step, ntot, scene_text, walls, code_version);
    io_write_particles(file, p, ntot);
    if (io_grains) { /* every grain of the run, on every rank (dem_whole: collective) */
        dem_t *whole = dem_whole((dem_t *)io_grains);
        io_write_dem(file, whole);
        dem_whole_free(io_grains, whole);
    }
    io_close_file(file);
    io_commit(tmp, path, 1);
    io_forget_tmp();
    return 0;
}

/* ---- XDMF ----------------------------------------------------------------- */

static void io_xdmf_item(FILE *fp, const struct io_field *f, const char *h5name, long long n)
{
    const char *nt = f->type == IO_REAL || f->type == IO_CREAL ? "Float" : f->type == IO_UINT8 ? "UChar" : "Int";
    int prec = f->type == IO_UINT8 ? 1 : 8;
    if (f->ncomp > 1)
        fprintf(fp, "          <DataItem Dimensions=\"%lld %d\"", n, f->ncomp);
    else
        fprintf(fp, "          <DataItem Dimensions=\"%lld\"", n);
    fprintf(fp, " NumberType=\"%s\" Precision=\"%d\" Format=\"HDF\">%s:/Particles/%s</DataItem>\n", nt, prec,
            h5name, f->name);
}

static void io_xdmf_grid(FILE *fp, int index, double time, long long n)
{
    char h5name[32];
    snprintf(h5name, sizeof h5name, "snapshot_%05d.h5", index);
    if (io_grains) /* the fluid and the grains side by side, one time */
        fprintf(fp, "      <Grid Name=\"step_%05d\" GridType=\"Collection\" CollectionType=\"Spatial\">\n"
                    "      <Time Value=\"%.17g\"/>\n", index, time);
    fprintf(fp, "      <Grid Name=\"snapshot_%05d\" GridType=\"Uniform\">\n", index);
    fprintf(fp, "        <Time Value=\"%.17g\"/>\n", time);
    fprintf(fp,
            "        <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"%lld\" NodesPerElement=\"1\">\n"
            "          <DataItem Dimensions=\"%lld\" NumberType=\"Int\" Precision=\"%d\" Format=\"HDF\">"
            "%s:/Topology/Vertices</DataItem>\n        </Topology>\n",
            n, n, io_vertex_bytes(n), h5name);
    for (int i = 0; i < io_nfields; i++) {
        const struct io_field *f = &io_fields[i];
        int geom = strcmp(f->name, "Coordinates") == 0;
        if (geom)
            fprintf(fp, "        <Geometry GeometryType=\"XYZ\">\n");
        else
            fprintf(fp, "        <Attribute Name=\"%s\" AttributeType=\"%s\" Center=\"Node\">\n", f->name,
                    f->ncomp == 6 ? "Tensor6" : f->ncomp > 1 ? "Vector" : "Scalar");
        io_xdmf_item(fp, f, h5name, n);
        fprintf(fp, geom ? "        </Geometry>\n" : "        </Attribute>\n");
    }
    fprintf(fp, "      </Grid>\n");
    if (!io_grains) return;
    const size_t g = io_grains->n;
    fprintf(fp, "      <Grid Name=\"grains_%05d\" GridType=\"Uniform\">\n"
                "        <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"%zu\" NodesPerElement=\"1\">\n"
                "          <DataItem Dimensions=\"%zu\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">"
                "%s:/DEM/Vertices</DataItem>\n        </Topology>\n"
                "        <Geometry GeometryType=\"XYZ\">\n          <DataItem Dimensions=\"%zu 3\" NumberType=\"Float\""
                " Precision=\"8\" Format=\"HDF\">%s:/DEM/Coordinates</DataItem>\n        </Geometry>\n", index, g, g,
                h5name, g, h5name);
    static const char *const at[6] = {"Velocities", "AngularVelocities", "FluidVelocity", "Diameter", "Contacts",
                                      "FluidFraction"};
    for (int k = 0; k < 6; ++k)
        fprintf(fp, "        <Attribute Name=\"%s\" AttributeType=\"%s\" Center=\"Node\">\n          <DataItem "
                    "Dimensions=\"%zu%s\" NumberType=\"%s\" Precision=\"%d\" Format=\"HDF\">%s:/DEM/%s</DataItem>\n"
                    "        </Attribute>\n", at[k], k < 3 ? "Vector" : "Scalar", g, k < 3 ? " 3" : "",
                k == 4 ? "Int" : "Float", k == 4 ? 4 : 8, h5name, at[k]);
    fprintf(fp, "      </Grid>\n      </Grid>\n");
}

/* Rank 0 writes OUTDIR/snapshots.xmf.tmp: 0, or 1 (cannot open it) or 2
 * (cannot write or close it), errno telling why. */
static int io_xdmf_file(const char *outdir, int nsnap, const double *times, const long long *npart,
                        const unsigned char *present, int dim)
{
    char tmp[IO_PATH_MAX];
    io_join(tmp, outdir, "snapshots.xmf", ".tmp");
    snprintf(io_open.tmp, sizeof io_open.tmp, "%s", tmp);
    FILE *fp = fopen(tmp, "w");
    if (!fp) return 1;
    fprintf(fp, "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
                "<Xdmf Version=\"2.0\">\n  <Domain>\n");
    fprintf(fp, "    <Information Name=\"Dimension\" Value=\"%d\"/>\n", dim);
    fprintf(fp, "    <Grid Name=\"snapshots\" GridType=\"Collection\""
                " CollectionType=\"Temporal\">\n");
    for (int i = 0; i < nsnap; i++)
        if (!present || present[i]) io_xdmf_grid(fp, i, times[i], npart[i]);
    fprintf(fp, "    </Grid>\n  </Domain>\n</Xdmf>\n");
    int bad = fflush(fp) != 0 || ferror(fp);
    int err = errno;
    if (fclose(fp) != 0) bad = 1, err = errno;
    errno = err;
    return bad ? 2 : 0;
}

int io_write_xdmf(const char *outdir, int nsnap, const double *times, const long long *npart,
                  const unsigned char *present, int dim)
{
    int bad = 0;
    if (io_rank() == 0) bad = io_xdmf_file(outdir, nsnap, times, npart, present, dim);
    io_write_agree(bad, "%s", bad == 1 ? "cannot open it" : "cannot write or close it");
    if (io_rank() == 0) {
        char path[IO_PATH_MAX];
        io_join(path, outdir, "snapshots.xmf", "");
        io_commit(io_open.tmp, path, 0);
    }
    io_forget_tmp();
    return 0;
}
