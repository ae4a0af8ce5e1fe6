/* run.h — one run from its built state to its end (DESIGN.md "One step",
 * "Files a run writes"): the decomposition set up from the scene
 * (run_decompose), the steps to Run:t_end with their snapshots,
 * diagnostics rows and checkpoints (run_steps, src/run.c), the blow-up
 * guard and the particles that leave the run (src/run_guard.c), and the log
 * lines at the start and the end (src/report.c). src/main.c reads the
 * command line and calls these in order. */
#ifndef SPHSEG_RUN_H
#define SPHSEG_RUN_H
#include "output/checkpoint.h"
#include "output/diag.h"
#include "sim/sim.h"

/* The command line (src/main.c). */
typedef struct run_cli {
    const char *scene, *outdir, *backend;
    int n_over;
    char **over;         /* the -P overrides */
    const char *restart; /* --restart FILE|DIR, or NULL */
    double wall0;        /* wall clock at start-up, for Run:max_wall_time */
    int overwrite;       /* --overwrite: a fresh run may replace another run's files in OUTDIR */
    int argc;            /* the command line as given, for the how-to-continue message */
    char **argv;
} run_cli;

/* What a run has written and where. */
typedef struct outputs {
    int n;
    double *times;
    long long *npart;
    char *text;
    const char *dir;
    double wall0;           /* wall clock at start-up (Run:max_wall_time) */
    const char *restart;    /* the checkpoint this run continues, or NULL */
    const char *scene;      /* the scene file, for the how-to-continue message */
    const run_cli *c;       /* the command line, for the how-to-continue message */
    unsigned char *present; /* per snapshot: it is in dir (a restart into a new OUTDIR lacks the earlier ones) */
    char walls[512];        /* the container's wall primitives by id (wall_list), for the snapshot headers */
} outputs;

/* Collective. Several ranks, or one with periodic axes: the decomposition
 * (mpi/decomp.h) from the scene's Parallel keys, the stage table's ghost
 * arrays and the backend's ghost depth into s->halo; restarting on the
 * checkpoint's rank count (rs), its cut is taken over, so that the run
 * continues bit-identically. */
void run_decompose(sim_t *s, const ckpt_run *rs);
/* Collective. s->gate: the gates still standing (a restart after one opened
 * has none of its dummies). */
void run_gates_standing(sim_t *s);
/* Collective. Step from s->t to Run:t_end (or Run:max_steps, or an early
 * stop with a checkpoint), writing the outputs; rs: the checkpoint's run
 * state on a restart, else NULL. Ends with the done: report. */
void run_steps(sim_t *s, outputs *o, ckpt_run *rs);

/* src/run_guard.c. Collective: particles leave the run, every rank drops
 * its own (here_host: this rank's host copy is up to date): gate 0, the
 * material below the outlet (counted in s->out_n, s->out_cv); else the
 * dummies of the gates of bit mask gate (bit k: wall primitive k). The state
 * is prepared again at s->t. */
void run_drain(sim_t *s, int here_host, unsigned gate);
/* Collective: after a step, exit 3 on a particle in a blow-up state
 * (closing d first), and drain the outlet. */
void run_check_finite(sim_t *s, diag *d);

/* src/report.c. The start-up lines (a checkpoint's open window that
 * Segregation:every 1 cannot take is refused, exit 2); the end of a run;
 * an early stop's how-to-continue line. */
void report_start(sim_t *s, const outputs *o, const run_cli *c);
void report_end(sim_t *s, diag *d, double io);
void report_stopped(const outputs *o, const sim_t *s, const ckpt_clock *ck, enum ckpt_stop why);

#endif
