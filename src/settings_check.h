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

/* Material:mu_law partial: no static yield, and no better convergence in
 * the drum (docs/granular.md "Well-posedness"), once at start-up of a
 * computed granular flow. */
void settings_warn_mu_law(const struct scene *sc);

#endif
