/* particles.h — the structure-of-arrays particle store (DESIGN.md).
 * Material particles carry C; dummy particles (walls) carry only kinematics
 * and take part in boundary detection and wall source terms. */
#ifndef SPHSEG_PARTICLES_H
#define SPHSEG_PARTICLES_H
#include <stddef.h>
#include <stdint.h>
#include "physics/hd.h"

enum part_kind { KIND_MATERIAL = 0, KIND_DUMMY = 1 };

/* HCSR boundary classes (paper §4.2.2, figure 4). */
enum part_bclass {
    BC_INTERIOR = 0,       /* Omega_I: full support */
    BC_FREE_SURFACE = 1,   /* Omega_F: free-surface particle (umbrella test 4.19) */
    BC_FREE_VICINITY = 2,  /* Omega_f: near the free surface (4.20) */
    BC_WALL_SURFACE = 3,   /* Omega_W: surface particle with dummy neighbours */
    BC_WALL_VICINITY = 4,  /* Omega_w: dummy neighbours, not Omega_W (4.21) */
    BC_DUMMY = 5           /* Omega_s: dummy (fictitious) particle */
};

typedef struct particles {
    int dim;
    size_t n;   /* particles owned by this rank (material + dummy), at [0, n) */
    size_t ng;  /* ghost copies of other ranks' particles, at [n, n + ng) (mpi/halo.h);
                 * 0 on one rank */
    size_t cap; /* allocated (n + ng <= cap) */
    real *x[3];   /* position, m */
    real *X0[3];  /* reference (initial) position, m, for prescribed kinematics */
    real *v[3];   /* velocity, m/s */
    real *vol;    /* volume m_i/rho_i, m^d */
    creal *C;     /* small-grain concentration, - (double in both precisions: hd.h) */
    creal *C_n;   /* C at the start of the step (predictor-corrector) */
    creal *dCdt;  /* concentration rate, 1/s */
    real *gdot;   /* shear-rate magnitude, 1/s */
    real *gsum;   /* concentration windows (Segregation:every): the shear rate integrated
                   * over the open window, -; divided by its length at the window's
                   * concentration step, where it is the window's mean shear rate, 1/s */
    real *nrm[3]; /* HCSR normal, pointing into the material */
    real *psi;    /* smoothed degenerate function psi~ (4.14, 4.18) */
    real *segV;   /* segregation velocity V(C, gdot), m/s, per rate evaluation */
    real *segQ;   /* segregation flux Q = V F(C), m/s (eq. 2.6) */
    real *segD;   /* diffusivity D(C, gdot), m^2/s */
    real *sig[6];   /* Cauchy stress, Pa, tension positive: xx, yy, zz, xy, xz, yz
                     * (material: integrated; dummy: extrapolated, eq. 4.3) */
    real *sig_n[6]; /* stress at the start of the step */
    real *dsig[6];  /* stress rate (Jaumann elastic trial rate, C1), Pa/s;
                     * also the Shepard filter's scratch */
    preal *x_n[3];  /* position at the start of the step, m (double in both builds: hd.h) */
    real *xr[3];    /* the single build's rounding remainder of x: the position is x + xr
                     * to double precision (hd.h); 0 in the double build, m */
    real *v_n[3];   /* velocity at the start of the step, m/s */
    real *acc[3];   /* acceleration (3.9) with gravity, m/s^2 */
    real *L[6];   /* renormalisation (-sum_j V_j w_ij x_ij x_ij)^-1, symmetric:
                   * xx, yy, zz, xy, xz, yz (conservative scheme) */
    int64_t *id;  /* global particle ID */
    uint8_t *kind;   /* enum part_kind */
    uint8_t *bclass; /* enum part_bclass */
    uint8_t *wall;   /* a dummy's wall (enum wall_id, src/physics/wall.h), set by setup; 0 for material */
} particles_t;

void part_alloc(particles_t *p, int dim, size_t cap);
void part_free(particles_t *p);
/* Grow the arrays to hold at least cap particles, keeping their contents. */
void part_reserve(particles_t *p, size_t cap);
/* Apply permutation: new[k] = old[perm[k]], k < n + ng, for every array. */
void part_permute(particles_t *p, const size_t *perm);
/* Keep particles keep[0..m-1] (increasing indices), in that order, at
 * [0, m); p->n = m, p->ng = 0. */
void part_compact(particles_t *p, const size_t *keep, size_t m);
size_t part_bytes_per_particle(void);
/* The per-particle arrays as a list (for backends that keep their own copies,
 * e.g. on a GPU): count, element size in bytes, and the k-th pointer. */
size_t part_narrays(void);
size_t part_array_esize(size_t k);
void *part_array_get(const particles_t *p, size_t k);
void part_array_set(particles_t *p, size_t k, void *ptr);
/* The index k of the array p points to with ptr (e.g. p->gdot), or -1. */
int part_array_find(const particles_t *p, const void *ptr);
/* Bytes of one packed record of the arrays arr[0..narr-1]. */
size_t part_record_bytes(const int *arr, int narr);
/* Pack particles idx[0..m-1] (idx NULL: 0..m-1) as records of the arrays
 * arr[] (record-major: one particle's fields contiguous) into buf. */
void part_pack(const particles_t *p, const size_t *idx, size_t m, const int *arr, int narr, char *buf);
/* Unpack m records into particles idx[0..m-1] (idx NULL: at, at+1, ...). */
void part_unpack(particles_t *p, const size_t *idx, size_t at, size_t m, const int *arr, int narr,
                 const char *buf);

#endif
