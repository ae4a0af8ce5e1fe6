/* report.c — what a run says in its log: the start-up lines, the done: line
 * with the halo's totals, and the command that continues a run stopped
 * early (src/run.h). */
#include <signal.h>
#include <string.h>
#include "core/error.h"
#include "core/tuning.h"
#include "mpi/comm.h"
#include "run.h"
#include "settings_check.h"
#include "core/version.h"
#include "sim/stages.h"

/* arg, single-quoted for a POSIX shell when it holds anything but plain
 * characters, appended to b. */
static void shell_word(char *b, size_t n, const char *arg)
{
    size_t used = strlen(b);
    if (arg[0] && strspn(arg, "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_./:=+-,@%") ==
                      strlen(arg)) {
        snprintf(b + used, n - used, " %s", arg);
        return;
    }
    snprintf(b + used, n - used, " '");
    for (const char *q = arg; *q && (used = strlen(b)) + 8 < n; ++q)
        snprintf(b + used, n - used, *q == '\'' ? "'\\''" : "%c", *q);
    used = strlen(b);
    snprintf(b + used, n - used, "'");
}

/* Stopped early by a signal, Run:max_wall_time or OUTDIR/STOP, the
 * checkpoint written: the command that continues. It is the command line
 * this run was given (the binary as argv[0] named it, the scene, -o, -P,
 * --backend), with any --restart (and --overwrite, a fresh run's option)
 * taken out and --restart OUTDIR added; on several ranks with the launcher
 * "mpirun -np N" before it (N this run's rank count: a job's own launcher,
 * srun or mpiexec with its flags, is not known here and may differ). */
void report_stopped(const outputs *o, const sim_t *s, const ckpt_clock *ck, enum ckpt_stop why)
{
    if (why == CKPT_STOPFILE) ckpt_clear_stop(ck);
    char cmd[8192] = "", cause[64], np[32];
    if (comm_size() > 1) {
        snprintf(np, sizeof np, "%d", comm_size());
        shell_word(cmd, sizeof cmd, "mpirun"), shell_word(cmd, sizeof cmd, "-np"), shell_word(cmd, sizeof cmd, np);
    }
    for (int a = 0; a < o->c->argc; ++a) {
        const char *arg = o->c->argv[a];
        if (a > 0 && !strcmp(arg, "--overwrite")) continue;
        if (a > 0 && !strcmp(arg, "--restart") && a + 1 < o->c->argc) {
            ++a;
            continue;
        }
        shell_word(cmd, sizeof cmd, arg);
        if (a > 0 && (!strcmp(arg, "-o") || !strcmp(arg, "-P") || !strcmp(arg, "--backend")) && a + 1 < o->c->argc)
            shell_word(cmd, sizeof cmd, o->c->argv[++a]); /* its value, whatever it looks like */
    }
    shell_word(cmd, sizeof cmd, "--restart"), shell_word(cmd, sizeof cmd, o->dir);
    int sig = ck->signal;
    snprintf(cause, sizeof cause, "received %s", sig == SIGTERM ? "SIGTERM" : sig == SIGUSR1 ? "SIGUSR1"
                                                 : sig == SIGINT ? "SIGINT" : sig == SIGHUP ? "SIGHUP" : "a signal");
    message("stopping at step %ld, t = %.9g s: %s; wrote %s/checkpoint.h5. Continue with\n  %s", s->step, s->t,
            why == CKPT_WALL ? "the next step would pass Run:max_wall_time"
            : why == CKPT_SIGNAL ? cause : "found the STOP file", o->dir, cmd + 1);
}

/* The end of a run: the last progress line, the halo's and the run's totals
 * (the done: line; io is the wall time in output), the windows of C. */
void report_end(sim_t *s, diag *d, double io)
{
    double ntot = (double)comm_sum_ll((long long)s->p.n);
    d->ntot = ntot; /* the last progress line and the done: line count the same particles */
    diag_progress(d, s, 1, io);
    /* the same instant as that line's (diag_progress keeps it), so the two
     * rates agree to their printed figures however the ranks are scheduled
     * before the collectives below */
    double wall = d->wall_last_progress - d->wall0, stepping = wall - io;
    /* the halo time of the done: line is the time the computation stood
     * still for it: all of it on the CPU; on the GPU, which overlaps the
     * refreshes with interior work, what the device timeline shows */
    double comm = s->halo ? comm_max(s->halo->wall_comm) : 0, halo = comm;
    if (s->halo && s->halo->exposed_measured) {
        halo = comm_max(s->halo->wall_exposed);
        message("domains: the device stood still %.3f s for the halo on the slowest rank (exchanges at list "
                "builds, packing, copies and waits not hidden behind interior work)", halo);
    }
    if (s->halo)
        message("domains: %lld particle migrations between ranks, %.3f s of host time in halo calls on the slowest "
                "rank (%.3f s of it in MPI waits%s), %.4g MB and %.4g messages sent per rank per step (mean)",
                comm_sum_ll(s->halo->migrated), comm, comm_max(s->halo->wall_wait),
                s->halo->exposed_measured ? "; with the GPU, also waits for the device before a pack" : "",
                s->step > d->step0 ? 1e-6 * (double)comm_sum_ll(s->halo->bytes) / comm_size() / (double)(s->step - d->step0) : 0.0,
                s->step > d->step0 ? (double)comm_sum_ll(s->halo->messages) / comm_size() / (double)(s->step - d->step0) : 0.0);
    if (s->halo && comm_sum_ll(s->halo->recut_checks) > 0)
        message("load balance: %ld checks past the threshold, %ld re-cuts, %.3f s on the slowest rank (the state "
                "to the host, the re-cut, back and prepared again)", s->halo->recut_checks, s->halo->recuts,
                comm_max(s->halo->recut_s));
    double rate = stepping > 0 ? (double)(s->step - d->step0) * ntot / stepping : 0.0;
    message("done: %ld steps, %.3f s wall, %.4e particle-steps/s (the particles of all %d rank(s), %.4e per rank, per "
            "second of the wall less output), max |drift of sum C V| %.3e, %.3f s of the wall in output and "
            "diagnostics (not in the rate), %.3f s in halo exchange", s->step, wall, rate, comm_size(),
            rate / comm_size(), d->max_drift, io, halo);
    if (s->dem && s->step > d->step0) /* the run's, restarts included (a checkpoint carries them) */
        message("dem: %zu grains, %ld DEM steps in %ld fluid steps (%.1f a fluid step)", s->dem->ntot, s->dem->steps,
                s->step, (double)s->dem->steps / (double)s->step);
    if (s->dem && s->dem->split) { /* the same on every rank: they divide the grains at one coupling */
        const double no = (double)s->dem->no, ng = (double)(s->dem->n - s->dem->no);
        message("dem: divided among %d ranks: %.0f to %.0f grains owned and %.0f to %.0f ghosts a rank at the last "
                "coupling, %lld grain migrations; %lld exchanges, %lld couplings refreshed the ghosts only",
                comm_size(), comm_min(no), comm_max(no), comm_min(ng), comm_max(ng), comm_sum_ll(s->dem->migrated),
                s->dem->exchanges, s->dem->refreshes);
    }
    if (s->win.on && s->win.windows > 0)
        message("concentration: %ld windows of %.1f flow steps on average, %ld midpoint steps of C", s->win.windows,
                (double)(s->step - d->step0 - s->win.k) / (double)s->win.windows, s->win.substeps);
}

/* The start-up lines: the run (particles, h, what is solved, ranks, backend,
 * OUTDIR), the tuning settings that are set, the walls, the flow's sound
 * speed and filter (and a drum's settings outside the measured range), the
 * concentration's windows; a checkpoint's open window that
 * Segregation:every 1 cannot take is refused (exit 2). */
/* Flow:stabilization and its coefficient, for the start-up line. */
static const char *stab_text(const struct scene *sc, char *b, size_t n)
{
    const struct scene_flow *f = &sc->flow;
    if (f->stabilization == STAB_RIEMANN)
        snprintf(b, n, "stabilization riemann (eta %g)", f->riemann_eta);
    else if (f->stabilization == STAB_DELTA)
        snprintf(b, n, "stabilization delta (delta %g)", f->delta);
    else
        snprintf(b, n, "alpha_av = %g", f->alpha_av);
    return b;
}

/* The threads line: OpenMP threads per rank and where the count comes
 * from, the ranks and threads on rank 0's node against its cores, the load;
 * then the oversubscription warnings. */
static void threads_log(const run_threads *t)
{
    char load[128] = "";
    if (t->load >= 0)
        snprintf(load, sizeof load, "; load average %.2f over the last minute%s", t->load,
                 t->load >= t->cores ? ", as many as its cores: other processes share them" : "");
    if (!t->openmp)
        message("threads: this build has no OpenMP (one thread per rank); %d rank(s) on rank 0's node, %d core(s) "
                "there%s", t->node_ranks, t->cores, load);
    else
        message("threads: %d OpenMP thread(s) per rank (%s%s%s); rank 0's node runs %d rank(s), %lld thread(s), on "
                "%d core(s)%s%s", t->threads, t->env[0] ? "OMP_NUM_THREADS=" : "OMP_NUM_THREADS unset: the OpenMP "
                "default, one per core", t->env, "", t->node_ranks, t->node_threads, t->cores,
                t->quota ? " (its CPU quota)" : "", load);
    settings_warn_threads(t);
}

/* The fields the run allocates (part_alloc_fields, from the stage rows
 * that run: stage_store_fields) and the store's bytes a particle; the
 * backend's scratch comes in its memory line at the end. */
static void report_fields(const particles_t *p)
{
    char left[512];
    int n = 0, m = 0;
    size_t o = 0;
    left[0] = 0;
    for (size_t k = 0, f = (size_t)-1; k < part_narrays(); ++k) {
        if ((size_t)part_array_field(k) == f) continue;
        f = (size_t)part_array_field(k), ++m;
        if (p->fields >> f & 1) ++n;
        else {
            char one[64];
            o += (size_t)snprintf(left + o, o < sizeof left ? sizeof left - o : 0, "%s%s", o ? ", " : "",
                                  stage_fields_str(1u << f, one, sizeof one));
        }
    }
    message("fields: %d of %d allocated, %zu bytes a particle (store; all %d: %zu), + the backend's scratch (its "
            "memory line at the end)%s%s", n, m, part_store_bytes(p), m, part_bytes_per_particle(),
            n < m ? "; not held: " : "", left);
}

void report_start(sim_t *s, const outputs *o, const run_cli *c)
{
    const struct scene *sc = s->sc;
    const char *scheme = !s->seg_on ? "off"
                         : sc->segregation.scheme == SEG_SCHEME_CONSERVATIVE ? "conservative"
                         : sc->segregation.scheme == SEG_SCHEME_DIRECT       ? "direct" : "paper";
    run_threads th;
    settings_threads(&th);
    message("sphseg %s: %s, %zu material + %zu dummy particles, h = %.4g m, flow %s, segregation %s, "
            "%d rank(s) x %d OpenMP thread(s), backend %s, output %s", SPHSEG_VERSION, sc->path, s->n_material,
            (size_t)comm_sum_ll((long long)s->p.n) - s->n_material, (double)s->seg.k.h,
            s->flow_on ? "computed" : "prescribed", scheme, comm_size(), th.threads, s->be->name, o->dir);
    threads_log(&th);
    tuning_log();
    report_fields(&s->p);
    char wl[1024], st[128];
    message("container: walls %s", wall_list(s, 1, wl, sizeof wl));
    if (s->flow_on) {
        char sh[128] = "Shepard filter off"; /* its interval: a step is at most cfl_flow h / c_s (3.19) */
        if (sc->flow.shepard_every > 0)
            snprintf(sh, sizeof sh, "%s filter every %u steps (at most %.3g acoustic times h/c_s)",
                     sc->flow.stress_filter == FLOW_FILTER_MLS ? "first-order (mls) Shepard" : "Shepard",
                     sc->flow.shepard_every, sc->flow.shepard_every * sc->run.cfl_flow);
        char kg[96] = "";
        if (s->flow.kgc)
            snprintf(kg, sizeof kg, ", corrected kernel gradient (blended to I below d = %.3g)",
                     (double)s->flow.kgc_det);
        message("flow: c_s = %.4g m/s, h/c_s = %.3g s, %s, %s%s", (double)s->flow.cs,
                (double)(s->seg.k.h / s->flow.cs), sh, stab_text(sc, st, sizeof st), kg);
    }
    if (s->dem) {
        const dem_t *g = s->dem;
        static const char *const motion[] = {"free", "rigid", "fixed"};
        message("dem: %zu grains of d = %.4g m, %.4g kg/m^3, motion %s, %s coupling; DEM step %.3g s (the contact "
                "time / %d)", g->ntot, (double)g->c.d, (double)g->c.rho, motion[g->motion],
                g->coupling == DEM_TWO_WAY ? "two-way" : "one-way", g->dt, (int)DEM_STEPS_PER_CONTACT);
    }
    if (s->flow_on) {
        settings_warn_stabilization(sc);
        settings_warn_mu_law(sc);
        settings_warn_gradient_correction(sc);
        settings_warn_shift(sc);
    }
    if (s->flow_on && sc->geometry.type == GEOM_DRUM) settings_warn_drum(sc); /* measured on drums */
    settings_warn_scales(sc, s->flow_on, s->seg_on);
    if (s->win.on && sc->segregation.every_k)
        message("concentration: one midpoint step every %u flow steps (Segregation:every), at the window's mean "
                "shear rate", sc->segregation.every_k);
    else if (s->win.on)
        message("concentration: one midpoint step every K flow steps, K from its own time-step bounds, at most %d "
                "(Segregation:every auto), at the window's mean shear rate", integrate_conc_auto_max());
    else if (s->win.k > 0)
        input_error("%s: the checkpoint has an open concentration window (%ld flow steps): restart it with "
                    "Segregation:every other than 1", c->restart, s->win.k);
}
