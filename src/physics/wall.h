/* wall.h — dummy-particle walls (paper §4.1) and the Shepard stress filter
 * (3.12). Groundwork for the issue "Granular flow": not yet called by the
 * driver. A dummy d gathers over the material particles m in its support;
 * stress is tension-positive (stress.h), so the hydrostatic term of (4.3),
 * written by the paper for compression-positive stress, enters with a minus. */
#ifndef SPHSEG_WALL_H
#define SPHSEG_WALL_H
#include "hd.h"

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
