/* wall.h — dummy-particle walls (paper §4.1): wall geometry and motion,
 * dummy velocity (4.1, 4.2) and stress (4.3), and the Shepard stress filter
 * sums (3.12); called by the flow bodies (flow.h). A dummy d gathers over the material particles m in its support;
 * stress is tension-positive (stress.h), so the hydrostatic term of (4.3),
 * written by the paper for compression-positive stress, enters with a minus. */
#ifndef SPHSEG_WALL_H
#define SPHSEG_WALL_H
#include <math.h>
#include "../core/hd.h"

/* The container as data: a list of wall primitives (wall_geom.prim), each
 * with its own shape, slip and motion. Every dummy carries the 1-based
 * index of its primitive (particles_t.wall), set once by setup
 * (wall_id_at, or by the builder that placed it), so that its normal, its
 * slip, its velocity and acceleration and the test "beyond the container"
 * all come from that primitive, each by one formula below. The built-in
 * containers (Geometry:type) are lists of these (setup.c, setup_builders).
 *
 * Shapes: a plane (a point p on it and the unit normal n into the
 * material; a box face, a base, a gate, a lid) and a cylinder about an axis
 * along z through p of radius `radius`, the material inside (a drum) or,
 * with `outside` set, outside it (a post: an obstacle in the flow).
 * Motions: fixed; translating at u; rotating at omega (rad/s,
 * counter-clockwise positive seen with y up) about the z axis through c,
 * for a plane only with a normal along z (the end walls of a drum), which
 * the rotation keeps. A gate is a primitive whose dummies leave the run at
 * open_at (src/run.c). */
enum wall_shape { WALL_PLANE = 0, WALL_CYLINDER = 1 };
enum wall_move { WALL_FIXED = 0, WALL_TRANSLATE = 1, WALL_ROTATE = 2 };
/* The most primitives a container has (the 3D column with a runout, a gate
 * and a lid has 7). The table travels by value in the contexts, so the GPU
 * reads it from the kernel parameters. */
enum { WALL_PRIM_MAX = 12 };
/* The most Coulomb walls whose friction acts on the particles
 * (Walls:coulomb_force particles; wall_prim.contact; flow_contact_team): a 3D
 * slot's floor, two side walls and an end wall. */
enum { WALL_CONTACT_MAX = 4 };
/* wall_prim.claim: how a primitive takes its dummies (wall_id_at). */
enum wall_claim {
    WALL_CLAIM_NONE = 0,  /* only the dummies its builder placed for it (a gate, a lid) */
    WALL_CLAIM_LAST = 1,  /* as SIDE, after every SIDE primitive (a container's gate: a dummy that is
                           * also a permanent wall's stays when the gate opens) */
    WALL_CLAIM_SIDE = 2,  /* those that lie beyond it, the furthest beyond winning */
    WALL_CLAIM_FIRST = 3  /* as SIDE, before every SIDE primitive (a box's base keeps its corners) */
};

typedef struct wall_prim {
    int shape;       /* enum wall_shape */
    int move;        /* enum wall_move */
    int slip;        /* 1 free slip (4.2), 0 no slip (4.1) */
    real mu_w;       /* > 0: Coulomb friction (slip 0 while it sticks; wall_coulomb), the coefficient */
    int contact;     /* Walls:coulomb_force particles: this Coulomb wall's slot 1..WALL_CONTACT_MAX of
                      * flow_contact_team (physics/flow.h); 0: its friction acts through its dummies alone */
    int bound;       /* 1: material beyond it by more than h has left the container (step_outside);
                      * 0 for a wall with an opening (an outlet's base), a gate, a lid */
    int claim;       /* enum wall_claim */
    int outside;     /* cylinder: 1 the material outside it (a post), 0 inside (a drum) */
    real p[3];       /* plane: a point of it; cylinder: a point of its axis (along z), m */
    real n[3];       /* plane: unit normal, pointing into the material */
    real radius;     /* cylinder: radius, m */
    real u[3];       /* translating: velocity, m/s */
    real c[3];       /* rotating: a point of the axis (along z), m */
    double omega;    /* rotating: angular velocity, rad/s, counter-clockwise > 0 */
    double open_at;  /* a gate: its dummies leave the run at this time, s; < 0: not a gate */
    real t[3];       /* plane: a unit direction in it, along which it is bounded (a segment) */
    real t_lo, t_hi; /* plane: its extent along t from p, m, corners included (step_outside tests
                      * only there); an unbounded plane: t = 0, t_lo < 0 < t_hi */
} wall_prim;

typedef struct wall_geom {
    int n;               /* primitives in use */
    int periodic;        /* bit d set: axis d is periodic (Geometry:periodic), no walls across it */
    real period[3];      /* the period of each periodic axis, from 0, m */
    wall_prim prim[WALL_PRIM_MAX];
} wall_geom;

/* The primitive of a dummy with wall id `id` (1-based; setup guarantees 1..n). */
HD_INLINE const wall_prim *wall_of(const wall_geom *w, int id) { return &w->prim[id - 1]; }

/* Position and velocity at time t of the point of primitive q whose
 * reference position is X0: rotated by omega t about the z axis through c
 * (z kept), translated by u t, or at rest. */
HD_INLINE void wall_prim_motion(const wall_prim *q, const real X0[3], double t, real x[3], real u[3])
{
    x[0] = X0[0], x[1] = X0[1], x[2] = X0[2];
    u[0] = u[1] = u[2] = 0;
    if (q->move == WALL_TRANSLATE) {
        for (int a = 0; a < 3; ++a) x[a] = (real)((double)X0[a] + (double)q->u[a] * t), u[a] = q->u[a];
    } else if (q->move == WALL_ROTATE) {
        double th = q->omega * t, c = cos(th), s = sin(th);
        double rx = (double)X0[0] - q->c[0], ry = (double)X0[1] - q->c[1];
        double qx = c * rx - s * ry, qy = s * rx + c * ry;
        x[0] = (real)(q->c[0] + qx);
        x[1] = (real)(q->c[1] + qy);
        u[0] = (real)(-q->omega * qy); /* omega e_z x r */
        u[1] = (real)(q->omega * qx);
    }
}

HD_INLINE void wall_motion(const wall_geom *w, int id, const real X0[3], double t, real x[3], real u[3])
{
    wall_prim_motion(wall_of(w, id), X0, t, x, u);
}

/* Velocity of primitive q at the point x it has now: omega e_z x (x - c)
 * turning, u translating, 0 at rest. */
HD_INLINE void wall_velocity_at(const wall_prim *q, const real x[3], real uw[3])
{
    uw[0] = uw[1] = uw[2] = 0;
    if (q->move == WALL_TRANSLATE) uw[0] = q->u[0], uw[1] = q->u[1], uw[2] = q->u[2];
    else if (q->move == WALL_ROTATE) {
        uw[0] = (real)(-q->omega * (double)(x[1] - q->c[1]));
        uw[1] = (real)(q->omega * (double)(x[0] - q->c[0]));
    }
}

/* Unit normal (into the material) of primitive q at its point x, and
 * whether q is free-slip: a plane's own normal (a rotating plane's is along
 * the axis, which the rotation keeps); a cylinder's towards its axis, a
 * post's away from it. */
HD_INLINE int wall_prim_normal(const wall_prim *q, const real x[3], real n[3])
{
    n[0] = n[1] = n[2] = 0;
    if (q->shape == WALL_CYLINDER) {
        real dx = q->p[0] - x[0], dy = q->p[1] - x[1];
        real r = sqrt_r(dx * dx + dy * dy);
        if (q->outside) r = -r;
        if (r != 0) n[0] = dx / r, n[1] = dy / r;
    } else {
        n[0] = q->n[0], n[1] = q->n[1], n[2] = q->n[2];
    }
    return q->slip;
}

HD_INLINE int wall_normal_of(const wall_geom *w, int id, const real x[3], real n[3])
{
    return wall_prim_normal(wall_of(w, id), x, n);
}

/* How far the reference-frame point x lies beyond primitive q (negative:
 * on the material's side): along -n from a plane, radially out of a
 * cylinder, radially into a post. */
HD_INLINE real wall_prim_depth(const wall_prim *q, const real x[3])
{
    if (q->shape == WALL_CYLINDER) {
        real dx = q->p[0] - x[0], dy = q->p[1] - x[1];
        real d = sqrt_r(dx * dx + dy * dy) - q->radius;
        return q->outside ? -d : d;
    }
    return -(q->n[0] * (x[0] - q->p[0]) + q->n[1] * (x[1] - q->p[1]) + q->n[2] * (x[2] - q->p[2]));
}

/* The wall of a dummy at reference position X0: among the primitives that
 * claim by position and that X0 lies beyond, a WALL_CLAIM_FIRST one before
 * any other, then the one it lies furthest beyond, the first listed on a
 * tie (a box's corner dummies go to its base; a drum's to the cylinder or
 * an end wall, whichever they lie further beyond). 0 if none. */
HD_INLINE int wall_id_at(const wall_geom *w, const real X0[3])
{
    int best = 0, best_claim = 0;
    real best_depth = 0;
    for (int k = 0; k < w->n; ++k) {
        const wall_prim *q = &w->prim[k];
        if (q->claim == WALL_CLAIM_NONE) continue;
        real d = wall_prim_depth(q, X0);
        if (!(d > 0)) continue;
        if (!best || q->claim > best_claim || (q->claim == best_claim && d > best_depth))
            best = k + 1, best_claim = q->claim, best_depth = d;
    }
    return best;
}

/* Acceleration of the wall `id` at x (turning: centripetal
 * -omega^2 (x - c)); the wall stress (4.3) extrapolates with g - a_w
 * (Adami et al. 2012). */
HD_INLINE void wall_accel(const wall_geom *w, int id, const real x[3], real a[3])
{
    const wall_prim *q = wall_of(w, id);
    a[0] = a[1] = a[2] = 0;
    if (q->move != WALL_ROTATE) return;
    real o2 = (real)(q->omega * q->omega);
    a[0] = -o2 * (x[0] - q->c[0]);
    a[1] = -o2 * (x[1] - q->c[1]);
}

/* Is the point x beyond a bounding primitive by more than h at time t (a
 * bounded plane, a segment: within its extent, so that material may leave
 * through a gap between two)?
 * A translating primitive is tested in its own frame (x - u t); a turning
 * one as it stands (a cylinder, or a plane across the axis, which the
 * rotation keeps). */
HD_INLINE int wall_beyond(const wall_geom *w, const double x[3], double t, double h)
{
    for (int k = 0; k < w->n; ++k) {
        const wall_prim *q = &w->prim[k];
        if (!q->bound) continue;
        double y[3] = {x[0], x[1], x[2]};
        if (q->move == WALL_TRANSLATE)
            for (int a = 0; a < 3; ++a) y[a] -= q->u[a] * t;
        double d, s = 0;
        if (q->shape == WALL_CYLINDER) {
            d = hypot(y[0] - q->p[0], y[1] - q->p[1]) - q->radius;
            if (q->outside) d = -d;
        } else {
            d = -(q->n[0] * (y[0] - q->p[0]) + q->n[1] * (y[1] - q->p[1]) + q->n[2] * (y[2] - q->p[2]));
            s = q->t[0] * (y[0] - q->p[0]) + q->t[1] * (y[1] - q->p[1]) + q->t[2] * (y[2] - q->p[2]);
        }
        if (d > h && s >= q->t_lo && s <= q->t_hi) return 1;
    }
    return 0;
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

/* A Coulomb wall's sticking speed over the sound speed (flow_ctx.v_stick). */
#ifndef COULOMB_STICK
#define COULOMB_STICK 1e-3
#endif

/* A Coulomb wall (wall_prim.mu_w > 0; Walls:slip coulomb). The traction
 * the dummy's stress sd puts on the wall, t = sd n (n into the material),
 * has a normal stress sigma_n = -n.t (compression; none in tension) and a
 * shear part tau = t - (n.t) n; u_rel is the material's tangential
 * velocity against the wall's (the Shepard mean of 4.1). It sticks while
 * |u_rel| <= v_stick and |tau| <= mu_w sigma_n: the no-slip velocity and
 * the extrapolated stress (4.1, 4.3) stand. Else it slides: the velocity is
 * free slip's (4.2) and the traction's shear part is set to mu_w sigma_n
 * along u_rel (kinetic friction, resisting the motion as the static shear
 * resists the pull), or along tau when the material starts from rest;
 * sigma_n is kept. v_stick keeps a sliding layer from sticking again while
 * it moves (a no-slip dummy under a moving layer shears the layer's own
 * stress up to its yield: friction above mu_w). The decision is each
 * dummy's, at each evaluation. */
HD_INLINE void wall_coulomb(const wall_sums *ws, const real uw[3], const real n[3], real mu_w, real v_stick, real ud[3],
                            real sd[6])
{
    const real t[3] = {sd[0] * n[0] + sd[3] * n[1] + sd[4] * n[2], sd[3] * n[0] + sd[1] * n[1] + sd[5] * n[2],
                       sd[4] * n[0] + sd[5] * n[1] + sd[2] * n[2]};
    const real tn = t[0] * n[0] + t[1] * n[1] + t[2] * n[2];
    const real tau[3] = {t[0] - tn * n[0], t[1] - tn * n[1], t[2] - tn * n[2]};
    const real at = sqrt_r(tau[0] * tau[0] + tau[1] * tau[1] + tau[2] * tau[2]);
    const real allowed = mu_w * (tn < 0 ? -tn : R(0.0));
    real ur[3], un = 0;
    for (int a = 0; a < 3; ++a) ur[a] = (ws->w > 0 ? ws->u[a] / ws->w : R(0.0)) - uw[a];
    for (int a = 0; a < 3; ++a) un += ur[a] * n[a];
    for (int a = 0; a < 3; ++a) ur[a] -= un * n[a];
    const real us = sqrt_r(ur[0] * ur[0] + ur[1] * ur[1] + ur[2] * ur[2]);
    if (us <= v_stick && !(at > allowed)) return; /* sticks */
    real e[3] = {0, 0, 0}; /* the kinetic traction's direction */
    if (us > v_stick)
        for (int a = 0; a < 3; ++a) e[a] = ur[a] / us;
    else
        for (int a = 0; a < 3; ++a) e[a] = tau[a] / at;
    real dt[3]; /* the shear part's change: allowed e - tau */
    for (int a = 0; a < 3; ++a) dt[a] = allowed * e[a] - tau[a];
    sd[0] += R(2.0) * dt[0] * n[0], sd[1] += R(2.0) * dt[1] * n[1], sd[2] += R(2.0) * dt[2] * n[2];
    sd[3] += dt[0] * n[1] + n[0] * dt[1], sd[4] += dt[0] * n[2] + n[0] * dt[2];
    sd[5] += dt[1] * n[2] + n[1] * dt[2];
    wall_velocity(ws, uw, n, 1, ud);
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
