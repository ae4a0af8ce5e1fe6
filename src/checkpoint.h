/* checkpoint.h — full-state checkpoints and restarts (DESIGN.md "Files a run
 * writes": "Checkpoints are full-state HDF5 files that restart bit-for-bit
 * on the same rank count").
 *
 * OUTDIR/checkpoint.h5 (the latest; the one before is kept as
 * OUTDIR/checkpoint_prev.h5), written collectively by all ranks with
 * parallel HDF5 (MPI-IO) to checkpoint.h5.tmp, then renamed:
 *   /Header       attributes Code ("sphseg"), Version, Checkpoint (1),
 *                 Precision ("double" | "single"), RealBytes, Dimension,
 *                 NumRanks, NumPart_Total, NumArrays, Time, Step, Dt, Amax,
 *                 WindowSteps, WindowTarget, WindowLength (the open
 *                 concentration window: steps, its K, seconds; sim.h),
 *                 Scene (the used-parameters text);
 *   /Diagnostics  attributes SmallVolume0 (sum C_i V_i at t = 0), MaxDrift,
 *                 Warned (the diag state);
 *   /Outputs      attribute Count; datasets Times (Count doubles) and
 *                 NumPart (Count int64): the snapshots written so far, for
 *                 the XDMF index;
 *   /Decomposition (multi-rank runs) attributes Method, Axis, CoarseCells
 *                 (3), CoarseCellWidth (halo_t.blk: METIS coarse-cell edge in
 *                 lattice cells, the cutting backend's ghost depth); datasets Bounds (NumRanks + 1 slab bounds) and
 *                 Owners (the rank of each METIS coarse cell): mpi/halo.h;
 *   /Particles    RankCounts (NumRanks int64: the particles each rank held,
 *                 in rank order) and one dataset NN (00, 01, ...) per array
 *                 of the particle store (part_array_get), raw bytes as
 *                 unsigned integers of the array's element size (attribute
 *                 ElementBytes), each rank's block contiguous at its offset,
 *                 in the rank's store order.
 *
 * A restart on the same rank count gives every rank its own block back, so
 * the run continues bit-identically; on another rank count each rank takes an
 * even contiguous share of the rows, which the distribution step (mpi/)
 * must then route to the ranks that own the positions. */
#ifndef SPHSEG_CHECKPOINT_H
#define SPHSEG_CHECKPOINT_H
#include "sim.h"

/* The run state beside sim_t that a checkpoint carries. */
typedef struct ckpt_run {
    double small0, max_drift; /* diag: sum C_i V_i at t = 0, largest |drift| so far */
    int warned;               /* diag: the drift warning was given */
    int nsnap;                /* snapshots written so far */
    double *times;            /* their times (malloc'd by ckpt_read) */
    long long *npart;         /* their particle totals (malloc'd by ckpt_read) */
    /* the domain decomposition (multi-rank runs; read back only on the same
     * rank count, so that the restart cuts the domain as the run did) */
    int dec_present, dec_method, dec_axis, dec_cg[3];
    int dec_blk;              /* METIS: coarse-cell edge in lattice cells (halo_t.blk); HALO_DEPTH when
                               * the checkpoint predates the attribute */
    long *dec_bound;          /* NumRanks + 1 slab bounds */
    int *dec_part;            /* METIS: the owner of each coarse cell */
} ckpt_run;

/* Collective: write OUTDIR/checkpoint.h5 from s (host copy: call to_host
 * first), r and scene_text; the previous checkpoint.h5 becomes
 * checkpoint_prev.h5. Any failure ends the run with status 1. Returns the
 * wall seconds it took. */
double ckpt_write(const char *outdir, const sim_t *s, const ckpt_run *r, const char *scene_text);

/* Collective: load the particles (s->p, allocated here) and s->t, step, dt,
 * amax, n_material from file, and r. A missing file, one that is not a sphseg
 * checkpoint, or one of another precision, dimension or store layout stops
 * every rank with status 2 and one line naming the file and the problem. A
 * scene that differs from the stored one is a warning (a longer t_end is the
 * usual reason). */
void ckpt_read(const char *file, sim_t *s, ckpt_run *r);
void ckpt_run_free(ckpt_run *r);

/* When to stop a run early (Run:max_wall_time, OUTDIR/STOP). */
typedef struct ckpt_clock {
    double wall0;      /* wall clock at start-up (diag_wall) */
    double loop0;      /* wall clock at the first step of this session */
    double last_check; /* last look for the STOP file (rank 0) */
    double write_s;    /* wall seconds of the last checkpoint write */
    double max_wall;   /* Run:max_wall_time, 0 = none */
    char stop[4200];   /* OUTDIR/STOP */
} ckpt_clock;

enum ckpt_stop { CKPT_GO = 0, CKPT_WALL = 1, CKPT_STOPFILE = 2 };
enum { CKPT_STOP_EVERY_S = 5 }; /* wall seconds between looks for OUTDIR/STOP */

void ckpt_clock_start(ckpt_clock *c, double wall0, double max_wall, const char *outdir);
/* Collective, once per step: rank 0 decides, every rank gets the answer.
 * CKPT_WALL when the next step (the mean step time of this session so far,
 * plus the last checkpoint's write time) would likely pass Run:max_wall_time;
 * CKPT_STOPFILE when OUTDIR/STOP exists (looked for at the first step and
 * then every CKPT_STOP_EVERY_S wall seconds). */
enum ckpt_stop ckpt_poll(ckpt_clock *c, long steps_done);
/* Rank 0 removes OUTDIR/STOP (after the checkpoint it asked for is written). */
void ckpt_clear_stop(const ckpt_clock *c);

#endif
