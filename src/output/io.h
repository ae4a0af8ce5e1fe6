/* io.h — snapshot output: parallel HDF5 snapshots and the XDMF index that
 * opens them in ParaView (DESIGN.md "Files a run writes").
 *
 * OUTDIR/snapshot_NNNNN.h5
 *   /Header     attributes Time (double, s), Step (int64), Dimension (int),
 *               NumPart_Total (int64), Code ("sphseg"), Version, Scene (the
 *               scene text). Strings are variable-length UTF-8 attributes, so
 *               a scene of any size fits and h5py returns them as str.
 *   /Particles/<Name> one dataset per entry of io_fields[], N (scalars) or
 *               N x 3 (vectors, z = 0 in 2D), each with string attributes
 *               Description and Units. Floating fields are stored as 64-bit
 *               IEEE doubles whatever the build precision.
 *   /Topology/Vertices 0 .. N-1 (32-bit integers while N < 2^31, else
 *               64-bit): the XDMF Polyvertex connectivity, one cell per
 *               particle. ParaView's default readers (Xdmf3ReaderS/T) build
 *               no cells without it, and its views then show nothing.
 * OUTDIR/snapshots.xmf
 *   XDMF 2 temporal collection over snapshot_00000.h5 ... (Polyvertex
 *   topology from /Topology/Vertices, XYZ geometry from Coordinates, every
 *   other field an attribute).
 *
 * Both writers go to "<name>.tmp" and rename, so no half-written file ever
 * exists under a final name. A failed write (disk full, quota) ends the run
 * with status 4 (EXIT_WRITE) and one line, on every rank together, after
 * closing the file and removing the temporary: every rank learns of a
 * write that failed on any rank before the next collective call
 * (io_write_agree), and a file system without room for the whole file
 * stops the run before the file is created (io_create_file). The
 * functions return 0. */
#ifndef SPHSEG_IO_H
#define SPHSEG_IO_H
#include "dem/dem.h"
#include "core/particles.h"

enum io_type { IO_REAL = 0, IO_UINT8 = 1, IO_INT64 = 2, IO_CREAL = 3 }; /* CREAL: creal (hd.h) */

/* One output field, declared once (STYLE.md "Output fields are a table"). */
struct io_field {
    const char *name;        /* dataset name under /Particles */
    enum io_type type;       /* element type in memory (real and creal are stored as double) */
    int ncomp;               /* 1 or 3 */
    const char *units;       /* SI units, "-" if none */
    const char *description; /* one line */
    /* The array holding component c (0 <= c < ncomp) of every particle. */
    const void *(*array)(const particles_t *p, int c);
};

extern const struct io_field io_fields[];
extern const int io_nfields;

/* Collective over MPI_COMM_WORLD: write OUTDIR/snapshot_<index %05d>.h5.
 * Each rank contributes its p->n particles (ranks may hold none, any subset
 * of IDs); N is their sum. The file lists all N in increasing ParticleIDs
 * order whatever the rank count (rows are redistributed by ID rank, io.c);
 * IDs must be unique (a duplicate stops the run, status 1); p itself is not
 * modified. scene_text, walls and code_version must be the same on every
 * rank (scene_text and walls may be NULL: stored as ""). walls names the
 * container's wall primitives, which the Wall field indexes ("1 base,
 * 2 xlo, ..."), in the header attribute Walls. */
/* The run's DEM grains (src/dem/dem.h; NULL: none): each snapshot then has
 * the group /DEM (Coordinates, Velocities, AngularVelocities, Diameter,
 * Contacts, FluidFraction, FluidVelocity, ParticleIDs) and the XDMF shows them beside the
 * fluid (a spatial collection per time). One rank only (settings_check). */
void io_set_grains(const dem_t *d);
int io_write_snapshot(const char *outdir, int index, const particles_t *p, double time, long step,
                      const char *scene_text, const char *walls, const char *code_version);

/* Collective: write OUTDIR/snapshots.xmf indexing snapshots 0 .. nsnap-1
 * (times[i], npart[i] particles each; only those with present[i] != 0 when
 * present is not NULL: a restart into a new OUTDIR lists only the snapshots
 * there) for dimension dim (2 or 3). Rank 0 writes; every rank learns
 * whether it could. */
int io_write_xdmf(const char *outdir, int nsnap, const double *times, const long long *npart,
                  const unsigned char *present, int dim);

/* HDF5 helpers shared with the checkpoint writer (src/output/checkpoint.c); every
 * call is checked (H5CHECK). Variable-length UTF-8 string attribute (value
 * NULL is stored as ""); scalar attribute of file type ftype from a value of
 * memory type mtype; collective create (truncate) of path with the MPI-IO
 * driver and collective metadata (userblock: bytes reserved at the start of
 * the file, 0 or a power of two >= 512; need: the bytes the caller will
 * write, for the check of free space), exit status 4 if it cannot be
 * created or its file system has less room than need and a margin;
 * io_close_file closes it (collective; a failed close is a failed write);
 * io_write_rows is a collective H5Dwrite of the dataset called name, its
 * outcome agreed; io_forget_tmp once the temporary is renamed;
 * io_write_agree (collective) ends the run on every rank together, status
 * 4 and one line, when any rank passes failed (errno telling why);
 * io_write_failed ends the run from one rank with status 4 naming the file
 * being written, what failed and the space left, after closing that file
 * (one rank alone: the job is aborted) and removing its temporary.
 * hid_t is int64_t (HDF5 >= 1.10), so hdf5.h is not needed here. */
void io_attr_string(int64_t loc, const char *name, const char *value);
void io_attr_scalar(int64_t loc, const char *name, int64_t ftype, int64_t mtype, const void *val);
int64_t io_create_file(const char *path, size_t userblock, double need);
void io_close_file(int64_t file);
void io_write_rows(int64_t dset, int64_t mtype, int64_t mspace, int64_t fspace, int64_t dxpl, const void *buf,
                   const char *name);
void io_write_agree(int failed, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void io_forget_tmp(void);
/* Rows [start, start + count) of the 1D file space fspace (none when count
 * is 0, of the memory space mspace too: the rank still takes part in the
 * collective call); returns a collective transfer list (H5Pclose it). */
int64_t io_select_rows(int64_t fspace, int64_t mspace, uint64_t start, uint64_t count);
void io_write_failed(const char *fmt, ...) __attribute__((format(printf, 1, 2), noreturn));

#endif
