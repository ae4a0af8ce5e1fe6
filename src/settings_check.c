/* settings_check.c — the run's settings against what the build and the
 * machine can do (exit 2) and against the range measured accurate
 * (warnings); src/settings_check.h. */
#include "settings_check.h"
#include <math.h>
#include <string.h>
#include "core/error.h"
#include "core/tuning.h"
#include "mpi/comm.h"
#include "run/sim.h"

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

int settings_check(const struct scene *sc, const char *backend)
{
    check_output_counts(sc);
    int ndev = check_backend(backend);
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
