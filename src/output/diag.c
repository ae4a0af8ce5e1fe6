/* diag.c — see diag.h. */
#include "diag.h"
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include "core/error.h"
#include "core/ksum.h"
#include "io.h"
#include "mpi/comm.h"

/* Rank 0's rows: a failed write (disk full, quota) ends the run with status
 * 4, never a diagnostics.csv cut mid-row that says the run went well. */
static void diag_check(diag *d, int failed, const char *what)
{
    if (!failed) return;
    int err = errno;
    char part[4200];
    snprintf(part, sizeof part, "%s.part", d->path);
    errno = err;
    error_exit(EXIT_WRITE, "cannot write %s (%s): %s", part, what, strerror(err));
}

double diag_wall(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Particle i's mass over rho: vol, or beside DEM grains two ways its fluid
 * volume phi (vol is then the space it represents, phi / eps: dem_body.h
 * dem_fluid_volume; phi is set at the first coupling). */
static double diag_mass_volume(const particles_t *p, size_t i)
{
    return p->phi && p->phi[i] > 0 ? (double)p->phi[i] : (double)p->vol[i];
}

diag_values diag_measure(const sim_t *s)
{
    const particles_t *p = &s->p;
    ksum small = {0, 0};
    double ke = 0, vmax = 0, cmin = INFINITY, cmax = -INFINITY;
    long long nm = 0;
    for (size_t i = 0; i < p->n; ++i) {
        if (p->kind[i] != KIND_MATERIAL) continue;
        double v2 = 0;
        for (int d = 0; d < 3; ++d) v2 += (double)p->v[d][i] * p->v[d][i];
        ksum_add(&small, (double)p->C[i] * p->vol[i]);
        ke += 0.5 * s->sc->physics.rho * diag_mass_volume(p, i) * v2;
        vmax = fmax(vmax, sqrt(v2));
        cmin = fmin(cmin, p->C[i]);
        cmax = fmax(cmax, p->C[i]);
        nm++;
    }
    diag_values v;
    v.n_material = comm_sum_ll(nm);
    v.small_volume = comm_sum_compensated(small.s, small.c);
    v.kinetic_energy = comm_sum(ke);
    v.max_speed = comm_max(vmax);
    v.C_min = comm_min(cmin);
    v.C_max = comm_max(cmax);
    v.n_outflow = comm_sum_ll(s->out_n);
    v.small_outflow = comm_sum(s->out_cv);
    v.drift = 0;
    return v;
}

/* The earlier run's rows file, whole (malloc'd), or NULL if there is none. */
static char *diag_slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    size_t cap = 1 << 16, n = 0, got;
    char *b = malloc(cap + 1);
    while (b && (got = fread(b + n, 1, cap - n, f)) > 0)
        if ((n += got) == cap) b = realloc(b, (cap *= 2) + 1);
    fclose(f);
    if (!b) error_exit(1, "out of memory reading %s", path);
    b[n] = 0;
    return b;
}

/* Copy the header line and the rows with step <= last from text to f. */
static int diag_keep_rows(FILE *f, const char *text, long last)
{
    int bad = 0;
    for (int first = 1; *text; first = 0) {
        size_t len = strcspn(text, "\n");
        char *end;
        long step = strtol(text, &end, 10);
        if (first || (end != text && *end == ',' && step <= last)) bad |= fprintf(f, "%.*s\n", (int)len, text) < 0;
        text += len + (text[len] != 0);
    }
    return bad;
}

/* The state of a run's diagnostics from (small0, max_drift, warned), and on
 * rank 0 OUTDIR/diagnostics.csv.part opened: the header and the earlier
 * run's rows up to this step when keep_old (a restart), else the header. */
static void diag_start(diag *d, const char *outdir, const sim_t *s, double small0, double max_drift, int warned,
                       int keep_old)
{
    d->small0 = small0;
    d->max_drift = max_drift;
    d->warned = warned;
    d->wall0 = d->wall_last_progress = diag_wall();
    d->t0 = s->t;
    d->step0 = s->step;
    d->ntot = (double)comm_sum_ll((long long)s->p.n);
    d->f = NULL;
    snprintf(d->path, sizeof d->path, "%s/diagnostics.csv", outdir);
    if (comm_rank() != 0) return;
    char part[4200];
    snprintf(part, sizeof part, "%s.part", d->path);
    char *old = NULL;
    if (keep_old) {
        old = diag_slurp(part);
        if (!old) old = diag_slurp(d->path);
        if (!old) warning("restart: no %s or %s to continue: rows start afresh", d->path, part);
    }
    d->f = fopen(part, "w");
    diag_check(d, !d->f, "open");
    int bad = old ? diag_keep_rows(d->f, old, s->step)
                  : fprintf(d->f, "step,time,dt,n_material,small_volume,small_volume_drift,kinetic_energy,"
                                  "max_speed,wall_s,C_min,C_max,n_outflow,small_volume_outflow%s\n",
                            s->dem ? ",dem_kinetic_energy,dem_exchange_x,dem_exchange_y,dem_exchange_z" : "") < 0;
    diag_check(d, bad || fflush(d->f) != 0, "header");
    free(old);
}

void diag_open(diag *d, const char *outdir, const sim_t *s)
{
    diag_start(d, outdir, s, diag_measure(s).small_volume, 0, 0, 0);
}

void diag_reopen(diag *d, const char *outdir, const sim_t *s, double small0, double max_drift, int warned)
{
    diag_start(d, outdir, s, small0, max_drift, warned, 1);
}

void diag_row(diag *d, const sim_t *s)
{
    diag_values v = diag_measure(s);
    d->ntot = (double)comm_sum_ll((long long)s->p.n); /* an outlet removes particles */
    double inside_out = v.small_volume + v.small_outflow; /* an outlet's outflow still counts */
    v.drift = d->small0 != 0 ? (inside_out - d->small0) / d->small0 : inside_out;
    d->max_drift = fmax(d->max_drift, fabs(v.drift));
    /* the concentration equation's conservation: without it C is held, and
     * beside DEM grains two ways the volumes follow eps (dem_fluid_volume) */
    if (s->seg_on && fabs(v.drift) > s->sc->segregation.drift_tol && !d->warned) {
        d->warned = 1;
        if (comm_rank() == 0)
            warning("step %ld, t = %.6g s: relative drift of sum C_i V_i is %.3e, past "
                    "Segregation:drift_tol = %.3g", s->step, s->t, v.drift, s->sc->segregation.drift_tol);
    }
    double dke = 0, dex[3] = {0, 0, 0};
    if (s->dem) dem_totals(s->dem, &dke, dex); /* collective: the grains are divided among the ranks */
    if (!d->f) return;
    int bad = fprintf(d->f, "%ld,%.17g,%.17g,%lld,%.17g,%.17g,%.17g,%.17g,%.6f,%.17g,%.17g,%lld,%.17g", s->step,
                      s->t, s->dt, v.n_material, v.small_volume, v.drift, v.kinetic_energy, v.max_speed,
                      diag_wall() - d->wall0, v.C_min, v.C_max, v.n_outflow, v.small_outflow) < 0;
    if (s->dem) /* the grains: kinetic energy, J; momentum the fluid gave them so far, N s */
        bad |= fprintf(d->f, ",%.17g,%.17g,%.17g,%.17g", dke, dex[0], dex[1], dex[2]) < 0;
    bad |= fputc('\n', d->f) == EOF;
    diag_check(d, bad || fflush(d->f) != 0, "a row");
}

/* h:mm:ss; an estimate past 10^8 h (or not finite) is shown as such,
 * never cast to an integer it does not fit. */
static void diag_hms(double sec, char *buf, size_t n)
{
    if (!(sec >= 0 && sec < 3.6e11)) {
        snprintf(buf, n, "> 1e8 h");
        return;
    }
    long t = (long)(sec + 0.5);
    snprintf(buf, n, "%02ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
}

void diag_progress(diag *d, const sim_t *s, int force, double io)
{
    double now = diag_wall();
    if (!force && now - d->wall_last_progress < s->sc->run.progress_s) return;
    d->wall_last_progress = now;
    double el = now - d->wall0, frac = s->t / s->sc->run.t_end, done = s->t - d->t0, stepping = el - io;
    double rate = stepping > 0 ? (double)(s->step - d->step0) * d->ntot / stepping : 0;
    char eta[32];
    diag_hms(done > 0 ? el * (s->sc->run.t_end - s->t) / done : 0, eta, sizeof eta);
    message("step %8ld  t = %10.4f s (%5.1f%%)  dt = %.3e s  %.3e particle-steps/s (all ranks, output excluded)  "
            "ETA %s", s->step, s->t, 100 * frac, s->dt, rate, eta);
}

void diag_close(diag *d)
{
    if (!d->f) return;
    FILE *f = d->f;
    d->f = NULL;
    if (fclose(f) != 0) diag_check(d, 1, "close");
    char part[4200];
    snprintf(part, sizeof part, "%s.part", d->path);
    if (rename(part, d->path) != 0) warning("cannot rename %s", part);
}
