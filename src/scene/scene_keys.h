/* scene_keys.h — every key of the scene file, declared once (no include
 * guard: src/scene/scene.h, src/scene/scene.c and src/scene/scene_doc.c include it once per
 * use, after src/scene/scene_keys_none.h, defining the row macros they read):
 * the members of the section structs (scene.h), the libcyaml schema, the
 * defaults, the ranges of the numbers, the documentation (sphseg --keys,
 * docs/keys.md) and so the echo (used_params.yml) all come from these rows.
 *
 *   SECTION(Name, member of struct scene, its struct) ... END_SECTION(member)
 *   KF(Section, member, struct, key, REQ|OPT, default, lo, hi, open, when, doc)  a number (double); a
 *      range lo..hi (open: LO_OPEN, HI_OPEN, CLOSED), checked when `when` (ALWAYS, IF_CONSTANT,
 *      IF_SHEAR_RATE; NO_RANGE: none)
 *   KE(..., key, type, names, default, doc)  one of the names, held as `type` (an enum of scene.h,
 *      int or unsigned)
 *   KU(..., key, default, doc)  an unsigned   KS(..., key, min, max, default, doc)  a string (char *)
 *   KV(..., key, n, default, doc)  n doubles
 *   KL(..., key, entry struct, entry, max, doc)  a list of mappings (a pointer and key_count), each
 *      entry's keys in ENTRY(entry, struct, Name) ... END_ENTRY(entry, struct), rows EKF, EKE, EKU,
 *      EKS, EKV (no default: zero, and no range: the checks of scene_check.c check_wall and
 *      check_region)
 * A default is YAML text, NULL for a required key or one without a default.
 * The doc is the key's one description: units, default, meaning.
 * A new key is one row here: its member in the section's struct follows
 * (scene.h; the members that are not keys are there, SCENE_NOT_KEYS_). */
/* once per translation unit: the names of the enumerated keys (not for
 * scene.h, which reads the rows only: SCENE_KEYS_ROWS_ONLY) */
#if !defined(SPHSEG_SCENE_KEYS_NAMES) && !defined(SCENE_KEYS_ROWS_ONLY)
#define SPHSEG_SCENE_KEYS_NAMES
static const cyaml_strval_t geom_types[] = {
    {"shearbox", GEOM_SHEARBOX}, {"column", GEOM_COLUMN}, {"drum", GEOM_DRUM}, {"container", GEOM_CONTAINER}};
static const cyaml_strval_t kin_types[] = {
    {"rest", KIN_REST}, {"oscillatory_shear", KIN_OSCILLATORY_SHEAR}, {"computed", KIN_COMPUTED}};
static const cyaml_strval_t slips[] = {{"no_slip", SLIP_NO}, {"free_slip", SLIP_FREE}, {"coulomb", SLIP_COULOMB}};
static const cyaml_strval_t end_slips[] = {
    {"side", SLIP_AS_SIDE}, {"no_slip", SLIP_NO}, {"free_slip", SLIP_FREE}, {"coulomb", SLIP_COULOMB}};
static const cyaml_strval_t coulomb_forces[] = {{"dummies", COULOMB_DUMMIES}, {"particles", COULOMB_PARTICLES}};
static const cyaml_strval_t rot_dirs[] = {{"clockwise", ROT_CLOCKWISE},
                                          {"counterclockwise", ROT_COUNTERCLOCKWISE}};
static const cyaml_strval_t init_stresses[] = {{"zero", INIT_STRESS_ZERO},
                                               {"geostatic", INIT_STRESS_GEOSTATIC}};
static const cyaml_strval_t seg_fluxes[] = {{"symmetric", SEG_FLUX_SYMMETRIC},
                                            {"asymmetric", SEG_FLUX_ASYMMETRIC}};
static const cyaml_strval_t seg_models[] = {{"constant", SEG_MODEL_CONSTANT},
                                            {"shear_rate", SEG_MODEL_SHEAR_RATE}};
static const cyaml_strval_t seg_schemes[] = {
    {"paper", SEG_SCHEME_PAPER}, {"direct", SEG_SCHEME_DIRECT}, {"conservative", SEG_SCHEME_CONSERVATIVE}};
static const cyaml_strval_t seg_limiters[] = {{"none", SEG_LIMITER_NONE}, {"donor", SEG_LIMITER_DONOR}};
static const cyaml_strval_t seg_gdots[] = {{"total", SEG_GDOT_TOTAL}, {"yielded", SEG_GDOT_YIELDED}};
static const cyaml_strval_t flow_shiftings[] = {{"off", SHIFT_OFF}, {"fickian", SHIFT_FICKIAN}};
static const cyaml_strval_t flow_shift_rules[] = {{"none", SHIFT_SURFACE_NONE},
                                                  {"tangential", SHIFT_SURFACE_TANGENTIAL},
                                                  {"fade", SHIFT_SURFACE_FADE}};
static const cyaml_strval_t flow_backgrounds[] = {{"momentum", FLOW_BACKGROUND_MOMENTUM},
                                                   {"excluded", FLOW_BACKGROUND_EXCLUDED}};
static const cyaml_strval_t on_off[] = {{"off", 0}, {"on", 1}};
static const cyaml_strval_t fill_bys[] = {{"lattice", FILL_LATTICE}, {"area", FILL_AREA}};
static const cyaml_strval_t run_presets[] = {
    {"none", PRESET_NONE}, {"paper", PRESET_PAPER}, {"converged", PRESET_CONVERGED}, {"fast", PRESET_FAST}};
static const cyaml_strval_t part_methods[] = {{"slabs", PART_SLABS}, {"metis", PART_METIS}};
static const cyaml_strval_t periodic_axes[] = {
    {"none", PERIODIC_NONE}, {"x", PERIODIC_X}, {"y", PERIODIC_Y}, {"xy", PERIODIC_XY}, {"z", PERIODIC_Z},
    {"xz", PERIODIC_XZ}, {"yz", PERIODIC_YZ}, {"xyz", PERIODIC_XYZ}};
static const cyaml_strval_t mat_models[] = {{"granular", MAT_GRANULAR}, {"newtonian", MAT_NEWTONIAN}};
static const cyaml_strval_t flow_stabs[] = {
    {"monaghan", STAB_MONAGHAN}, {"riemann", STAB_RIEMANN}, {"delta", STAB_DELTA}};
static const cyaml_strval_t flow_filters[] = {{"shepard", FLOW_FILTER_SHEPARD}, {"mls", FLOW_FILTER_MLS}};
static const cyaml_strval_t mat_yields[] = {{"drucker_prager", YIELD_DRUCKER_PRAGER}, {"mu_I", YIELD_MU_I}};
static const cyaml_strval_t mat_mu_laws[] = {{"regularized", MAT_MU_REGULARIZED}, {"partial", MAT_MU_PARTIAL}};
static const cyaml_strval_t run_integrators[] = {{"predictor_corrector", INTEGRATOR_PREDICTOR_CORRECTOR},
                                                  {"leapfrog", INTEGRATOR_LEAPFROG}};
static const cyaml_strval_t slab_axes[] = {{"auto", AXIS_AUTO}, {"x", AXIS_X}, {"y", AXIS_Y}, {"z", AXIS_Z}};

static const cyaml_strval_t cwall_shapes[] = {
    {"segment", CWALL_SEGMENT}, {"cylinder", CWALL_CYLINDER}, {"ends", CWALL_ENDS}};
static const cyaml_strval_t cwall_motions[] = {
    {"fixed", CWALL_FIXED}, {"translating", CWALL_TRANSLATING}, {"turning", CWALL_TURNING}};
static const cyaml_strval_t cwall_sides[] = {{"inside", CWALL_INSIDE}, {"outside", CWALL_OUTSIDE}};
static const cyaml_strval_t region_shapes[] = {
    {"box", REGION_BOX}, {"sector", REGION_SECTOR}, {"fill", REGION_FILL}, {"column", REGION_COLUMN}};
static const cyaml_strval_t dem_couplings[] = {{"one_way", DEM_ONE_WAY}, {"two_way", DEM_TWO_WAY}};
static const cyaml_strval_t dem_places[] = {{"single", DEM_SINGLE}, {"block", DEM_BLOCK}};
static const cyaml_strval_t dem_motions[] = {{"free", DEM_FREE}, {"rigid", DEM_RIGID}, {"fixed", DEM_FIXED}};
enum { ALWAYS, IF_CONSTANT, IF_SHEAR_RATE, NO_RANGE }; /* which Segregation:model checks a range */
enum { CLOSED = 0, LO_OPEN = 1, HI_OPEN = 2 };          /* bound kinds, ORed */
#endif

ENTRY(cwall, scene_wall, "Container:walls")
    EKS("Container:walls", scene_wall, name, 1, 32,
       "for the log and the snapshot header Walls; default wallK (K its place in the list)")
    EKE("Container:walls", scene_wall, shape, enum cwall_shape, cwall_shapes,
       "segment | cylinder | ends (3D: the end walls z = 0 and z = depth, which take this entry's slip and motion; without one they are fixed and slip as Walls:side_slip); default segment")
    EKV("Container:walls", scene_wall, from, 2,
       "segment: its ends (x, y), m; the material lies on its left going from -> to, so a closed container lists its walls counter-clockwise")
    EKV("Container:walls", scene_wall, to, 2,
       "segment: its ends (x, y), m; the material lies on its left going from -> to, so a closed container lists its walls counter-clockwise")
    EKV("Container:walls", scene_wall, centre, 2,
       "cylinder: its axis (along z) at (x, y), m; ends turning: the axis they turn about")
    EKF("Container:walls", scene_wall, radius,
       "cylinder: radius, m")
    EKE("Container:walls", scene_wall, material, enum cwall_side, cwall_sides,
       "cylinder: inside (a drum) | outside (a post: its dummies are nl rings inside its radius); default inside")
    EKE("Container:walls", scene_wall, slip, enum wall_slip, slips,
       "no_slip (4.1) | free_slip (4.2) | coulomb (no slip until the wall's shear traction reaches Walls:mu_w times "
       "its normal stress, then sliding at that traction); default no_slip")
    EKE("Container:walls", scene_wall, motion, enum cwall_motion, cwall_motions,
       "fixed | translating | turning (a cylinder, or the ends, about the axis along z through centre); default fixed")
    EKV("Container:walls", scene_wall, velocity, 3,
       "translating: m/s; default [0, 0, 0]")
    EKF("Container:walls", scene_wall, rpm,
       "turning: rev/min, >= 0")
    EKE("Container:walls", scene_wall, direction, enum rot_dir, rot_dirs,
       "turning: clockwise | counterclockwise (seen with y up); default clockwise")
    EKF("Container:walls", scene_wall, open_at,
       "s, >= 0: the wall is a gate, removed at this time; absent: it stays")
    EKU("Container:walls", scene_wall, priority,
       "a lattice site behind two walls is a dummy of the one of higher priority, else of the one it lies further behind (a box's base: 1, keeping its corners); default 0; a gate's are taken last")
END_ENTRY(cwall, scene_wall)
/* An entry of Container:regions: where the material is at the start and its
 * C. Regions must not overlap and must lie inside the walls. */
ENTRY(region, scene_region, "Container:regions")
    EKE("Container:regions", scene_region, shape, enum region_shape, region_shapes,
       "box | sector | fill | column (3D: an upright circular column, its axis along y through centre = (x, z), radius r_out, from floor (default 0) up to level); default box")
    EKV("Container:regions", scene_region, lo, 2,
       "box: lower-left and upper-right corners (x, y), m")
    EKV("Container:regions", scene_region, hi, 2,
       "box: lower-left and upper-right corners (x, y), m")
    EKV("Container:regions", scene_region, centre, 2,
       "sector: centre (x, y), m; column: its axis at (x, z), m")
    EKF("Container:regions", scene_region, r_in,
       "sector: radii, m, 0 <= r_in < r_out; column: r_out its radius")
    EKF("Container:regions", scene_region, r_out,
       "sector: radii, m, 0 <= r_in < r_out; column: r_out its radius")
    EKF("Container:regions", scene_region, from_deg,
       "sector: counter-clockwise from from_deg to to_deg, degrees from +x")
    EKF("Container:regions", scene_region, to_deg,
       "sector: counter-clockwise from from_deg to to_deg, degrees from +x")
    EKF("Container:regions", scene_region, level,
       "fill: everything inside the walls below y = level, m; column: its top")
    EKF("Container:regions", scene_region, floor,
       "fill, column: and at or above y = floor, m; absent: no lower bound")
    EKF("Container:regions", scene_region, C,
       "initial small-grain concentration, [0, 1]; default 0")
END_ENTRY(region, scene_region)
SECTION("Run", run, scene_run)
    KF("Run", run, scene_run, t_end, REQ, NULL, 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "s, required")
    KF("Run", run, scene_run, cfl_diffusion, OPT, "0.1", 0, 1, LO_OPEN, ALWAYS,
      "dt <= cfl_diffusion h^2 / D_max; default 0.1, stable < 1/7")
    KF("Run", run, scene_run, cfl_segregation, OPT, "0.2", 0, 1, LO_OPEN, ALWAYS,
      "dt <= cfl_segregation h / max|d(VF)/dC|; default 0.2")
    KF("Run", run, scene_run, cfl_kinematic, OPT, "1", 0, 1, LO_OPEN, ALWAYS,
      "dt <= cfl_kinematic h / |u|_max; default 1 (time resolution of the moving geometry, not stability)")
    KF("Run", run, scene_run, cfl_flow, OPT, "0.1", 0, 10, LO_OPEN, ALWAYS,
      "chi_CFL of (3.19): dt <= chi min(sqrt(h/a_max), h/c_s); default 0.1")
    KE("Run", run, scene_run, integrator, enum run_integrator, run_integrators, "predictor_corrector",
      "predictor_corrector (default: the paper's midpoint rule 3.17-3.18, two rate evaluations a step) | leapfrog"
      " (its predictor takes the last step's corrector rates: one evaluation a step); docs/method.md \"Time integration\"")
    KF("Run", run, scene_run, dt_max, OPT, "1e30", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "s, upper bound on dt; default 1e30 (none)")
    KF("Run", run, scene_run, progress_s, OPT, "10", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "wall seconds between progress lines; default 10")
    KU("Run", run, scene_run, max_steps, "0",
      "stop after this many steps (writing a last snapshot); 0 = no limit (default)")
    KF("Run", run, scene_run, max_wall_time, OPT, "0", 0, INFINITY, HI_OPEN, ALWAYS,
      "wall s: write a checkpoint and stop (exit 0) before the next step would pass it (src/output/checkpoint.h); default 0 = no limit")
    KF("Run", run, scene_run, list_skin, OPT, "0.1", 0, 1, LO_OPEN, ALWAYS,
      "Verlet skin of the neighbour lists, in units of h: a list reaches 2h + skin and is rebuilt "
      "once a particle may have moved skin/2; a larger skin means fewer rebuilds (each an exchange on several "
      "ranks) and longer lists (0.1 was the fastest on one GPU and on two: docs/performance.md); at "
      "most 1 (ghosts are 3 cells of 2h "
      "deep); on the GPU results differ at round-off only; the CPU backend's list gives the same bits for any skin "
      "(on several ranks its builds are exchanges, ghosts kept in between; with periodic axes or DEM grains it is "
      "built at every stage); default 0.1")
    KS("Run", run, scene_run, backend, 0, CYAML_UNLIMITED, "auto",
      "\"auto\" (default: gpu when built with CUDA and a device is present) | \"cpu\" | \"gpu\"")
    KE("Run", run, scene_run, preset, enum run_preset, run_presets, "none",
      "a named group of keys, set as if given with -P before the user's own -P (which win over it):"
      " none (default) | paper (the paper's method, docs/method.md) | converged (the drum scenes' flow at"
      " Material:E=1e5, Run:cfl_flow=0.2) | fast (the same at Material:E=3e4); docs/guide.md \"Presets\"")
END_SECTION(run)
SECTION("Geometry", geometry, scene_geometry)
    KE("Geometry", geometry, scene_geometry, type, enum geom_type, geom_types, "shearbox",
      "shearbox | column | drum | container (the walls and regions of the Container section); default shearbox")
    KU("Geometry", geometry, scene_geometry, dim, "2",
      "2, or 3 for the column, the drum and a container; default 2")
    KF("Geometry", geometry, scene_geometry, dr, REQ, NULL, 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "initial particle spacing, m, required")
    KF("Geometry", geometry, scene_geometry, h_factor, OPT, "1.5", 1, 3, CLOSED, ALWAYS,
      "h = h_factor dr; default 1.5 (lattice moments within 0.5 %, tests/test_kernel.c)")
    KF("Geometry", geometry, scene_geometry, height, OPT, "0.087", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "material height H, m; a container periodic along y: the period; default 0.087")
    KF("Geometry", geometry, scene_geometry, width, OPT, "0.037", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "box width, m; a container periodic along x: the period; default 0.037")
    KF("Geometry", geometry, scene_geometry, depth, OPT, "0.037", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "3D column and container: extent along z, m; default 0.037")
    KF("Geometry", geometry, scene_geometry, radius, OPT, "0.035", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "drum: inner radius R, m; default 0.035")
    KF("Geometry", geometry, scene_geometry, length, OPT, "0.02", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "3D drum: length along the axis (z) between the end walls, m; default 0.02")
    KF("Geometry", geometry, scene_geometry, fill, OPT, "0.42", 0, 1, LO_OPEN | HI_OPEN, ALWAYS,
      "drum: filling level R_f = (H + R)/2R (paper §6), in (0,1); default 0.42")
    KE("Geometry", geometry, scene_geometry, fill_by, int, fill_bys, "lattice",
      "drum: how the material meets Geometry:fill: lattice (the square lattice's points r <= R - dr/2 below y = H: its"
      " area N dr^2 falls short of the segment's by about the wall's length times dr/2 and jumps by a row with dr,"
      " 0.947, 0.988, 0.997 of it at dr 1, 0.5, 0.25 mm in the EV drum) | area (the lattice's rows moved with the fill"
      " line, which is raised until N dr^2 is the area of the segment of radius R below H, within a few particles;"
      " docs/validation.md \"The segregation under refinement\"); default lattice")
    KE("Geometry", geometry, scene_geometry, periodic, unsigned, periodic_axes, "none",
       "column or container: the axes without walls, where the material continues periodically: none | x | y | xy | z | xz | yz | xyz"
       " (y and z need a container, z needs dim 3); the period is Geometry:width along x, :height along y, :depth along z, from 0,"
       " at least 6 supports 2h (a scene with DEM grains: 4 on the CPU backend, 6 on the GPU, and 2 DEM:d); walls and regions must lie"
       " within it; a 3D container periodic in z has no end walls; one with DEM grains periodic along xyz may have no wall; default none")
    KE("Geometry", geometry, scene_geometry, lid, int, on_off, "off",
      "column: on | off: a rigid wall over the material at y = height (a channel between the base and the lid, with the base's slip); default off")
    KF("Geometry", geometry, scene_geometry, runout, OPT, "0", 0, INFINITY, HI_OPEN, ALWAYS,
       "column, m: the floor continues this far past the material (x from width to width + runout), closed by a side wall there;"
       " the material is held at x = width by a gate until Walls:gate_open; default 0 (no runout, no gate)")
    KF("Geometry", geometry, scene_geometry, outlet_width, OPT, "0", 0, INFINITY, HI_OPEN, ALWAYS,
      "column: an opening of this width (m) in the base, centred on x = width/2 (3D: a square opening, also centred on z = depth/2), through which material falls; default 0 (none)")
END_SECTION(geometry)
SECTION("Kinematics", kinematics, scene_kinematics)
    KE("Kinematics", kinematics, scene_kinematics, velocity, enum kin_type, kin_types, "oscillatory_shear",
      "rest | oscillatory_shear | computed; default oscillatory_shear")
    KF("Kinematics", kinematics, scene_kinematics, gamma0, OPT, "0.5773502691896257", 0, INFINITY, HI_OPEN, ALWAYS,
      "shear amplitude (tan of max wall angle); default tan 30 deg")
    KF("Kinematics", kinematics, scene_kinematics, period, OPT, "13", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "T, s; default 13")
END_SECTION(kinematics)
/* The grains: their sizes, read by the flow's mu(I) (d_avg in I, eq. 2.13)
 * and by the segregation (V, D of eq. 2.7), so that a flow-only run needs
 * no segregation key. Until this section existed they were
 * Segregation:d_small and :d_large, which are still read (with a warning). */
SECTION("Grains", grains, scene_grains)
    KF("Grains", grains, scene_grains, d_small, OPT, "0.004", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "d^S, m; default 0.004")
    KF("Grains", grains, scene_grains, d_large, OPT, "0.008", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "d^L, m; default 0.008; > d_small")
END_SECTION(grains)
SECTION("Segregation", segregation, scene_segregation)
    KE("Segregation", segregation, scene_segregation, enabled, int, on_off, "on",
      "on | off: solve the concentration equation; default on")
    KE("Segregation", segregation, scene_segregation, flux, enum seg_flux, seg_fluxes, "symmetric",
      "symmetric (2.8) | asymmetric (2.9); default symmetric")
    KF("Segregation", segregation, scene_segregation, A, OPT, "1.6", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "eq. (2.9); default 1.6")
    KF("Segregation", segregation, scene_segregation, kappa, OPT, "0.89", 0, 1, HI_OPEN, ALWAYS,
      "eq. (2.9), in [0,1); default 0.89")
    KE("Segregation", segregation, scene_segregation, model, enum seg_model, seg_models, "constant",
      "constant | shear_rate (2.7); default constant")
    KF("Segregation", segregation, scene_segregation, V, OPT, NULL, 0, INFINITY, HI_OPEN, IF_CONSTANT,
      "m/s, constant model")
    KF("Segregation", segregation, scene_segregation, D, OPT, NULL, 0, INFINITY, LO_OPEN | HI_OPEN, IF_CONSTANT,
      "m^2/s, constant model")
    KF("Segregation", segregation, scene_segregation, chi_V, OPT, "0.11", 0, INFINITY, HI_OPEN, IF_SHEAR_RATE,
      "eq. (2.7b), shear_rate model; default 0.11")
    KF("Segregation", segregation, scene_segregation, chi_D, OPT, "0.0307", 0, INFINITY, LO_OPEN | HI_OPEN, IF_SHEAR_RATE,
      "eq. (2.7a), shear_rate model; default 0.0307")
    KE("Segregation", segregation, scene_segregation, scheme, enum seg_scheme, seg_schemes, "conservative",
      "paper | direct | conservative; default conservative")
    KE("Segregation", segregation, scene_segregation, renormalize, int, on_off, "on",
      "on | off: conservative scheme's symmetric kernel renormalisation (restores consistency where the support is cut); default on")
    KE("Segregation", segregation, scene_segregation, limiter, enum seg_limiter, seg_limiters, "donor",
       "none | donor: conservative scheme only. donor caps each pair's segregation flux Q_i + Q_j at 2 A (V_i + V_j) min(C_u, 1 - C_d)"
       " (u gives small grains, d takes them) and bounds dt with a wave speed of at least A V, so C stays in [0, 1];"
       " none leaves the flux uncapped (C may leave [0, 1]); default donor (docs/method.md, \"Bounded C\")")
    KE("Segregation", segregation, scene_segregation, shear_rate, enum seg_gdot, seg_gdots, "total",
       "total | yielded: the shear rate of eq. (2.7)'s V and D; total, the whole strain rate's (the paper's); yielded, that"
       " shear rate where the stress is on or past the static yield cone (sqrt(J2) >= k(mu_s) p, or p <= 0) and 0 inside it,"
       " where the bed deforms elastically and does not flow; default total (docs/seg_refine.md)")
    KF("Segregation", segregation, scene_segregation, drift_tol, OPT, "1e-3", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "relative drift of sum C_i V_i that triggers a warning; default 1e-3")
    KS("Segregation", segregation, scene_segregation, every, 0, CYAML_UNLIMITED, "auto",
      "auto | K >= 1: with computed flow, C advances once every K flow steps (integrate.c); default auto")
END_SECTION(segregation)
SECTION("Initial", initial, scene_initial)
    KF("Initial", initial, scene_initial, C_below, OPT, "0", 0, 1, CLOSED, ALWAYS,
      "C for y/H <= split; default 0")
    KF("Initial", initial, scene_initial, C_above, OPT, "1", 0, 1, CLOSED, ALWAYS,
      "C for y/H > split; default 1")
    KF("Initial", initial, scene_initial, split, OPT, "0.5", 0, 1, CLOSED, ALWAYS,
      "split height as a fraction of H; default 0.5")
    KE("Initial", initial, scene_initial, stress, enum init_stress, init_stresses, "geostatic",
      "zero | geostatic (sigma_yy = -rho g depth, sigma_xx = sigma_zz = K0 sigma_yy, K0 = nu/(1-nu), then returned to the yield cone); default geostatic")
    KF("Initial", initial, scene_initial, pressure, OPT, "0", 0, INFINITY, HI_OPEN, ALWAYS,
       "Pa, >= 0: a uniform pressure added to the material's initial stress (a Newtonian fluid's background pressure, which keeps"
       " its pressure above the tension cut-off); default 0")
END_SECTION(initial)
SECTION("Output", output, scene_output)
    KF("Output", output, scene_output, dt, REQ, NULL, 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "s between snapshots, required")
    KF("Output", output, scene_output, diag_dt, OPT, NULL, 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "s between diagnostics rows; default dt/20")
    KE("Output", output, scene_output, snapshots, int, on_off, "on",
      "on | off: write snapshot files (off: benchmarks, diagnostics only); default on")
    KF("Output", output, scene_output, checkpoint_dt, OPT, "0", 0, INFINITY, HI_OPEN, ALWAYS,
      "s of simulated time between checkpoints (OUTDIR/checkpoint.h5); default 0 = none")
END_SECTION(output)
SECTION("Physics", physics, scene_physics)
    KV("Physics", physics, scene_physics, gravity, 3, "[0, -9.81, 0]",
      "m/s^2; default (0, -9.81, 0); 2D lives in the x-y plane")
    KF("Physics", physics, scene_physics, rho, OPT, "1500", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "bulk density, kg/m^3 (eqs. 2.3-2.4; paper Table 1); default 1500")
END_SECTION(physics)
/* The mu(I) elastoplastic material (paper §2.3, Table 1), or a Newtonian
 * fluid; computed flow only. */
SECTION("Material", material, scene_material)
    KE("Material", material, scene_material, model, enum mat_model, mat_models, "granular",
      "granular | newtonian; default granular")
    KE("Material", material, scene_material, yield, enum stress_yield, mat_yields, "drucker_prager",
       "granular: the yield surface sqrt(J2) = k p: drucker_prager (the paper's k = k_mu(mu(I)) = 3 mu / sqrt(9 + 12 mu^2), eq. 2.12)"
       " | mu_I (k = mu(I), Jop, Forterre & Pouliquen 2006); default drucker_prager (docs/method.md)")
    KF("Material", material, scene_material, eta, OPT, "0.001", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "newtonian: dynamic viscosity, Pa s; default 1e-3")
    KF("Material", material, scene_material, E, OPT, "1e7", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "Young's modulus, Pa; default 1e7 (newtonian: with nu, the bulk modulus K = E / (3 (1 - 2 nu)) and the sound speed sqrt(K / rho))")
    KF("Material", material, scene_material, nu, OPT, "0.3", 0, 0.5, HI_OPEN, ALWAYS,
      "Poisson's ratio, [0, 0.5); default 0.3")
    KF("Material", material, scene_material, rho_s, OPT, "2500", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "intrinsic grain density, kg/m^3; default 2500")
    KF("Material", material, scene_material, mu_s, OPT, "0.382", 0, INFINITY, HI_OPEN, ALWAYS,
      "static friction; default 0.382")
    KF("Material", material, scene_material, mu_d, OPT, "0.682", 0, INFINITY, HI_OPEN, ALWAYS,
      "dynamic friction, >= mu_s; default 0.682")
    KF("Material", material, scene_material, I0, OPT, "0.279", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "reference inertial number; default 0.279")
    KF("Material", material, scene_material, lambda, OPT, "0.001", 0, INFINITY, HI_OPEN, ALWAYS,
      "regularization of (2.14), 1/s; default 0.001")
    KE("Material", material, scene_material, mu_law, enum mat_mu_law, mat_mu_laws, "regularized",
       "granular: mu(I) at low I: regularized (the paper's eq. 2.14, a static yield) | partial (Barker & Gray 2017: below the lower"
       " edge I_N1 of the well-posed window, mu = sqrt(Material:pr_alpha / ln(A / I)), continuous at I_N1; no static yield);"
       " default regularized (docs/method.md, \"The yield surface and the friction law\")")
    KF("Material", material, scene_material, pr_alpha, OPT, "1.9", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "Material:mu_law partial: alpha; default 1.9 (Barker & Gray 2017)")
END_SECTION(material)
/* Momentum and stress solver options; computed flow only. */
SECTION("Flow", flow, scene_flow)
    KE("Flow", flow, scene_flow, stabilization, enum flow_stab, flow_stabs, "monaghan",
       "what damps the acoustic noise: monaghan (the paper's artificial viscosity 3.10, Flow:alpha_av) | riemann (the"
       " low-dissipation Riemann solver of Zhang, Hu & Adams 2017, Flow:riemann_eta) | delta (delta-SPH pressure diffusion"
       " 2 Flow:delta h c_s, Antuono et al. 2010); default monaghan (docs/method.md, \"Stabilisation and the drum scenes' flow\")")
    KF("Flow", flow, scene_flow, alpha_av, OPT, "0.1", 0, INFINITY, HI_OPEN, ALWAYS,
      "artificial viscosity coefficient (3.10), Flow:stabilization monaghan; default 0.1; 0 = off")
    KF("Flow", flow, scene_flow, riemann_eta, OPT, "3", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "Flow:stabilization riemann: the limiter's eta in beta = min(eta dU, c_s); default 3 (Zhang, Hu & Adams 2017)")
    KF("Flow", flow, scene_flow, bed_damping, OPT, "0", 0, INFINITY, HI_OPEN, ALWAYS,
       "Flow:stabilization riemann, -: Monaghan's (3.10) with this alpha on material pairs below the yield surface only, weighted by"
       " 1 - max(q_i, q_j), q = sqrt(J2) / (k(mu_s) p); damps the quasi-static bed's elastic noise; default 0 = off (docs/method.md)")
    KE("Flow", flow, scene_flow, riemann_diffusion, unsigned, on_off, "off",
       "Flow:stabilization riemann: on | off: also diffuse the pressure at the Riemann solver's rate K / (rho c_s), less the"
       " hydrostatic part; default off (it compacts a free surface: docs/method.md)")
    KF("Flow", flow, scene_flow, delta, OPT, "0.1", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "Flow:stabilization delta: the diffusion coefficient delta of delta-SPH; default 0.1 (Antuono et al. 2010; Marrone et al. 2011)")
    KU("Flow", flow, scene_flow, shepard_every, "30",
       "Shepard filter (3.12) every N steps; default 30; 0 = off; keep N Run:cfl_flow >= 3 acoustic times h / c_s"
       " (docs/performance.md, \"Stiffness, step and filter\")")
    KE("Flow", flow, scene_flow, stress_filter, enum flow_filter, flow_filters, "shepard",
       "the stress filter of Flow:shepard_every: shepard (the paper's 3.12, the kernel average of the material neighbours' stresses)"
       " | mls (its first-order moving-least-squares form, Colagrossi & Landrini 2003, exact for a linear stress where the support"
       " is cut); default shepard (docs/method.md)")
    KE("Flow", flow, scene_flow, gradient_correction, unsigned, on_off, "off",
       "on | off: the corrected kernel gradient B_i grad W_ij, B_i = M_i^-1, M_i = sum_j V_j x_ji (x) grad_i W_ij (Randles &"
       " Libersky 1996; Bonet & Lok 1999), in the velocity gradient (3.14) and the stress divergence (3.9); blended toward I where"
       " the product of M_i's two smallest principal moments < Flow:gradient_correction_det; use with Flow:shifting fickian;"
       " default off, the paper's (docs/method.md)")
    KF("Flow", flow, scene_flow, gradient_correction_det, OPT, "0.6", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
       "Flow:gradient_correction on, -: below this d_i, the product of M_i's two smallest principal moments (det M_i in 2D,"
       " det M_i / its largest eigenvalue in 3D, so a 3D state uniform along z blends as in 2D), the correction is blended"
       " toward the identity (w = d_i / this); d = 1 in the bulk, 0.37 in the top row of a flat free surface at h = 1.5 dr;"
       " default 0.6 (docs/method.md)")
    KF("Flow", flow, scene_flow, damping, OPT, "0", 0, INFINITY, HI_OPEN, ALWAYS,
      "velocity damping -zeta u added to (3.9), 1/s, for settling (dynamic relaxation); default 0")
    KF("Flow", flow, scene_flow, damping_until, OPT, "0", 0, INFINITY, HI_OPEN, ALWAYS,
      "damping acts while t < damping_until, s; default 0")
    KE("Flow", flow, scene_flow, shifting, enum shift_kind, flow_shiftings, "off",
       "particle shifting: off (the paper's) | fickian (Lind et al. 2012): each step a material particle moves by"
       " -A h |u| dt sum_j V_j (1 + 0.2 (W_ij/W(dr))^4) grad W_ij, not at a free surface (Flow:shift_surface), u and"
       " sigma carried by a Taylor step, C and volume unchanged; default off")
    KF("Flow", flow, scene_flow, shift_coeff, OPT, "2", 0, INFINITY, HI_OPEN, ALWAYS,
      "A of Flow:shifting fickian (D = A h |u| dt), -; Lind et al. (2012) take 2; default 2")
    KF("Flow", flow, scene_flow, shift_surface, OPT, "0.5", 0, 1, LO_OPEN, ALWAYS,
      "s of Flow:shifting fickian's free surface: a particle whose divergence of position div r is below d - s is"
      " at a free surface and not shifted, -; Lind et al. (2012) take 1/2 in 2D; a numerical parameter the drums'"
      " surface speed depends on (docs/drum3d.md); default 0.5")
    KE("Flow", flow, scene_flow, shift_surface_rule, enum shift_surface_rule, flow_shift_rules, "none",
       "what Flow:shifting fickian does at a free surface (Flow:shift_surface): none (not shifted) | tangential (the"
       " shift less its part along the surface normal n, n along sum_j V_j grad W_ij, as in Sun et al. 2017's delta+-SPH)"
       " | fade (no threshold, Flow:shift_surface unused: every particle keeps its shift's tangential part and a share"
       " w = 2 div r / d - 1 in [0, 1] of its normal part, 0 at a flat surface, where div r = d/2, 1 in a whole support;"
       " a study's: it mixes C at the surface, the drums' segregation index a quarter lower, docs/drum3d.md); default none")
    KE("Flow", flow, scene_flow, background_pressure, enum flow_background, flow_backgrounds, "momentum",
       "Newtonian fluid: its background pressure Initial:pressure acts in the momentum pair term (3.9) (momentum) | is left out"
       " of it (excluded; Adami, Hu & Adams 2013); the granular material ignores it; default momentum")
END_SECTION(flow)
/* Rigid walls by dummy particles (paper §4.1). */
SECTION("Walls", walls, scene_walls)
    KE("Walls", walls, scene_walls, slip, enum wall_slip, slips, "no_slip",
      "box base and drum wall: no_slip (4.1) | free_slip (4.2) | coulomb (Coulomb friction Walls:mu_w: no slip while "
      "the wall's shear traction is below mu_w times its normal stress, else sliding at that traction); default no_slip")
    KE("Walls", walls, scene_walls, side_slip, enum wall_slip, slips, "free_slip",
      "box side walls; default free_slip")
    KE("Walls", walls, scene_walls, end_slip, int, end_slips, "side",
      "3D box, column or container: the end walls z = 0 and z = depth (a quasi-2D channel's side walls), apart from "
      "the walls x = 0 and x = width: side (as Walls:side_slip) | no_slip | free_slip | coulomb; a container's entry "
      "of shape ends takes precedence; default side")
    KF("Walls", walls, scene_walls, mu_w, OPT, "0", 0, INFINITY, HI_OPEN, ALWAYS,
      "the wall friction coefficient (tan of the wall friction angle) of every wall whose slip is coulomb, -; >= 0, "
      "> 0 where a wall is coulomb; default 0")
    KE("Walls", walls, scene_walls, coulomb_force, enum coulomb_force, coulomb_forces, "dummies",
      "where a coulomb wall's friction acts: dummies (the dummy's traction limited to mu_w times its normal stress) | "
      "particles (besides that, each material particle's tangential force from the wall's dummies is replaced by mu_w "
      "times their normal force on it while it slides, or by what stops its slip: a stress-free layer, whose weight "
      "the dummies carry through the stabilisation's pair term, then meets the wall's friction; docs/method.md, "
      "\"Wall friction on the particles\"); default dummies")
    KF("Walls", walls, scene_walls, gate_open, OPT, "0", 0, INFINITY, HI_OPEN, ALWAYS,
      "s: the gate of a column with a runout (Geometry:runout) is removed at this time, >= 0; default 0 (at the start)")
    KF("Walls", walls, scene_walls, rpm, OPT, "0", 0, INFINITY, HI_OPEN, ALWAYS,
      "drum rotation speed, rev/min, >= 0; default 0")
    KE("Walls", walls, scene_walls, direction, enum rot_dir, rot_dirs, "clockwise",
      "clockwise | counterclockwise (seen with y up); default clockwise")
    KV("Walls", walls, scene_walls, velocity, 3, "[0, 0, 0]",
      "box walls (shear box excepted): prescribed translation velocity, m/s, of the whole container; default [0, 0, 0]")
END_SECTION(walls)
/* Multi-rank runs (mpi/halo.h): the slab decomposition and its balance. */
SECTION("Parallel", parallel, scene_parallel)
    KE("Parallel", parallel, scene_parallel, method, enum part_method, part_methods, "slabs",
      "slabs (default) | metis: METIS k-way parts of the coarse-cell graph")
    KE("Parallel", parallel, scene_parallel, axis, enum slab_axis, slab_axes, "auto",
      "auto (the longest extent of the particles) | x | y | z; default auto")
    KU("Parallel", parallel, scene_parallel, balance_every, "200",
      "steps between load-balance checks; 0 = never; default 200")
    KF("Parallel", parallel, scene_parallel, balance_threshold, OPT, "0.1", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "move the slab bounds when the slowest rank's compute time exceeds the mean by more than this fraction; default 0.1")
END_SECTION(parallel)
/* An outlet: material particles that fall below a horizontal plane leave the
 * run (run_guard.c run_drain); their count and sum C_i V_i go to
 * diagnostics.csv, and the conservation check counts them. */
SECTION("Outlet", outlet, scene_outlet)
    KE("Outlet", outlet, scene_outlet, enabled, int, on_off, "off",
      "on | off; default off")
    KF("Outlet", outlet, scene_outlet, below, OPT, "0", 0, 0, 0, NO_RANGE,
      "the plane's height y, m; default 0")
END_SECTION(outlet)
/* A container described as data (Geometry:type container; scene.h, enum
 * cwall_shape and the rest): its walls and its material. */
SECTION("Container", container, scene_container)
    KL("Container", container, scene_container, walls, scene_wall, cwall_entry, SCENE_WALLS_MAX,
      "Geometry:type container: its walls, a list of segments and cylinders in the x-y plane (Container:walls:K keys below; inputs/hopper_2d.yml)")
    KL("Container", container, scene_container, regions, scene_region, region_entry, SCENE_REGIONS_MAX,
      "Geometry:type container: where the material starts, a list of boxes, sectors and fills, each with its C (Container:regions:K keys below)")
END_SECTION(container)
/* DEM grains in a Newtonian fluid (Markauskas et al. 2016; src/dem/dem.c,
 * src/physics/dem.h): present when d > 0. */
SECTION("DEM", dem, scene_dem)
    KF("DEM", dem, scene_dem, d, OPT, "0", 0, INFINITY, HI_OPEN, ALWAYS,
      "grain diameter, m; 0 (default): no grains. A scene with grains needs Material:model newtonian; it runs on any number of ranks on either backend")
    KF("DEM", dem, scene_dem, rho, OPT, "1200", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "grain density, kg/m^3; default 1200 (the DEM paper's block, §8)")
    KE("DEM", dem, scene_dem, coupling, enum dem_coupling, dem_couplings, "two_way",
      "one_way (the grains feel the fluid, eqs. 19-23; the fluid not the grains) | two_way (also the interaction source 14 and the fluid fraction 15-16 in the fluid's momentum); default two_way")
    KF("DEM", dem, scene_dem, kn, OPT, "1000", 0, INFINITY, LO_OPEN | HI_OPEN, ALWAYS,
      "normal contact stiffness, N/m; default 1000 (a numerical choice: the DEM step is t_c / 20)")
    KF("DEM", dem, scene_dem, kt, OPT, "0", 0, INFINITY, HI_OPEN, ALWAYS,
      "tangential contact stiffness, N/m; 0 (default): 2/7 kn, the ratio that gives the normal and tangential oscillations one period")
    KF("DEM", dem, scene_dem, e, OPT, "0.9", 0, 1, LO_OPEN, ALWAYS,
      "normal restitution coefficient (0, 1], which sets the normal damping; default 0.9")
    KF("DEM", dem, scene_dem, mu, OPT, "0.3", 0, INFINITY, HI_OPEN, ALWAYS,
      "Coulomb friction coefficient of a contact (grain-grain and grain-wall); default 0.3")
    KF("DEM", dem, scene_dem, t_damp, OPT, "0", 0, INFINITY, HI_OPEN, ALWAYS,
      "s: gravity on the grains grows over this time by eqs. (3)-(4); 0 (default): at once")
    KE("DEM", dem, scene_dem, placement, enum dem_place, dem_places, "single",
      "single (one grain at DEM:at) | block (a lattice of block_n grains, spacing block_spacing, from block_origin); default single")
    KV("DEM", dem, scene_dem, at, 3, "[0, 0, 0]",
      "single: the grain's centre (x, y, z), m")
    KV("DEM", dem, scene_dem, block_n, 3, "[1, 1, 1]",
      "block: grains along x, y, z (whole numbers >= 1; 1 along z in 2D)")
    KF("DEM", dem, scene_dem, block_spacing, OPT, "0", 0, INFINITY, HI_OPEN, ALWAYS,
      "block: distance between neighbouring grains' centres, m, >= d")
    KV("DEM", dem, scene_dem, block_origin, 3, "[0, 0, 0]",
      "block: the centre of its grain of lowest x, y, z, m")
    KE("DEM", dem, scene_dem, motion, enum dem_motion, dem_motions, "free",
      "free (each grain its own) | rigid (the grains move as one rigid body, translating and turning: the block "
      "of §8; across a periodic axis it translates only) | fixed (held in place: the porous block of §7); default free")
END_SECTION(dem)
