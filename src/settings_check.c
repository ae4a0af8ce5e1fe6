/* settings_check.c — the run's settings against what the build and the
 * machine can do (exit 2) and against the range measured accurate
 * (warnings); src/settings_check.h. */
#define _GNU_SOURCE /* sched_getaffinity, CPU_COUNT, getloadavg */
#include "settings_check.h"
#include <math.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "core/omp_shim.h"
#include "core/error.h"
#include "core/tuning.h"
#include "mpi/comm.h"
#include "sim/sim.h"

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

/* The backend's name, and a GPU when one is asked for; the usable devices. */
static int check_backend(const char *backend)
{
    if (strcmp(backend, "cpu") != 0 && strcmp(backend, "gpu") != 0 && strcmp(backend, "auto") != 0)
        input_error("--backend %s: expected auto, cpu or gpu", backend);
#ifdef SPHSEG_CUDA
    int ndev = strcmp(backend, "cpu") != 0 ? gpu_devices() : 0;
    if (!strcmp(backend, "gpu") && ndev == 0)
        input_error("--backend gpu: no usable CUDA device is visible (check nvidia-smi and "
                    "CUDA_VISIBLE_DEVICES), or run with --backend cpu");
    return ndev;
#else
    if (!strcmp(backend, "gpu"))
        input_error("--backend gpu: this build has no CUDA backend (build with nvcc on the PATH and "
                    "GPU=1), or run with --backend cpu");
    return 0;
#endif
}

/* A scene with DEM grains passes the scene's check with periods of
 * SCENE_PERIOD_SUPPORTS_CPU supports (the CPU's ghosts); the GPU's need
 * SCENE_PERIOD_SUPPORTS. --backend gpu: refused; auto: the CPU. */
static void check_dem_period(const struct scene *sc, const char *backend, int *ndev)
{
    const struct scene_geometry *g = &sc->geometry;
    static const char *const key[3] = {"width", "height", "depth"};
    const double len[3] = {g->width, g->height, g->depth}, need = SCENE_PERIOD_SUPPORTS * 2 * g->h_factor * g->dr;
    for (int a = 0; a < 3; ++a) {
        if (!(g->periodic >> a & 1) || len[a] >= need) continue;
        if (strcmp(backend, "gpu") != 0) {
            *ndev = 0; /* auto: the CPU, whose ghosts fit */
            return;
        }
        char where[512];
        input_error("%s: a periodic axis of a scene with DEM grains needs a period of at least %d supports 2h = %.4g m "
                    "on the GPU backend (its ghosts are 3 cells deep), got %.4g; run it with --backend cpu (4 supports "
                    "there) or widen the period", scene_key_where(sc, "Geometry", key[a], where, sizeof where),
                    SCENE_PERIOD_SUPPORTS, need, len[a]);
    }
}

int settings_check(const struct scene *sc, const char *backend)
{
    check_output_counts(sc);
    int ndev = check_backend(backend);
    if (sc->dem.on && ndev > 0) check_dem_period(sc, backend, &ndev);
    if (sc->parallel.axis == AXIS_Z && sc->geometry.dim == 2)
        input_error("Parallel:axis: z is not an axis of a 2D scene (x or y, or auto)");
    const tuning *tu = tuning_get();
    if (tu->skew_rank == -2)
        input_error("SPHSEG_BALANCE_SKEW=%.64s: expected RANK:FACTOR, a rank and a factor > 0 (e.g. 0:3)",
                    tu->skew_text);
    if (tu->skew_rank >= comm_size()) /* a skew that would never apply */
        input_error("SPHSEG_BALANCE_SKEW=%.64s: rank %d, but the run has %d rank(s)", tu->skew_text, tu->skew_rank,
                    comm_size());
    return ndev;
}

/* The measured references (docs/gpu.md "Stiffness, artificial viscosity and
 * CFL"): the flow depends on the modulus through the artificial viscosity
 * alpha c_s h (c_s ~ sqrt E), so a softer material (a longer step) must
 * raise alpha to keep alpha sqrt(E). */
#define FLOW_E_REF 1e7     /* Table 1's E, Pa */
#define FLOW_ALPHA_REF 0.1 /* and the paper's alpha (3.10) */
#define FLOW_E_MIN 1e4     /* the softest E measured accurate (alpha sqrt(E) held) */
/* The shortest Shepard interval, in acoustic times h / c_s, that the drum's
 * study found harmless (docs/granular.md "The time step and the Shepard
 * filter": 1.5 slowed the 2D EV drum by 6 %, 3 by at most 2 %, 6 not at all) */
#define FLOW_SHEPARD_AC_MIN 3.0

void settings_warn_alpha_sqrt_e(const struct scene *sc)
{
    if (sc->flow.stabilization != STAB_MONAGHAN) return; /* alpha_av is monaghan's alone */
    double r = sc->flow.alpha_av * sqrt(sc->material.E) / (FLOW_ALPHA_REF * sqrt(FLOW_E_REF));
    if (r < 0.5 || r > 2)
        warning("Flow:alpha_av * sqrt(Material:E) is %.3g times Table 1's (alpha 0.1 at E = 10 MPa): the artificial "
                "viscosity alpha c_s h sets how fast a drum flows (EV drum at Table 1 resolution, t = 5 s: E = 0.1 "
                "MPa with alpha 0.1 flows 42 %% faster and segregates 84 %% faster than E = 10 MPa, with alpha 1.0 "
                "within 4 %%); to soften the material for a longer step keep alpha sqrt(E): alpha = %.3g here "
                "(docs/gpu.md)", r, FLOW_ALPHA_REF * sqrt(FLOW_E_REF / sc->material.E));
}

void settings_warn_stabilization(const struct scene *sc)
{
    const struct scene_flow *f = &sc->flow;
    if (f->stabilization == STAB_DELTA || (f->stabilization == STAB_RIEMANN && f->riemann_diffusion))
        warning("%s: the pressure diffusion compacts a free surface at a constant rate (a 1 cm chute layer at 25 "
                "degrees sinks 0.23 mm/s with riemann's, 0.075 mm/s with delta's, at dr 0.5 mm), and in the 2D drum "
                "at 10 kPa particles left through the wall within 3-8 s (docs/granular.md \"Stabilisation\")",
                f->stabilization == STAB_DELTA ? "Flow:stabilization delta" : "Flow:riemann_diffusion on");
}

void settings_warn_gradient_correction(const struct scene *sc)
{
    if (sc->flow.gradient_correction && sc->flow.shifting == SHIFT_OFF)
        warning("Flow:gradient_correction on without Flow:shifting: the corrected velocity gradient lets grains laid "
                "against a wall creep into it, about 2 mm/s in the 2D drum, until one leaves (at 1.8-3.4 s with "
                "Flow:gradient_correction_det 0.1-0.45, 38 s at 0.6); Flow:shifting fickian keeps them out "
                "(40 s held) and the drum converges with it (docs/granular.md \"The corrected gradient\")");
}

void settings_warn_shift(const struct scene *sc)
{
    if (sc->flow.shifting != SHIFT_OFF && sc->flow.shift_surface_rule == SHIFT_SURFACE_FADE)
        warning("Flow:shift_surface_rule fade keeps a share of the surface rows' outward shift, which mixes C at the "
                "surface: the 2D EV drum's segregation index 26-28 %% under the rule none's at dr 0.7-0.35 mm, t = "
                "8-10 s (docs/drum3d.md \"No threshold\"); none (the default) or tangential cut that part");
}

void settings_warn_mu_law(const struct scene *sc)
{
    if (sc->material.model == MAT_GRANULAR && sc->material.mu_law == MAT_MU_PARTIAL)
        warning("Material:mu_law partial: mu(I) has no static yield, so nothing rests on a slope (a mu_I chute layer "
                "flows at I = 1.5e-3 at 20 degrees, below Pouliquen's onset at 20.9), and the drum's answer changes "
                "with dr as much as with the regularized law (docs/granular.md \"Well-posedness\")");
}

void settings_warn_drum(const struct scene *sc)
{
    settings_warn_alpha_sqrt_e(sc);
    if (sc->material.E < FLOW_E_MIN)
        warning("Material:E = %.3g Pa is softer than the softest measured accurate, %.0e Pa (alpha sqrt(E) held: "
                "EV drum at Table 1 resolution, t = 10 s, segregation index 2.5 %% low; the 3D drum at dr = 1 mm, "
                "t = 36 s, 6 %% low against E = 0.1 MPa; docs/gpu.md): the elastic strain under self-weight, "
                "rho g H / E, grows as 1/E", sc->material.E, FLOW_E_MIN);
    if (sc->run.cfl_flow > 0.2)
        warning("Run:cfl_flow = %g > 0.2: the drum's flow was measured accurate up to 0.2 (mid-chord speed 6 %% off "
                "at 0.4, docs/granular.md)", sc->run.cfl_flow);
    /* The filter's interval in acoustic times h / c_s: a step is at most
     * cfl_flow of one (3.19), so shepard_every steps are at most their product */
    double every_ac = sc->flow.shepard_every * sc->run.cfl_flow;
    if (sc->flow.shepard_every > 0 && every_ac < FLOW_SHEPARD_AC_MIN)
        warning("Flow:shepard_every * Run:cfl_flow = %g < %g: the Shepard filter then smooths the stress less than %g "
                "acoustic times h / c_s apart, and that slows the drum (2D EV drum, dr 0.5 mm, E 0.1 MPa: the top "
                "grains 6 %% slower at 1.5; at 6 the same as unfiltered, whatever cfl_flow, within 0.7 %%; "
                "docs/granular.md \"The time step and the Shepard filter\"); with a shorter step raise "
                "Flow:shepard_every in proportion", every_ac, FLOW_SHEPARD_AC_MIN, FLOW_SHEPARD_AC_MIN);
}

/* Grain sizes against the container and dr. The continuum (mu(I), eq.
 * 2.13; the segregation's V and D, eq. 2.7) averages over many grains: the
 * coarsest scene it was checked on, the paper's shear box (van der Vaart et
 * al. 2015: 37 mm wide, 8 mm beads), holds 4.6 large grains across, the
 * shipped chute layer 5; fewer than 4 is outside what the model is meant
 * for. An SPH particle stands for a piece of that continuum: the shipped
 * scenes put at most 6.4 particle spacings in a large grain
 * (inputs/column_2d.yml; the paper's Table 1: 1), and at 50 a kernel
 * support (2h = 3 dr) spans a seventeenth of a grain, detail the model does
 * not have. Either is most often a size in mm typed as m. */
#define SCALE_GRAINS_ACROSS_MIN 4.0
#define SCALE_GRAIN_DR_MAX 50.0
/* A drum's Froude number omega^2 R / g: rolling 1e-4 to 1e-2, cascading
 * 1e-3 to 1e-1, cataracting 0.1 to 1, centrifuging from 1 (Mellmann 2001,
 * Powder Technol. 118, 251; the paper's drum runs 9.8e-4 at 5 rpm). From
 * 0.1 grains leave the bed in free flight, which the dense continuum does
 * not model. */
#define SCALE_FROUDE_MAX 0.1

static void warn_grains(const struct scene *sc)
{
    const struct scene_geometry *g = &sc->geometry;
    double d = sc->grains.d_large, ext[3], L = INFINITY;
    scene_extent(sc, ext);
    for (int a = 0; a < 3; ++a)
        if (ext[a] > 0) L = fmin(L, ext[a]);
    const char *what = g->type == GEOM_DRUM ? (g->dim == 3 && g->length < 2 * g->radius ? "the drum's length"
                                                                                         : "the drum's diameter")
                       : g->type == GEOM_CONTAINER ? "the container's walls and regions, at their narrowest"
                                                   : "the box's smallest side";
    char where[512];
    if (isfinite(L) && d * SCALE_GRAINS_ACROSS_MIN > L)
        warning("%s: Grains:d_large = %.3g m: %s, %.3g m, holds %.2g large grains across, fewer than %g: the continuum "
                "(mu(I), eq. 2.13; the segregation's V and D, eq. 2.7) averages over many grains, and the coarsest "
                "scene it was checked on, the paper's shear box (37 mm wide, 8 mm beads), holds 4.6; grain sizes are "
                "in m (mm typed as m?)", scene_key_where(sc, "Grains", "d_large", where, sizeof where), d, what, L,
                L / d, SCALE_GRAINS_ACROSS_MIN);
    if (d > SCALE_GRAIN_DR_MAX * g->dr)
        warning("%s: Grains:d_large = %.3g m is %.3g particle spacings Geometry:dr = %.3g m, more than %g: an SPH "
                "particle stands for a piece of the continuum holding many grains (the shipped scenes put at most "
                "6.4 dr in a large grain, the paper's Table 1 one), and a kernel support 2h = %.3g m resolves a "
                "small part of one grain; grain sizes are in m (mm typed as m?)", scene_key_where(sc, "Grains",
                "d_large", where, sizeof where), d, d / g->dr, g->dr, SCALE_GRAIN_DR_MAX, 2 * g->h_factor * g->dr);
}

/* One turning drum's Froude number against SCALE_FROUDE_MAX. */
static void warn_froude(const struct scene *sc, const char *where, const char *key, double rpm, double R)
{
    const double *gv = sc->physics.gravity;
    double omega = rpm * 2 * M_PI / 60, gn = sqrt(gv[0] * gv[0] + gv[1] * gv[1] + gv[2] * gv[2]);
    double fr = omega * omega * R / gn;
    if (fr >= SCALE_FROUDE_MAX)
        warning("%s: %s = %g rev/min on a drum of radius %.3g m gives a Froude number omega^2 R / g = %.3g, at least "
                "%g: from 0.1 grains are thrown off the bed (cataracting), from 1 the material centrifuges with the "
                "wall, and the dense continuum models neither; rolling and cascading run at Fr 1e-4 to 1e-1 "
                "(Mellmann 2001; the paper's drum 9.8e-4 at 5 rpm); Fr = %g is %.3g rev/min here", where, key, rpm,
                R, fr, SCALE_FROUDE_MAX, SCALE_FROUDE_MAX, 60 / (2 * M_PI) * sqrt(SCALE_FROUDE_MAX * gn / R));
}

void settings_warn_scales(const struct scene *sc, int flow_on, int seg_on)
{
    int grains_used = (flow_on && sc->material.model == MAT_GRANULAR) ||
                      (seg_on && sc->segregation.model == SEG_MODEL_SHEAR_RATE);
    if (grains_used) warn_grains(sc);
    if (!flow_on) return;
    char where[512], key[96];
    if (sc->geometry.type == GEOM_DRUM)
        warn_froude(sc, scene_key_where(sc, "Walls", "rpm", where, sizeof where), "Walls:rpm", sc->walls.rpm,
                    sc->geometry.radius);
    if (sc->geometry.type != GEOM_CONTAINER) return;
    for (unsigned i = 0; i < sc->container.walls_count; ++i) {
        const struct scene_wall *w = &sc->container.walls[i];
        if (w->shape != CWALL_CYLINDER || w->motion != CWALL_TURNING || w->material != CWALL_INSIDE) continue;
        char k[48];
        snprintf(k, sizeof k, "walls:%u:rpm", i + 1);
        snprintf(key, sizeof key, "Container:walls:%u:rpm", i + 1);
        warn_froude(sc, scene_key_where(sc, "Container", k, where, sizeof where), key, w->rpm, w->radius);
    }
}

/* The cores a cgroup's CPU quota allows (cgroup v2 cpu.max, v1
 * cpu.cfs_quota_us / cpu.cfs_period_us), rounded up; 0 without a quota. */
static int cgroup_cores(void)
{
    double quota = -1, period = 0;
    FILE *f = fopen("/sys/fs/cgroup/cpu.max", "r");
    if (f) {
        char q[32] = "";
        if (fscanf(f, "%31s %lf", q, &period) == 2 && strcmp(q, "max") != 0) quota = atof(q);
        fclose(f);
    } else if ((f = fopen("/sys/fs/cgroup/cpu/cpu.cfs_quota_us", "r"))) {
        if (fscanf(f, "%lf", &quota) != 1) quota = -1;
        fclose(f);
        if ((f = fopen("/sys/fs/cgroup/cpu/cpu.cfs_period_us", "r"))) {
            if (fscanf(f, "%lf", &period) != 1) period = 0;
            fclose(f);
        }
    }
    return quota > 0 && period > 0 ? (int)ceil(quota / period - 1e-9) : 0;
}

void settings_threads(run_threads *t)
{
    memset(t, 0, sizeof *t);
    t->threads = omp_get_max_threads();
    t->ranks = comm_size();
    t->node_ranks = comm_local_size();
    t->node_threads = comm_node_sum_ll(t->threads);
    /* the cores of this node the run may use: the union of its ranks'
     * affinity masks (the whole node when a rank cannot tell), at most the
     * cgroup's quota */
    cpu_set_t mine;
    CPU_ZERO(&mine);
    int known = sched_getaffinity(0, sizeof mine, &mine) == 0;
    t->rank_cores = known ? CPU_COUNT(&mine) : (int)sysconf(_SC_NPROCESSORS_ONLN);
    if (!known)
        for (int c = 0; c < t->rank_cores && c < CPU_SETSIZE; ++c) CPU_SET(c, &mine);
    comm_node_bor((unsigned char *)&mine, (int)sizeof mine);
    t->cores = CPU_COUNT(&mine);
    int quota = cgroup_cores();
    if (quota > 0 && quota < t->cores) t->cores = quota, t->quota = 1;
    if (quota > 0 && quota < t->rank_cores) t->rank_cores = quota;
    /* the worst node and rank, for rank 0's warning */
    t->over_nodes = (int)comm_sum_ll(comm_local_rank() == 0 && t->node_threads > t->cores);
    t->over_ranks = (int)comm_sum_ll(t->threads > t->rank_cores);
    double la[1];
    t->load = getloadavg(la, 1) == 1 ? la[0] : -1;
    const char *env = getenv("OMP_NUM_THREADS");
    snprintf(t->env, sizeof t->env, "%.40s", env ? env : "");
#ifdef _OPENMP
    t->openmp = 1;
#endif
}

void settings_warn_threads(const run_threads *t)
{
    if (t->over_nodes)
        warning("%lld OpenMP threads on %s node (%d rank(s) x %d) share %d core(s)%s: oversubscribed threads wait for "
                "each other at every parallel loop, and the run goes several times slower (issue 55: the shear box on "
                "a loaded 2-core machine took 136 s with the default threads, 26 s with one); set OMP_NUM_THREADS to "
                "at most the cores over the ranks per node, %d here (OMP_NUM_THREADS=%d mpirun -np ... sphseg ...)",
                t->node_threads, t->over_nodes > 1 ? "each such" : "rank 0's", t->node_ranks, t->threads, t->cores,
                t->quota ? " (its CPU quota)" : "", t->cores / t->node_ranks > 0 ? t->cores / t->node_ranks : 1,
                t->cores / t->node_ranks > 0 ? t->cores / t->node_ranks : 1);
    else if (t->over_ranks)
        warning("%d rank(s) run more OpenMP threads (%d) than the cores they are bound to (%d on rank 0): the threads "
                "of a rank share its cores and wait for each other at every parallel loop; set OMP_NUM_THREADS to "
                "the cores per rank, or bind each rank to as many cores as it has threads (mpirun --map-by "
                "slot:PE=N, srun --cpus-per-task=N)", t->over_ranks, t->threads, t->rank_cores);
}
