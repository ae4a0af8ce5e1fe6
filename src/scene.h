/* scene.h — the parameters of one run, loaded from a YAML scene file with
 * libcyaml (scene.c), overridden by -P Section:key=value, validated, and
 * echoed to OUTDIR/used_params.yml. Physical SI units throughout.
 * The key names are a contract (users and scripts rely on them). */
#ifndef SPHSEG_SCENE_H
#define SPHSEG_SCENE_H
#include <stddef.h>

enum seg_flux { SEG_FLUX_SYMMETRIC = 0, SEG_FLUX_ASYMMETRIC = 1 };
enum seg_model { SEG_MODEL_CONSTANT = 0, SEG_MODEL_SHEAR_RATE = 1 };
/* paper: eq. (2.10)/(3.13) with HCSR boundaries (§4.2) and C1 boundary
 * gradients (App. E); direct: eq. (2.5) with the same boundaries (App. A);
 * conservative: pairwise antisymmetric fluxes, no source terms. */
enum seg_scheme { SEG_SCHEME_PAPER = 0, SEG_SCHEME_DIRECT = 1, SEG_SCHEME_CONSERVATIVE = 2 };
/* none: the conservative scheme's central pair flux Q_i + Q_j as it is; donor:
 * capped by the donor's C and the receiver's room (seg_kern.h
 * seg_flux_donor), which keeps C in [0, 1]. */
enum seg_limiter { SEG_LIMITER_NONE = 0, SEG_LIMITER_DONOR = 1 };
enum flow_shifting { FLOW_SHIFT_OFF = 0, FLOW_SHIFT_FICKIAN = 1 }; /* = enum shift_kind, physics/shift.h */
enum flow_background { FLOW_BACKGROUND_MOMENTUM = 0, FLOW_BACKGROUND_EXCLUDED = 1 };
enum geom_type { GEOM_SHEARBOX = 0, GEOM_COLUMN = 1, GEOM_DRUM = 2, GEOM_CONTAINER = 3 };
/* Geometry:periodic, one bit per axis (bit d: axis d). */
enum periodic_axes {
    PERIODIC_NONE = 0, PERIODIC_X = 1, PERIODIC_Y = 2, PERIODIC_XY = 3, PERIODIC_Z = 4, PERIODIC_XZ = 5,
    PERIODIC_YZ = 6, PERIODIC_XYZ = 7
};
/* rest and oscillatory_shear prescribe the velocity (no momentum or stress
 * solved); computed solves the granular flow (momentum 3.9, stress 2.16). */
enum kin_type { KIN_REST = 0, KIN_OSCILLATORY_SHEAR = 1, KIN_COMPUTED = 2 };
enum wall_slip { SLIP_NO = 0, SLIP_FREE = 1 };
enum rot_dir { ROT_CLOCKWISE = 0, ROT_COUNTERCLOCKWISE = 1 };
enum init_stress { INIT_STRESS_ZERO = 0, INIT_STRESS_GEOSTATIC = 1 };
/* granular: the mu(I) elastoplastic material of the paper; newtonian: a weakly
 * compressible Newtonian fluid (pressure from the bulk modulus, viscous
 * momentum of Morris et al. 1997). */
enum mat_model { MAT_GRANULAR = 0, MAT_NEWTONIAN = 1 };
/* the granular material's yield surface: drucker_prager, the paper's cone
 * sqrt(J2) = k_mu(mu(I)) p (2.11-2.12); mu_I, the tensorial law |tau| =
 * sqrt(J2) = mu(I) p of Jop, Forterre & Pouliquen (2006) (physics/stress.h) */
enum mat_yield { MAT_YIELD_DRUCKER_PRAGER = 0, MAT_YIELD_MU_I = 1 };
/* Flow:stabilization: monaghan, the paper's artificial viscosity (3.10);
 * riemann, the low-dissipation Riemann solver of Zhang, Hu & Adams (2017);
 * delta, delta-SPH pressure diffusion alone (physics/momentum.h). The values
 * are the flow bodies' STAB_* (physics/flow.h). */
enum flow_stab { FLOW_STAB_MONAGHAN = 0, FLOW_STAB_RIEMANN = 1, FLOW_STAB_DELTA = 2 };

struct scene_run {
    double t_end;           /* s, required */
    double cfl_diffusion;   /* dt <= cfl_diffusion h^2 / D_max; default 0.1, stable < 1/7 */
    double cfl_segregation; /* dt <= cfl_segregation h / max|d(VF)/dC|; default 0.2 */
    double cfl_kinematic;   /* dt <= cfl_kinematic h / |u|_max; default 1 (time resolution of the moving geometry, not stability) */
    double cfl_flow;        /* chi_CFL of (3.19): dt <= chi min(sqrt(h/a_max), h/c_s); default 0.1 */
    double dt_max;          /* s, upper bound on dt; default 1e30 (none) */
    double progress_s;      /* wall seconds between progress lines; default 10 */
    unsigned max_steps;     /* stop after this many steps (writing a last snapshot); 0 = no limit (default) */
    double max_wall_time;   /* wall s: write a checkpoint and stop (exit 0) before the next step would pass
                             * it (src/checkpoint.h); default 0 = no limit */
    double list_skin;       /* GPU neighbour lists' Verlet skin, in units of h, (0, 1]; default 0.1 */
    char *backend;          /* "auto" (default: gpu when built with CUDA and a device is present) | "cpu" | "gpu" */
};

struct scene_geometry {
    enum geom_type type; /* shearbox | column | drum | container (the walls and regions of the Container
                          * section); default shearbox */
    unsigned dim;        /* 2, or 3 for the column, the drum and a container; default 2 */
    double dr;           /* initial particle spacing, m, required */
    double h_factor;     /* h = h_factor * dr; default 1.5 (lattice moments within 0.5 %, tests/test_kernel.c) */
    double height;       /* material height H, m; default 0.087 */
    double width;        /* box width, m; a container periodic along x: the period; default 0.037 */
    double depth;        /* 3D column and container: extent along z, m; default 0.037 */
    double radius;       /* drum: inner radius R, m; default 0.035 */
    double length;       /* 3D drum: length along the axis (z) between the end walls, m; default 0.02 */
    double fill;         /* drum: filling level R_f = (H + R)/2R (paper §6), in (0,1); default 0.42 */
    int lid;             /* column: on | off: a rigid wall over the material at y = height (a channel
                          * between the base and the lid, with the base's slip); default off */
    double runout;       /* column: the floor continues this far past the material (x from width to
                          * width + runout), closed by a side wall there; the material is held at
                          * x = width by a gate until Walls:gate_open; default 0 (no runout, no gate) */
    double outlet_width; /* column: an opening of this width (m) in the base, centred on x = width/2
                          * (3D: a square opening, also centred on z = depth/2), through which material
                          * falls; default 0 (none) */
    unsigned periodic;   /* column or container: the axes without walls, where the material continues periodically
                          * (enum periodic_axes: none | x | z | xz; the period is the width along x,
                          * the depth along z, from 0); default none */
};

struct scene_kinematics {
    enum kin_type velocity; /* rest | oscillatory_shear | computed; default oscillatory_shear */
    double gamma0;          /* shear amplitude (tan of max wall angle); default tan 30 deg */
    double period;          /* T, s; default 13 */
};

/* The grains: their sizes, read by the flow's mu(I) (d_avg in I, eq. 2.13)
 * and by the segregation (V, D of eq. 2.7), so that a flow-only run needs
 * no segregation key. Until this section existed they were
 * Segregation:d_small and :d_large, which are still read (with a warning). */
struct scene_grains {
    double d_small; /* d^S, m; default 0.004 */
    double d_large; /* d^L, m; default 0.008; > d_small */
};

struct scene_segregation {
    int enabled;            /* on | off: solve the concentration equation; default on */
    enum seg_flux flux;     /* symmetric (2.8) | asymmetric (2.9); default symmetric */
    double A;               /* eq. (2.9); default 1.6 */
    double kappa;           /* eq. (2.9), in [0,1); default 0.89 */
    enum seg_model model;   /* constant | shear_rate (2.7); default constant */
    double V;               /* m/s, constant model */
    double D;               /* m^2/s, constant model */
    double chi_V;           /* eq. (2.7b), shear_rate model; default 0.11 */
    double chi_D;           /* eq. (2.7a), shear_rate model; default 0.0307 */
    enum seg_scheme scheme; /* paper | direct | conservative; default conservative */
    int renormalize;        /* on | off: conservative scheme's symmetric kernel
                             * renormalisation (restores consistency where the
                             * support is cut); default on */
    enum seg_limiter limiter; /* none | donor: conservative scheme's bound on the
                               * pair segregation flux (keeps C in [0, 1]); default donor */
    double drift_tol;       /* relative drift of sum C_i V_i that triggers a warning; default 1e-3 */
    char *every;            /* auto | K >= 1: with computed flow, C advances once every K flow
                             * steps (integrate.c); default auto */
    unsigned every_k;       /* every as a number: K, or 0 for auto (set by the checks) */
};

struct scene_initial {
    double C_below; /* C for y/H <= split; default 0 */
    double C_above; /* C for y/H > split; default 1 */
    double split;   /* split height as a fraction of H; default 0.5 */
    enum init_stress stress; /* zero | geostatic (sigma_yy = -rho g depth, sigma_xx = sigma_zz
                              * = K0 sigma_yy, K0 = nu/(1-nu), then returned to the yield
                              * cone); default geostatic */
    double pressure;         /* Pa, >= 0: a uniform pressure added to that initial stress of the material
                              * (a Newtonian fluid's background pressure, which keeps its pressure above
                              * the tension cut-off where the flow lowers it); default 0 */
};

/* The mu(I) elastoplastic material (paper §2.3, Table 1), or a Newtonian
 * fluid; computed flow only. */
struct scene_material {
    enum mat_model model; /* granular | newtonian; default granular */
    enum mat_yield yield; /* granular: drucker_prager (the paper's k_mu cone, 2.12) | mu_I (sqrt(J2) =
                           * mu(I) p, Jop, Forterre & Pouliquen 2006); default drucker_prager */
    double eta;    /* newtonian: dynamic viscosity, Pa s; default 1e-3 */
    double E;      /* Young's modulus, Pa; default 1e7 (newtonian: with nu, the bulk modulus
                    * K = E / (3 (1 - 2 nu)) and the sound speed sqrt(K / rho)) */
    double nu;     /* Poisson's ratio, [0, 0.5); default 0.3 */
    double rho_s;  /* intrinsic grain density, kg/m^3; default 2500 */
    double mu_s;   /* static friction; default 0.382 */
    double mu_d;   /* dynamic friction, >= mu_s; default 0.682 */
    double I0;     /* reference inertial number; default 0.279 */
    double lambda; /* regularization of (2.14), 1/s; default 0.001 */
};

/* Momentum and stress solver options; computed flow only. */
struct scene_flow {
    enum flow_stab stabilization; /* monaghan (default, the paper's) | riemann | delta */
    double alpha_av;        /* artificial viscosity coefficient (3.10), monaghan; default 0.1; 0 = off */
    double riemann_eta;     /* riemann: the limiter's eta; default 3 (Zhang, Hu & Adams 2017) */
    unsigned riemann_diffusion; /* riemann: on | off (default): the Riemann pressure diffusion K / (rho c_s) */
    double delta;           /* delta: the diffusion coefficient; default 0.1 (Antuono et al. 2010) */
    unsigned shepard_every; /* Shepard filter (3.12) every N steps; default 30; 0 = off */
    double damping;         /* velocity damping -zeta u added to (3.9), 1/s, for settling
                             * (dynamic relaxation); default 0 */
    double damping_until;   /* damping acts while t < damping_until, s; default 0 */
    enum flow_shifting shifting; /* particle shifting: off (the paper's) | fickian (Lind et al. 2012) */
    double shift_coeff;     /* A of the shift D = A h |u| dt, -; default 2 */
    enum flow_background background_pressure; /* Newtonian fluid: Initial:pressure in (3.9) or left out of it */
};

/* Rigid walls by dummy particles (paper §4.1). */
struct scene_walls {
    enum wall_slip slip;      /* box base and drum wall: no_slip (4.1) | free_slip (4.2); default no_slip */
    enum wall_slip side_slip; /* box side walls; default free_slip */
    double rpm;               /* drum rotation speed, rev/min, >= 0; default 0 */
    enum rot_dir direction;   /* clockwise | counterclockwise (seen with y up); default clockwise */
    double gate_open;         /* s: the gate of a column with a runout (Geometry:runout) is removed at this
                               * time, >= 0; default 0 (at the start) */
    double velocity[3];       /* box walls (shear box excepted): prescribed translation velocity,
                               * m/s, of the whole container; default [0, 0, 0] */
};

struct scene_output {
    double dt;      /* s between snapshots, required */
    double diag_dt; /* s between diagnostics rows; default dt/20 */
    int snapshots;  /* on | off: write snapshot files (off: benchmarks, diagnostics only); default on */
    double checkpoint_dt; /* s of simulated time between checkpoints (OUTDIR/checkpoint.h5); default 0 = none */
};

struct scene_physics {
    double gravity[3]; /* m/s^2; default (0, -9.81, 0); 2D lives in the x-y plane */
    double rho;        /* bulk density, kg/m^3 (eqs. 2.3-2.4; paper Table 1); default 1500 */
};

/* Multi-rank runs (mpi/halo.h): the slab decomposition and its balance. */
enum slab_axis { AXIS_X = 0, AXIS_Y = 1, AXIS_Z = 2, AXIS_AUTO = 3 };
enum part_method { PART_SLABS = 0, PART_METIS = 1 };
struct scene_parallel {
    enum part_method method;  /* slabs (default) | metis: METIS k-way parts of the coarse-cell graph */
    enum slab_axis axis;      /* auto (the longest extent of the particles) | x | y | z; default auto */
    unsigned balance_every;   /* steps between load-balance checks; 0 = never; default 200 */
    double balance_threshold; /* move the slab bounds when the slowest rank's compute time exceeds
                               * the mean by more than this fraction; default 0.1 */
};

/* An outlet: material particles that fall below a horizontal plane leave the
 * run (run_guard.c run_drain); their count and sum C_i V_i go to
 * diagnostics.csv, and the conservation check counts them. */
struct scene_outlet {
    int enabled;  /* on | off; default off */
    double below; /* the plane's height y, m; default 0 */
};

/* A container described as data (Geometry:type container): its walls and
 * its material, in the x-y plane; a 3D container is that section extruded
 * along z over Geometry:depth, closed by end walls at z = 0 and z = depth
 * (setup_container.c). */
enum cwall_shape { CWALL_SEGMENT = 0, CWALL_CYLINDER = 1, CWALL_ENDS = 2 };
enum cwall_motion { CWALL_FIXED = 0, CWALL_TRANSLATING = 1, CWALL_TURNING = 2 };
/* a cylinder's material: inside it (a drum) or outside (a post, an obstacle) */
enum cwall_side { CWALL_INSIDE = 0, CWALL_OUTSIDE = 1 };
enum region_shape { REGION_BOX = 0, REGION_SECTOR = 1, REGION_FILL = 2, REGION_COLUMN = 3 };

/* One entry of Container:walls. */
struct scene_wall {
    char *name;               /* for the log and the snapshot header Walls; default wallK (K its place in the list) */
    enum cwall_shape shape;   /* segment | cylinder | ends (3D: the end walls z = 0 and z = depth, which
                               * take this entry's slip and motion; without one they are fixed and slip
                               * as Walls:side_slip); default segment */
    double from[2], to[2];    /* segment: its ends (x, y), m; the material lies on its left going from -> to,
                               * so a closed container lists its walls counter-clockwise */
    double centre[2];         /* cylinder: its axis (along z) at (x, y), m */
    double radius;            /* cylinder: radius, m */
    enum cwall_side material; /* cylinder: inside (a drum) | outside (a post: its dummies are nl rings
                               * inside its radius); default inside */
    enum wall_slip slip;      /* no_slip (4.1) | free_slip (4.2); default no_slip */
    enum cwall_motion motion; /* fixed | translating | turning (a cylinder, or the ends, about the axis
                               * along z through centre); default fixed */
    double velocity[3];       /* translating: m/s; default [0, 0, 0] */
    double rpm;               /* turning: rev/min, >= 0 */
    enum rot_dir direction;   /* turning: clockwise | counterclockwise (seen with y up); default clockwise */
    double open_at;           /* s, >= 0: the wall is a gate, removed at this time; absent: it stays */
    unsigned priority;        /* a lattice site behind two walls is a dummy of the one of higher priority,
                               * else of the one it lies further behind (a box's base: 1, keeping its
                               * corners); default 0; a gate's are taken last */
    int gate;                 /* set by the checks: open_at was given */
};

/* One entry of Container:regions: where the material is at the start and
 * its C. Regions must not overlap and must lie inside the walls. */
struct scene_region {
    enum region_shape shape; /* box | sector | fill | column (3D: an upright circular column, its axis along y
                              * through centre = (x, z), radius r_out, from floor (default 0) up to level);
                              * default box */
    double lo[2], hi[2];     /* box: lower-left and upper-right corners (x, y), m */
    double centre[2];        /* sector: centre (x, y), m; column: its axis at (x, z), m */
    double r_in, r_out;      /* sector: radii, m, 0 <= r_in < r_out; column: r_out its radius */
    double from_deg, to_deg; /* sector: counter-clockwise from from_deg to to_deg, degrees from +x */
    double level;            /* fill: everything inside the walls below y = level, m; column: its top */
    double floor;            /* fill, column: and at or above y = floor, m; absent: no lower bound */
    int has_floor;           /* set by the checks: floor was given */
    double C;                /* initial small-grain concentration, [0, 1]; default 0 */
};

struct scene_container {
    struct scene_wall *walls;
    unsigned walls_count;
    struct scene_region *regions;
    unsigned regions_count;
};

/* The most walls and regions a container lists (the end walls of 3D take
 * two of the wall primitives, WALL_PRIM_MAX). */
enum { SCENE_WALLS_MAX = 10, SCENE_REGIONS_MAX = 32 };

struct scene_keys; /* where each key was set (scene.c) */

struct scene {
    struct scene_run run;
    struct scene_geometry geometry;
    struct scene_kinematics kinematics;
    struct scene_grains grains;
    struct scene_segregation segregation;
    struct scene_initial initial;
    struct scene_output output;
    struct scene_physics physics;
    struct scene_material material;
    struct scene_flow flow;
    struct scene_walls walls;
    struct scene_parallel parallel;
    struct scene_outlet outlet;
    struct scene_container container;
    char *path; /* the scene file as given */
    char *text; /* the scene file's text, for snapshot headers */
    struct scene_keys *keys; /* for scene_key_line / scene_key_where */
};

/* The core of scene_load, which does not exit: load path, apply the overrides
 * over[0..n_over-1] ("Section:key=value", later ones win), fill defaults,
 * validate. Returns 0, or nonzero with *s zeroed and err holding one line
 * "FILE:LINE: Section:key: why" (no "sphseg: error: " prefix; "-P ARG" in
 * place of FILE:LINE for an override; "FILE: why" when the file cannot be
 * read). SCENE_ERRLEN bytes always suffice. */
enum { SCENE_ERRLEN = 1024 };
/* The shortest period of a periodic axis, in supports 2h: the ghost layers
 * (3 cells of 2h on the GPU) of both sides fit in it. */
enum { SCENE_PERIOD_SUPPORTS = 6 };
/* The largest Segregation:every a scene may give. */
enum { SCENE_EVERY_MAX = 1000000 };
int scene_parse(struct scene *s, const char *path, int n_over, char **over, char *err,
                size_t errlen);

/* Load, apply overrides ("Section:key=value"), fill defaults, validate.
 * On any bad input: prints one line "sphseg: error: FILE:LINE: Section:key: why"
 * (on rank 0) and exits with status 2, before anything is written.
 * Returns 0 on success. */
int scene_load(struct scene *s, const char *path, int n_over, char **over);

/* Write every parameter with the value used (defaults included) as YAML, with
 * the same section and key names; numbers read back exactly. Writes
 * file.tmp, then renames it to file. Returns 0, or -1 on failure. */
int scene_write_used(const struct scene *s, const char *file);

/* The used parameters as a YAML string (malloc'd), for snapshot headers. */
char *scene_used_text(const struct scene *s);

/* The default of "Section:key" as the YAML text of its row in the key table
 * (src/scene_keys.h), or NULL (no default, or no such key). */
const char *scene_key_default(const char *name);

/* For errors found after loading (DESIGN.md "Errors"): the 1-based line of
 * Section:key in the scene file; for a key not written there (a default, or
 * given only by -P) the line of its section, or 1. */
int scene_key_line(const struct scene *s, const char *section, const char *key);

/* Where Section:key was set, into buf[n]: "FILE:LINE" as above, or
 * "-P Section:key=value" when an override set it. Returns buf. Use as
 * input_error("%s: Geometry:dr: why", scene_key_where(s, "Geometry", "dr", b, sizeof b)). */
const char *scene_key_where(const struct scene *s, const char *section, const char *key, char *buf,
                            size_t n);

/* Every key of the scene file, documented from the key table
 * (src/scene_keys.h), as Markdown to f (sphseg --keys, docs/keys.md). */
#include <stdio.h>
void scene_keys_markdown(FILE *f);

/* Free what scene_load/scene_parse allocated; *s is zeroed. */
void scene_free(struct scene *s);

#endif
