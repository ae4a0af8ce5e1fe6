/* checkpoint.h — full-state checkpoints and restarts (DESIGN.md "Files a run
 * writes": "Checkpoints are full-state HDF5 files that restart bit-for-bit
 * on the same rank count").
 *
 * OUTDIR/checkpoint.h5 (the latest; the one before is kept as
 * OUTDIR/checkpoint_prev.h5), written collectively by all ranks with
 * parallel HDF5 (MPI-IO) to checkpoint.h5.tmp, sealed, then renamed:
 *   user block    the first CKPT_USERBLOCK bytes, which HDF5 skips: the seal,
 *                 eight 8-byte words at bytes 0..63, the rest zero:
 *                   0  "SPHSEGCK"        32  step
 *                   8  format            40  the bits of the double time
 *                  16  file size         48  check
 *                  24  checksum          56  0 (reserved)
 *                 all but the first little-endian uint64. The checksum is the
 *                 sum over the 8-byte little-endian words w_i (i = 1, 2, ...;
 *                 the last zero-padded) of the bytes past the user block of
 *                 mix(w_i + i * G) mod 2^64, G = 0x9E3779B97F4A7C15, mix
 *                 being splitmix64's finaliser; the check covers the seal
 *                 itself: h = 0, then h = mix(h ^ (v_k + (k + 1) * G)) for the
 *                 words v_0..v_5 at bytes 0..47 (mod 2^64), and 1 where that
 *                 gives 0. A reader refuses a changed, cut or extended file,
 *                 a changed seal (a flipped step would choose the wrong
 *                 checkpoint) or a nonzero byte in the rest of the user block
 *                 (which neither covers), before HDF5 reads any of it; a seal whose check
 *                 is 0 was written before the check existed (format 3
 *                 all the same) and is taken as a legacy seal, its step and
 *                 time then checked against /Header's by ckpt_read;
 *   /Header       attributes Code ("sphseg"), Version, Checkpoint (CKPT_FORMAT),
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
 *                 in the rank's store order;
 *   /DEM          (a scene with DEM grains, src/dem/dem.h) attributes Count
 *                 (grains), ContactsMax (DEM_CMAX), Steps (DEM steps so
 *                 far), ExchangeX/Y/Z (the momentum the fluid gave the
 *                 grains, N s); one dataset per array of dem_state_get, flat
 *                 grain by grain (Count x its elements a grain: 1, or
 *                 DEM_CMAX partners, or 3 DEM_CMAX spring components), as
 *                 8-byte floats or signed integers of the array's size:
 *                 CoordinatesX/Y/Z, VelocitiesX/Y/Z, AngularVelocitiesX/Y/Z,
 *                 InteractionForceX/Y/Z, DragForceX/Y/Z, FluidVelocityX/Y/Z,
 *                 FluidFraction, KernelSum, ParticleIDs, Contacts,
 *                 ContactPartners, ContactSprings. Written by rank 0 from the
 *                 whole store (dem_whole), read by every rank; the first
 *                 coupling divides the grains among the ranks.
 *
 * A restart on the same rank count gives every rank its own block back, so
 * the run continues bit-identically; on another rank count each rank takes an
 * even contiguous share of the rows, which the distribution step (mpi/)
 * must then route to the ranks that own the positions. The grains come back
 * whole on any rank count (each rank reads them all); on another rank count
 * their sums over the fluid, added over other ranks, then differ from the
 * run's to round-off (src/dem/dem.h). */
#ifndef SPHSEG_CHECKPOINT_H
#define SPHSEG_CHECKPOINT_H
#include "sim/sim.h"

/* 3: a dummy's Wall is the 1-based index of its wall primitive (wall.h), no
 * longer a fixed wall id. */
enum { CKPT_FORMAT = 3, CKPT_USERBLOCK = 512 };

/* The run state beside sim_t that a checkpoint carries. */
typedef struct ckpt_run {
    double small0, max_drift; /* diag: sum C_i V_i at t = 0, largest |drift| so far */
    int warned;               /* diag: the drift warning was given */
    long long out_n;          /* Outlet: material particles that left so far (all ranks) */
    double out_cv;            /* Outlet: their sum C_i V_i (all ranks) */
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
 * checkpoint_prev.h5 (hard link, then rename: checkpoint.h5 always names a
 * complete checkpoint). A failed write (disk full) ends the run with status
 * 4, the earlier checkpoints intact. Returns the wall seconds it took. */
double ckpt_write(const char *outdir, const sim_t *s, const ckpt_run *r, const char *scene_text);

/* The seal of a checkpoint file (user block). */
typedef struct ckpt_seal {
    long long step;
    double time;
    unsigned long long size, sum;
    int legacy; /* its check word is 0: written before the check existed */
} ckpt_seal;
/* Collective: 0 when path is a sealed checkpoint of this format whose seal
 * check and checksum match its bytes (seal filled in); -1 when it cannot be
 * read, 1 when it is not a regular file (a FIFO is refused without opening
 * it for a blocking read), not a checkpoint or damaged; why says so (every
 * rank). */
int ckpt_verify(const char *path, ckpt_seal *seal, char *why, size_t n);

/* Collective (src/output/checkpoint_read.c): load the particles (s->p, allocated
 * here) and s->t, step, dt, amax, n_material from file, the grains' state into
 * s->dem (made from the scene: a checkpoint without /DEM for a scene with
 * grains, or with it for one without, is refused), and r. file may be
 * a directory: its newest valid checkpoint (checkpoint.h5 or
 * checkpoint_prev.h5) is taken, and its name written to chosen (a warning
 * says why the other was passed over, unless it is just the older one or
 * absent). A file whose seal's step or time is not its /Header's, or that
 * is missing, damaged (checksum), not a sphseg checkpoint, of another
 * precision, dimension, store layout, of a scene whose state-defining keys
 * differ (each named), or whose contents are out of range stops every rank
 * with status 2 and one line from rank 0. Run-control keys that differ are
 * listed. */
void ckpt_read(const char *file, sim_t *s, ckpt_run *r, char *chosen, size_t n);
/* Compare the checkpoint's used-parameters text (stored) with this run's
 * scene, key by key (src/output/checkpoint_keys.c), each key of each entry
 * of a list (Container:walls, Container:regions) on its own and the list's
 * length. Keys that define the state (Geometry, Material, Physics, Initial,
 * Kinematics, Walls, Container, DEM, and the modules Segregation:enabled,
 * scheme and renormalize) must match: otherwise exit 2, one line from rank 0 naming
 * each one that differs once with both values ("Container:walls:4
 * (hopper_right):to ([0.06, 0] in the checkpoint, [0.061, 0] now)"). Model
 * keys (the other Segregation keys, Grains, Flow, Outlet) that differ are a
 * warning naming each; run-control keys (Run, Output, Parallel) may differ
 * and are listed. */
void ckpt_check_scene(const char *file, const char *stored, const struct scene *sc);
void ckpt_run_free(ckpt_run *r);

/* When to stop a run early (Run:max_wall_time, OUTDIR/STOP). */
typedef struct ckpt_clock {
    double wall0;      /* wall clock at start-up (diag_wall) */
    double loop0;      /* wall clock at the first step of this session */
    double last_check; /* last look for the STOP file (rank 0) */
    double write_s;    /* wall seconds of the last checkpoint write */
    double max_wall;   /* Run:max_wall_time, 0 = none */
    int signal;        /* the signal that asked for the stop (CKPT_SIGNAL) */
    char stop[4200];   /* OUTDIR/STOP */
} ckpt_clock;

enum ckpt_stop { CKPT_GO = 0, CKPT_WALL = 1, CKPT_STOPFILE = 2, CKPT_SIGNAL = 3 };
enum { CKPT_STOP_EVERY_S = 5 }; /* wall seconds between looks for OUTDIR/STOP */
#define CKPT_SIGNAL_ECHO_S 0.25    /* a second signal this soon after the first is a copy of it */

/* SIGTERM, SIGUSR1, SIGINT and SIGHUP ask for a stop: the step ends, a
 * checkpoint is written and the run exits 0 (ckpt_poll); a second SIGTERM,
 * SIGINT or SIGHUP ends the process at once (one within CKPT_SIGNAL_ECHO_S
 * of the first is taken for a copy of it: SLURM signals each task and srun
 * forwards the same signal), and so does one before ckpt_signals_stepping
 * (set-up: nothing to save); a SIGUSR1 then waits for the first step. */
void ckpt_signals_install(void);
void ckpt_signals_stepping(void);
void ckpt_clock_start(ckpt_clock *c, double wall0, double max_wall, const char *outdir);
/* Collective, once per step: every rank gets the same answer.
 * CKPT_SIGNAL when any rank received a stop signal (c->signal);
 * CKPT_WALL when the next step (the mean step time of this session so far,
 * plus the last checkpoint's write time) would likely pass Run:max_wall_time;
 * CKPT_STOPFILE when OUTDIR/STOP exists (looked for at the first step and
 * then every CKPT_STOP_EVERY_S wall seconds); rank 0 decides these two. */
enum ckpt_stop ckpt_poll(ckpt_clock *c, long steps_done);
/* Rank 0 removes OUTDIR/STOP (after the checkpoint it asked for is written). */
void ckpt_clear_stop(const ckpt_clock *c);

#endif
