/* scene_check.c — the checks of a loaded scene that span keys (scene_ctx.h),
 * after the walk (each key and scalar on its own) and the ranges of the key
 * table (scene.c): the geometry (dimension, sizes against dr, periodic axes),
 * the walls and regions of Geometry:type container entry by entry, the
 * choices that exclude each other (kinematics, materials, what is solved),
 * gravity and wall velocity, a column's runout, lid and opening, an outlet,
 * the backend and Segregation:every. Each error names the key it is about,
 * located where it was set (scene_fail_at). */
#define _POSIX_C_SOURCE 200809L
#include "scene_ctx.h"
#include "mpi/halo.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- Geometry ------------------------------------------------------------------------ */

/* The dimension for the type, the sizes against dr, the periodic axes and
 * their periods (cpu_only: against the CPU's ghosts, a scene with DEM
 * grains; the GPU's rule for it is src/settings_check.c's). */
_Static_assert(SCENE_PERIOD_SUPPORTS_CPU >= 2 * HALO_DEPTH, "a period holds the CPU's ghost layers of both sides");
static int check_geometry(struct scene_ctx *c, const struct scene_geometry *g, int cpu_only)
{
    char a[32], b[32];
    if (g->dim == 3 && g->type == GEOM_SHEARBOX)
        return scene_fail_at(c, "Geometry:dim", "3D is supported for Geometry:type column or drum only (use 2)");
    if (g->dim != 2 && g->dim != 3) return scene_fail_at(c, "Geometry:dim", "must be 2 or 3, got %u", g->dim);
    if (g->dim == 3 && g->type == GEOM_DRUM && g->length < 4 * g->dr) {
        scene_fmt_double(a, sizeof a, 4 * g->dr);
        scene_fmt_double(b, sizeof b, g->length);
        return scene_fail_at(c, "Geometry:length", "must be >= 4*dr = %s, got %s", a, b);
    }
    if (g->dim == 3 && g->type == GEOM_COLUMN && g->depth < 4 * g->dr) {
        scene_fmt_double(a, sizeof a, 4 * g->dr);
        scene_fmt_double(b, sizeof b, g->depth);
        return scene_fail_at(c, "Geometry:depth", "must be >= 4*dr = %s, got %s", a, b);
    }
    if (g->periodic != PERIODIC_NONE && g->type != GEOM_COLUMN && g->type != GEOM_CONTAINER)
        return scene_fail_at(c, "Geometry:periodic", "needs Geometry:type column or container (the walls of a %s are fixed)",
                       g->type == GEOM_DRUM ? "drum" : "shear box");
    if ((g->periodic & PERIODIC_Z) && g->dim != 3)
        return scene_fail_at(c, "Geometry:periodic", "z needs Geometry:dim 3");
    if ((g->periodic & PERIODIC_Y) && g->type != GEOM_CONTAINER)
        return scene_fail_at(c, "Geometry:periodic", "y needs Geometry:type container (a column has a base across y)");
    /* a period must hold the ghost layers of both sides (mpi/halo.h): 3 cells
     * of 2h each way on the GPU, so 6 supports; shorter would need images of
     * images. The CPU's are HALO_DEPTH = 2 cells deep: 4 supports there */
    const int sup = cpu_only ? SCENE_PERIOD_SUPPORTS_CPU : SCENE_PERIOD_SUPPORTS;
    for (int d = 0; d < 3; ++d) {
        double len = d == 0 ? g->width : d == 1 ? g->height : g->depth;
        double need = sup * 2 * g->h_factor * g->dr;
        if (!(g->periodic & (1u << d)) || len >= need) continue;
        return scene_fail_at(c, d == 0 ? "Geometry:width" : d == 1 ? "Geometry:height" : "Geometry:depth",
                       "a periodic axis needs a period of at least %d supports 2h = %.4g m%s, got %.4g", sup, need,
                       cpu_only ? " (the CPU's ghosts, a scene with DEM grains)" : "", len);
    }
    if (g->type == GEOM_CONTAINER) return 0; /* its walls and regions: check_container */
    if (g->type == GEOM_DRUM) {
        scene_fmt_double(a, sizeof a, 8 * g->dr);
        scene_fmt_double(b, sizeof b, g->radius);
        if (g->radius < 8 * g->dr) return scene_fail_at(c, "Geometry:radius", "must be >= 8*dr = %s, got %s", a, b);
        return 0;
    }
    scene_fmt_double(a, sizeof a, 4 * g->dr);
    scene_fmt_double(b, sizeof b, g->width);
    if (g->width < 4 * g->dr) return scene_fail_at(c, "Geometry:width", "must be >= 4*dr = %s, got %s", a, b);
    scene_fmt_double(b, sizeof b, g->height);
    if (g->height < 4 * g->dr) return scene_fail_at(c, "Geometry:height", "must be >= 4*dr = %s, got %s", a, b);
    return 0;
}

/* ---- Geometry:type container ------------------------------------------------------ */

/* Container:walls:K (K = i + 1) on its own, and against the walls before it
 * (ends twice, names). Sets its gate flag and its default name. */
static int check_wall(struct scene_ctx *c, struct scene *s, unsigned i)
{
    const struct scene_container *k = &s->container;
    struct scene_wall *w = &s->container.walls[i];
    const double dr = s->geometry.dr;
    const double *v = w->velocity;
    char nm[SCENE_NAME + 40];
#define AT(key) (snprintf(nm, sizeof nm, "Container:walls:%u%s%s", i + 1, *(key) ? ":" : "", key), nm)
    for (int a = 0; a < 2; ++a)
        if (!isfinite(w->from[a]) || !isfinite(w->to[a]) || !isfinite(w->centre[a]))
            return scene_fail_at(c, AT(""), "a coordinate is not finite");
    if (!isfinite(w->radius) || !isfinite(w->rpm) || !isfinite(w->open_at) || !isfinite(v[0]) ||
        !isfinite(v[1]) || !isfinite(v[2]))
        return scene_fail_at(c, AT(""), "a value is not finite");
    if (w->shape == CWALL_SEGMENT && hypot(w->to[0] - w->from[0], w->to[1] - w->from[1]) < 2 * dr)
        return scene_fail_at(c, AT("to"), "a segment must be at least 2 dr long (from and to too close)");
    if (w->shape == CWALL_CYLINDER && w->material == CWALL_INSIDE && !(w->radius >= 8 * dr))
        return scene_fail_at(c, AT("radius"), "must be >= 8 dr = %.4g m, got %.4g", 8 * dr, w->radius);
    /* a post: its dummies fill it, so it may be small; but a radius under 2 dr
     * is not resolved by the lattice around it */
    if (w->shape == CWALL_CYLINDER && w->material == CWALL_OUTSIDE && !(w->radius >= 2 * dr))
        return scene_fail_at(c, AT("radius"), "a post (material outside) must be >= 2 dr = %.4g m, got %.4g", 2 * dr,
                             w->radius);
    if (w->shape != CWALL_CYLINDER && w->material == CWALL_OUTSIDE)
        return scene_fail_at(c, AT("material"), "outside: only a cylinder (a post) has its material outside");
    if (w->motion == CWALL_TURNING && w->shape == CWALL_SEGMENT)
        return scene_fail_at(c, AT("motion"), "only a cylinder turns (about its own axis), or a 3D container's ends");
    if (w->shape == CWALL_ENDS && s->geometry.dim != 3)
        return scene_fail_at(c, AT("shape"), "ends: the end walls of a 3D container (Geometry:dim 3)");
    for (unsigned j = 0; j < i && w->shape == CWALL_ENDS; ++j)
        if (k->walls[j].shape == CWALL_ENDS) return scene_fail_at(c, AT("shape"), "ends given twice (also wall %u)", j + 1);
    if (w->motion != CWALL_TURNING && w->rpm != 0) return scene_fail_at(c, AT("rpm"), "needs motion turning");
    if (!(w->rpm >= 0)) return scene_fail_at(c, AT("rpm"), "must be >= 0, got %.4g", w->rpm);
    if (w->motion != CWALL_TRANSLATING && (v[0] != 0 || v[1] != 0 || v[2] != 0))
        return scene_fail_at(c, AT("velocity"), "needs motion translating");
    if (s->geometry.dim == 2 && v[2] != 0) return scene_fail_at(c, AT("velocity"), "z entry must be 0 in 2D");
    w->gate = scene_leaf_find(c, AT("open_at")) != NULL;
    if (w->gate && !(w->open_at >= 0))
        return scene_fail_at(c, AT("open_at"), "a gate opens at t >= 0, got %.4g", w->open_at);
    if (w->gate && w->shape != CWALL_SEGMENT) return scene_fail_at(c, AT("open_at"), "only a segment can be a gate");
    if (w->priority > 100) return scene_fail_at(c, AT("priority"), "must be <= 100, got %u", w->priority);
    if (!w->name) {
        char def[16];
        snprintf(def, sizeof def, "wall%u", i + 1);
        if (!(w->name = strdup(def))) return scene_fail(c, -1, 0, NULL, "out of memory");
    }
    for (const char *q = w->name; *q; ++q)
        if (!isalnum((unsigned char)*q) && *q != '_')
            return scene_fail_at(c, AT("name"), "letters, digits and _ only, got '%.32s'", w->name);
    for (unsigned j = 0; j < i; ++j)
        if (!strcmp(k->walls[j].name, w->name))
            return scene_fail_at(c, AT("name"), "'%s' names wall %u already", w->name, j + 1);
    if (s->geometry.dim == 3 && (!strcmp(w->name, "end_lo") || !strcmp(w->name, "end_hi")))
        return scene_fail_at(c, AT("name"), "'%s' is the name of an end wall of a 3D container", w->name);
#undef AT
    return 0;
}

/* Container:regions:K (K = i + 1) on its own. Sets its floor flag. */
static int check_region(struct scene_ctx *c, struct scene *s, unsigned i)
{
    struct scene_region *r = &s->container.regions[i];
    char nm[SCENE_NAME + 40];
#define AT(key) (snprintf(nm, sizeof nm, "Container:regions:%u%s%s", i + 1, *(key) ? ":" : "", key), nm)
    const double vals[] = {r->lo[0], r->lo[1], r->hi[0], r->hi[1], r->centre[0], r->centre[1], r->r_in,
                           r->r_out, r->from_deg, r->to_deg, r->level, r->C};
    for (size_t q = 0; q < ARRAY_LEN(vals); ++q)
        if (!isfinite(vals[q])) return scene_fail_at(c, AT(""), "a value is not finite");
    if (!(r->C >= 0 && r->C <= 1)) return scene_fail_at(c, AT("C"), "must be in [0, 1], got %.4g", r->C);
    if (r->shape == REGION_BOX && !(r->lo[0] < r->hi[0] && r->lo[1] < r->hi[1]))
        return scene_fail_at(c, AT("hi"), "must lie above and right of lo");
    if (r->shape == REGION_SECTOR && !(r->r_in >= 0 && r->r_in < r->r_out))
        return scene_fail_at(c, AT("r_out"), "needs 0 <= r_in < r_out, got r_in %.4g, r_out %.4g", r->r_in, r->r_out);
    r->has_floor = scene_leaf_find(c, AT("floor")) != NULL;
    if (r->has_floor && !(r->floor < r->level))
        return scene_fail_at(c, AT("floor"), "must lie below level, got floor %.4g, level %.4g", r->floor, r->level);
    if (r->shape == REGION_SECTOR && r->from_deg == r->to_deg)
        return scene_fail_at(c, AT("to_deg"), "an empty sector: from_deg equals to_deg");
    if (r->shape == REGION_COLUMN && s->geometry.dim != 3)
        return scene_fail_at(c, AT("shape"), "column: an upright column of a 3D container (Geometry:dim 3)");
    if (r->shape == REGION_COLUMN && !(r->r_out > 0))
        return scene_fail_at(c, AT("r_out"), "a column's radius must be > 0, got %.4g", r->r_out);
#undef AT
    return 0;
}

/* Container:walls and :regions (Geometry:type container): each entry on
 * its own, located as Container:walls:K:key; what needs the lattice
 * (overlapping regions, a region beyond the walls) is found by the builder
 * (setup_container.c). Sets each wall's gate flag and default name. */
static int check_container(struct scene_ctx *c, struct scene *s)
{
    const struct scene_container *k = &s->container;
    const double dr = s->geometry.dr;
    if (s->geometry.type != GEOM_CONTAINER) {
        if (k->walls_count) return scene_fail_at(c, "Container:walls", "needs Geometry:type container");
        if (k->regions_count) return scene_fail_at(c, "Container:regions", "needs Geometry:type container");
        return 0;
    }
    /* none: a DEM scene (the CPU's, tested there) periodic along xyz */
    if (!k->walls_count && !(s->geometry.dim == 3 && s->geometry.periodic == PERIODIC_XYZ && s->dem.d > 0))
        return scene_fail_at(c, "Container:walls", "Geometry:type container needs at least one wall (none: a 3D scene with "
                             "DEM grains periodic along xyz)");
    if (!k->regions_count)
        return scene_fail_at(c, "Container:regions", "Geometry:type container needs at least one region of material");
    for (unsigned i = 0; i < k->walls_count; ++i)
        if (check_wall(c, s, i)) return -1;
    for (unsigned i = 0; i < k->regions_count; ++i)
        if (check_region(c, s, i)) return -1;
    for (unsigned i = 0; i < k->walls_count; ++i)
        if (k->walls[i].shape == CWALL_ENDS && (s->geometry.periodic & PERIODIC_Z))
            return scene_fail_at(c, "Geometry:periodic", "z: a container periodic along z has no end walls (Container:walls:%u "
                                 "is of shape ends)", i + 1);
    if (s->geometry.dim == 3 && s->geometry.depth < 4 * dr)
        return scene_fail_at(c, "Geometry:depth", "must be >= 4*dr = %.4g, got %.4g", 4 * dr, s->geometry.depth);
    if (s->geometry.dim == 3 && k->walls_count > SCENE_WALLS_MAX)
        return scene_fail_at(c, "Container:walls", "at most %d walls", SCENE_WALLS_MAX);
    return 0;
}

/* ---- the choices across sections ----------------------------------------------------- */

/* What is solved: the material, the kinematics against the geometry, the
 * concentration, the grain sizes. */
static int check_models(struct scene_ctx *c, const struct scene *s)
{
    int box = s->geometry.type == GEOM_SHEARBOX, vel = s->kinematics.velocity;
    if (!(s->material.mu_s <= s->material.mu_d))
        return scene_fail_at(c, "Material:mu_d", "must be >= Material:mu_s");
    if (vel == KIN_OSCILLATORY_SHEAR && !box && s->geometry.type != GEOM_CONTAINER)
        return scene_fail_at(c, "Kinematics:velocity", "oscillatory_shear needs Geometry:type shearbox or container");
    if (vel == KIN_COMPUTED && box)
        return scene_fail_at(c, "Kinematics:velocity",
                             "computed needs Geometry:type column or drum (the shear box's walls are prescribed)");
    if (!s->segregation.enabled && vel != KIN_COMPUTED && !(s->dem.d > 0)) /* DEM grains are solved */
        return scene_fail_at(c, "Segregation:enabled", "off with prescribed velocity leaves nothing to solve");
    if (s->segregation.shear_rate == SEG_GDOT_YIELDED && vel != KIN_COMPUTED)
        return scene_fail_at(c, "Segregation:shear_rate", "yielded needs Kinematics:velocity computed (a prescribed flow "
                             "has no stress to tell the yielded grains)");
    if (!(s->grains.d_small < s->grains.d_large))
        return scene_fail_at(c, "Grains:d_large", "must be larger than Grains:d_small");
    return 0;
}

/* Physics:gravity and Walls:velocity: finite, in the x-y plane in 2D. */
static int check_vectors(struct scene_ctx *c, const struct scene *s)
{
    const double *g = s->physics.gravity, *wv = s->walls.velocity;
    for (int k = 0; k < 3; ++k)
        if (!isfinite(g[k])) return scene_fail_at(c, "Physics:gravity", "entry %d is not finite", k + 1);
    if (g[0] == 0 && g[1] == 0 && g[2] == 0) return scene_fail_at(c, "Physics:gravity", "must not be all zero");
    for (int k = 0; k < 3; ++k)
        if (!isfinite(wv[k])) return scene_fail_at(c, "Walls:velocity", "entry %d is not finite", k + 1);
    if (s->geometry.dim == 2 && wv[2] != 0)
        return scene_fail_at(c, "Walls:velocity", "z entry must be 0 in 2D (the x-y plane)");
    if ((wv[0] != 0 || wv[1] != 0 || wv[2] != 0) && s->geometry.type != GEOM_COLUMN)
        return scene_fail_at(c, "Walls:velocity", "a translating container needs Geometry:type column");
    if (s->geometry.dim == 2 && g[2] != 0)
        return scene_fail_at(c, "Physics:gravity", "z entry must be 0 in 2D (the x-y plane)");
    /* a Coulomb wall takes its friction from Walls:mu_w */
    int coulomb = s->walls.slip == SLIP_COULOMB || s->walls.side_slip == SLIP_COULOMB ||
                  scene_end_slip(s) == SLIP_COULOMB;
    for (unsigned i = 0; i < s->container.walls_count; ++i) coulomb |= s->container.walls[i].slip == SLIP_COULOMB;
    if (coulomb && !(s->walls.mu_w > 0))
        return scene_fail_at(c, "Walls:mu_w", "a wall with slip coulomb needs Walls:mu_w > 0 (the tangent of the "
                             "wall friction angle); it is %g", s->walls.mu_w);
    if (s->walls.coulomb_force == COULOMB_PARTICLES && !coulomb)
        return scene_fail_at(c, "Walls:coulomb_force", "particles needs a wall with slip coulomb (Walls:slip, "
                             "side_slip, end_slip or a container's entry)");
    if (s->walls.coulomb_force == COULOMB_PARTICLES && s->kinematics.velocity != KIN_COMPUTED)
        return scene_fail_at(c, "Walls:coulomb_force", "particles needs computed flow (Kinematics:velocity computed)");
    return 0;
}

/* A column's runout (a gate), lid and opening, and an outlet. */
static int check_openings(struct scene_ctx *c, const struct scene *s)
{
    const struct scene_geometry *g = &s->geometry;
    int vel = s->kinematics.velocity;
    if (g->runout > 0) {
        double need = (ceil(2.0 * g->h_factor - 1e-9) + 1) * g->dr;
        if (g->type != GEOM_COLUMN || vel != KIN_COMPUTED)
            return scene_fail_at(c, "Geometry:runout", "needs Geometry:type column and Kinematics:velocity computed");
        if (g->periodic & PERIODIC_X) return scene_fail_at(c, "Geometry:runout", "needs walls along x (Geometry:periodic)");
        if (g->runout < need)
            return scene_fail_at(c, "Geometry:runout", "must be 0 or at least the gate's thickness plus dr, %.4g m, got %.4g",
                                 need, g->runout);
        if (g->outlet_width > 0)
            return scene_fail_at(c, "Geometry:outlet_width", "an opening in a base with a runout is not supported");
    }
    if (g->lid && (g->type != GEOM_COLUMN || g->runout > 0))
        return scene_fail_at(c, "Geometry:lid", "needs Geometry:type column without a runout");
    if (g->outlet_width > 0 && g->type != GEOM_COLUMN)
        return scene_fail_at(c, "Geometry:outlet_width", "needs Geometry:type column (an opening in its base)");
    if (g->outlet_width > 0 &&
        !(g->outlet_width <= g->width - 2 * g->dr && (g->dim == 2 || g->outlet_width <= g->depth - 2 * g->dr)))
        return scene_fail_at(c, "Geometry:outlet_width", "%.4g m leaves less than 2 dr of base beside the opening",
                             g->outlet_width);
    if (s->outlet.enabled && ((g->type != GEOM_COLUMN && g->type != GEOM_CONTAINER) || vel != KIN_COMPUTED))
        return scene_fail_at(c, "Outlet:enabled", "needs Geometry:type column or container and Kinematics:velocity computed");
    if (s->outlet.enabled && g->type == GEOM_COLUMN && !(s->outlet.below <= 0))
        return scene_fail_at(c, "Outlet:below", "must be at or below the base, y <= 0 (the plane would cut the material "
                             "at the start), got %.4g", s->outlet.below);
    return 0;
}

/* DEM grains (DEM:d > 0): a Newtonian fluid with computed flow, 3D, the
 * placement's keys whole and inside the container's extent. A periodic axis
 * (the coupling and the contacts take minimum images) needs a period of at
 * least 2 d, so that a grain meets one image of another. */
static int check_dem(struct scene_ctx *c, struct scene *s)
{
    struct scene_dem *k = &s->dem;
    k->on = k->d > 0;
    if (!k->on) return 0;
    if (s->material.model != MAT_NEWTONIAN)
        return scene_fail_at(c, "DEM:d", "grains need a fluid: Material:model newtonian");
    /* one_way: the fluid may be held at rest (Kinematics:velocity rest), the fluid of eq. (27) */
    if (s->kinematics.velocity != KIN_COMPUTED && (s->kinematics.velocity != KIN_REST || k->coupling != DEM_ONE_WAY))
        return scene_fail_at(c, "Kinematics:velocity", "DEM grains need computed flow, or rest with DEM:coupling one_way");
    if (s->geometry.dim != 3)
        return scene_fail_at(c, "DEM:d", "grains are spheres in a 3D fluid: needs Geometry:dim 3");
    double ext[3];
    scene_extent(s, ext);
    for (int a = 0; a < 3; ++a)
        if ((s->geometry.periodic >> a & 1) && !(ext[a] >= 2.0 * k->d))
            return scene_fail_at(c, "Geometry:periodic", "DEM grains need a period of at least 2 DEM:d = %.4g m along "
                                 "%c, got %.4g", 2.0 * k->d, 'x' + a, ext[a]);
    if (k->placement == DEM_BLOCK) {
        for (int a = 0; a < 3; ++a) {
            double n = k->block_n[a];
            if (!(n >= 1 && n <= 1e4 && n == floor(n)))
                return scene_fail_at(c, "DEM:block_n", "expected whole numbers from 1 to 10000, got %g "
                                     "along %c", n, 'x' + a);
        }
        if (!(k->block_spacing >= k->d))
            return scene_fail_at(c, "DEM:block_spacing", "%.4g m is less than DEM:d %.4g m", k->block_spacing, k->d);
    }
    for (int a = 0; a < 3 && s->geometry.type != GEOM_CONTAINER; ++a) {
        double lo = k->placement == DEM_BLOCK ? k->block_origin[a] : k->at[a];
        double hi = k->placement == DEM_BLOCK ? lo + (k->block_n[a] - 1) * k->block_spacing : lo;
        if (lo - 0.5 * k->d < 0 || hi + 0.5 * k->d > ext[a])
            return scene_fail_at(c, k->placement == DEM_BLOCK ? "DEM:block_origin" : "DEM:at",
                                 "a grain reaches outside the container along %c (0 to %.4g m)", 'x' + a, ext[a]);
    }
    return 0;
}

/* The checks across keys, in this order; the first that fails is reported. */
int scene_check_special(struct scene_ctx *c, struct scene *s)
{
    const char *backend = s->run.backend ? s->run.backend : "";
    int vel = s->kinematics.velocity;
    if (check_geometry(c, &s->geometry, s->dem.d > 0) || check_container(c, s) || check_models(c, s) || check_vectors(c, s) ||
        check_openings(c, s) || check_dem(c, s))
        return -1;
    if (s->geometry.periodic != PERIODIC_NONE && vel != KIN_COMPUTED)
        return scene_fail_at(c, "Geometry:periodic", "needs Kinematics:velocity computed");
    if ((s->geometry.periodic & PERIODIC_Y) && s->initial.stress == INIT_STRESS_GEOSTATIC)
        return scene_fail_at(c, "Initial:stress", "geostatic needs a free surface above the material; a container periodic "
                             "along y has none (Geometry:periodic)");
    if (strcmp(backend, "cpu") != 0 && strcmp(backend, "gpu") != 0 && strcmp(backend, "auto") != 0)
        return scene_fail_at(c, "Run:backend", "expected auto, cpu or gpu, got '%.40s'", backend);
    return 0;
}

/* ---- Segregation:every ------------------------------------------------------------ */

/* Segregation:every: "auto" (every_k = 0) or a whole number of flow steps
 * from 1 to SCENE_EVERY_MAX. */
int scene_check_every(struct scene_ctx *c, struct scene_segregation *g)
{
    const char *e = g->every ? g->every : "";
    if (!strcmp(e, "auto")) {
        g->every_k = 0;
        return 0;
    }
    char *end;
    errno = 0;
    long k = strtol(e, &end, 10);
    if (!*e || *end || errno || k < 1 || k > SCENE_EVERY_MAX)
        return scene_fail_at(c, "Segregation:every", "expected auto or a whole number of flow steps from 1 to %d, got "
                       "'%.40s'", SCENE_EVERY_MAX, e);
    g->every_k = (unsigned)k;
    return 0;
}
