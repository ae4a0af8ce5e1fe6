/* setup.c — initial particles and physics contexts of a scene.
 * Shear box (paper §5) and granular column: material on a square lattice of spacing dr filling
 * [0, W] x [0, H]; ceil(2h/dr) layers of dummy particles below the base and
 * outside both side walls (the walls reach the same number of layers above
 * the material), no side walls when x is periodic (Geometry:periodic: the
 * base ends at the period, and the lattice continues through the images);
 * no dummies at the top, which is a free surface.
 * Drum (2D and 3D) and 3D column below. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "core/error.h"
#include "mpi/comm.h"
#include "setup.h"
#include "stages.h"

typedef struct box_layout {
    long nx, ny, nl; /* material columns, rows; dummy layers */
    long ns;         /* dummy layers of each side wall: nl, or 0 when x is periodic */
    long nr;         /* lattice columns of the runout past the material (Geometry:runout), 0 if none */
    size_t n_mat, n_dum;
} box_layout;

static box_layout setup_layout(const struct scene *sc)
{
    const struct scene_geometry *g = &sc->geometry;
    box_layout b;
    b.nx = lround(g->width / g->dr);
    b.ny = lround(g->height / g->dr);
    b.nl = (long)ceil(2.0 * g->h_factor - 1e-9);
    b.ns = g->periodic & PERIODIC_X ? 0 : b.nl;
    b.nr = lround(g->runout / g->dr);
    b.n_mat = (size_t)(b.nx * b.ny);
    b.n_dum = (size_t)(b.nl * (b.nx + b.nr + 2 * b.ns) * (g->lid ? 2 : 1) + 2 * b.ns * (b.ny + b.nl) +
                       (b.nr ? b.nl * (b.ny + b.nl) : 0));
    return b;
}

/* The scene's particles k (global index = ID) in [lo, hi) are this rank's
 * share: an even part of all n, built here; the decomposition then sends
 * each particle to the rank owning its position (mpi/halo.h). One rank
 * builds them all. */
static struct {
    size_t lo, hi;
} setup_win;

/* Allocate this rank's share of n particles; exit with status 2 if it
 * would not fit in this machine. */
void setup_alloc(sim_t *s, int dim, size_t n)
{
    const struct scene *sc = s->sc;
    size_t r = (size_t)comm_rank(), P = (size_t)comm_size();
    setup_win.lo = n * r / P, setup_win.hi = n * (r + 1) / P;
    size_t share = setup_win.hi - setup_win.lo;
    const uint32_t fields = stage_store_fields(stage_flags(s));
    double need = (double)share * (double)(part_fields_bytes(fields) + 64); /* + grid, scratch */
    double have = (double)sysconf(_SC_PHYS_PAGES) * (double)sysconf(_SC_PAGESIZE);
    char where[512];
    if (need > 0.8 * have)
        input_error("%s: Geometry:dr: %.3g m gives %zu particles, %zu on each of %zu rank(s), needing %.1f GiB "
                    "per rank; this machine has %.1f GiB", scene_key_where(sc, "Geometry", "dr", where, sizeof where),
                    sc->geometry.dr, n, share, P, need / 1073741824.0, have / 1073741824.0);
    part_alloc_fields(&s->p, dim, share, fields);
}

/* Particle k of the scene at (x, y, z), stored if it is in this rank's
 * share; C is set for material only. */
void setup_put(particles_t *p, size_t k, double x, double y, double z, int kind, double vol, double C)
{
    if (k < setup_win.lo || k >= setup_win.hi) return;
    size_t i = k - setup_win.lo;
    p->X0[0][i] = p->x[0][i] = (real)x;
    p->X0[1][i] = p->x[1][i] = (real)y;
    p->X0[2][i] = p->x[2][i] = (real)z;
    p->kind[i] = (uint8_t)kind;
    p->wall[i] = 0; /* setup_walls */
    p->vol[i] = (real)vol;
    p->id[i] = (int64_t)k;
    p->psi[i] = 1;
    if (kind == KIND_MATERIAL) p->C[i] = (real)C;
}

void setup_put_wall(particles_t *p, size_t k, int id)
{
    if (k >= setup_win.lo && k < setup_win.hi) p->wall[k - setup_win.lo] = (uint8_t)id;
}

/* This rank's particles once the scene's first k are placed. */
size_t setup_count(size_t k)
{
    return k <= setup_win.lo ? 0 : (k < setup_win.hi ? k : setup_win.hi) - setup_win.lo;
}

static void setup_box(sim_t *s)
{
    const struct scene *sc = s->sc;
    double dr = sc->geometry.dr, vol = dr * dr;
    box_layout b = setup_layout(sc);
    setup_alloc(s, 2, b.n_mat + b.n_dum);
    particles_t *p = &s->p;
    size_t k = 0;
    double H = b.ny * dr, split = sc->initial.split * H;
    for (long j = 0; j < b.ny; ++j)
        for (long i = 0; i < b.nx; ++i, ++k) {
            double y = (j + 0.5) * dr;
            setup_put(p, k, (i + 0.5) * dr, y, 0, KIND_MATERIAL, vol, y <= split ? sc->initial.C_below : sc->initial.C_above);
        }
    double W = b.nx * dr, ow = sc->geometry.outlet_width;
    for (long l = 0; l < b.nl; ++l) /* base, less its opening */
        for (long i = -b.ns; i < b.nx + b.nr + b.ns; ++i) {
            if (fabs((i + 0.5) * dr - 0.5 * W) < 0.5 * ow) continue;
            setup_put(p, k++, (i + 0.5) * dr, -(l + 0.5) * dr, 0, KIND_DUMMY, vol, 0);
        }
    for (long j = 0; j < b.ny + b.nl; ++j) /* side walls */
        for (long l = 0; l < b.ns; ++l) {
            setup_put(p, k++, -(l + 0.5) * dr, (j + 0.5) * dr, 0, KIND_DUMMY, vol, 0);
            setup_put(p, k++, (b.nx + b.nr + l + 0.5) * dr, (j + 0.5) * dr, 0, KIND_DUMMY, vol, 0);
        }
    for (long l = 0; sc->geometry.lid && l < b.nl; ++l) /* the lid, nl layers over the material */
        for (long i = -b.ns; i < b.nx + b.ns; ++i, ++k) {
            setup_put(p, k, (i + 0.5) * dr, H + (l + 0.5) * dr, 0, KIND_DUMMY, vol, 0);
            if (k >= setup_win.lo && k < setup_win.hi) p->wall[k - setup_win.lo] = (uint8_t)wall_named(s, "lid");
        }
    for (long j = 0; b.nr && j < b.ny + b.nl; ++j) /* the gate, nl layers past the material */
        for (long l = 0; l < b.nl; ++l, ++k) {
            setup_put(p, k, (b.nx + l + 0.5) * dr, (j + 0.5) * dr, 0, KIND_DUMMY, vol, 0);
            if (k >= setup_win.lo && k < setup_win.hi) p->wall[k - setup_win.lo] = (uint8_t)wall_named(s, "gate");
        }
    p->n = setup_count(k);
    s->n_material = b.n_mat;
    s->surface_y = H;
    if (fabs(H - sc->geometry.height) > 1e-6 * sc->geometry.height)
        warning("Geometry:height %.6g m is not a multiple of dr; the box is %.6g m high", sc->geometry.height, H);
}

/* Drum (paper §6, figure 15), axis along z through the origin. One plane:
 * material on the square lattice (i + 1/2) dr, (j + 1/2) dr inside
 * r <= R - dr/2 and below the flat free surface y = H = (2 R_f - 1) R;
 * nl = ceil(2h/dr) rings of dummies at radii R + (l + 1/2) dr, each with
 * round(2 pi r / dr) equally spaced particles. Concentration C_below below
 * split * (H + R) - R, else C_above. 2D: that plane at z = 0, volume dr^2.
 * 3D: nz = round(length / dr) material planes at z = (q + 1/2) dr between
 * the end walls z = 0 and z = nz dr, each with its nl rings; each end wall
 * nl planes of dummies beyond it, every one a full disc out to the outer
 * ring radius made of the same rings continued inward to the axis (radii
 * R + (l + 1/2) dr > 0, l < 0): a polar lattice of spacing dr with no gap
 * at r = R, where a square-lattice disc would leave holes that let
 * material leak through the corner; volume dr^3. */
typedef struct drum_layout {
    double dr, vol, R, H, split; /* spacing, particle volume, radius, surface, C split height (m) */
    double oy;                   /* the lattice's rows at (j + 1/2) dr + oy (m): 0, or aligned to H (fill_by area) */
    long nh, nl, nz, nend;       /* lattice half-width, rings, material planes, end-wall planes */
    int dim;
    const struct scene_initial *ini;
} drum_layout;

/* About the number of lattice points of one plane (r <= R - dr/2, y <= H, rows at (j + 1/2) dr + oy),
 * row by row: the points (i + 1/2) dr with |x| <= w are 2 floor(w / dr + 1/2) of them (drum_disc's own
 * test may differ by a point where one lies on the circle to round-off: it places the material). */
static long drum_plane_count(const drum_layout *d)
{
    long n = 0;
    double rc = d->R - 0.5 * d->dr;
    for (long j = -d->nh; j < d->nh; ++j) {
        double y = (j + 0.5) * d->dr + d->oy;
        if (y <= d->H && fabs(y) <= rc) n += 2 * (long)floor(sqrt(rc * rc - y * y) / d->dr + 0.5);
    }
    return n;
}

/* Geometry:fill_by area: the fill line H' and the rows with it (the top row at H' - dr/2), H' from H - dr
 * to H + 3 dr in steps of dr/512, the one whose plane's N dr^2 is nearest the area of the segment of the
 * drum (radius R) below H (the first such). The wall's gap of dr/2 then costs no material: the bed holds
 * the segment's area, its surface that much higher. */
static void drum_fill_area(drum_layout *d)
{
    double R = d->R, H = d->H, hr = fmax(-1.0, fmin(1.0, H / R));
    double A = R * R * (M_PI - acos(hr)) + H * sqrt(fmax(0.0, R * R - H * H)), target = A / (d->dr * d->dr);
    double H0 = H, best = INFINITY, bestH = H, bestoy = 0;
    for (int k = 0; k <= 4 * 512; ++k) {
        double He = H0 - d->dr + k * d->dr / 512;
        d->H = He;
        d->oy = He - d->dr * ceil(He / d->dr); /* in (-dr, 0]: the row j = ceil(He/dr) - 1 lies at He - dr/2 */
        double miss = fabs((double)drum_plane_count(d) - target);
        if (miss < best) best = miss, bestH = d->H, bestoy = d->oy;
    }
    d->H = bestH + 1e-9 * d->dr, d->oy = bestoy; /* the top row's test y <= H not at the mercy of rounding */
}

static drum_layout drum_layout_of(const struct scene *sc)
{
    const struct scene_geometry *g = &sc->geometry;
    drum_layout d;
    d.dim = (int)g->dim;
    d.dr = g->dr, d.R = g->radius, d.vol = d.dim == 3 ? d.dr * d.dr * d.dr : d.dr * d.dr;
    d.H = (2 * g->fill - 1) * d.R, d.split = -d.R + sc->initial.split * (d.H + d.R);
    d.nh = (long)ceil(d.R / d.dr) + 1, d.nl = (long)ceil(2.0 * g->h_factor - 1e-9);
    d.nz = d.dim == 3 ? lround(g->length / d.dr) : 1;
    d.nend = d.dim == 3 ? d.nl : 0;
    d.ini = &sc->initial;
    d.oy = 0;
    if (g->fill_by == FILL_AREA) drum_fill_area(&d);
    return d;
}

/* z of plane q (q < 0 and q >= nz: beyond the end walls); 0 in 2D. */
static double drum_z(const drum_layout *d, long q) { return d->dim == 3 ? (q + 0.5) * d->dr : 0.0; }

static void drum_put(particles_t *p, size_t k, double x, double y, double z, int kind, const drum_layout *d)
{
    setup_put(p, k, x, y, z, kind, d->vol, y <= d->split ? d->ini->C_below : d->ini->C_above);
}

/* The material of plane z: lattice points inside r <= R - dr/2 below the
 * fill line. p NULL: count only. Returns k advanced past them. */
static size_t drum_disc(particles_t *p, size_t k, const drum_layout *d, double z)
{
    for (long j = -d->nh; j < d->nh; ++j)
        for (long i = -d->nh; i < d->nh; ++i) {
            double x = (i + 0.5) * d->dr, y = (j + 0.5) * d->dr + d->oy;
            if (!(sqrt(x * x + y * y) <= d->R - 0.5 * d->dr && y <= d->H)) continue;
            if (p) drum_put(p, k, x, y, z, KIND_MATERIAL, d);
            k++;
        }
    return k;
}

/* The rings of dummies l0 <= l < nl of plane z, radii R + (l + 1/2) dr
 * (l0 = 0: the cylinder; l0 < 0: inward too, an end wall). p NULL: count
 * only. */
static size_t drum_rings(particles_t *p, size_t k, const drum_layout *d, double z, long l0)
{
    for (long l = l0; l < d->nl; ++l) {
        double r = d->R + (l + 0.5) * d->dr;
        long m = lround(2 * M_PI * r / d->dr);
        for (long q = 0; q < m; ++q, ++k)
            if (p) drum_put(p, k, r * cos(2 * M_PI * q / m), r * sin(2 * M_PI * q / m), z, KIND_DUMMY, d);
    }
    return k;
}

/* All particles of the drum, material first (p NULL: count only); returns
 * their number. Planes q < 0 and q >= nz are the end walls. */
static size_t drum_place(particles_t *p, const drum_layout *d)
{
    size_t k = 0;
    long l_axis = (long)floor(-d->R / d->dr - 0.5) + 1; /* innermost ring with radius > 0 */
    for (long q = 0; q < d->nz; ++q) k = drum_disc(p, k, d, drum_z(d, q));
    for (long q = -d->nend; q < d->nz + d->nend; ++q)
        k = drum_rings(p, k, d, drum_z(d, q), q < 0 || q >= d->nz ? l_axis : 0);
    return k;
}

static void setup_drum(sim_t *s)
{
    const struct scene *sc = s->sc;
    drum_layout d = drum_layout_of(sc);
    size_t n_mat = (size_t)d.nz * drum_disc(NULL, 0, &d, 0), n = drum_place(NULL, &d);
    setup_alloc(s, d.dim, n);
    particles_t *p = &s->p;
    p->n = setup_count(drum_place(p, &d));
    s->n_material = n_mat;
    /* the topmost material row: the geostatic depth is measured from there */
    double top = -INFINITY;
    for (size_t i = 0; i < setup_count(n_mat); ++i) top = fmax(top, (double)p->x[1][i] + 0.5 * d.dr);
    s->surface_y = comm_max(top);
    double L = d.nz * d.dr;
    if (d.dim == 3 && fabs(L - sc->geometry.length) > 1e-6 * sc->geometry.length)
        warning("Geometry:length %.6g m is not a multiple of dr; the drum is %.6g m long", sc->geometry.length, L);
}

/* Geostatic initial stress of a material at rest under a flat surface at
 * y = surface_y (gravity along -y): sigma_yy = -rho |g| depth, sigma_xx =
 * sigma_zz = K0 sigma_yy with K0 = nu / (1 - nu) (uniaxial strain), returned
 * to the yield cone of Material:yield with mu = mu_s (at rest). It only shortens the elastic
 * transient of a start from zero stress. Initial:pressure adds a uniform
 * pressure to the zero or geostatic stress. */
static void setup_stress(sim_t *s)
{
    const struct scene *sc = s->sc;
    particles_t *p = &s->p;
    const int geostatic = sc->initial.stress == INIT_STRESS_GEOSTATIC;
    const double p0 = sc->initial.pressure;
    if (!geostatic && !(p0 > 0)) return; /* zero stress */
    const double *gv = sc->physics.gravity;
    int fluid = sc->material.model == MAT_NEWTONIAN; /* hydrostatic: K0 = 1, no shear stress */
    double gn = sqrt(gv[0] * gv[0] + gv[1] * gv[1]), K0 = fluid ? 1.0 : sc->material.nu / (1 - sc->material.nu);
    real kmu = fluid ? R(0.0) : stress_yield_k((int)sc->material.yield, (real)sc->material.mu_s);
    for (size_t i = 0; i < p->n; ++i) {
        if (p->kind[i] != KIND_MATERIAL) continue;
        real sg[6] = {0, 0, 0, 0, 0, 0};
        if (geostatic) {
            double depth = fmax(0.0, s->surface_y - (double)p->x[1][i]);
            sg[1] = (real)(-sc->physics.rho * gn * depth);
            sg[0] = sg[2] = (real)(K0 * sg[1]);
            stress_return_map(sg, kmu);
        }
        for (int q = 0; q < 3; ++q) sg[q] -= (real)p0;
        for (int q = 0; q < 6; ++q) p->sig[q][i] = sg[q];
    }
}

/* 3D column: material on the lattice of spacing dr filling [0, W] x [0, H]
 * x [0, D]; nl = ceil(2h/dr) layers of dummies below the base (corners
 * included) and outside the four side walls, which reach nl layers above
 * the material; the top is a free surface. A periodic axis
 * (Geometry:periodic) has no side walls: the lattice and the base end at
 * the period, and the material continues through the ghosts' images
 * (mpi/halo.h). */
static void setup_box3d(sim_t *s)
{
    const struct scene *sc = s->sc;
    const struct scene_geometry *g = &sc->geometry;
    double dr = g->dr, vol = dr * dr * dr;
    long nx = lround(g->width / dr), ny = lround(g->height / dr), nz = lround(g->depth / dr);
    long nl = (long)ceil(2.0 * g->h_factor - 1e-9);
    long sx = g->periodic & PERIODIC_X ? 0 : nl, sz = g->periodic & PERIODIC_Z ? 0 : nl; /* side wall layers */
    long nr = lround(g->runout / dr);                                                   /* runout columns */
    size_t cap = (size_t)((nx + nr + 2 * sx) * (ny + 2 * nl) * (nz + 2 * sz));
    setup_alloc(s, 3, cap);
    particles_t *p = &s->p;
    size_t k = 0;
    double H = ny * dr, split = sc->initial.split * H;
    for (int pass = 0; pass < 2; ++pass) /* material first, then dummies */
        for (long j = -nl; j < ny + nl; ++j)
            for (long q = -sz; q < nz + sz; ++q)
                for (long i = -sx; i < nx + nr + sx; ++i) {
                    int inside = i >= 0 && i < nx + nr && q >= 0 && q < nz;
                    int lid = g->lid && inside && j >= ny; /* the lid's layers */
                    if (inside && j >= ny && !lid) continue; /* above the free surface */
                    int mat = inside && j >= 0 && j < ny && i < nx;
                    int gate = inside && j >= 0 && i >= nx && i < nx + nl; /* nr > 0 only */
                    if (inside && j >= 0 && !mat && !gate && !lid) continue; /* the runout's empty floor space */
                    if (mat != (pass == 0)) continue;
                    if (j < 0 && fabs((i + 0.5) * dr - 0.5 * nx * dr) < 0.5 * g->outlet_width &&
                        fabs((q + 0.5) * dr - 0.5 * nz * dr) < 0.5 * g->outlet_width)
                        continue; /* the base's opening */
                    double y = (j + 0.5) * dr;
                    setup_put(p, k, (i + 0.5) * dr, y, (q + 0.5) * dr, mat ? KIND_MATERIAL : KIND_DUMMY, vol,
                              y <= split ? sc->initial.C_below : sc->initial.C_above);
                    if ((gate || lid) && k >= setup_win.lo && k < setup_win.hi)
                        p->wall[k - setup_win.lo] = (uint8_t)wall_named(s, gate ? "gate" : "lid");
                    ++k;
                }
    p->n = setup_count(k);
    s->n_material = (size_t)(nx * ny * nz);
    s->surface_y = H;
}

/* Every dummy's wall (particles_t.wall) from its reference position,
 * wall_id_at; the gate's and the lid's were set where they were placed. */
static void setup_walls(sim_t *s)
{
    particles_t *p = &s->p;
    for (size_t i = 0; i < p->n; ++i) {
        if (p->kind[i] != KIND_DUMMY || p->wall[i]) continue;
        real X0[3] = {p->X0[0][i], p->X0[1][i], p->X0[2][i]};
        int id = wall_id_at(&s->flow.w, X0);
        if (!id) error_exit(1, "setup: dummy %lld at (%g, %g, %g) m lies beyond no wall", (long long)p->id[i],
                            (double)X0[0], (double)X0[1], (double)X0[2]);
        p->wall[i] = (uint8_t)id;
    }
}

/* The container's wall primitives (wall.h) of the built-in scenes. */

/* Appends a primitive named `name` with the motion of the scene's walls
 * (the box's translation, Walls:velocity) and the slip `slip` (enum
 * wall_slip: free slip, or no slip, with Walls:mu_w where coulomb); returns
 * it for the caller to shape. */
wall_prim *wall_add_prim(sim_t *s, const char *name, int shape, int slip, int bound, int claim)
{
    wall_geom *w = &s->flow.w;
    if (w->n >= WALL_PRIM_MAX) error_exit(1, "setup: more than %d wall primitives", WALL_PRIM_MAX);
    wall_prim *q = &w->prim[w->n];
    memset(q, 0, sizeof *q);
    s->wall_name[w->n++] = name;
    q->shape = shape, q->slip = slip == SLIP_FREE, q->bound = bound, q->claim = claim;
    q->mu_w = slip == SLIP_COULOMB ? (real)s->sc->walls.mu_w : R(0.0);
    q->open_at = -1;
    q->t_lo = (real)-1e30, q->t_hi = (real)1e30; /* unbounded */
    const double *u = s->sc->walls.velocity;
    if (u[0] != 0 || u[1] != 0 || u[2] != 0) {
        q->move = WALL_TRANSLATE;
        for (int d = 0; d < 3; ++d) q->u[d] = (real)u[d];
    }
    return q;
}

wall_prim *wall_plane(sim_t *s, const char *name, int slip, int bound, int claim, double px, double py,
                             double pz, double nx, double ny, double nz)
{
    wall_prim *q = wall_add_prim(s, name, WALL_PLANE, slip, bound, claim);
    q->p[0] = (real)px, q->p[1] = (real)py, q->p[2] = (real)pz;
    q->n[0] = (real)nx, q->n[1] = (real)ny, q->n[2] = (real)nz;
    return q;
}

/* Shear box and column: the base y = 0 (its corners; not bounding when an
 * outlet opens it), the side walls x = 0 and x = width and in 3D z = 0 and
 * z = depth (none across a periodic axis; those two slip as Walls:end_slip),
 * the gate x = width of the material with a runout, the lid y = height.
 * Widths in whole dr, the runout included, as the particles are placed. */
static void walls_box(sim_t *s)
{
    const struct scene *sc = s->sc;
    const struct scene_geometry *g = &sc->geometry;
    double dr = g->dr, W = (double)(lround(g->width / dr) + lround(g->runout / dr)) * dr;
    double D = g->dim == 3 ? (double)lround(g->depth / dr) * dr : 0.0, H = (double)lround(g->height / dr) * dr;
    const int sb = (int)sc->walls.slip, ss = (int)sc->walls.side_slip, se = scene_end_slip(sc);
    wall_plane(s, "base", sb, !sc->outlet.enabled, WALL_CLAIM_FIRST, 0, 0, 0, 0, 1, 0);
    if (!(g->periodic & PERIODIC_X)) {
        wall_plane(s, "xlo", ss, 1, WALL_CLAIM_SIDE, 0, 0, 0, 1, 0, 0);
        wall_plane(s, "xhi", ss, 1, WALL_CLAIM_SIDE, W, 0, 0, -1, 0, 0);
    }
    if (g->dim == 3 && !(g->periodic & PERIODIC_Z)) {
        wall_plane(s, "zlo", se, 1, WALL_CLAIM_SIDE, 0, 0, 0, 0, 0, 1);
        wall_plane(s, "zhi", se, 1, WALL_CLAIM_SIDE, 0, 0, D, 0, 0, -1);
    }
    if (g->runout > 0)
        wall_plane(s, "gate", ss, 0, WALL_CLAIM_NONE, (double)lround(g->width / dr) * dr, 0, 0, -1, 0, 0)->open_at =
            sc->walls.gate_open;
    if (g->lid) wall_plane(s, "lid", sb, 1, WALL_CLAIM_NONE, 0, H, 0, 0, -1, 0);
    s->flow.w.period[0] = (real)W, s->flow.w.period[2] = (real)D;
}

/* Drum: the cylinder r = R about the z axis and in 3D the end walls z = 0
 * and z = length (whole dr), all turning at Walls:rpm; the cylinder first,
 * so that it takes the corner dummies on a tie. */
static void walls_drum(sim_t *s)
{
    const struct scene *sc = s->sc;
    const struct scene_geometry *g = &sc->geometry;
    const int sb = (int)sc->walls.slip;
    double omega = sc->walls.rpm * 2.0 * M_PI / 60.0 * (sc->walls.direction == ROT_CLOCKWISE ? -1.0 : 1.0);
    double L = (double)lround(g->length / g->dr) * g->dr;
    wall_prim *q[3] = {wall_add_prim(s, "drum", WALL_CYLINDER, sb, 1, WALL_CLAIM_SIDE), NULL, NULL};
    q[0]->radius = (real)g->radius;
    if (g->dim == 3) {
        q[1] = wall_plane(s, "end_lo", sb, 1, WALL_CLAIM_SIDE, 0, 0, 0, 0, 0, 1);
        q[2] = wall_plane(s, "end_hi", sb, 1, WALL_CLAIM_SIDE, 0, 0, L, 0, 0, -1);
    }
    for (int k = 0; k < 3; ++k)
        if (q[k]) q[k]->move = WALL_ROTATE, q[k]->omega = omega; /* about the z axis, c = 0 */
}

/* The built-in containers, one row each: which scenes it serves, its walls
 * and its particles. */
static const struct setup_builder {
    enum geom_type type;
    unsigned dim; /* 0: either */
    void (*walls)(sim_t *);
    void (*place)(sim_t *);
} setup_builders[] = {
    {GEOM_SHEARBOX, 2, walls_box, setup_box},
    {GEOM_COLUMN, 2, walls_box, setup_box},
    {GEOM_COLUMN, 3, walls_box, setup_box3d},
    {GEOM_DRUM, 0, walls_drum, setup_drum},
    {GEOM_CONTAINER, 0, container_walls, container_place}, /* setup_container.c */
};

static const struct setup_builder *setup_builder_of(const struct scene *sc)
{
    for (size_t k = 0; k < sizeof setup_builders / sizeof *setup_builders; ++k)
        if (setup_builders[k].type == sc->geometry.type &&
            (!setup_builders[k].dim || setup_builders[k].dim == sc->geometry.dim))
            return &setup_builders[k];
    error_exit(1, "setup: no builder for Geometry:type %d in %uD", (int)sc->geometry.type, sc->geometry.dim);
    return NULL;
}

int wall_named(const sim_t *s, const char *name)
{
    for (int k = 0; k < s->flow.w.n; ++k)
        if (!strcmp(s->wall_name[k], name)) return k + 1;
    return 0;
}

char *wall_list(const sim_t *s, int longer, char *buf, size_t n)
{
    static const char *move[] = {"fixed", "translating", "turning"};
    size_t k = 0;
    buf[0] = 0;
    for (int i = 0; i < s->flow.w.n && k < n; ++i) {
        const wall_prim *q = &s->flow.w.prim[i];
        k += (size_t)snprintf(buf + k, n - k, "%s%d %s", i ? ", " : "", i + 1, s->wall_name[i]);
        char slip[64];
        if (q->mu_w > 0)
            snprintf(slip, sizeof slip, "Coulomb mu_w %.4g%s", (double)q->mu_w, q->contact ? " on the particles" : "");
        else snprintf(slip, sizeof slip, "%s", q->slip ? "free slip" : "no slip");
        if (longer && k < n)
            k += (size_t)snprintf(buf + k, n - k, " (%s, %s, %s%s)", q->shape == WALL_PLANE ? "plane" : q->outside ? "post" : "cylinder",
                                  slip, move[q->move], q->open_at >= 0 ? ", a gate" : "");
    }
    return buf;
}

void setup_particles(sim_t *s)
{
    setup_builder_of(s->sc)->place(s);
    setup_walls(s);
    if (s->flow_on) setup_stress(s);
}

/* The size key of the scene that sets its particle count with dr, for the
 * too-many-particles error: the drum's radius (and a 3D drum's length), a
 * box's width, height, depth or runout, a container's walls; the one of
 * these most off a lab-sized container (about 5 cm, the shipped scenes
 * 1-16 cm) in log. */
static const char *setup_size_key(const struct scene *sc, double *value)
{
    const struct scene_geometry *g = &sc->geometry;
    const struct {
        const char *key;
        double v;
        int on;
    } k[] = {{"radius", g->radius, g->type == GEOM_DRUM},
             {"length", g->length, g->type == GEOM_DRUM && g->dim == 3},
             {"width", g->width, g->type == GEOM_SHEARBOX || g->type == GEOM_COLUMN},
             {"height", g->height, g->type == GEOM_SHEARBOX || g->type == GEOM_COLUMN},
             {"depth", g->depth, (g->type == GEOM_COLUMN || g->type == GEOM_CONTAINER) && g->dim == 3},
             {"runout", g->runout, g->type == GEOM_COLUMN && g->runout > 0}};
    const char *best = NULL;
    double off = -1;
    for (size_t i = 0; i < sizeof k / sizeof k[0]; ++i) {
        double o = fabs(log10(k[i].v / 0.05)) + 100.0 * scene_key_overridden(sc, "Geometry", k[i].key);
        if (k[i].on && o > off) best = k[i].key, off = o, *value = k[i].v;
    }
    return best;
}

/* The particle count of the scene in O(1), from areas and volumes (within a
 * few per cent), before any lattice index is computed: a tiny dr is refused
 * in no time, and no lround overflows. Exit 2 when it would clearly not fit
 * (setup_alloc checks the exact count later), naming the key the user most
 * likely mistyped: the one a -P override set (dr or a size), else the one
 * further off its usual scale (dr about 1 mm, a container about 5 cm). */
static void setup_check_size(const struct scene *sc)
{
    const struct scene_geometry *g = &sc->geometry;
    double dr = g->dr, nl = ceil(2.0 * g->h_factor - 1e-9), n, ext[3];
    scene_extent(sc, ext);
    if (g->type == GEOM_DRUM) {
        double r = g->radius - 0.5 * dr, H = (2 * g->fill - 1) * g->radius, hr = fmax(-1.0, fmin(1.0, H / r));
        double plane = r * r * (M_PI - acos(hr)) + H * sqrt(fmax(0.0, r * r - H * H)); /* material area */
        double rings = 2 * M_PI * nl * (g->radius + 0.5 * nl * dr) * dr, disc = M_PI * pow(g->radius + nl * dr, 2);
        double nz = g->dim == 3 ? g->length / dr : 1;
        n = nz * (plane + rings) / (dr * dr) + (g->dim == 3 ? 2 * nl * disc / (dr * dr) : 0);
    } else if (g->type == GEOM_CONTAINER) { /* the box around its walls and regions, at most */
        n = (ext[0] / dr + 2 * nl) * (ext[1] / dr + 2 * nl) * (g->dim == 3 ? ext[2] / dr + 2 * nl : 1);
    } else if (g->dim == 3) {
        n = (g->width / dr + 2 * nl) * (g->height / dr + 2 * nl) * (g->depth / dr + 2 * nl);
    } else {
        n = (g->width / dr + 2 * nl) * (g->height / dr + nl);
    }
    double need = n / comm_size() * (double)(part_bytes_per_particle() + 64);
    double have = (double)sysconf(_SC_PHYS_PAGES) * (double)sysconf(_SC_PAGESIZE);
    if (need <= 0.9 * have && n < 1e15) return;
    char where[512], mem[160];
    snprintf(mem, sizeof mem, "%.3g GiB on each of %d rank(s); this machine has %.1f GiB", need / 1073741824.0,
             comm_size(), have / 1073741824.0);
    double size = 0;
    const char *key = setup_size_key(sc, &size);
    int wall_key = g->type == GEOM_CONTAINER && !(key && scene_key_overridden(sc, "Geometry", key));
    /* how far off its usual scale each is, in decades; a -P override first */
    double off_dr = fabs(log10(dr / 1e-3)) + 100.0 * scene_key_overridden(sc, "Geometry", "dr"), off_size = -1;
    if (wall_key)
        off_size = fabs(log10(fmax(ext[0], ext[1]) / 0.05)) + 100.0 * scene_key_overridden(sc, "Container", "walls");
    else if (key)
        off_size = fabs(log10(size / 0.05)) + 100.0 * scene_key_overridden(sc, "Geometry", key);
    char box[96];
    snprintf(box, sizeof box, g->dim == 3 ? "%.3g x %.3g x %.3g m" : "%.3g x %.3g m", ext[0], ext[1], ext[2]);
    if (off_dr >= off_size) /* dr, as before: "Geometry:dr: X m gives about ..." */
        input_error("%s: Geometry:dr: %.3g m gives about %.3g particles in a container %s, %s",
                    scene_key_where(sc, "Geometry", "dr", where, sizeof where), dr, n, box, mem);
    if (wall_key) /* the walls (and regions) span more than they should */
        input_error("%s: Container:walls: walls and regions spanning %s with Geometry:dr %.3g m give about %.3g "
                    "particles, %s", scene_key_where(sc, "Container", "walls", where, sizeof where), box, dr, n, mem);
    input_error("%s: Geometry:%s: %.3g m with Geometry:dr %.3g m gives about %.3g particles, %s",
                scene_key_where(sc, "Geometry", key, where, sizeof where), key, size, dr, n, mem);
}

/* Each module's context from its own keys; setup_contexts puts them
 * together (the walls from the container's builder). */

/* The concentration equation (seg.h): Segregation, Grains, gravity's direction. */
static seg_params seg_params_of(const struct scene *sc)
{
    const struct scene_segregation *g = &sc->segregation;
    seg_params sp;
    memset(&sp, 0, sizeof sp);
    int asym = g->flux == SEG_FLUX_ASYMMETRIC;
    sp.A = (real)(asym ? g->A : 1.0);
    sp.kappa = (real)(asym ? g->kappa : 0.0);
    sp.shear_model = g->model == SEG_MODEL_SHEAR_RATE;
    sp.V = (real)g->V, sp.D = (real)g->D;
    sp.chi_V = (real)g->chi_V, sp.chi_D = (real)g->chi_D;
    sp.d_small = (real)sc->grains.d_small, sp.d_large = (real)sc->grains.d_large;
    const double *gv = sc->physics.gravity;
    double gn = sqrt(gv[0] * gv[0] + gv[1] * gv[1] + gv[2] * gv[2]);
    for (int d = 0; d < 3; ++d) sp.ghat[d] = (real)(gv[d] / gn);
    sp.gdot_yielded = g->shear_rate == SEG_GDOT_YIELDED;
    sp.k_static = stress_yield_k((int)sc->material.yield, (real)sc->material.mu_s);
    return sp;
}

/* The prescribed motion (kin.h): Kinematics. */
static kin_params kin_params_of(const struct scene *sc)
{
    kin_params k;
    memset(&k, 0, sizeof k);
    k.type = (int)sc->kinematics.velocity;
    k.gamma0 = sc->kinematics.gamma0;
    k.omega = 2.0 * M_PI / sc->kinematics.period;
    return k;
}

/* The granular flow (flow.h) but its walls: Material, Physics, Flow, the
 * kernel and the segregation's grains (mu(I)'s d_avg). */
static void flow_ctx_of(const struct scene *sc, const sph_ctx *k, const seg_params *sp, flow_ctx *f)
{
    const struct scene_material *m = &sc->material;
    f->k = *k;
    stress_moduli((real)m->E, (real)m->nu, &f->m.G, &f->m.K);
    f->nu = m->model == MAT_NEWTONIAN ? (real)(m->eta / sc->physics.rho) : R(0.0);
    if (m->model == MAT_NEWTONIAN) f->m.G = 0; /* a fluid: pressure alone, the viscous force apart */
    f->visc_norm = R(1.0) / mom_visc_lattice(k->dim, k->h, k->dr);
    f->p_back = m->model == MAT_NEWTONIAN && sc->flow.background_pressure == FLOW_BACKGROUND_EXCLUDED
                    ? (real)(2 * sc->initial.pressure / (sc->physics.rho * sc->physics.rho))
                    : R(0.0);
    f->m.rho_s = (real)m->rho_s;
    f->m.mu_s = (real)m->mu_s, f->m.mu_d = (real)m->mu_d;
    f->m.I0 = (real)m->I0, f->m.lambda = (real)m->lambda;
    f->m.pr_alpha = f->m.pr_A = f->m.pr_IN1 = R(0.0); /* Material:mu_law regularized */
    if (m->model == MAT_GRANULAR && m->mu_law == MAT_MU_PARTIAL) {
        double IN1, A;
        char where[512];
        if (stress_partial_law(m->mu_s, m->mu_d, m->I0, m->pr_alpha, &IN1, &A))
            input_error("%s: Material:mu_law partial: mu(I) with mu_s %g, mu_d %g, I0 %g has no lower edge of a "
                        "well-posed window in I = 1e-8 to 1e4, so there is nothing to regularise; use "
                        "Material:mu_law regularized",
                        scene_key_where(sc, "Material", "mu_law", where, sizeof where), m->mu_s, m->mu_d, m->I0);
        f->m.pr_alpha = (real)m->pr_alpha, f->m.pr_A = (real)A, f->m.pr_IN1 = (real)IN1;
    }
    f->yield = (int)sc->material.yield;
    f->bed_k = stress_yield_k(f->yield, f->m.mu_s);
    f->rho = (real)sc->physics.rho;
    f->cs = stress_sound_speed(f->m.G, f->m.K, f->rho);
    f->v_stick = (real)(COULOMB_STICK * (double)f->cs); /* a Coulomb wall's sticking speed (wall_coulomb) */
    f->alpha_av = (real)sc->flow.alpha_av;
    f->stab = (int)sc->flow.stabilization;
    f->eta_r = (real)sc->flow.riemann_eta;
    f->bed_alpha = f->stab == STAB_RIEMANN && f->m.G > 0 ? (real)sc->flow.bed_damping : R(0.0);
    f->filter_mls = sc->flow.stress_filter == FLOW_FILTER_MLS;
    f->kgc = (int)sc->flow.gradient_correction;
    f->kgc_det = (real)sc->flow.gradient_correction_det;
    f->pdiff = flow_pdiff_coef(f->stab, (int)sc->flow.riemann_diffusion, (real)sc->flow.delta, f->m.K, f->rho,
                               f->cs, k->h);
    for (int d = 0; d < 3; ++d) f->g[d] = (real)sc->physics.gravity[d];
    f->sp = *sp;
}

void setup_contexts(sim_t *s)
{
    const struct scene *sc = s->sc;
    setup_check_size(sc);
    const struct scene_segregation *g = &sc->segregation;
    s->seg.k = sph_make((int)sc->geometry.dim, (real)(sc->geometry.h_factor * sc->geometry.dr),
                        (real)sc->geometry.dr);
    s->seg.sp = seg_params_of(sc);
    s->seg.scheme = (int)g->scheme;
    s->seg.renorm = g->renormalize;
    s->seg.limiter = (int)g->limiter;
    s->hcsr = g->enabled && g->scheme != SEG_SCHEME_CONSERVATIVE;
    s->kin = kin_params_of(sc);
    s->seg_on = g->enabled;
    s->flow_on = sc->kinematics.velocity == KIN_COMPUTED;

    flow_ctx_of(sc, &s->seg.k, &s->seg.sp, &s->flow);
    s->shift = shift_make(&s->seg.k, (int)sc->flow.shifting, (real)sc->flow.shift_coeff,
                          (real)sc->flow.shift_surface, (int)sc->flow.shift_surface_rule);
    wall_geom *w = &s->flow.w;
    memset(w, 0, sizeof *w);
    w->periodic = (int)sc->geometry.periodic;
    setup_builder_of(sc)->walls(s);
    /* Walls:coulomb_force particles: each Coulomb wall a slot of the contact stage (flow_contact_team) */
    s->flow.contact = 0;
    if (sc->walls.coulomb_force == COULOMB_PARTICLES)
        for (int k = 0; k < w->n; ++k)
            if (w->prim[k].mu_w > 0) {
                if (s->flow.contact == WALL_CONTACT_MAX)
                    input_error("Walls:coulomb_force particles: more than %d Coulomb walls (%s)", WALL_CONTACT_MAX,
                                s->wall_name[k]);
                w->prim[k].contact = ++s->flow.contact;
            }

    step_ctx *st = &s->step_c; /* the driver's per-particle checks (step.h) */
    st->h = s->seg.k.h;
    st->gkin = kin_max_shear_rate(&s->kin);
    st->flow_on = s->flow_on, st->seg_on = s->seg_on;
    st->kin = s->kin;
    st->sp = s->seg.sp;
    st->w = *w;
    st->seg_cap = g->scheme == SEG_SCHEME_CONSERVATIVE && g->limiter == SEG_LIMITER_DONOR;
    st->outlet = sc->outlet.enabled;
    st->outlet_below = sc->outlet.below;
    const double gv[3] = {sc->physics.gravity[0], sc->physics.gravity[1], sc->physics.gravity[2]};
    s->dem = dem_create(sc, (double)s->seg.k.h, (double)s->flow.rho, (double)s->flow.nu, (double)s->flow.m.K, gv);
}
