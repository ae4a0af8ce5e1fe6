/* main.c — the sphseg driver:
 *   mpirun -np N build/sphseg SCENE.yml [-o OUTDIR] [-P Section:key=value ...] [--restart FILE|DIR]
 *                             [--overwrite]
 * Loads and validates the scene (exit 2 on bad input, before anything is
 * written), builds the particles (or loads them and the run state from a
 * checkpoint, src/checkpoint.h), then steps to Run:t_end writing snapshots
 * every Output:dt, a diagnostics row every Output:diag_dt and a checkpoint
 * every Output:checkpoint_dt. */
#include <errno.h>
#include <math.h>
#include <mpi.h>
#include <signal.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include "checkpoint.h"
#include "diag.h"
#include "core/error.h"
#include "io.h"
#include "mpi/comm.h"
#include "mpi/decomp.h"
#include "outdir.h"
#include "sim.h"
#include "stages.h"
#include "version.h"

typedef struct cli {
    const char *scene, *outdir, *backend;
    int n_over;
    char **over;
    const char *restart; /* --restart FILE|DIR, or NULL */
    double wall0;        /* wall clock at start-up, for Run:max_wall_time */
    int overwrite;       /* --overwrite: a fresh run may replace another run's files in OUTDIR */
} cli;

static void usage(void)
{
    message("usage: sphseg SCENE.yml [-o OUTDIR] [-P Section:key=value ...] [--backend auto|cpu|gpu]\n"
            "              [--restart FILE|DIR] [--overwrite]\n"
            "  -o OUTDIR   output folder (default out/<scene name>)\n"
            "  -P ...      override one scene parameter, e.g. -P Geometry:dr=0.00087\n"
            "  --backend   auto (default: gpu when built with CUDA and a device is present), cpu or gpu;\n"
            "              overrides Run:backend\n"
            "  --restart FILE|DIR  continue the run saved in the checkpoint FILE, or the newest valid one in DIR\n"
            "              (checkpoint.h5 or checkpoint_prev.h5): the particles and run state come from it, the\n"
            "              parameters from SCENE.yml and -P, whose state-defining keys must match the checkpoint's\n"
            "              (a longer Run:t_end extends a run); snapshots and diagnostics.csv continue in OUTDIR\n"
            "  --overwrite a fresh run may replace the files of an earlier run in OUTDIR (else: exit 2)\n"
            "  SIGTERM, SIGUSR1, SIGINT: finish the step, write a checkpoint, exit 0; a second SIGTERM ends at once\n"
            "  --keys      print every scene key with its type, default, range and meaning (Markdown, docs/keys.md)\n"
            "  --version   print the version");
}

static cli parse_cli(int argc, char **argv)
{
    cli c = {NULL, NULL, NULL, 0, calloc((size_t)argc, sizeof(char *)), NULL, diag_wall(), 0};
    for (int a = 1; a < argc; ++a) {
        if (!strcmp(argv[a], "-h") || !strcmp(argv[a], "--help")) {
            usage();
            MPI_Finalize();
            exit(0);
        } else if (!strcmp(argv[a], "--keys")) {
            if (comm_rank() == 0) scene_keys_markdown(stdout);
            MPI_Finalize();
            exit(0);
        } else if (!strcmp(argv[a], "--version")) {
            message("sphseg %s", SPHSEG_VERSION);
            MPI_Finalize();
            exit(0);
        } else if (!strcmp(argv[a], "--restart")) {
            if (a + 1 >= argc) input_error("command line: --restart needs a FILE (see sphseg --help)");
            c.restart = argv[++a];
            if (!c.restart[0]) input_error("command line: --restart needs a FILE or DIR, not an empty name");
        } else if (!strcmp(argv[a], "--overwrite")) {
            c.overwrite = 1;
        } else if ((!strcmp(argv[a], "-o") || !strcmp(argv[a], "-P") || !strcmp(argv[a], "--backend")) &&
                   a + 1 < argc) {
            const char *v = argv[++a];
            if (argv[a - 1][1] == 'o' && !v[0]) input_error("command line: -o needs a directory name, not an empty one");
            if (argv[a - 1][1] == 'o') c.outdir = v;
            else if (argv[a - 1][1] == 'P') c.over[c.n_over++] = (char *)v;
            else c.backend = v;
        } else if (argv[a][0] == '-' || c.scene) {
            input_error("command line: unexpected argument '%s' (see sphseg --help)", argv[a]);
        } else {
            c.scene = argv[a];
        }
    }
    if (!c.scene) input_error("command line: no scene file given (see sphseg --help)");
    return c;
}

static char *default_outdir(const char *scene)
{
    const char *b = strrchr(scene, '/');
    b = b ? b + 1 : scene;
    size_t n = strlen(b);
    if (n > 4 && !strcmp(b + n - 4, ".yml")) n -= 4;
    char *o = malloc(n + 8);
    snprintf(o, n + 8, "out/%.*s", (int)n, b);
    return o;
}

static void make_dirs(const char *path)
{
    char buf[4096];
    snprintf(buf, sizeof buf, "%s", path);
    for (char *q = buf + 1; *q; ++q)
        if (*q == '/') {
            *q = 0;
            if (mkdir(buf, 0777) && errno != EEXIST) error_exit(EXIT_WRITE, "cannot create %s: %s", buf, strerror(errno));
            *q = '/';
        }
    if (mkdir(buf, 0777) && errno != EEXIST) error_exit(EXIT_WRITE, "cannot create %s: %s", buf, strerror(errno));
}

typedef struct outputs {
    int n;
    double *times;
    long long *npart;
    char *text;
    const char *dir;
    double wall0;          /* wall clock at start-up (Run:max_wall_time) */
    const char *restart;   /* the checkpoint this run continues, or NULL */
    const char *scene;     /* the scene file, for the how-to-continue message */
    const cli *c;          /* the command line, for the how-to-continue message */
    unsigned char *present; /* per snapshot: it is in dir (a restart into a new OUTDIR lacks the earlier ones) */
    char walls[512];        /* the container's wall primitives by id (wall_list), for the snapshot headers */
} outputs;

static void write_snapshot(outputs *o, sim_t *s)
{
    if (!s->sc->output.snapshots) return;
    if (!s->hcsr) s->be->prepare(s, s->t, 2); /* classes and normals for the record */
    s->be->to_host(s);
    io_write_snapshot(o->dir, o->n, &s->p, s->t, s->step, o->text, o->walls, SPHSEG_VERSION);
    o->times = realloc(o->times, (size_t)(o->n + 1) * sizeof(double));
    o->npart = realloc(o->npart, (size_t)(o->n + 1) * sizeof(long long));
    o->present = realloc(o->present, (size_t)(o->n + 1));
    if (!o->times || !o->npart || !o->present) error_exit(EXIT_SYSTEM, "out of memory");
    o->times[o->n] = s->t;
    o->npart[o->n] = comm_sum_ll((long long)s->p.n);
    o->present[o->n] = 1;
    o->n++;
    io_write_xdmf(o->dir, o->n, o->times, o->npart, o->present, s->p.dim);
}

/* A blow-up stops the run with exit status 3 (DESIGN.md "Errors"), naming
 * the step, time and particle; the last snapshot written stays intact:
 *  - a non-finite concentration, or one far outside [0, 1] (below -1 or
 *    above 2; small overshoots of an explicit scheme are tolerated and show
 *    in diagnostics.csv as C_min, C_max);
 *  - computed flow: a non-finite position, velocity or stress; a particle
 *    outside its container (beyond a wall by more than h); a particle that
 *    moved more than h in one step (the CFL condition violated: the
 *    neighbour geometry was not resolved in time). */
static void blowup(const sim_t *s, diag *d, size_t i, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static void blowup(const sim_t *s, diag *d, size_t i, const char *fmt, ...)
{
    const particles_t *p = &s->p;
    char why[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(why, sizeof why, fmt, ap);
    va_end(ap);
    diag_close(d);
    error_exit(EXIT_NUMERICAL, "step %ld, t = %.9g s: particle %lld at (%.6g, %.6g) m %s (dt = %.3g s)", s->step,
               s->t, (long long)p->id[i], (double)p->x[0][i], (double)p->x[1][i], why, s->dt);
}

/* Particles leave the run (collective: every rank drops its own, here_host
 * when this rank's host copy is up to date): gate 0, the material below the
 * outlet, whose count and sum C_i V_i are kept for the diagnostics; else
 * the dummies of the gates of bit mask `gate` (bit k: wall primitive k).
 * The store shrinks, the backend
 * takes it over, and the state is prepared again at t (as after a load
 * balance). */
static void drain(sim_t *s, int here_host, unsigned gate)
{
    if (!here_host) s->be->to_host(s);
    particles_t *p = &s->p;
    size_t *keep = malloc((p->n + 1) * sizeof *keep), m = 0;
    if (!keep) error_exit(1, "out of memory");
    for (size_t i = 0; i < p->n; ++i) {
        if (gate && p->wall[i] && (gate >> (p->wall[i] - 1) & 1)) continue;
        if (!gate && p->kind[i] == KIND_MATERIAL && (double)p->x[1][i] < s->step_c.outlet_below) {
            s->out_n++;
            s->out_cv += (double)p->C[i] * (double)p->vol[i];
        } else {
            keep[m++] = i;
        }
    }
    p->ng = 0;
    if (m < p->n) part_compact(p, keep, m);
    free(keep);
    s->be->from_host(s);
    s->be->prepare(s, s->t, !s->win.on);
}

/* Particle i is in a blow-up state, or below the outlet (returns 1). */
static int check_failed(sim_t *s, diag *d, size_t i)
{
    s->be->to_host(s);
    const particles_t *p = &s->p;
    double mv = 0;
    for (int c = 0; c < 3; ++c) mv += pow((double)p->x[c][i] - (double)p->x_n[c][i], 2);
    switch (step_guard(i, p, &s->step_c, s->t)) {
    case STEP_BAD_C:
        blowup(s, d, i, "has concentration %g: the scheme went unstable (see docs/shearbox.md for where "
               "each scheme is stable)", (double)p->C[i]);
        break;
    case STEP_BAD_STATE:
        blowup(s, d, i, "has a non-finite position, velocity or stress: the flow went unstable "
               "(see docs/granular.md, stability limits)");
        break;
    case STEP_BAD_OUTSIDE:
        blowup(s, d, i, "left its container through a wall");
        break;
    case STEP_OUTLET:
        return 1;
    default:
        blowup(s, d, i, "moved %.3g m > h = %.3g m in one step: CFL condition violated (lower Run:cfl_flow)",
               sqrt(mv), (double)s->seg.k.h);
    }
    return 0;
}

/* The backend finds the lowest-index material particle in a blow-up state
 * (step_guard, physics/step.h); the host copy names it. A particle below an
 * outlet is no failure: every rank drains its outlet (drain). */
static void check_finite(sim_t *s, diag *d)
{
    long first = s->be->check(s);
    int out = 0;
    if (first >= 0) out = check_failed(s, d, (size_t)first);
    if (s->step_c.outlet && comm_max(out) > 0) drain(s, first >= 0, 0);
}

/* The arrays a ghost carries: what the run's stages read of ghosts
 * (src/stages.h). */
static int parallel_ghost_arrays(const sim_t *s, int *arr)
{
    void *a[PART_NARRAYS];
    int n = stage_arrays(&s->p, stage_ghost_fields(stage_flags(s)), 0, a);
    for (int k = 0; k < n; ++k) arr[k] = part_array_find(&s->p, a[k]);
    return n;
}

/* Several ranks, or one with periodic axes: the decomposition (mpi/decomp.h)
 * from the scene's Parallel keys, the stage table's ghost arrays and the
 * backend's ghost depth; restarting on the checkpoint's rank count, its cut
 * is taken over, so that the run continues bit-identically. */
static void parallel_start(sim_t *s, const ckpt_run *rs)
{
    const int per = (int)s->sc->geometry.periodic;
    if (comm_size() == 1 && !per) return; /* one rank with periodic axes: its own images (mpi/halo.h) */
    int arr[PART_NARRAYS];
    decomp_config c = {.dim = s->p.dim, .support = R(2.0) * s->seg.k.h,
                       .method = s->sc->parallel.method == PART_METIS ? HALO_METIS : HALO_SLABS,
                       .axis = s->sc->parallel.axis == AXIS_AUTO ? -1 : (int)s->sc->parallel.axis,
                       .depth = s->be->ghost_depth, .arr = arr, .narr = parallel_ghost_arrays(s, arr),
                       .periodic = per, .backend = s->be->name};
    for (int d = 0; d < 3; ++d) c.period[d] = s->flow.w.period[d];
    decomp_saved saved = {0};
    if (rs && rs->dec_present)
        saved = (decomp_saved){.method = rs->dec_method, .axis = rs->dec_axis, .blk = rs->dec_blk,
                               .cg = {rs->dec_cg[0], rs->dec_cg[1], rs->dec_cg[2]}, .bound = rs->dec_bound,
                               .part = rs->dec_part};
    s->halo = decomp_start(&c, rs && rs->dec_present ? &saved : NULL, &s->p);
}

/* Drums: settings of the computed flow outside the range measured to be accurate
 * (docs/gpu.md "Stiffness, artificial viscosity and CFL"): the flow depends
 * on the modulus through the artificial viscosity alpha c_s h (c_s ~ sqrt
 * E), so a softer material (a longer step) must raise alpha to keep
 * alpha sqrt(E); E below the softest measured accurate; Run:cfl_flow above 0.2. */
#define FLOW_E_REF 1e7     /* Table 1's E, Pa */
#define FLOW_ALPHA_REF 0.1 /* and the paper's alpha (3.10) */
#define FLOW_E_MIN 1e4     /* the softest E measured accurate (alpha sqrt(E) held) */
static void flow_warn_settings(const struct scene *sc)
{
    double r = sc->flow.alpha_av * sqrt(sc->material.E) / (FLOW_ALPHA_REF * sqrt(FLOW_E_REF));
    if (r < 0.5 || r > 2)
        warning("Flow:alpha_av * sqrt(Material:E) is %.3g times Table 1's (alpha 0.1 at E = 10 MPa): the artificial "
                "viscosity alpha c_s h sets how fast a drum flows (EV drum at Table 1 resolution, t = 5 s: E = 0.1 "
                "MPa with alpha 0.1 flows 42 %% faster and segregates 84 %% faster than E = 10 MPa, with alpha 1.0 "
                "within 4 %%); to soften the material for a longer step keep alpha sqrt(E): alpha = %.3g here "
                "(docs/gpu.md)", r, FLOW_ALPHA_REF * sqrt(FLOW_E_REF / sc->material.E));
    if (sc->material.E < FLOW_E_MIN)
        warning("Material:E = %.3g Pa is softer than the softest measured accurate, %.0e Pa (alpha sqrt(E) held: "
                "EV drum at Table 1 resolution, t = 10 s, segregation index 2.5 %% low; the 3D drum at dr = 1 mm, "
                "t = 36 s, 6 %% low against E = 0.1 MPa; docs/gpu.md): the elastic strain under self-weight, "
                "rho g H / E, grows as 1/E", sc->material.E, FLOW_E_MIN);
    if (sc->run.cfl_flow > 0.2)
        warning("Run:cfl_flow = %g > 0.2: the drum's flow was measured accurate up to 0.2 (mid-chord speed 6 %% off "
                "at 0.4, docs/granular.md)", sc->run.cfl_flow);
}

/* Snapshots, diagnostics rows and checkpoints that Run:t_end asks for: a
 * count beyond a sane bound (Output:dt = 1e-300 with t_end = 1e300) is bad
 * input, not a run that writes every step forever. */
static void check_output_counts(const struct scene *sc)
{
    const struct {
        const char *key;
        double every, most;
    } o[] = {{"dt", sc->output.dt, 1e5}, {"diag_dt", sc->output.diag_dt, 1e8},
             {"checkpoint_dt", sc->output.checkpoint_dt, 1e6}};
    for (size_t k = 0; k < sizeof o / sizeof o[0]; ++k) {
        double count = sc->run.t_end / o[k].every;
        if (o[k].every <= 0 || (sc->output.snapshots == 0 && k == 0) || count <= o[k].most) continue;
        char where[512];
        input_error("%s: Output:%s = %.3g s asks for %.3g outputs up to Run:t_end = %.3g s, more than %.0e: "
                    "raise Output:%s or lower Run:t_end", scene_key_where(sc, "Output", o[k].key, where, sizeof where),
                    o[k].key, o[k].every, count, sc->run.t_end, o[k].most, o[k].key);
    }
}

/* Next event time (output, diagnostics, end), rounded onto its grid. */
static double next_event(double t, double every, double t_end)
{
    double k = floor(t / every * (1 + 1e-12)) + 1;
    return fmin(k * every, t_end);
}

/* Every Parallel:balance_every steps: move the slab bounds if the measured
 * compute time is out of balance (mpi/halo.h), then prepare the state at t
 * again (the particles moved between ranks; prepare is idempotent). */
static void parallel_balance(sim_t *s, double *cost)
{
    unsigned every = s->sc->parallel.balance_every;
    if (!s->halo || every == 0 || s->step % (long)every != 0) return;
    double thr = s->sc->parallel.balance_threshold, imb = halo_imbalance(s->halo, *cost);
    if (imb > thr) {
        s->be->to_host(s); /* the re-cut reads positions and moves whole particles */
        if (halo_recut(s->halo, &s->p, *cost, imb, thr)) {
            s->be->from_host(s);
            s->be->prepare(s, s->t, !s->win.on);
        }
    }
    *cost = 0;
}

/* A checkpoint of the state after the step (src/checkpoint.h); its write
 * time is the margin Run:max_wall_time keeps. */
static void write_checkpoint(outputs *o, sim_t *s, const diag *d, ckpt_clock *ck)
{
    s->be->to_host(s);
    ckpt_run r = {.small0 = d->small0, .max_drift = d->max_drift, .warned = d->warned, .nsnap = o->n,
                  .times = o->times, .npart = o->npart, .out_n = comm_sum_ll(s->out_n), .out_cv = comm_sum(s->out_cv)};
    ck->write_s = ckpt_write(o->dir, s, &r, o->text);
}

/* Which of a restart's earlier snapshots are in OUTDIR (rank 0 looks; the
 * XDMF index lists only those): all of them when the run continues in its
 * own OUTDIR, none when it continues into a new one. */
static void snapshots_present(outputs *o)
{
    o->present = malloc((size_t)(o->n > 0 ? o->n : 1));
    if (!o->present) error_exit(EXIT_SYSTEM, "out of memory");
    int missing = 0;
    for (int i = 0; i < o->n; ++i) {
        char path[4200];
        snprintf(path, sizeof path, "%s/snapshot_%05d.h5", o->dir, i);
        o->present[i] = comm_rank() != 0 || access(path, F_OK) == 0;
        missing += !o->present[i];
    }
    if (missing)
        message("restart: %d of the %d earlier snapshots are not in %s; snapshots.xmf lists those that are", missing,
                o->n, o->dir);
}

/* A fresh run writes the diagnostics row and snapshot of t = 0. A restart
 * (rs) has both from the earlier run: it takes the diagnostics state and the
 * snapshot list from the checkpoint, so rows, snapshot numbers and the XDMF
 * index continue. Either way the state is prepared at t (after a step it
 * already is; prepare is idempotent, so a restart continues bit-identically).
 * Returns the wall seconds of the first diagnostics row and snapshot, which
 * the done: line's wall includes but its rate does not (0 on a restart). */
static double run_start(sim_t *s, outputs *o, diag *d, ckpt_run *rs)
{
    s->be->prepare(s, s->t, 1);
    if (s->halo) /* the halo figures of the done: line cover the steps only */
        s->halo->wall_comm = s->halo->wall_wait = s->halo->wall_exposed = 0,
        s->halo->bytes = s->halo->messages = s->halo->migrated = 0;
    s->be->to_host(s);
    if (!rs) {
        diag_open(d, o->dir, s);
        diag_row(d, s);
        write_snapshot(o, s);
        return diag_wall() - d->wall0;
    }
    diag_reopen(d, o->dir, s, rs->small0, rs->max_drift, rs->warned);
    s->out_n = comm_rank() == 0 ? rs->out_n : 0; /* the outflow so far: the sums count it once */
    s->out_cv = comm_rank() == 0 ? rs->out_cv : 0.0;
    o->n = rs->nsnap, o->times = rs->times, o->npart = rs->npart; /* o takes them over */
    rs->times = NULL, rs->npart = NULL;
    snapshots_present(o);
    message("restart from %s: step %ld, t = %.9g s, %d snapshot(s) so far", o->restart, s->step, s->t, o->n);
    if (s->t >= s->sc->run.t_end)
        message("nothing to do: t = %.9g s >= Run:t_end = %.9g s (raise Run:t_end to go on)", s->t,
                s->sc->run.t_end);
    return 0;
}

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
 * checkpoint written: the command that continues, with this run's -P
 * options (a different Run:t_end is allowed). */
static void run_stopped(const outputs *o, const sim_t *s, const ckpt_clock *ck, enum ckpt_stop why)
{
    if (why == CKPT_STOPFILE) ckpt_clear_stop(ck);
    char cmd[8192] = "sphseg", cause[64];
    shell_word(cmd, sizeof cmd, o->scene);
    shell_word(cmd, sizeof cmd, "-o"), shell_word(cmd, sizeof cmd, o->dir);
    shell_word(cmd, sizeof cmd, "--restart"), shell_word(cmd, sizeof cmd, o->dir);
    for (int k = 0; k < o->c->n_over; ++k) shell_word(cmd, sizeof cmd, "-P"), shell_word(cmd, sizeof cmd, o->c->over[k]);
    if (o->c->backend) shell_word(cmd, sizeof cmd, "--backend"), shell_word(cmd, sizeof cmd, o->c->backend);
    int sig = ck->signal;
    snprintf(cause, sizeof cause, "received %s", sig == SIGTERM ? "SIGTERM" : sig == SIGUSR1 ? "SIGUSR1"
                                                 : sig == SIGINT ? "SIGINT" : sig == SIGHUP ? "SIGHUP" : "a signal");
    message("stopping at step %ld, t = %.9g s: %s; wrote %s/checkpoint.h5. Continue with\n  %s", s->step, s->t,
            why == CKPT_WALL ? "the next step would pass Run:max_wall_time"
            : why == CKPT_SIGNAL ? cause : "found the STOP file", o->dir, cmd);
}

/* The end of a run: the last progress line, the halo's and the run's totals
 * (the done: line; io is the wall time in output), the windows of C. */
static void run_report(sim_t *s, diag *d, double io)
{
    diag_progress(d, s, 1);
    double wall = diag_wall() - d->wall0, stepping = wall - io, ntot = (double)comm_sum_ll((long long)s->p.n);
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
    message("done: %ld steps, %.3f s wall, %.4e particle-steps/s, max |drift of sum C V| %.3e, %.3f s of the "
            "wall in output and diagnostics (not in the rate), %.3f s in halo exchange", s->step, wall,
            stepping > 0 ? (double)(s->step - d->step0) * ntot / stepping : 0.0, d->max_drift, io, halo);
    if (s->win.on && s->win.windows > 0)
        message("concentration: %ld windows of %.1f flow steps on average, %ld midpoint steps of C", s->win.windows,
                (double)(s->step - d->step0 - s->win.k) / (double)s->win.windows, s->win.substeps);
}

static void run(sim_t *s, outputs *o, ckpt_run *rs)
{
    const struct scene *sc = s->sc;
    diag d;
    double io;       /* wall seconds in snapshots, diagnostics rows and checkpoints, the first ones included */
    double cost = 0; /* this rank's compute seconds since the last load-balance check */
    io = run_start(s, o, &d, rs);
    double t_out = next_event(s->t, sc->output.dt, sc->run.t_end);
    double t_diag = next_event(s->t, sc->output.diag_dt, sc->run.t_end);
    /* checkpoints never shorten a step: a run with them is the run without */
    double ck_every = sc->output.checkpoint_dt;
    double t_ck = ck_every > 0 ? next_event(s->t, ck_every, INFINITY) : INFINITY;
    int ck_end = ck_every > 0 || sc->run.max_wall_time > 0;
    ckpt_clock ck;
    ckpt_clock_start(&ck, o->wall0, sc->run.max_wall_time, o->dir);
    ckpt_signals_stepping(); /* from here SIGTERM, SIGINT ask for a checkpoint; before, they end the run */
    while (s->t < sc->run.t_end) {
        unsigned lift = 0; /* the gates whose time has come: their dummies leave */
        for (int k = 0; k < s->flow.w.n; ++k)
            if ((s->gate >> k & 1) && s->t >= s->flow.w.prim[k].open_at * (1 - 1e-12)) lift |= 1u << k;
        if (lift) {
            drain(s, 0, lift);
            s->gate &= ~lift;
            for (int k = 0; k < s->flow.w.n; ++k)
                if (lift >> k & 1) message("t = %.6g s: the gate is open (wall %s)", s->t, s->wall_name[k]);
        }
        double t_next = fmin(t_out, t_diag), dt = integrate_dt(s);
        if (s->t + dt >= t_next * (1 - 1e-12)) dt = t_next - s->t;
        double t_step = diag_wall(), comm0 = s->halo ? s->halo->wall_comm : 0;
        integrate_step(s, dt);
        if (s->halo) cost += diag_wall() - t_step - (s->halo->wall_comm - comm0);
        parallel_balance(s, &cost);
        if (fabs(s->t - t_next) <= 1e-9 * fmax(1.0, t_next)) s->t = t_next;
        /* C in windows: closed after K steps, and at every diagnostics row,
         * snapshot and the end, so that they see C of t (not at max_steps
         * or an early stop: the checkpoint carries the open window) */
        integrate_conc(s, s->t >= t_diag || s->t >= t_out || s->t >= sc->run.t_end);
        check_finite(s, &d);
        int last = sc->run.max_steps > 0 && s->step >= (long)sc->run.max_steps;
        double t_io = diag_wall();
        if (s->t >= t_diag || last) {
            s->be->to_host(s);
            diag_row(&d, s);
            t_diag = next_event(s->t, sc->output.diag_dt, sc->run.t_end);
        }
        if (s->t >= t_out || last) {
            write_snapshot(o, s);
            t_out = next_event(s->t, sc->output.dt, sc->run.t_end);
        }
        enum ckpt_stop stop = ckpt_poll(&ck, s->step - d.step0);
        if (stop || s->t >= t_ck || (ck_end && (last || s->t >= sc->run.t_end))) {
            write_checkpoint(o, s, &d, &ck);
            t_ck = ck_every > 0 ? next_event(s->t, ck_every, INFINITY) : INFINITY;
        }
        io += diag_wall() - t_io;
        diag_progress(&d, s, 0);
        if (stop) {
            run_stopped(o, s, &ck, stop);
            break;
        }
        if (last) {
            message("stopping after Run:max_steps = %u steps at t = %.9g s", sc->run.max_steps, s->t);
            break;
        }
    }
    run_report(s, &d, io);
    diag_close(&d);
}

/* The start-up lines: the run (particles, h, what is solved, ranks, backend,
 * OUTDIR), the walls, the flow's sound speed and filter, the concentration's
 * windows; a checkpoint's open window that Segregation:every 1 cannot take
 * is refused (exit 2). */
static void start_report(sim_t *s, const outputs *o, const cli *c)
{
    const struct scene *sc = s->sc;
    const char *scheme = !s->seg_on ? "off"
                         : sc->segregation.scheme == SEG_SCHEME_CONSERVATIVE ? "conservative"
                         : sc->segregation.scheme == SEG_SCHEME_DIRECT       ? "direct" : "paper";
    message("sphseg %s: %s, %zu material + %zu dummy particles, h = %.4g m, flow %s, segregation %s, "
            "%d rank(s), backend %s, output %s", SPHSEG_VERSION, sc->path, s->n_material,
            (size_t)comm_sum_ll((long long)s->p.n) - s->n_material,
            (double)s->seg.k.h, s->flow_on ? "computed" : "prescribed", scheme, comm_size(), s->be->name, o->dir);
    char wl[1024];
    message("container: walls %s", wall_list(s, 1, wl, sizeof wl));
    if (s->flow_on)
        message("flow: c_s = %.4g m/s, h/c_s = %.3g s, Shepard filter every %u steps, alpha_av = %g",
                (double)s->flow.cs, (double)(s->seg.k.h / s->flow.cs), sc->flow.shepard_every, sc->flow.alpha_av);
    if (s->flow_on && sc->geometry.type == GEOM_DRUM) flow_warn_settings(sc); /* measured on drums */
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

int main(int argc, char **argv)
{
    MPI_Init(&argc, &argv);
    ckpt_signals_install();
    cli c = parse_cli(argc, argv);
    struct scene sc;
    scene_load(&sc, c.scene, c.n_over, c.over);
    check_output_counts(&sc);
    const char *backend = c.backend ? c.backend : sc.run.backend;
    if (strcmp(backend, "cpu") != 0 && strcmp(backend, "gpu") != 0 && strcmp(backend, "auto") != 0)
        input_error("--backend %s: expected auto, cpu or gpu", backend);
#ifdef SPHSEG_CUDA
    int ndev = strcmp(backend, "cpu") != 0 ? gpu_devices() : 0;
    if (!strcmp(backend, "gpu") && ndev == 0)
        input_error("--backend gpu: no usable CUDA device is visible (check nvidia-smi and "
                    "CUDA_VISIBLE_DEVICES), or run with --backend cpu");
#else
    int ndev = 0;
    (void)ndev;
    if (!strcmp(backend, "gpu"))
        input_error("--backend gpu: this build has no CUDA backend (build with nvcc on the PATH and "
                    "GPU=1), or run with --backend cpu");
#endif
    if (sc.parallel.axis == AXIS_Z && sc.geometry.dim == 2)
        input_error("Parallel:axis: z is not an axis of a 2D scene (x or y, or auto)");
    sim_t s = {0};
    s.sc = &sc;
    s.be = backend_cpu();
#ifdef SPHSEG_CUDA
    if (ndev > 0) s.be = backend_gpu(comm_local_rank());
#endif
    setup_contexts(&s);
    integrate_conc_init(&s);
    ckpt_run rs = {0};
    char chosen[4200] = "";
    if (c.restart)
        ckpt_read(c.restart, &s, &rs, chosen, sizeof chosen); /* exits 2 on a bad checkpoint */
    else
        setup_particles(&s); /* exits 2 if it would not fit */
    parallel_start(&s, c.restart ? &rs : NULL);
    /* the gates still standing (a restart after one opened has none of its dummies) */
    for (int k = 0; k < s.flow.w.n; ++k) {
        long long ng = 0;
        for (size_t i = 0; s.flow.w.prim[k].open_at >= 0 && i < s.p.n; ++i) ng += s.p.wall[i] == k + 1;
        if (comm_sum_ll(ng) > 0) s.gate |= 1u << k;
    }
    outputs o = {0, NULL, NULL, NULL, c.outdir ? c.outdir : default_outdir(c.scene), c.wall0,
                 c.restart ? chosen : NULL, c.scene, &c, NULL, ""};
    make_dirs(o.dir);
    outdir_claim(o.dir, c.overwrite, o.restart); /* exits 2 if OUTDIR is in use or holds another run */
    char used[4200];
    snprintf(used, sizeof used, "%s/used_params.yml", o.dir);
    if (comm_rank() == 0 && scene_write_used(&sc, used) != 0)
        error_exit(EXIT_WRITE, "cannot write %s: %s", used, strerror(errno));
    o.text = scene_used_text(&sc);
    wall_list(&s, 0, o.walls, sizeof o.walls);
    start_report(&s, &o, &c);
    run(&s, &o, c.restart ? &rs : NULL);
    ckpt_run_free(&rs);
    free(o.present);
    s.be->finish(&s);
    if (s.halo) halo_free(s.halo), free(s.halo);
    part_free(&s.p);
    scene_free(&sc);
    MPI_Finalize();
    return 0;
}
