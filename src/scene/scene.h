/* scene.h — the parameters of one run, loaded from a YAML scene file with
 * libcyaml (scene.c), overridden by -P Section:key=value, validated, and
 * echoed to OUTDIR/used_params.yml. Physical SI units throughout.
 * The key names are a contract (users and scripts rely on them). */
#ifndef SPHSEG_SCENE_H
#define SPHSEG_SCENE_H
#include <stddef.h>
#include "physics/options.h" /* the physics' choices: Flow:stabilization, Material:yield, ... */

enum seg_flux { SEG_FLUX_SYMMETRIC = 0, SEG_FLUX_ASYMMETRIC = 1 };
enum seg_model { SEG_MODEL_CONSTANT = 0, SEG_MODEL_SHEAR_RATE = 1 };
enum flow_background { FLOW_BACKGROUND_MOMENTUM = 0, FLOW_BACKGROUND_EXCLUDED = 1 };
enum geom_type { GEOM_SHEARBOX = 0, GEOM_COLUMN = 1, GEOM_DRUM = 2, GEOM_CONTAINER = 3 };
/* Geometry:fill_by (a drum's material, src/sim/setup.c): the lattice below the fill line, or the fill line
 * moved so that the material's area is the segment's. */
enum fill_by { FILL_LATTICE = 0, FILL_AREA = 1 };
/* Geometry:periodic, one bit per axis (bit d: axis d). */
enum periodic_axes {
    PERIODIC_NONE = 0, PERIODIC_X = 1, PERIODIC_Y = 2, PERIODIC_XY = 3, PERIODIC_Z = 4, PERIODIC_XZ = 5,
    PERIODIC_YZ = 6, PERIODIC_XYZ = 7
};
enum wall_slip { SLIP_NO = 0, SLIP_FREE = 1, SLIP_COULOMB = 2 };
/* Walls:end_slip side: the end walls z = 0 and z = depth slip as Walls:side_slip (scene_end_slip) */
#define SLIP_AS_SIDE 3 /* past enum wall_slip: the key writer reads enums as unsigned */
/* Walls:coulomb_force: where a Coulomb wall's friction acts: dummies, the
 * dummy's traction limited to mu_w times its normal stress (wall_coulomb);
 * particles, besides that, each material particle's tangential force from the
 * wall is mu_w times the wall's normal force on it, or what stops its slip
 * (flow_contact_team, physics/flow.h) */
enum coulomb_force { COULOMB_DUMMIES = 0, COULOMB_PARTICLES = 1 };
enum rot_dir { ROT_CLOCKWISE = 0, ROT_COUNTERCLOCKWISE = 1 };
enum init_stress { INIT_STRESS_ZERO = 0, INIT_STRESS_GEOSTATIC = 1 };
/* Run:preset: a named group of keys (scene_preset.c) */
enum run_preset { PRESET_NONE = 0, PRESET_PAPER = 1, PRESET_CONVERGED = 2, PRESET_FAST = 3 };
/* granular: the mu(I) elastoplastic material of the paper; newtonian: a weakly
 * compressible Newtonian fluid (pressure from the bulk modulus, viscous
 * momentum of Morris et al. 1997). */
enum mat_model { MAT_GRANULAR = 0, MAT_NEWTONIAN = 1 };
/* Material:mu_law, mu(I) at low I: regularized, the paper's (2.14) (mu -> mu_s
 * as gdot -> 0: a static yield); partial, the partial regularisation of
 * Barker & Gray (2017): sqrt(alpha / ln(A / I)) below the well-posed window's
 * lower edge I_N1 (no static yield: at gdot = 0 mu is the law's at the I of
 * gdot = lambda, physics/stress.h stress_mu) */
enum mat_mu_law { MAT_MU_REGULARIZED = 0, MAT_MU_PARTIAL = 1 };
/* Flow:stress_filter: shepard, the paper's zeroth-order kernel average (3.12);
 * mls, its first-order moving-least-squares form, exact for a linear stress
 * field where the support is cut (physics/flow.h flow_shepard_team). */
enum flow_filter { FLOW_FILTER_SHEPARD = 0, FLOW_FILTER_MLS = 1 };

/* Multi-rank runs (mpi/halo.h): Parallel:axis and :method. */
enum slab_axis { AXIS_X = 0, AXIS_Y = 1, AXIS_Z = 2, AXIS_AUTO = 3 };
enum part_method { PART_SLABS = 0, PART_METIS = 1 };

/* A container described as data (Geometry:type container): its walls and
 * its material, in the x-y plane; a 3D container is that section extruded
 * along z over Geometry:depth, closed by end walls at z = 0 and z = depth
 * (setup_container.c). */
enum cwall_shape { CWALL_SEGMENT = 0, CWALL_CYLINDER = 1, CWALL_ENDS = 2 };
enum cwall_motion { CWALL_FIXED = 0, CWALL_TRANSLATING = 1, CWALL_TURNING = 2 };
/* a cylinder's material: inside it (a drum) or outside (a post, an obstacle) */
enum cwall_side { CWALL_INSIDE = 0, CWALL_OUTSIDE = 1 };
/* DEM:placement and DEM:motion (src/dem/dem.c). */
enum dem_place { DEM_SINGLE = 0, DEM_BLOCK = 1 };
enum dem_motion { DEM_FREE = 0, DEM_RIGID = 1, DEM_FIXED = 2 };
enum region_shape { REGION_BOX = 0, REGION_SECTOR = 1, REGION_FILL = 2, REGION_COLUMN = 3 };

/* The most walls and regions a container lists (the end walls of 3D take
 * two of the wall primitives, WALL_PRIM_MAX). */
enum { SCENE_WALLS_MAX = 10, SCENE_REGIONS_MAX = 32 };

/* The struct of each section (struct scene_run, scene_geometry, ...,
 * scene_container) and of each list entry (struct scene_wall, scene_region)
 * comes from the rows of src/scene/scene_keys.h: one member per key, named as the
 * key, in the rows' order, of the type libcyaml's schema (scene.c) fills:
 *   KF, EKF  double               KE, EKE  its row's type (an enum above, int, unsigned)
 *   KU, EKU  unsigned             KS, EKS  char * (malloc'd by libcyaml)
 *   KV, EKV  double key[n]        KL       struct entry *key and unsigned key_count
 * Units, default and meaning: the row's doc (sphseg --keys, docs/keys.md).
 *
 * The members that are not keys, set by the checks (src/scene/scene_check.c) after
 * loading, end their struct: SCENE_NOT_KEYS_<section's member or entry's
 * name>, empty where there are none. */
#define SCENE_NOT_KEYS_segregation unsigned every_k; /* Segregation:every as a number: K, or 0 for auto */
#define SCENE_NOT_KEYS_cwall int gate;        /* Container:walls:K: open_at was given */
#define SCENE_NOT_KEYS_region int has_floor;  /* Container:regions:K: floor was given */
#define SCENE_NOT_KEYS_run
#define SCENE_NOT_KEYS_geometry
#define SCENE_NOT_KEYS_kinematics
#define SCENE_NOT_KEYS_grains
#define SCENE_NOT_KEYS_initial
#define SCENE_NOT_KEYS_output
#define SCENE_NOT_KEYS_physics
#define SCENE_NOT_KEYS_material
#define SCENE_NOT_KEYS_flow
#define SCENE_NOT_KEYS_walls
#define SCENE_NOT_KEYS_parallel
#define SCENE_NOT_KEYS_outlet
#define SCENE_NOT_KEYS_container
#define SCENE_NOT_KEYS_dem int on; /* DEM:d > 0: the scene has grains */

#define SCENE_KEYS_ROWS_ONLY /* the rows, not the names of the enumerated keys (libcyaml's) */
#include "scene_keys_undef.h"
#define ENTRY(name, st, title) struct st {
#define END_ENTRY(name, st) SCENE_NOT_KEYS_##name };
#define SECTION(sec, m, st) struct st {
#define END_SECTION(m) SCENE_NOT_KEYS_##m };
#define KF(sec, m, st, k, req, def, lo, hi, open, when, doc) double k;
#define KE(sec, m, st, k, type, strs, def, doc) type k;
#define KU(sec, m, st, k, def, doc) unsigned k;
#define KS(sec, m, st, k, mn, mx, def, doc) char *k;
#define KV(sec, m, st, k, n, def, doc) double k[n];
#define KL(sec, m, st, k, est, entry, max, doc) struct est *k; unsigned k##_count;
#define EKF(sec, st, k, doc) double k;
#define EKE(sec, st, k, type, strs, doc) type k;
#define EKU(sec, st, k, doc) unsigned k;
#define EKS(sec, st, k, mn, mx, doc) char *k;
#define EKV(sec, st, k, n, doc) double k[n];
#include "scene_keys.h"

struct scene_keys; /* where each key was set (scene.c) */

struct scene {
    /* one member per section, as the section's SECTION row names it:
     * struct scene_run run, struct scene_geometry geometry, ... */
#include "scene_keys_none.h"
#undef SECTION
#define SECTION(sec, m, st) struct st m;
#include "scene_keys.h"
#include "scene_keys_undef.h"
#undef SCENE_KEYS_ROWS_ONLY
    char *path; /* the scene file as given */
    char *text; /* the scene file's text, for snapshot headers */
    struct scene_keys *keys; /* for scene_key_line / scene_key_where */
};

/* The slip of a 3D box's, column's or container's end walls z = 0 and z =
 * depth (enum wall_slip): Walls:end_slip, or where it is side, Walls:side_slip. */
static inline int scene_end_slip(const struct scene *s)
{
    return s->walls.end_slip == SLIP_AS_SIDE ? (int)s->walls.side_slip : s->walls.end_slip;
}

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
/* The same on the CPU, whose ghosts are HALO_DEPTH = 2 cells of 2h deep
 * (mpi/halo.h): a scene with DEM grains is checked against it here
 * (scene_check.c), and against SCENE_PERIOD_SUPPORTS where the GPU runs
 * it (src/settings_check.c). */
enum { SCENE_PERIOD_SUPPORTS_CPU = 4 };
/* The largest Segregation:every a scene may give. */
enum { SCENE_EVERY_MAX = 1000000 };
int scene_parse(struct scene *s, const char *path, int n_over, char **over, char *err,
                size_t errlen);

/* Load, apply overrides ("Section:key=value"), fill defaults, validate.
 * On any bad input: prints one line "sphseg: error: FILE:LINE: Section:key: why"
 * (on rank 0) and exits with status 2, before anything is written.
 * Returns 0 on success. */
int scene_load(struct scene *s, const char *path, int n_over, char **over);
/* The keys ("Section:key=value", NULL-ended) that Run:preset p sets, or NULL (none). */
const char *const *scene_preset_keys(int p);
const char *scene_preset_name(int p);
/* The x-y box of a container's walls (less the end walls) and regions, m. */
void scene_container_box(const struct scene_container *k, double lo[2], double hi[2]);

/* Write every parameter with the value used (defaults included) as YAML, with
 * the same section and key names; numbers read back exactly. Writes
 * file.tmp, then renames it to file. Returns 0, or -1 on failure. */
int scene_write_used(const struct scene *s, const char *file);

/* The used parameters as a YAML string (malloc'd), for snapshot headers. */
char *scene_used_text(const struct scene *s);

/* The default of "Section:key" as the YAML text of its row in the key table
 * (src/scene/scene_keys.h), or NULL (no default, or no such key). */
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

/* Whether a -P override set Section:key (else the file or the default). */
int scene_key_overridden(const struct scene *s, const char *section, const char *key);

/* The extent of the scene's container along x, y and z (m; z 0 in 2D): a
 * box's width, height (and depth; a column's runout included), a drum's
 * diameter (and length), a container's walls and regions (the box around
 * the segments' ends, the cylinders, the boxes, sectors and columns, fills
 * below their level) and its depth. */
void scene_extent(const struct scene *s, double ext[3]);

/* Every key of the scene file, documented from the key table
 * (src/scene/scene_keys.h), as Markdown to f (sphseg --keys, docs/keys.md). */
#include <stdio.h>
void scene_keys_markdown(FILE *f);

/* Free what scene_load/scene_parse allocated; *s is zeroed. */
void scene_free(struct scene *s);

#endif
