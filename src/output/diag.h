/* diag.h — run diagnostics: the global conservation check of sum C_i V_i,
 * OUTDIR/diagnostics.csv (DESIGN.md contract) and rank 0's progress line. */
#ifndef SPHSEG_DIAG_H
#define SPHSEG_DIAG_H
#include <stdio.h>
#include "sim/sim.h"

typedef struct diag {
    FILE *f;          /* rank 0 only */
    char path[4096];  /* final name; rows go to path.part until diag_close */
    double small0;    /* sum C_i V_i at t = 0 */
    double max_drift; /* largest |relative drift| seen */
    int warned;
    double wall0, wall_last_progress;
    double t0;        /* simulated time at the start of this session (restarts) */
    double ntot;      /* particles of all ranks, at the start and at the last diagnostics row */
    long step0;       /* step at the start of this session */
} diag;

typedef struct diag_values {
    long long n_material;
    double small_volume, drift, kinetic_energy, max_speed, C_min, C_max;
    long long n_outflow; /* material particles that left through the outlet so far */
    double small_outflow; /* their sum C_i V_i: the drift is that of small_volume + small_outflow */
} diag_values;

double diag_wall(void);
/* Global reductions of the diagnostics (collective). */
diag_values diag_measure(const sim_t *s);
void diag_open(diag *d, const char *outdir, const sim_t *s);
/* A restart's diag_open: rows continue in the file of the earlier run
 * (diagnostics.csv.part if a killed run left one, else diagnostics.csv),
 * keeping its header and its rows up to step s->step, no new header; the
 * t = 0 reference small0, max_drift and warned come from the checkpoint. */
void diag_reopen(diag *d, const char *outdir, const sim_t *s, double small0, double max_drift, int warned);
/* Append one row (collective: reduces over ranks), warn on drift. */
void diag_row(diag *d, const sim_t *s);
/* Progress line on rank 0 if progress_s wall seconds have passed (or force;
 * rank-local: no collective). Its rate counts the particles of all ranks
 * (d->ntot) per second of this session's wall time less io, the seconds
 * spent in output and diagnostics: the done: line's rate, so far. */
void diag_progress(diag *d, const sim_t *s, int force, double io);
/* Rename diagnostics.csv.part to diagnostics.csv. */
void diag_close(diag *d);

#endif
