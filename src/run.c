/* run.c — the run loop: from the built (or restarted) state to Run:t_end,
 * with the decomposition set up first, snapshots every Output:dt, a
 * diagnostics row every Output:diag_dt, a checkpoint every
 * Output:checkpoint_dt, the load balance, the gates and the early stops
 * (src/run.h). */
#include <math.h>
#include <stdlib.h>
#include <unistd.h>
#include "core/error.h"
#include "core/tuning.h"
#include "output/io.h"
#include "mpi/comm.h"
#include "mpi/decomp.h"
#include "run.h"
#include "sim/stages.h"
#include "core/version.h"

/* The arrays a ghost carries: what the run's stages read of ghosts
 * (src/sim/stages.h). */
static int parallel_ghost_arrays(const sim_t *s, int *arr)
{
    void *a[PART_NARRAYS];
    int n = stage_arrays(&s->p, stage_ghost_fields(stage_flags(s)), 0, a);
    for (int k = 0; k < n; ++k) arr[k] = part_array_find(&s->p, a[k]);
    return n;
}

/* The decomposition's settings gathered from the scene, the stage table and
 * the backend (src/run.h); mpi/decomp.c makes it. */
void run_decompose(sim_t *s, const ckpt_run *rs)
{
    const int per = (int)s->sc->geometry.periodic;
    if (comm_size() == 1 && !per) return; /* one rank with periodic axes: its own images (mpi/halo.h) */
    int arr[PART_NARRAYS];
    decomp_config c = {.dim = s->p.dim, .support = R(2.0) * s->seg.k.h,
                       .method = s->sc->parallel.method == PART_METIS ? HALO_METIS : HALO_SLABS,
                       .axis = s->sc->parallel.axis == AXIS_AUTO ? -1 : (int)s->sc->parallel.axis,
                       .depth = s->dem && s->be->ghost_depth_fresh ? s->be->ghost_depth_fresh : s->be->ghost_depth,
                       .arr = arr, .narr = parallel_ghost_arrays(s, arr),
                       .periodic = per, .backend = s->be->name};
    for (int d = 0; d < 3; ++d) c.period[d] = s->flow.w.period[d];
    decomp_saved saved = {0};
    if (rs && rs->dec_present)
        saved = (decomp_saved){.method = rs->dec_method, .axis = rs->dec_axis, .blk = rs->dec_blk,
                               .cg = {rs->dec_cg[0], rs->dec_cg[1], rs->dec_cg[2]}, .bound = rs->dec_bound,
                               .part = rs->dec_part};
    s->halo = decomp_start(&c, rs && rs->dec_present ? &saved : NULL, &s->p);
}

void run_gates_standing(sim_t *s)
{
    for (int k = 0; k < s->flow.w.n; ++k) {
        long long ng = 0;
        for (size_t i = 0; s->flow.w.prim[k].open_at >= 0 && i < s->p.n; ++i) ng += s->p.wall[i] == k + 1;
        if (comm_sum_ll(ng) > 0) s->gate |= 1u << k;
    }
}

static void write_snapshot(outputs *o, sim_t *s)
{
    if (!s->sc->output.snapshots) return;
    if (!s->hcsr) s->be->prepare(s, s->t, 2); /* classes and normals for the record */
    s->be->to_host(s);
    io_set_grains(s->dem);
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

/* Next event time (output, diagnostics, end), rounded onto its grid. */
static double next_event(double t, double every, double t_end)
{
    double k = floor(t / every * (1 + 1e-12)) + 1;
    return fmin(k * every, t_end);
}

/* Every Parallel:balance_every steps: move the slab bounds if the measured
 * compute time is out of balance (mpi/halo.h), then prepare the state at t
 * again (the particles moved between ranks; prepare is idempotent). A
 * backend that keeps neighbour lists between builds (relist: the GPU) builds
 * them afresh and prepares again at every check on any rank count, one rank
 * included, re-cut or not, so that its builds, and so its sums' order, fall
 * on the same steps whatever the ranks. */
static void parallel_balance(sim_t *s, double *cost)
{
    unsigned every = s->sc->parallel.balance_every;
    if (every == 0 || s->step % (long)every != 0) return;
    int moved = 0;
    if (s->halo) {
        const tuning *tu = tuning_get(); /* SPHSEG_BALANCE_SKEW: one rank's time counted F times */
        double c = *cost * (tu->skew_rank == comm_rank() ? tu->skew_factor : 1.0);
        double thr = s->sc->parallel.balance_threshold, imb = halo_imbalance(s->halo, c);
        if (imb > thr) {
            double t0 = diag_wall();
            s->be->to_host(s); /* the re-cut reads positions and moves whole particles */
            if (halo_recut(s->halo, &s->p, c, imb, thr)) {
                s->be->from_host(s);
                s->be->prepare(s, s->t, !s->win.on);
                s->halo->recuts++;
                moved = 1;
            }
            s->halo->recut_checks++;
            s->halo->recut_s += diag_wall() - t0;
        }
    }
    if (!moved && s->be->relist) {
        s->be->relist(s);
        s->be->prepare(s, s->t, !s->win.on);
    }
    *cost = 0;
}

/* A checkpoint of the state after the step (src/output/checkpoint.h); its write
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

/* The gates whose time has come: their dummies leave. */
static void open_gates(sim_t *s)
{
    unsigned lift = 0;
    for (int k = 0; k < s->flow.w.n; ++k)
        if ((s->gate >> k & 1) && s->t >= s->flow.w.prim[k].open_at * (1 - 1e-12)) lift |= 1u << k;
    if (!lift) return;
    run_drain(s, 0, lift);
    s->gate &= ~lift;
    for (int k = 0; k < s->flow.w.n; ++k)
        if (lift >> k & 1) message("t = %.6g s: the gate is open (wall %s)", s->t, s->wall_name[k]);
}

void run_steps(sim_t *s, outputs *o, ckpt_run *rs)
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
        open_gates(s);
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
        run_check_finite(s, &d);
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
        diag_progress(&d, s, 0, io);
        if (stop) {
            report_stopped(o, s, &ck, stop);
            break;
        }
        if (last) {
            message("stopping after Run:max_steps = %u steps at t = %.9g s", sc->run.max_steps, s->t);
            break;
        }
    }
    report_end(s, &d, io);
    diag_close(&d);
}
