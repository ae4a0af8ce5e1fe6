/* setup_container.c — Geometry:type container: a container described in the
 * scene (Container:walls, Container:regions; scene.h) built as wall
 * primitives (wall.h) and particles on the square lattice (i + 1/2) dr,
 * (j + 1/2) dr of the built-in scenes.
 *
 * Walls. A segment from a to b is a plane through a whose normal is the
 * left of a -> b (into the material), bounded along a -> b: its dummies are
 * the lattice sites that lie behind it by at most nl = ceil(2h/dr) layers
 * and whose projection falls on it, past an end by nl dr where another
 * segment joins there (the corner), not past a free end or an end where
 * only a gate joins (an opening stays open). A cylinder's are nl rings outside its radius; a post's (a
 * cylinder with the material outside) nl rings inside its radius (fewer in a post under nl dr). A site
 * that two walls want goes to the one it lies further behind, a gate's last
 * (wall_id_at's rule), so a dummy of a permanent wall stays when a gate
 * opens.
 *
 * Material. The sites inside a region that are not dummies; a region site
 * behind a wall, or inside two regions, is an input error. A region `fill`
 * is every site inside the walls below its level, where inside means on the
 * material's side of the nearest wall.
 *
 * 3D: the plane extruded along z over nz = round(depth/dr) lattice planes,
 * closed by end walls end_lo (z = 0) and end_hi (z = nz dr), nl planes of dummies
 * each, under every site inside the walls (inside a cylinder: the drum's
 * polar discs instead); a wall's dummy column runs through them, a corner
 * site going to the wall it lies further behind. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "core/error.h"
#include "mpi/comm.h"
#include "setup.h"

/* The lattice of the plane: sites (i0 + i + 1/2) dr, (j0 + j + 1/2) dr. */
typedef struct ctr_lattice {
    double dr;
    long i0, j0, ni, nj, nl, nz; /* origin, size, dummy layers, z planes (1 in 2D) */
    int nw;                      /* the scene's walls: primitives 1..nw (the end walls follow in 3D) */
    unsigned *ent;               /* ent[k]: the Container:walls entry of primitive k + 1 */
    int *site;                   /* per site: > 0 wall id of a dummy, < 0 -(region + 1) of material, 0 empty */
} ctr_lattice;

static double site_x(const ctr_lattice *L, long i) { return (L->i0 + i + 0.5) * L->dr; }
static double site_y(const ctr_lattice *L, long j) { return (L->j0 + j + 0.5) * L->dr; }

/* Depth behind cylinder q (wall_prim_depth, in double, as wall_beyond):
 * radially out of a drum, radially into a post. */
static double ctr_cyl_depth(const wall_prim *q, double x, double y)
{
    double d = hypot(x - q->p[0], y - q->p[1]) - q->radius;
    return q->outside ? -d : d;
}

/* Depth behind primitive q (wall_prim_depth, in double) and whether the
 * point falls within its extent. */
static double ctr_depth(const wall_prim *q, double x, double y, int *within)
{
    if (q->shape == WALL_CYLINDER) {
        *within = 1;
        return ctr_cyl_depth(q, x, y);
    }
    double dx = x - q->p[0], dy = y - q->p[1], s = q->t[0] * dx + q->t[1] * dy;
    *within = s >= q->t_lo && s <= q->t_hi;
    return -(q->n[0] * dx + q->n[1] * dy);
}

/* The walls' geometry is held in the build's precision (wall_prim: float
 * in the single build), so a site that lies on a wall's line (the hopper's
 * 45-degree walls pass through lattice sites) is found a rounding error
 * behind it or in front. Within a few units of the last place of the
 * coordinates a site counts as on the material's side, in either build:
 * the single build then lays out what the double build does (inputs/
 * hopper_2d.yml stopped with "reaches behind the walls" there). */
static double ctr_on_line(const ctr_lattice *L, double x, double y)
{
    return 8.0 * (double)REAL_EPS * (fabs(x) + fabs(y) + L->dr);
}

/* The wall whose dummy the site (x, y) is, or 0: behind it by more than
 * ctr_on_line and at most nl dr within its extent, by wall_id_at's
 * preference. */
static int ctr_dummy_wall(const sim_t *s, const ctr_lattice *L, double x, double y, double *depth)
{
    const double tol = ctr_on_line(L, x, y);
    int best = 0, best_claim = 0;
    double best_d = 0;
    for (int k = 0; k < L->nw; ++k) {
        const wall_prim *q = &s->flow.w.prim[k];
        if (q->shape == WALL_CYLINDER) continue; /* its dummies are rings (ctr_place) */
        int within;
        double d = ctr_depth(q, x, y, &within);
        if (!within || !(d > tol) || d > L->nl * L->dr) continue;
        if (!best || q->claim > best_claim || (q->claim == best_claim && d > best_d))
            best = k + 1, best_claim = q->claim, best_d = d;
    }
    *depth = best_d;
    return best;
}

/* A scene wall's segment ends, for the inside test (the extent less any
 * corner overlap). */
typedef struct ctr_seg {
    double ax, ay, bx, by;
} ctr_seg;

/* Inside the walls: on the material's side of the nearest wall (of the
 * permanent ones and the gates) or on its line (ctr_on_line), ties at a
 * shared end broken towards inside. */
static int ctr_inside(const sim_t *s, const ctr_lattice *L, const ctr_seg *seg, double x, double y)
{
    double best = INFINITY, sign = -1;
    for (int k = 0; k < L->nw; ++k) {
        const wall_prim *q = &s->flow.w.prim[k];
        double dist, depth;
        if (q->shape == WALL_CYLINDER) {
            depth = ctr_cyl_depth(q, x, y);
            dist = fabs(depth);
        } else {
            const ctr_seg *g = &seg[k];
            double ex = g->bx - g->ax, ey = g->by - g->ay, l2 = ex * ex + ey * ey;
            double u = fmax(0.0, fmin(1.0, ((x - g->ax) * ex + (y - g->ay) * ey) / l2));
            dist = hypot(x - g->ax - u * ex, y - g->ay - u * ey);
            depth = -(q->n[0] * (x - g->ax) + q->n[1] * (y - g->ay));
        }
        if (dist < best - 1e-12 * L->dr) best = dist, sign = depth;
        else if (dist <= best + 1e-12 * L->dr && depth < sign) sign = depth; /* a tie: inside wins */
    }
    return sign < 0 || (sign < ctr_on_line(L, x, y) && best < ctr_on_line(L, x, y));
}

/* Within dr/2 of a cylinder, on either side (r in (R - dr/2, R + dr/2]):
 * its first ring of dummies lies at R + dr/2 (a post's at R - dr/2), so
 * such a site holds no material (as in the drum), but an end wall covers
 * it in 3D. */
static int ctr_cylinder_band(const sim_t *s, const ctr_lattice *L, double x, double y)
{
    for (int k = 0; k < L->nw; ++k) {
        const wall_prim *q = &s->flow.w.prim[k];
        if (q->shape != WALL_CYLINDER) continue;
        double r = hypot(x - q->p[0], y - q->p[1]);
        if (r > q->radius - 0.5 * L->dr && r <= q->radius + 0.5 * L->dr) return 1;
    }
    return 0;
}

/* Within a cylinder or dr/2 past it (r <= R + dr/2): in 3D its end walls
 * there are polar discs, its rings continued inward to the axis (as the
 * drum's: a lattice disc would leave holes at r = R). Not a post: the end
 * walls under the material around it are lattice planes, and its own rings
 * run through the end planes. */
static int ctr_in_cylinder(const sim_t *s, const ctr_lattice *L, double x, double y)
{
    for (int k = 0; k < L->nw; ++k) {
        const wall_prim *q = &s->flow.w.prim[k];
        if (q->shape == WALL_CYLINDER && !q->outside && hypot(x - q->p[0], y - q->p[1]) <= q->radius + 0.5 * L->dr)
            return 1;
    }
    return 0;
}

/* Does region r hold the site (x, y)? */
static int ctr_in_region(const sim_t *s, const ctr_lattice *L, const ctr_seg *seg, const struct scene_region *r,
                         double x, double y)
{
    switch (r->shape) {
    case REGION_BOX: return x >= r->lo[0] && x < r->hi[0] && y >= r->lo[1] && y < r->hi[1];
    case REGION_SECTOR: {
        double dx = x - r->centre[0], dy = y - r->centre[1], rr = hypot(dx, dy);
        if (rr < r->r_in || rr >= r->r_out) return 0;
        double a = atan2(dy, dx) * 180.0 / M_PI, span = fmod(fmod(r->to_deg - r->from_deg, 360.0) + 360.0, 360.0);
        double rel = fmod(fmod(a - r->from_deg, 360.0) + 360.0, 360.0);
        return span == 0 ? 1 : rel < span; /* a full turn when to - from is a multiple of 360 */
    }
    case REGION_COLUMN: /* its section's strip here; ctr_in_column cuts it along z (ctr_place) */
        return fabs(x - r->centre[0]) < r->r_out && y < r->level && (!r->has_floor || y >= r->floor) &&
               ctr_inside(s, L, seg, x, y);
    default: /* a fill of a container periodic along x or y stays within the period */
        if ((s->sc->geometry.periodic & PERIODIC_X) && !(x > 0 && x < (double)s->flow.w.period[0])) return 0;
        if ((s->sc->geometry.periodic & PERIODIC_Y) && !(y > 0 && y < (double)s->flow.w.period[1])) return 0;
        return y < r->level && (!r->has_floor || y >= r->floor) && ctr_inside(s, L, seg, x, y);
    }
}

/* Does the material site (x, y) of region c (< 0, as L->site) hold material
 * in the z plane at z? Every plane but a column's outside its radius. */
static int ctr_in_column(const struct scene_container *k, int c, double x, double z)
{
    const struct scene_region *r = &k->regions[-c - 1];
    return r->shape != REGION_COLUMN || hypot(x - r->centre[0], z - r->centre[1]) < r->r_out;
}

/* The motion of scene wall w onto primitive q. */
static void ctr_motion(wall_prim *q, const struct scene_wall *w)
{
    if (w->motion == CWALL_TRANSLATING) {
        q->move = WALL_TRANSLATE;
        for (int d = 0; d < 3; ++d) q->u[d] = (real)w->velocity[d];
    } else if (w->motion == CWALL_TURNING) {
        q->move = WALL_ROTATE;
        q->omega = w->rpm * 2.0 * M_PI / 60.0 * (w->direction == ROT_CLOCKWISE ? -1.0 : 1.0);
        q->c[0] = (real)w->centre[0], q->c[1] = (real)w->centre[1];
    }
}

void container_walls(sim_t *s)
{
    const struct scene *sc = s->sc;
    const struct scene_container *k = &sc->container;
    const double dr = sc->geometry.dr, nl = ceil(2.0 * sc->geometry.h_factor - 1e-9);
    const struct scene_wall *ends = NULL; /* a 3D container's end walls, when listed (shape ends) */
    for (unsigned i = 0; i < k->walls_count; ++i) {
        const struct scene_wall *w = &k->walls[i];
        wall_prim *q;
        const int slip = (int)w->slip;
        if (w->shape == CWALL_ENDS) {
            ends = w;
            continue;
        }
        if (w->shape == CWALL_CYLINDER) {
            q = wall_add_prim(s, w->name, WALL_CYLINDER, slip, 1, WALL_CLAIM_SIDE + (int)w->priority);
            q->p[0] = (real)w->centre[0], q->p[1] = (real)w->centre[1], q->radius = (real)w->radius;
            q->outside = w->material == CWALL_OUTSIDE;
        } else {
            double ex = w->to[0] - w->from[0], ey = w->to[1] - w->from[1], len = hypot(ex, ey);
            q = wall_plane(s, w->name, slip, !w->gate, w->gate ? WALL_CLAIM_LAST : WALL_CLAIM_SIDE + (int)w->priority, w->from[0],
                           w->from[1], 0, -ey / len, ex / len, 0);
            q->t[0] = (real)(ex / len), q->t[1] = (real)(ey / len);
            /* the extent: the segment, past an end by nl dr where another segment joins */
            int join_a = 0, join_b = 0;
            for (unsigned j = 0; j < k->walls_count; ++j) {
                const struct scene_wall *o = &k->walls[j];
                if (j == i || o->shape != CWALL_SEGMENT || (o->gate && !w->gate))
                    continue; /* a permanent wall does not reach under a gate: the opening stays clear */
                for (int e = 0; e < 2; ++e) {
                    const double *pt = e ? o->to : o->from;
                    join_a |= hypot(pt[0] - w->from[0], pt[1] - w->from[1]) < 1e-9 * dr;
                    join_b |= hypot(pt[0] - w->to[0], pt[1] - w->to[1]) < 1e-9 * dr;
                }
            }
            q->t_lo = (real)(join_a ? -nl * dr : 0.0);
            q->t_hi = (real)(join_b ? len + nl * dr : len);
            if (w->gate) q->open_at = w->open_at;
        }
        ctr_motion(q, w);
    }
    /* a periodic axis: the period is Geometry:width along x, Geometry:height along y, Geometry:depth along z,
     * from 0, whole dr */
    s->flow.w.period[0] = (real)((double)lround(sc->geometry.width / dr) * dr);
    s->flow.w.period[1] = (real)((double)lround(sc->geometry.height / dr) * dr);
    s->flow.w.period[2] = (real)((double)lround(sc->geometry.depth / dr) * dr);
    if (sc->geometry.dim == 3 && !(sc->geometry.periodic & PERIODIC_Z)) {
        /* the end walls: as the entry of shape ends, else fixed, slipping as Walls:end_slip */
        double D = (double)lround(sc->geometry.depth / dr) * dr;
        const int ss = ends ? (int)ends->slip : scene_end_slip(sc);
        wall_prim *lo = wall_plane(s, "end_lo", ss, 1, WALL_CLAIM_SIDE, 0, 0, 0, 0, 0, 1);
        wall_prim *hi = wall_plane(s, "end_hi", ss, 1, WALL_CLAIM_SIDE, 0, 0, D, 0, 0, -1);
        if (ends) ctr_motion(lo, ends), ctr_motion(hi, ends);
    }
}

/* Where region K (0-based) was given, for an input error. */
static const char *ctr_where(const struct scene *sc, const char *list, unsigned K, char *buf, size_t n)
{
    char key[48];
    snprintf(key, sizeof key, "%s:%u", list, K + 1);
    return scene_key_where(sc, "Container", key, buf, n);
}

/* A wall that no other wall joins must have material within 2h of one of
 * its dummies at the start (a cylinder: inside it or within 2h): a lone
 * wall far from everything is a misplaced one (a coordinate in mm, a sign).
 * A wall joined to another may stand apart (the end wall of a runout). */
static void ctr_check_near(const sim_t *s, const ctr_lattice *L, const ctr_seg *seg)
{
    const double h2 = 2 * s->sc->geometry.h_factor * L->dr;
    const long reach = (long)ceil(h2 / L->dr);
    char *near = calloc((size_t)L->nw + 1, 1);
    if (!near) error_exit(1, "out of memory");
    for (long j = 0; j < L->nj; ++j) /* each material site marks the walls of the dummies around it */
        for (long i = 0; i < L->ni; ++i) {
            if (L->site[j * L->ni + i] >= 0) continue;
            double x = site_x(L, i), y = site_y(L, j);
            for (int k = 0; k < L->nw; ++k) {
                const wall_prim *q = &s->flow.w.prim[k];
                /* a drum: material inside it or within 2h; a post: within 2h of it */
                double d = q->shape == WALL_CYLINDER ? ctr_cyl_depth(q, x, y) : INFINITY;
                if (q->outside ? fabs(d) <= h2 : d <= h2) near[k + 1] = 1;
            }
            for (long dj = -reach; dj <= reach; ++dj)
                for (long di = -reach; di <= reach; ++di) {
                    long jj = j + dj, ii = i + di;
                    if (jj < 0 || jj >= L->nj || ii < 0 || ii >= L->ni || hypot(di, dj) * L->dr > h2) continue;
                    int c = L->site[jj * L->ni + ii];
                    if (c > 0) near[c] = 1;
                }
        }
    char where[512];
    for (int k = 0; k < L->nw; ++k) {
        const wall_prim *q = &s->flow.w.prim[k];
        double len = hypot(seg[k].bx - seg[k].ax, seg[k].by - seg[k].ay);
        int joined = q->shape == WALL_PLANE && (q->t_lo < 0 || q->t_hi > len + 1e-9 * L->dr);
        if (!near[k + 1] && !joined)
            input_error("%s: Container:walls:%u: no material within 2h = %.4g m of it at the start and no wall joins "
                        "it: is it where it should be?", ctr_where(s->sc, "walls", L->ent[k], where, sizeof where),
                        L->ent[k] + 1, h2);
    }
    free(near);
}

/* The signed area (m^2) that the scene's segments sweep around the mean of
 * their ends, sum (a - c) x (b - c) / 2: > 0 when they go counter-clockwise
 * (the material on the left of each from -> to, inside them), < 0 when
 * clockwise. The names of the segments with that mean on their right go
 * into names (comma separated); *first is the entry of the first one. */
static double ctr_signed_area(const sim_t *s, const ctr_lattice *L, const ctr_seg *seg, char *names, size_t n,
                              unsigned *first)
{
    double cx = 0, cy = 0, area = 0;
    int m = 0;
    names[0] = 0;
    *first = 0;
    for (int k = 0; k < L->nw; ++k)
        if (s->flow.w.prim[k].shape == WALL_PLANE) cx += seg[k].ax + seg[k].bx, cy += seg[k].ay + seg[k].by, m += 2;
    if (m < 4) return 0; /* one segment sweeps no area */
    cx /= m, cy /= m;
    size_t used = 0;
    for (int k = 0; k < L->nw; ++k) {
        if (s->flow.w.prim[k].shape != WALL_PLANE) continue;
        double c = (seg[k].ax - cx) * (seg[k].by - cy) - (seg[k].bx - cx) * (seg[k].ay - cy);
        area += 0.5 * c;
        if (c < 0 && used < n) {
            if (!used) *first = L->ent[k];
            used += (size_t)snprintf(names + used, n - used, "%s%s", used ? ", " : "", s->wall_name[k]);
        }
    }
    return area;
}

/* A region site behind the walls: when the segments go clockwise (the
 * material on the right of each from -> to), the order is the mistake, not
 * the region, and the error says so, naming the walls. When they go
 * counter-clockwise but some turn their right to the middle of the walls'
 * ends, hint (into hint[n], else empty) that those may be reversed. */
static void ctr_check_order(const sim_t *s, const ctr_lattice *L, const ctr_seg *seg, char *hint, size_t n)
{
    char names[400], where[512];
    unsigned first;
    double area = ctr_signed_area(s, L, seg, names, sizeof names, &first);
    hint[0] = 0;
    if (area < -1e-6 * L->dr * L->dr)
        input_error("%s: Container:walls: the walls go clockwise, with the material on their right (%s): a wall "
                    "keeps the material on its left going from -> to, so a container lists its walls "
                    "counter-clockwise; swap each one's from and to", ctr_where(s->sc, "walls", first, where,
                    sizeof where), names);
    if (area > 1e-6 * L->dr * L->dr && names[0])
        snprintf(hint, n, " (wall(s) %s go against the others, with the middle of the walls on their right: a "
                 "wall keeps the material on its left going from -> to; swap from and to where it belongs on the "
                 "other side)", names);
}

/* The first wall that the ray from (px, py) along the unit vector (rx, ry)
 * meets (its 1-based primitive id, 0 if none), its distance, and whether it
 * meets the wall's front (the material's side: r . n < 0, n into the
 * material) or its back. Segments within their ends (a shared end meets
 * either), cylinders at their first crossing; gates count (at t = 0). */
static int ctr_ray(const sim_t *s, const ctr_lattice *L, const ctr_seg *seg, double px, double py, double rx,
                   double ry, int *front)
{
    int hit = 0;
    double best = INFINITY;
    *front = 0;
    for (int k = 0; k < L->nw; ++k) {
        const wall_prim *q = &s->flow.w.prim[k];
        double t = INFINITY, nx, ny;
        if (q->shape == WALL_CYLINDER) {
            double dx = px - q->p[0], dy = py - q->p[1], b = dx * rx + dy * ry;
            double disc = b * b - (dx * dx + dy * dy - (double)q->radius * q->radius);
            if (disc < 0) continue;
            double t0 = -b - sqrt(disc), t1 = -b + sqrt(disc);
            t = t0 > 0 ? t0 : t1 > 0 ? t1 : INFINITY;
            nx = (px + t * rx - q->p[0]) / q->radius, ny = (py + t * ry - q->p[1]) / q->radius; /* radially out */
            if (!q->outside) nx = -nx, ny = -ny; /* a drum's material is inside */
        } else {
            double ex = seg[k].bx - seg[k].ax, ey = seg[k].by - seg[k].ay, den = rx * ey - ry * ex;
            if (fabs(den) < 1e-12 * hypot(ex, ey)) continue; /* parallel */
            double ax = seg[k].ax - px, ay = seg[k].ay - py, u = (ax * ry - ay * rx) / den;
            if (u < -1e-9 || u > 1 + 1e-9) continue;
            t = (ax * ey - ay * ex) / den;
            nx = q->n[0], ny = q->n[1];
        }
        /* a site on the wall's line (a 45-degree wall through lattice sites) meets it at t = 0 going into
         * it, not going away from it */
        double rn = rx * nx + ry * ny, eps = 1e-9 * L->dr;
        if (t > -eps && (t > eps || rn < 0) && t < best) best = t, hit = k + 1, *front = rn < 0;
    }
    return hit;
}

/* The two ends of different segments nearest to (x, y) that join no other
 * segment, as "NAME's (x, y) and NAME's (x, y) m, D m apart" in b (empty
 * when there are not two). */
static void ctr_free_ends(const sim_t *s, const ctr_lattice *L, const ctr_seg *seg, double x, double y, char *b,
                          size_t n)
{
    int kb[2] = {-1, -1};
    double best[2] = {INFINITY, INFINITY}, px[2] = {0, 0}, py[2] = {0, 0};
    b[0] = 0;
    for (int k = 0; k < L->nw; ++k) {
        if (s->flow.w.prim[k].shape != WALL_PLANE) continue;
        for (int e = 0; e < 2; ++e) {
            double ex = e ? seg[k].bx : seg[k].ax, ey = e ? seg[k].by : seg[k].ay;
            int joined = 0;
            for (int o = 0; o < L->nw && !joined; ++o)
                if (o != k && s->flow.w.prim[o].shape == WALL_PLANE)
                    joined = hypot(seg[o].ax - ex, seg[o].ay - ey) < 1e-9 * L->dr ||
                             hypot(seg[o].bx - ex, seg[o].by - ey) < 1e-9 * L->dr;
            double d = hypot(ex - x, ey - y);
            if (joined) continue;
            if (d < best[0]) {
                if (kb[0] != k) best[1] = best[0], kb[1] = kb[0], px[1] = px[0], py[1] = py[0];
                best[0] = d, kb[0] = k, px[0] = ex, py[0] = ey;
            } else if (d < best[1] && k != kb[0]) {
                best[1] = d, kb[1] = k, px[1] = ex, py[1] = ey;
            }
        }
    }
    if (kb[1] >= 0)
        snprintf(b, n, "; the wall ends nearest to it that join no other wall: %s's (%.6g, %.6g) and %s's (%.6g, "
                 "%.6g) m, %.3g m apart", s->wall_name[kb[0]], px[0], py[0], s->wall_name[kb[1]], px[1], py[1],
                 hypot(px[0] - px[1], py[0] - py[1]));
}

/* Material at the start that no wall holds where the scene meant it to be
 * (warnings, one per region and kind; the run goes on): a site of a fill
 * with no wall across gravity on one side (a fill above a wall's top stands
 * free and spills; below an opening or in a gap between a wall and a gate
 * it falls at once), or any region's site that meets the back of a wall
 * first along or across gravity (behind a gate, outside the container).
 * A periodic axis holds what it runs along. */
static void ctr_check_held(const sim_t *s, const ctr_lattice *L, const ctr_seg *seg)
{
    const struct scene *sc = s->sc;
    const double *g = sc->physics.gravity, gl = hypot(g[0], g[1]);
    if (!(gl > 0)) return; /* gravity along z: nothing falls in the plane */
    const double dx = g[0] / gl, dy = g[1] / gl; /* down */
    const double dir[4][2] = {{dx, dy}, {-dx, -dy}, {-dy, dx}, {dy, -dx}}; /* down, up, across both ways */
    const unsigned per = sc->geometry.periodic;
    const unsigned nr = sc->container.regions_count;
    long *n_free = calloc(nr, sizeof *n_free), *n_back = calloc(nr, sizeof *n_back);
    double (*at)[4] = calloc(nr, sizeof *at); /* the first free site (x, y), the first behind (x, y) */
    int *back_wall = calloc(nr, sizeof *back_wall);
    if (!n_free || !n_back || !at || !back_wall) error_exit(1, "out of memory");
    for (long j = 0; j < L->nj; ++j)
        for (long i = 0; i < L->ni; ++i) {
            int c = L->site[j * L->ni + i];
            if (c >= 0) continue;
            unsigned r = (unsigned)(-c - 1);
            double x = site_x(L, i), y = site_y(L, j);
            int free_side = 0, back = 0;
            for (int d = 0; d < 4 && !back; ++d) {
                int front, w = ctr_ray(s, L, seg, x, y, dir[d][0], dir[d][1], &front);
                int along_period = ((per & PERIODIC_X) && fabs(dir[d][0]) > 1e-9) ||
                                   ((per & PERIODIC_Y) && fabs(dir[d][1]) > 1e-9);
                if (w && !front) back = w;
                else if (!w && d >= 2 && !along_period) free_side = 1;
            }
            if (back && !n_back[r]++) at[r][2] = x, at[r][3] = y, back_wall[r] = back;
            if (!back && free_side && sc->container.regions[r].shape == REGION_FILL && !n_free[r]++)
                at[r][0] = x, at[r][1] = y;
        }
    double top = -INFINITY; /* the highest wall end, up against gravity */
    for (int k = 0; k < L->nw; ++k) {
        const wall_prim *q = &s->flow.w.prim[k];
        if (q->shape == WALL_CYLINDER)
            top = fmax(top, -(q->p[0] * dx + q->p[1] * dy) + q->radius);
        else
            top = fmax(top, fmax(-(seg[k].ax * dx + seg[k].ay * dy), -(seg[k].bx * dx + seg[k].by * dy)));
    }
    char where[512];
    for (unsigned r = 0; r < nr; ++r) {
        if (n_free[r]) {
            double h = -(at[r][0] * dx + at[r][1] * dy);
            char ends[256] = "";
            if (h <= top) ctr_free_ends(s, L, seg, at[r][0], at[r][1], ends, sizeof ends);
            warning("%s: Container:regions:%u: %ld of its sites have no wall beside them across gravity at the start "
                    "(the first at (%.6g, %.6g) m): %s%s; lower its level or close the walls", ctr_where(sc, "regions",
                    r, where, sizeof where), r + 1, n_free[r], at[r][0], at[r][1],
                    h > top ? "the fill rises above the walls' highest end and stands free on top of them, spilling "
                              "at t = 0"
                            : "the fill reaches past a wall that ends lower, or into an opening or a gap between "
                              "walls (a gate that does not meet its neighbours), and falls or spills at t = 0",
                    ends);
        }
        if (n_back[r]) {
            const int w = back_wall[r];
            warning("%s: Container:regions:%u: %ld of its sites lie behind wall %s at the start (the first at "
                    "(%.6g, %.6g) m: it meets that wall's back first, along or across gravity)%s", ctr_where(sc,
                    "regions", r, where, sizeof where), r + 1, n_back[r], s->wall_name[w - 1], at[r][2], at[r][3],
                    s->flow.w.prim[w - 1].open_at >= 0 ? ": material below or behind a gate, outside what it closes"
                                                       : ": material outside the container");
        }
    }
    free(n_free), free(n_back), free(at), free(back_wall);
}

/* Classify every site of the plane (L->site); exits 2 on overlapping
 * regions, a region reaching behind a wall or holding no site, and a wall
 * with no dummy. */
static void ctr_classify(const sim_t *s, ctr_lattice *L, const ctr_seg *seg)
{
    const struct scene *sc = s->sc;
    const struct scene_container *k = &sc->container;
    char where[512];
    long *held = calloc(k->regions_count, sizeof *held), *dums = calloc((size_t)L->nw + 1, sizeof *dums);
    if (!held || !dums) error_exit(1, "out of memory");
    for (long j = 0; j < L->nj; ++j)
        for (long i = 0; i < L->ni; ++i) {
            double x = site_x(L, i), y = site_y(L, j), depth;
            int reg = -1, w = ctr_dummy_wall(s, L, x, y, &depth);
            for (unsigned r = 0; r < k->regions_count; ++r) {
                if (!ctr_in_region(s, L, seg, &k->regions[r], x, y)) continue;
                if (reg >= 0)
                    input_error("%s: Container:regions:%u: overlaps region %d at (%.6g, %.6g) m",
                                ctr_where(sc, "regions", r, where, sizeof where), r + 1, reg + 1, x, y);
                reg = (int)r;
            }
            if (reg >= 0 && !w && ctr_inside(s, L, seg, x, y) && ctr_cylinder_band(s, L, x, y))
                reg = -1; /* too near a cylinder's first ring: empty */
            if (reg >= 0 && (w || !ctr_inside(s, L, seg, x, y))) {
                char hint[600];
                ctr_check_order(s, L, seg, hint, sizeof hint); /* walls listed clockwise: say that */
                input_error("%s: Container:regions:%d: reaches behind the walls at (%.6g, %.6g) m%s%s%s",
                            ctr_where(sc, "regions", (unsigned)reg, where, sizeof where), reg + 1, x, y,
                            w ? ", into the dummies of wall " : "", w ? s->wall_name[w - 1] : "", hint);
            }
            for (int a = 0; a < 2; ++a) {
                double per = (double)s->flow.w.period[a], xa = a ? y : x;
                if (!((s->sc->geometry.periodic >> a & 1) && (w || reg >= 0) && !(xa > 0 && xa < per))) continue;
                if (w)
                    input_error("%s: Container:walls:%u: reaches past the period [0, %.6g) m of the periodic %c axis "
                                "(at %c = %.6g m); its images continue it", ctr_where(sc, "walls", L->ent[w - 1], where,
                                sizeof where), L->ent[w - 1] + 1, per, "xy"[a], "xy"[a], xa);
                input_error("%s: Container:regions:%d: reaches past the period [0, %.6g) m of the periodic %c axis (at "
                            "%c = %.6g m)", ctr_where(sc, "regions", (unsigned)reg, where, sizeof where), reg + 1, per,
                            "xy"[a], "xy"[a], xa);
            }
            L->site[j * L->ni + i] = w ? w : reg >= 0 ? -(reg + 1) : 0;
            if (reg >= 0) held[reg]++;
            dums[w]++;
        }
    for (unsigned r = 0; r < k->regions_count; ++r)
        if (!held[r])
            input_error("%s: Container:regions:%u: holds no lattice site of spacing Geometry:dr = %.4g m inside the "
                        "walls", ctr_where(sc, "regions", r, where, sizeof where), r + 1, L->dr);
    for (int w = 1; w <= L->nw; ++w)
        if (!dums[w] && s->flow.w.prim[w - 1].shape != WALL_CYLINDER) /* a cylinder's are rings */
            input_error("%s: Container:walls:%u: has no dummy particle (another wall lies over it)",
                        ctr_where(sc, "walls", L->ent[w - 1], where, sizeof where), L->ent[w - 1] + 1);
    ctr_check_near(s, L, seg);
    ctr_check_held(s, L, seg);
    free(held);
    free(dums);
}

/* Place the particles of the classified lattice (p NULL: count only);
 * material first (by row, then z plane, then column, as the built-in
 * column), then the dummies; returns their number and the material's. */
static size_t ctr_place(sim_t *s, particles_t *p, const ctr_lattice *L, const ctr_seg *seg, size_t *n_mat,
                        double *top)
{
    const struct scene_container *k = &s->sc->container;
    const int d3 = s->sc->geometry.dim == 3;
    const double dr = L->dr, vol = d3 ? dr * dr * dr : dr * dr;
    const long nl = d3 && !(s->sc->geometry.periodic & PERIODIC_Z) ? L->nl : 0, nz = L->nz; /* end-wall layers */
    const int zlo = L->nw + 1, zhi = L->nw + 2; /* the end walls' ids in 3D */
    size_t n = 0;
    *top = -INFINITY;
    for (long j = 0; j < L->nj; ++j)
        for (long q = 0; q < nz; ++q)
            for (long i = 0; i < L->ni; ++i) {
                int c = L->site[j * L->ni + i];
                if (c >= 0 || !ctr_in_column(k, c, site_x(L, i), (q + 0.5) * dr)) continue;
                double y = site_y(L, j);
                if (p) setup_put(p, n, site_x(L, i), y, d3 ? (q + 0.5) * dr : 0, KIND_MATERIAL, vol, k->regions[-c - 1].C);
                *top = fmax(*top, y + 0.5 * dr);
                n++;
            }
    *n_mat = n;
    for (long j = 0; j < L->nj; ++j)
        for (long i = 0; i < L->ni; ++i) {
            int c = L->site[j * L->ni + i];
            double x = site_x(L, i), y = site_y(L, j), depth = 0;
            if (c <= 0 && !(nl && ctr_inside(s, L, seg, x, y) && !ctr_in_cylinder(s, L, x, y)))
                continue; /* no dummy here (inside a cylinder: its polar end discs, below) */
            if (c > 0) ctr_dummy_wall(s, L, x, y, &depth);
            for (long q = -nl; q < nz + nl; ++q) {
                int w = c, beyond = q < 0 || q >= nz;
                if (c <= 0 && !beyond) continue; /* inside: the end walls' planes only */
                if (beyond) { /* an end wall's, or a corner: the wall it lies further behind */
                    double dz = (q < 0 ? -q - 0.5 : q - nz + 0.5) * dr;
                    if (c <= 0 || dz > depth) w = q < 0 ? zlo : zhi;
                }
                if (p) {
                    setup_put(p, n, x, y, d3 ? (q + 0.5) * dr : 0, KIND_DUMMY, vol, 0);
                    setup_put_wall(p, n, w);
                }
                n++;
            }
        }
    /* each cylinder's nl rings of dummies at radii R + (l + 1/2) dr, round(2 pi r / dr) each (as the
     * drum), in every z plane; beyond the end planes also the rings continued inward to the axis (the
     * end walls' polar discs), a corner going to the wall it lies further behind. A post's nl rings
     * lie at R - (l + 1/2) dr, those with radius > 0, in every plane (its end-plane corners alike). */
    for (int k = 0; k < L->nw; ++k) {
        const wall_prim *cq = &s->flow.w.prim[k];
        if (cq->shape != WALL_CYLINDER) continue;
        long l_axis = (long)floor(-cq->radius / dr - 0.5) + 1; /* the innermost ring with radius > 0 */
        long l_end = cq->outside ? (long)fmin((double)L->nl, floor(cq->radius / dr - 0.5) + 1) : L->nl;
        for (long q = -nl; q < nz + nl; ++q)
            for (long l = !cq->outside && (q < 0 || q >= nz) ? l_axis : 0; l < l_end; ++l) {
                double r = cq->outside ? cq->radius - (l + 0.5) * dr : cq->radius + (l + 0.5) * dr;
                long m = lround(2 * M_PI * r / dr);
                if (m < 1) m = 1;
                for (long a = 0; a < m; ++a, ++n)
                    if (p) {
                        double x = cq->p[0] + r * cos(2 * M_PI * a / m), y = cq->p[1] + r * sin(2 * M_PI * a / m);
                        double z = d3 ? (q + 0.5) * dr : 0;
                        int w = k + 1;
                        if (q < 0 || q >= nz) { /* beyond an end: the wall it lies further behind, by the
                                                 * arithmetic of wall_id_at (the drum's own rule) */
                            const real X[3] = {(real)x, (real)y, (real)z};
                            int e = q < 0 ? zlo : zhi;
                            if (wall_prim_depth(&s->flow.w.prim[e - 1], X) > wall_prim_depth(cq, X)) w = e;
                        }
                        setup_put(p, n, x, y, z, KIND_DUMMY, vol, 0);
                        setup_put_wall(p, n, w);
                    }
            }
    }
    return n;
}

void container_place(sim_t *s)
{
    const struct scene *sc = s->sc;
    const struct scene_container *k = &sc->container;
    ctr_lattice L;
    memset(&L, 0, sizeof L);
    L.dr = sc->geometry.dr;
    L.nl = (long)ceil(2.0 * sc->geometry.h_factor - 1e-9);
    L.nz = sc->geometry.dim == 3 ? lround(sc->geometry.depth / L.dr) : 1;
    ctr_seg *seg = calloc(k->walls_count, sizeof *seg);
    L.ent = calloc(k->walls_count, sizeof *L.ent);
    if (!seg || !L.ent) error_exit(1, "out of memory");
    /* the lattice: the walls' box, and the regions' boxes, with nl + 1 sites to spare */
    for (unsigned i = 0; i < k->walls_count; ++i) {
        const struct scene_wall *w = &k->walls[i];
        if (w->shape == CWALL_ENDS) continue; /* the end walls of 3D: no primitive of its own */
        L.ent[L.nw] = i;
        seg[L.nw++] = (ctr_seg){w->from[0], w->from[1], w->to[0], w->to[1]};
    }
    double lo[2], hi[2]; /* the walls' and the regions' box (a fill may rise above the walls) */
    scene_container_box(k, lo, hi);
    char where[512];
    for (int a = 0; a < 2; ++a) { /* a periodic axis: the whole period, and every cylinder's rings within it */
        if (!(sc->geometry.periodic >> a & 1)) continue;
        double per = (double)s->flow.w.period[a];
        lo[a] = fmin(lo[a], 0.0), hi[a] = fmax(hi[a], per);
        for (int q = 0; q < L.nw; ++q) {
            const wall_prim *cq = &s->flow.w.prim[q];
            double reach = cq->radius + (cq->outside ? 0.0 : L.nl * L.dr);
            if (cq->shape == WALL_CYLINDER && !(cq->p[a] - reach >= 0 && cq->p[a] + reach <= per))
                input_error("%s: Container:walls:%u: the cylinder%s reaches past the period [0, %.6g) m of the "
                            "periodic %c axis; its images continue it", ctr_where(sc, "walls", L.ent[q], where,
                            sizeof where), L.ent[q] + 1, cq->outside ? "" : " and its dummies", per, "xy"[a]);
        }
    }
    L.i0 = (long)floor(lo[0] / L.dr) - L.nl - 1, L.j0 = (long)floor(lo[1] / L.dr) - L.nl - 1;
    L.ni = (long)ceil(hi[0] / L.dr) + L.nl + 1 - L.i0, L.nj = (long)ceil(hi[1] / L.dr) + L.nl + 1 - L.j0;
    if ((double)L.ni * (double)L.nj > 4e9)
        error_exit(2, "Container: the walls span %ld x %ld lattice sites of Geometry:dr; too many", L.ni, L.nj);
    L.site = calloc((size_t)(L.ni * L.nj), sizeof *L.site);
    if (!L.site) error_exit(1, "out of memory");
    ctr_classify(s, &L, seg);
    size_t n_mat;
    double top;
    size_t n = ctr_place(s, NULL, &L, seg, &n_mat, &top);
    setup_alloc(s, (int)sc->geometry.dim, n);
    ctr_place(s, &s->p, &L, seg, &n_mat, &top);
    s->p.n = setup_count(n);
    s->n_material = n_mat;
    s->surface_y = top;
    if (sc->outlet.enabled && top - 0.5 * L.dr >= 0) {
        /* material at the start below the outlet plane would leave at once */
        double ymin = INFINITY;
        for (size_t i = 0; i < setup_count(n_mat); ++i) ymin = fmin(ymin, (double)s->p.x[1][i]);
        ymin = comm_min(ymin);
        if (ymin < sc->outlet.below)
            input_error("%s: Outlet:below: %.4g m lies above material at y = %.4g m at the start",
                        scene_key_where(sc, "Outlet", "below", where, sizeof where), sc->outlet.below, ymin);
    }
    free(L.site);
    free(L.ent);
    free(seg);
}
