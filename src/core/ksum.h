/* ksum.h — compensated (Neumaier) summation, for the conservation check's
 * sum C_i V_i: a plain sum of n terms carries a round-off of order
 * n^(1/2)..n times the unit round-off, which changes whenever the particles
 * are reordered (every list build) and so showed up as a "drift" of 1e-13 to
 * 1e-12 in the first steps of a run of 1e5-1e6 particles that conserved the
 * sum exactly pair by pair. The compensated sum is exact to about one unit
 * round-off of the total whatever the order. Needs IEEE arithmetic as
 * written (no -ffast-math). */
#ifndef SPHSEG_KSUM_H
#define SPHSEG_KSUM_H
#include <math.h>

typedef struct ksum {
    double s; /* running sum */
    double c; /* the round-off it lost, to be added back */
} ksum;

static inline void ksum_add(ksum *k, double x)
{
    double t = k->s + x;
    k->c += fabs(k->s) >= fabs(x) ? (k->s - t) + x : (x - t) + k->s;
    k->s = t;
}

static inline double ksum_value(ksum k) { return k.s + k.c; }

#endif
