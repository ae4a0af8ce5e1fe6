/* sph.h — the discretisation constants every neighbour loop needs. */
#ifndef SPHSEG_SPH_H
#define SPHSEG_SPH_H
#include "../core/hd.h"
#include "kernel.h"

typedef struct sph_ctx {
    int dim;
    real h;        /* smoothing length, m */
    real alpha;    /* kernel normalisation, eq. (3.3) */
    real support2; /* (2h)^2 */
    real dr;       /* initial particle spacing, m */
    real eta2;     /* (0.1 h)^2, clipping constant of eq. (3.8) */
} sph_ctx;

HD_INLINE sph_ctx sph_make(int dim, real h, real dr)
{
    sph_ctx k;
    k.dim = dim;
    k.h = h;
    k.alpha = kernel_alpha(dim, h);
    k.support2 = R(4.0) * h * h;
    k.dr = dr;
    k.eta2 = R(0.01) * h * h;
    return k;
}

HD_INLINE real sph_norm(const real v[3]) { return v[0] * v[0] + v[1] * v[1] + v[2] * v[2]; }

/* v / |v|, or zero when |v| is negligible against scale. */
HD_INLINE void sph_unit(real v[3], real scale)
{
    real n2 = sph_norm(v);
    if (n2 <= scale * scale * R(1e-12)) {
        v[0] = v[1] = v[2] = 0;
        return;
    }
    real s = R(1.0) / sqrt_r(n2);
    v[0] *= s;
    v[1] *= s;
    v[2] *= s;
}

#endif
