/* main.c — the sphseg driver:
 *   mpirun -np N build/sphseg SCENE.yml [-o OUTDIR] [-P Section:key=value ...]
 * Loads and validates the scene (exit 2 on bad input, before anything is
 * written), builds the particles, then steps to Run:t_end writing snapshots
 * every Output:dt and a diagnostics row every Output:diag_dt. */
#include <errno.h>
#include <math.h>
#include <mpi.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include "diag.h"
#include "error.h"
#include "io.h"
#include "mpi/comm.h"
#include "sim.h"
#include "version.h"

typedef struct cli {
    const char *scene, *outdir, *backend;
    int n_over;
    char **over;
} cli;

static void usage(void)
{
    message("usage: sphseg SCENE.yml [-o OUTDIR] [-P Section:key=value ...] [--backend cpu]\n"
            "  -o OUTDIR   output folder (default out/<scene name>)\n"
            "  -P ...      override one scene parameter, e.g. -P Geometry:dr=0.00087\n"
            "  --backend   cpu (the CUDA backend arrives with the GPU issue)\n"
            "  --version   print the version");
}

static cli parse_cli(int argc, char **argv)
{
    cli c = {NULL, NULL, NULL, 0, calloc((size_t)argc, sizeof(char *))};
    for (int a = 1; a < argc; ++a) {
        if (!strcmp(argv[a], "-h") || !strcmp(argv[a], "--help")) {
            usage();
            MPI_Finalize();
            exit(0);
        } else if (!strcmp(argv[a], "--version")) {
            message("sphseg %s", SPHSEG_VERSION);
            MPI_Finalize();
            exit(0);
        } else if ((!strcmp(argv[a], "-o") || !strcmp(argv[a], "-P") || !strcmp(argv[a], "--backend")) &&
                   a + 1 < argc) {
            const char *v = argv[++a];
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
            if (mkdir(buf, 0777) && errno != EEXIST) error_exit(1, "cannot create %s", buf);
            *q = '/';
        }
    if (mkdir(buf, 0777) && errno != EEXIST) error_exit(1, "cannot create %s", buf);
}

typedef struct outputs {
    int n;
    double *times;
    long long *npart;
    char *text;
    const char *dir;
} outputs;

static void write_snapshot(outputs *o, sim_t *s)
{
    if (!s->hcsr) s->be->prepare(s, s->t, 2); /* classes and normals for the record */
    io_write_snapshot(o->dir, o->n, &s->p, s->t, s->step, o->text, SPHSEG_VERSION);
    o->times = realloc(o->times, (size_t)(o->n + 1) * sizeof(double));
    o->npart = realloc(o->npart, (size_t)(o->n + 1) * sizeof(long long));
    o->times[o->n] = s->t;
    o->npart[o->n] = comm_sum_ll((long long)s->p.n);
    o->n++;
    if (comm_rank() == 0) io_write_xdmf(o->dir, o->n, o->times, o->npart, s->p.dim);
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

static int outside(const sim_t *s, size_t i)
{
    const particles_t *p = &s->p;
    const wall_geom *w = &s->flow.w;
    double h = s->seg.k.h, x = p->x[0][i], y = p->x[1][i];
    if (w->type == WALL_DRUM) return hypot(x - w->centre[0], y - w->centre[1]) > w->radius + h;
    double z = p->x[2][i];
    x -= w->u[0] * s->t, y -= w->u[1] * s->t, z -= w->u[2] * s->t; /* the box's own frame */
    int outz = w->depth > 0 && (z < -h || z > w->depth + h);
    return x < -h || x > w->width + h || y < -h || outz;
}

/* Which blow-up condition particle i meets: 0 none, 1 concentration, 2 non-finite
 * flow state, 3 outside its container, 4 moved more than h in the step. */
static int bad_state(const sim_t *s, size_t i)
{
    const particles_t *p = &s->p;
    const double h = s->seg.k.h, C = p->C[i];
    if (s->seg_on && !(isfinite(C) && C >= -1.0 && C <= 2.0)) return 1;
    if (!s->flow_on) return 0;
    double sum = 0, mv = 0;
    for (int c = 0; c < 3; ++c) {
        sum += (double)p->x[c][i] + (double)p->v[c][i];
        double dx = (double)p->x[c][i] - (double)p->x_n[c][i];
        mv += dx * dx;
    }
    for (int q = 0; q < 6; ++q) sum += (double)p->sig[q][i];
    if (!isfinite(sum)) return 2;
    if (outside(s, i)) return 3;
    return mv > h * h ? 4 : 0;
}

static void check_finite(const sim_t *s, diag *d)
{
    const particles_t *p = &s->p;
    const long n = (long)p->n;
    long first = n; /* the lowest index meeting a condition: deterministic */
#pragma omp parallel for schedule(static) reduction(min : first)
    for (long i = 0; i < n; ++i)
        if (p->kind[i] == KIND_MATERIAL && i < first && bad_state(s, (size_t)i)) first = i;
    if (first == n) return;
    size_t i = (size_t)first;
    double mv = 0;
    for (int c = 0; c < 3; ++c) mv += pow((double)p->x[c][i] - (double)p->x_n[c][i], 2);
    switch (bad_state(s, i)) {
    case 1:
        blowup(s, d, i, "has concentration %g: the scheme went unstable (see docs/shearbox.md for where "
               "each scheme is stable)", (double)p->C[i]);
        break;
    case 2:
        blowup(s, d, i, "has a non-finite position, velocity or stress: the flow went unstable "
               "(see docs/granular.md, stability limits)");
        break;
    case 3:
        blowup(s, d, i, "left its container through a wall");
        break;
    default:
        blowup(s, d, i, "moved %.3g m > h = %.3g m in one step: CFL condition violated (lower Run:cfl_flow)",
               sqrt(mv), (double)s->seg.k.h);
    }
}

/* Next event time (output, diagnostics, end), rounded onto its grid. */
static double next_event(double t, double every, double t_end)
{
    double k = floor(t / every * (1 + 1e-12)) + 1;
    return fmin(k * every, t_end);
}

static void run(sim_t *s, outputs *o)
{
    const struct scene *sc = s->sc;
    diag d;
    s->be->prepare(s, s->t, 1);
    diag_open(&d, o->dir, s);
    diag_row(&d, s);
    write_snapshot(o, s);
    double t_out = next_event(0, sc->output.dt, sc->run.t_end);
    double t_diag = next_event(0, sc->output.diag_dt, sc->run.t_end);
    while (s->t < sc->run.t_end) {
        double t_next = fmin(t_out, t_diag), dt = integrate_dt(s);
        if (s->t + dt >= t_next * (1 - 1e-12)) dt = t_next - s->t;
        integrate_step(s, dt);
        if (fabs(s->t - t_next) <= 1e-9 * fmax(1.0, t_next)) s->t = t_next;
        check_finite(s, &d);
        if (s->t >= t_diag) {
            diag_row(&d, s);
            t_diag = next_event(s->t, sc->output.diag_dt, sc->run.t_end);
        }
        if (s->t >= t_out) {
            write_snapshot(o, s);
            t_out = next_event(s->t, sc->output.dt, sc->run.t_end);
        }
        diag_progress(&d, s, 0);
    }
    diag_progress(&d, s, 1);
    double wall = diag_wall() - d.wall0;
    message("done: %ld steps, %.3f s wall, %.4e particle-steps/s, max |drift of sum C V| %.3e",
            s->step, wall, wall > 0 ? (double)s->step * (double)s->p.n / wall : 0.0, d.max_drift);
    diag_close(&d);
}

int main(int argc, char **argv)
{
    MPI_Init(&argc, &argv);
    cli c = parse_cli(argc, argv);
    struct scene sc;
    scene_load(&sc, c.scene, c.n_over, c.over);
    const char *backend = c.backend ? c.backend : sc.run.backend;
    if (strcmp(backend, "cpu") != 0)
        input_error("--backend %s: this build has the cpu backend only", backend);
    if (comm_size() > 1)
        input_error("%d ranks: multi-rank runs need the slab decomposition, which is not built "
                    "yet; run with one rank", comm_size());
    sim_t s = {0};
    s.sc = &sc;
    s.be = backend_cpu();
    setup_contexts(&s);
    setup_particles(&s); /* exits 2 if it would not fit */
    outputs o = {0, NULL, NULL, NULL, c.outdir ? c.outdir : default_outdir(c.scene)};
    make_dirs(o.dir);
    char used[4200];
    snprintf(used, sizeof used, "%s/used_params.yml", o.dir);
    if (comm_rank() == 0 && scene_write_used(&sc, used) != 0) error_exit(1, "cannot write %s", used);
    o.text = scene_used_text(&sc);
    const char *scheme = !s.seg_on ? "off"
                         : sc.segregation.scheme == SEG_SCHEME_CONSERVATIVE ? "conservative"
                         : sc.segregation.scheme == SEG_SCHEME_DIRECT       ? "direct" : "paper";
    message("sphseg %s: %s, %zu material + %zu dummy particles, h = %.4g m, flow %s, segregation %s, "
            "%d rank(s), output %s", SPHSEG_VERSION, sc.path, s.n_material, s.p.n - s.n_material,
            (double)s.seg.k.h, s.flow_on ? "computed" : "prescribed", scheme, comm_size(), o.dir);
    if (s.flow_on)
        message("flow: c_s = %.4g m/s, h/c_s = %.3g s, Shepard filter every %u steps, alpha_av = %g",
                (double)s.flow.cs, (double)(s.seg.k.h / s.flow.cs), sc.flow.shepard_every, sc.flow.alpha_av);
    run(&s, &o);
    s.be->finish(&s);
    part_free(&s.p);
    scene_free(&sc);
    MPI_Finalize();
    return 0;
}
