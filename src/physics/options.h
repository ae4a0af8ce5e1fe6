/* physics/options.h — the physics' enumerated choices, one enum per choice.
 * The bodies of src/physics/ switch on these values; the key table
 * (src/scene/scene_keys.h) names them for the scene file, its row taking the
 * enum as its type, so a scene's choice reaches the physics unchanged (no
 * twin enum, no mapper). A new choice: its enum here, its row there. */
#ifndef SPHSEG_PHYSICS_OPTIONS_H
#define SPHSEG_PHYSICS_OPTIONS_H

/* Flow:stabilization: monaghan, the paper's artificial viscosity (3.10);
 * riemann, the low-dissipation Riemann solver of Zhang, Hu & Adams (2017);
 * delta, delta-SPH pressure diffusion alone (physics/momentum.h). */
enum flow_stab { STAB_MONAGHAN = 0, STAB_RIEMANN = 1, STAB_DELTA = 2 };

/* Material:yield, the granular material's yield surface (physics/stress.h):
 * drucker_prager, the paper's cone sqrt(J2) = k_mu(mu(I)) p (2.11-2.12);
 * mu_I, the tensorial law |tau| = sqrt(J2) = mu(I) p of Jop, Forterre &
 * Pouliquen (2006). */
enum stress_yield { YIELD_DRUCKER_PRAGER = 0, YIELD_MU_I = 1 };

/* Flow:shifting: off (the paper's) | fickian (Lind et al. 2012; physics/shift.h). */
enum shift_kind { SHIFT_OFF = 0, SHIFT_FICKIAN = 1 };
/* Flow:shift_surface_rule: what a free-surface particle's shift keeps: none | its part along the surface |
 * a share that fades with div r (no threshold). */
enum shift_surface_rule { SHIFT_SURFACE_NONE = 0, SHIFT_SURFACE_TANGENTIAL = 1, SHIFT_SURFACE_FADE = 2 };

/* Segregation:scheme. paper: eq. (2.10)/(3.13) with HCSR boundaries (§4.2)
 * and C1 boundary gradients (App. E); direct: eq. (2.5) with the same
 * boundaries (App. A); conservative: pairwise antisymmetric fluxes, no
 * source terms (physics/seg_kern.h). */
enum seg_scheme { SEG_SCHEME_PAPER = 0, SEG_SCHEME_DIRECT = 1, SEG_SCHEME_CONSERVATIVE = 2 };

/* Segregation:limiter. none: the conservative scheme's central pair flux
 * Q_i + Q_j as it is; donor: capped by the donor's C and the receiver's room
 * (seg_kern.h seg_flux_donor), which keeps C in [0, 1]. */
enum seg_limiter { SEG_LIMITER_NONE = 0, SEG_LIMITER_DONOR = 1 };

/* Segregation:shear_rate. total: eq. (2.7)'s gdot of the whole strain rate
 * (the paper's); yielded: gdot where the stress is on or past the static
 * yield cone (stress_static_q >= 1), 0 inside it, where the bed deforms
 * elastically and does not flow (seg_drive_gdot, seg_kern.h). */
enum seg_gdot { SEG_GDOT_TOTAL = 0, SEG_GDOT_YIELDED = 1 };

/* Kinematics:velocity. rest and oscillatory_shear prescribe the velocity
 * (no momentum or stress solved, physics/kin.h); computed solves the
 * granular flow (momentum 3.9, stress 2.16). */
enum kin_type { KIN_REST = 0, KIN_OSCILLATORY_SHEAR = 1, KIN_COMPUTED = 2 };

/* Run:integrator (src/sim/integrate.c): predictor_corrector, the paper's
 * explicit midpoint rule (3.17-3.18), two rate evaluations a step;
 * leapfrog, the same midpoint rule whose predictor takes the rates of the
 * previous step's corrector, one rate evaluation a step (docs/method.md). */
enum run_integrator { INTEGRATOR_PREDICTOR_CORRECTOR = 0, INTEGRATOR_LEAPFROG = 1 };

/* DEM:coupling (src/physics/dem.h, src/dem/dem.c): one_way, the grains feel
 * the fluid (drag, eq. 19-23) and the fluid does not feel them; two_way, the
 * fluid also takes the interaction source (14), its fluid fraction (15-16) in
 * the momentum and the superficial density (the DEM paper's eq. 6). */
enum dem_coupling { DEM_ONE_WAY = 0, DEM_TWO_WAY = 1 };

#endif
