/* main.c — the sphseg driver:
 *   mpirun -np N build/sphseg SCENE.yml [-o OUTDIR] [-P Section:key=value ...] [--restart FILE|DIR]
 *                             [--overwrite]
 * Reads the command line, loads and validates the scene (exit 2 on bad
 * input, before anything is written; src/settings_check.h), builds the
 * particles (or loads them and the run state from a checkpoint,
 * src/output/checkpoint.h), decomposes the domain and steps to Run:t_end
 * (src/run.h), writing snapshots every Output:dt, a diagnostics row every
 * Output:diag_dt and a checkpoint every Output:checkpoint_dt. */
#include <errno.h>
#include <mpi.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include "output/checkpoint.h"
#include "core/error.h"
#include "mpi/comm.h"
#include "output/outdir.h"
#include "run.h"
#include "settings_check.h"
#include "sim/sim.h"
#include "core/version.h"

static void usage(void)
{
    message("usage: sphseg SCENE.yml [-o OUTDIR] [-P Section:key=value ...] [--backend auto|cpu|gpu]\n"
            "              [--restart FILE|DIR] [--overwrite]\n"
            "  -o OUTDIR   output folder (default out/<scene name>; with --restart, the checkpoint's folder)\n"
            "  -P ...      override one scene parameter, e.g. -P Geometry:dr=0.00087\n"
            "  --backend   auto (default: gpu when built with CUDA and a device is present), cpu or gpu;\n"
            "              overrides Run:backend\n"
            "  --restart FILE|DIR  continue the run saved in the checkpoint FILE, or the newest valid one in DIR\n"
            "              (checkpoint.h5 or checkpoint_prev.h5): the particles and run state come from it, the\n"
            "              parameters from SCENE.yml and -P, whose state-defining keys must match the checkpoint's\n"
            "              (a longer Run:t_end extends a run); snapshots and diagnostics.csv continue in OUTDIR\n"
            "              (without -o: the folder of the checkpoint)\n"
            "  --overwrite a fresh run may replace the files of an earlier run in OUTDIR (else: exit 2)\n"
            "  SIGTERM, SIGUSR1, SIGINT: finish the step, write a checkpoint, exit 0; a second SIGTERM ends at once\n"
            "  --keys      print every scene key with its type, default, range and meaning (Markdown, docs/keys.md)\n"
            "  --version   print the version");
}

static run_cli parse_cli(int argc, char **argv)
{
    run_cli c = {NULL, NULL, NULL, 0, calloc((size_t)argc, sizeof(char *)), NULL, diag_wall(), 0, argc, argv};
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

/* Without -o: a restart continues in the folder of its checkpoint (chosen:
 * the file taken), a fresh run writes to out/<scene name>. */
static char *default_outdir(const char *scene, const char *chosen)
{
    if (chosen) {
        const char *slash = strrchr(chosen, '/');
        size_t n = slash ? (size_t)(slash - chosen) + (slash == chosen) : 1;
        char *o = malloc(n + 1);
        if (o) snprintf(o, n + 1, "%.*s", (int)n, slash ? chosen : ".");
        return o;
    }
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

/* OUTDIR made and claimed (exits 2 if it is in use or holds another run),
 * used_params.yml written; o is what the run writes there. */
static void outputs_open(outputs *o, const sim_t *s, const run_cli *c, const char *chosen)
{
    const char *dir = c->outdir ? c->outdir : default_outdir(c->scene, c->restart ? chosen : NULL);
    *o = (outputs){0, NULL, NULL, NULL, dir, c->wall0, c->restart ? chosen : NULL, c->scene, c, NULL, ""};
    make_dirs(o->dir);
    outdir_claim(o->dir, c->overwrite, o->restart);
    char used[4200];
    snprintf(used, sizeof used, "%s/used_params.yml", o->dir);
    if (comm_rank() == 0 && scene_write_used(s->sc, used) != 0)
        error_exit(EXIT_WRITE, "cannot write %s: %s", used, strerror(errno));
    o->text = scene_used_text(s->sc);
    wall_list(s, 0, o->walls, sizeof o->walls);
}

int main(int argc, char **argv)
{
    MPI_Init(&argc, &argv);
    ckpt_signals_install();
    run_cli c = parse_cli(argc, argv);
    struct scene sc;
    scene_load(&sc, c.scene, c.n_over, c.over);
    if (sc.run.preset != PRESET_NONE) { /* what it set: the keys not given with -P (used_params.yml has all) */
        char line[1024];
        size_t n = 0;
        for (const char *const *k = scene_preset_keys((int)sc.run.preset); *k && n < sizeof line; ++k)
            n += (size_t)snprintf(line + n, sizeof line - n, " %s", *k);
        message("preset %s:%s (a -P of the same key wins over it)", scene_preset_name((int)sc.run.preset), line);
    }
    int ndev = settings_check(&sc, c.backend ? c.backend : sc.run.backend);
    (void)ndev;
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
    run_decompose(&s, c.restart ? &rs : NULL);
    run_gates_standing(&s);
    outputs o;
    outputs_open(&o, &s, &c, chosen);
    report_start(&s, &o, &c);
    run_steps(&s, &o, c.restart ? &rs : NULL);
    ckpt_run_free(&rs);
    free(o.present);
    s.be->finish(&s);
    if (s.halo) halo_free(s.halo), free(s.halo);
    part_free(&s.p);
    dem_free(s.dem);
    scene_free(&sc);
    MPI_Finalize();
    return 0;
}
