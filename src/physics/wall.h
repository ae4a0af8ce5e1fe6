/* wall.h — dummy-particle walls (paper §4.1): wall geometry and motion,
 * dummy velocity (4.1, 4.2) and stress (4.3), and the Shepard stress filter
 * sums (3.12); called by the flow bodies (flow.h). A dummy d gathers over the material particles m in its support;
 * stress is tension-positive (stress.h), so the hydrostatic term of (4.3),
 * written by the paper for compression-positive stress, enters with a minus. */
#ifndef SPHSEG_WALL_H
#define SPHSEG_WALL_H
#include <math.h>
#include "hd.h"

/* The rigid container of a scene. Box (shear box, column): a base below
 * y = 0 and side walls at x = 0 and x = width (in 3D also z = 0 and
 * z = depth), at rest. Drum: a circle of
 * radius R about centre, turning at omega (rad/s, counter-clockwise
 * positive) about the z axis; in 3D a cylinder of length depth along z,
 * closed by flat end walls at z = 0 and z = depth that turn with it. */
enum wall_type { WALL_BOX = 0, WALL_DRUM = 1 };

typedef struct wall_geom {
    int type;        /* enum wall_type */
    real width;      /* box: inner width (x), m */
    real depth;      /* 3D box: inner depth (z); 3D drum: length between the end walls (z); m; 0 in 2D */
    real centre[3];  /* drum: axis position, m */
    real radius;     /* drum: inner radius R, m */
    double omega;    /* drum: angular velocity, rad/s, counter-clockwise > 0 */
    int slip_base;   /* box base and drum walls (cylinder, end walls): 1 free slip (4.2), 0 no slip (4.1) */
    int slip_sides;  /* box side walls: 1 free slip, 0 no slip */
    real u[3];       /* box: translation velocity of the whole container, m/s */
    int periodic;    /* box: bit d set: no walls across axis d, which is periodic (x: period width,
                      * z: period depth, from 0; Geometry:periodic) */
} wall_geom;

/* Position and velocity at time t of the wall point (dummy) whose reference
 * position is X0: the drum (cylinder and end walls) turns rigidly by omega t
 * about the z axis through centre (z kept); the box translates by u t (at
 * rest when u = 0). */
HD_INLINE void wall_motion(const wall_geom *w, const real X0[3], double t, real x[3], real u[3])
{
    if (w->type != WALL_DRUM) {
        for (int a = 0; a < 3; ++a) x[a] = (real)((double)X0[a] + (double)w->u[a] * t), u[a] = w->u[a];
        return;
    }
    x[0] = X0[0], x[1] = X0[1], x[2] = X0[2];
    u[0] = u[1] = u[2] = 0;
    double th = w->omega * t, c = cos(th), s = sin(th);
    double rx = (double)X0[0] - w->centre[0], ry = (double)X0[1] - w->centre[1];
    double qx = c * rx - s * ry, qy = s * rx + c * ry;
    x[0] = (real)(w->centre[0] + qx);
    x[1] = (real)(w->centre[1] + qy);
    u[0] = (real)(-w->omega * qy); /* omega e_z x r */
    u[1] = (real)(w->omega * qx);
}

/* Drum normal at x (n zeroed by the caller): towards the axis on the
 * cylinder; +z / -z on the end walls of a 3D drum (depth > 0). Which wall a
 * dummy belongs to depends only on its radius r and its z, which the
 * rotation about z keeps, so the current position decides as the reference
 * position would. Corner dummies (beyond both, z < 0 or z > depth and
 * r > R): the wall they lie furthest beyond, the cylinder on a tie - the
 * rule of the box's side walls. Cylinder and end walls share slip_base. */
HD_INLINE int wall_normal_drum(const wall_geom *w, const real x[3], real n[3])
{
    real dx = w->centre[0] - x[0], dy = w->centre[1] - x[1];
    real r = (real)sqrt((double)(dx * dx + dy * dy));
    real oz = w->depth > 0 ? (x[2] < 0 ? -x[2] : x[2] - w->depth) : (real)-1e30;
    if (oz > 0 && oz > r - w->radius) n[2] = x[2] < 0 ? R(1.0) : R(-1.0);
    else if (r > 0) n[0] = dx / r, n[1] = dy / r;
    return w->slip_base;
}

/* Unit wall normal at dummy position x, pointing into the material, and
 * whether that wall is free-slip. Box: below the base (y < 0, corners
 * included) the base, else the nearer side wall (of the axes that are not
 * periodic). x is in the box's own frame
 * (a translating box: the caller subtracts u t, wall_frame). Drum:
 * wall_normal_drum. */
HD_INLINE int wall_normal(const wall_geom *w, const real x[3], real n[3])
{
    n[0] = n[1] = n[2] = 0;
    if (w->type == WALL_DRUM) return wall_normal_drum(w, x, n);
    if (x[1] < 0) {
        n[1] = 1;
        return w->slip_base;
    }
    /* side walls: the one the dummy lies furthest beyond (x or, in 3D, z) */
    real ox = w->periodic & 1 ? (real)-1e30 : x[0] < 0 ? -x[0] : x[0] - w->width;
    real oz = w->depth > 0 && !(w->periodic & 4) ? (x[2] < 0 ? -x[2] : x[2] - w->depth) : (real)-1e30;
    if (oz > ox) n[2] = x[2] < R(0.5) * w->depth ? R(1.0) : R(-1.0);
    else n[0] = x[0] < R(0.5) * w->width ? R(1.0) : R(-1.0);
    return w->slip_sides;
}

/* Which wall a dummy belongs to: set once by setup (wall_id_at, from its
 * reference position, or directly for a gate) and carried with the dummy
 * (particles_t.wall), so that its normal and slip come from the wall, not
 * from where it is. */
enum wall_id {
    WALL_ID_NONE = 0, /* material */
    WALL_ID_BASE = 1, /* box base (y < 0, corners included) */
    WALL_ID_XLO = 2,  /* box side wall at x = 0 */
    WALL_ID_XHI = 3,  /* box side wall at x = width */
    WALL_ID_ZLO = 4,  /* 3D box side wall at z = 0 */
    WALL_ID_ZHI = 5,  /* 3D box side wall at z = depth */
    WALL_ID_GATE = 6, /* box: the gate holding a column at x = gate_x until Walls:gate_open */
    WALL_ID_DRUM = 7, /* drum: cylinder and end walls (their normal follows the turning position) */
    WALL_ID_LID = 8,  /* box: a wall over the material at y = height (Geometry:lid), the base's slip */
    WALL_ID_MAX = 8
};

/* The wall of a dummy at reference position X0 by the rule of wall_normal. */
HD_INLINE int wall_id_at(const wall_geom *w, const real X0[3])
{
    if (w->type == WALL_DRUM) return WALL_ID_DRUM;
    real n[3];
    wall_normal(w, X0, n);
    if (n[1] > 0) return WALL_ID_BASE;
    if (n[2] != 0) return n[2] > 0 ? WALL_ID_ZLO : WALL_ID_ZHI;
    return n[0] > 0 ? WALL_ID_XLO : WALL_ID_XHI;
}

/* Unit normal (into the material) and slip of the wall `id` of a dummy at x:
 * a box's walls are planes, each its own normal; the drum's follows x
 * (wall_normal_drum). The gate faces -x (the column lies at x < gate_x) and
 * slips as the side walls. */
HD_INLINE int wall_normal_of(const wall_geom *w, int id, const real x[3], real n[3])
{
    n[0] = n[1] = n[2] = 0;
    switch (id) {
    case WALL_ID_BASE: n[1] = 1; return w->slip_base;
    case WALL_ID_XLO: n[0] = 1; return w->slip_sides;
    case WALL_ID_XHI: n[0] = -1; return w->slip_sides;
    case WALL_ID_ZLO: n[2] = 1; return w->slip_sides;
    case WALL_ID_ZHI: n[2] = -1; return w->slip_sides;
    case WALL_ID_GATE: n[0] = -1; return w->slip_sides;
    case WALL_ID_LID: n[1] = -1; return w->slip_base;
    default: return wall_normal(w, x, n);
    }
}

/* Acceleration of the wall at x (drum: centripetal -omega^2 (x - centre));
 * the wall stress (4.3) extrapolates with g - a_w (Adami et al. 2012). */
HD_INLINE void wall_accel(const wall_geom *w, const real x[3], real a[3])
{
    a[0] = a[1] = a[2] = 0;
    if (w->type != WALL_DRUM) return;
    real o2 = (real)(w->omega * w->omega);
    a[0] = -o2 * (x[0] - w->centre[0]);
    a[1] = -o2 * (x[1] - w->centre[1]);
}

typedef struct wall_sums {
    real w;     /* sum W_dm V_m */
    real u[3];  /* sum u_m W_dm V_m */
    real s[6];  /* sum sigma_m W_dm V_m */
    real gr[3]; /* sum m_m g_a (r_d - r_m)_a W_dm (diagonal of g (x) r_dm) */
} wall_sums;

/* Adds material particle m (kernel value W = W_dm, volume V, mass mass). */
HD_INLINE void wall_add(wall_sums *ws, real W, real V, real mass, const real u[3], const real s[6],
                        const real g[3], const real r_dm[3])
{
    real wv = W * V;
    ws->w += wv;
    for (int a = 0; a < 3; ++a) {
        ws->u[a] += u[a] * wv;
        ws->gr[a] += mass * g[a] * r_dm[a] * W;
    }
    for (int c = 0; c < 6; ++c) ws->s[c] += s[c] * wv;
}

/* Dummy velocity: no slip (4.1) u_d = 2 u_w - u_avg; free slip (4.2): the
 * normal part as (4.1), the tangential part u_avg's (n unit wall normal). */
HD_INLINE void wall_velocity(const wall_sums *ws, const real uw[3], const real n[3], int free_slip, real ud[3])
{
    real avg[3] = {0, 0, 0};
    if (ws->w > 0)
        for (int a = 0; a < 3; ++a) avg[a] = ws->u[a] / ws->w;
    if (!free_slip) {
        for (int a = 0; a < 3; ++a) ud[a] = R(2.0) * uw[a] - avg[a];
        return;
    }
    real an = avg[0] * n[0] + avg[1] * n[1] + avg[2] * n[2];
    real wn = uw[0] * n[0] + uw[1] * n[1] + uw[2] * n[2];
    real dn = R(2.0) * wn - an; /* normal component of the dummy */
    for (int a = 0; a < 3; ++a) ud[a] = avg[a] - an * n[a] + dn * n[a];
}

/* Dummy stress (4.3): (sum sigma_m W V - I o sum m g (x) r_dm W) / sum W V. */
HD_INLINE void wall_stress(const wall_sums *ws, real sd[6])
{
    for (int c = 0; c < 6; ++c) sd[c] = ws->w > 0 ? ws->s[c] / ws->w : R(0.0);
    if (ws->w > 0)
        for (int a = 0; a < 3; ++a) sd[a] -= ws->gr[a] / ws->w;
}

/* Shepard filter (3.12): sigma_i = sum_j sigma_j W_ij / sum_j W_ij, over the
 * material neighbours j (self included); accumulate, then divide. */
HD_INLINE void shepard_add(real acc[6], real *wsum, real W, const real sj[6])
{
    for (int c = 0; c < 6; ++c) acc[c] += sj[c] * W;
    *wsum += W;
}

#endif
