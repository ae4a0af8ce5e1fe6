/* settings_check.h — a run's settings held to what it can do and to what was
 * measured accurate, before any particle is built: the refusals that need
 * more than one key or the machine (exit 2, DESIGN.md "Errors") and the
 * warnings for settings outside the measured range. The checks of single
 * keys and of keys against each other are the scene loader's
 * (src/scene/scene_check.c). */
#ifndef SPHSEG_SETTINGS_CHECK_H
#define SPHSEG_SETTINGS_CHECK_H
#include "scene/scene.h"

/* Collective. Refuses (exit 2) output counts beyond a sane bound, a backend
 * name other than auto, cpu, gpu, --backend gpu without a usable device
 * (or without CUDA in the build) and Parallel:axis z in 2D. backend is the
 * command line's --backend, else Run:backend. Returns the usable CUDA
 * devices when the backend may be the GPU (0 otherwise, and without CUDA). */
int settings_check(const struct scene *sc, const char *backend);

/* The warnings for a drum's computed flow outside the range measured to be
 * accurate (docs/gpu.md "Stiffness, artificial viscosity and CFL"):
 * settings_warn_alpha_sqrt_e, a modulus below the softest measured accurate,
 * Run:cfl_flow above 0.2, and a Shepard filter less than 3 acoustic times
 * apart (Flow:shepard_every * Run:cfl_flow). */
void settings_warn_drum(const struct scene *sc);

/* Flow:alpha_av * sqrt(Material:E) more than a factor 2 off Table 1's:
 * the artificial viscosity alpha c_s h (c_s ~ sqrt E) sets how fast a drum
 * flows, so a softer material (a longer step) must raise alpha. */
void settings_warn_alpha_sqrt_e(const struct scene *sc);

/* Flow:stabilization delta, or riemann with Flow:riemann_diffusion on: what
 * their pressure diffusion was measured to do wrong (docs/granular.md
 * "Stabilisation"), once at start-up of a computed flow. riemann without it
 * is the drum and chute scenes' setting and says nothing. */
void settings_warn_stabilization(const struct scene *sc);

/* Flow:gradient_correction on with Flow:shifting off: the corrected
 * velocity gradient does not hold grains off a wall (docs/granular.md "The
 * corrected gradient"), once at start-up of a computed flow. */
void settings_warn_gradient_correction(const struct scene *sc);

/* Flow:shift_surface_rule fade with shifting on: it mixes C at a free
 * surface (docs/drum3d.md "No threshold"), once at start-up of a computed
 * flow. */
void settings_warn_shift(const struct scene *sc);

/* Material:mu_law partial: no static yield, and no better convergence in
 * the drum (docs/granular.md "Well-posedness"), once at start-up of a
 * computed granular flow. */
void settings_warn_mu_law(const struct scene *sc);

/* Scales outside what the model is meant for, once at start-up: the large
 * grains against the container (fewer than 4 across) and against
 * Geometry:dr (more than 50 dr), where the grain sizes are read (a granular
 * flow's mu(I), the shear_rate segregation model); a turning drum's (or a
 * container's turning cylinder's) Froude number omega^2 R / g from 0.1,
 * cataracting towards centrifuging (Mellmann 2001). */
void settings_warn_scales(const struct scene *sc, int flow_on, int seg_on);

/* The run's threads and the cores it has (collective, at start-up): OpenMP
 * threads per rank (omp_get_max_threads), ranks, ranks and threads on this
 * node, the node's cores the run may use (the union of its ranks' affinity
 * masks, at most a cgroup CPU quota), this rank's own; the nodes whose
 * threads outnumber their cores and the ranks bound to fewer cores than
 * they have threads (all ranks together), the load average, and
 * OMP_NUM_THREADS as set (empty: unset). */
typedef struct run_threads {
    int threads, ranks, node_ranks, cores, rank_cores, quota, over_nodes, over_ranks, openmp;
    long long node_threads;
    double load; /* 1-minute load average of this node, < 0 if unknown */
    char env[48];
} run_threads;
void settings_threads(run_threads *t);
/* Oversubscription: more threads on a node than its cores, or a rank with
 * more threads than the cores it is bound to (warnings, rank 0). */
void settings_warn_threads(const run_threads *t);

#endif
