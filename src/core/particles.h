/* core/particles.h — the structure-of-arrays particle store (DESIGN.md).
 * Material particles carry C; dummy particles (walls) carry only kinematics
 * and take part in boundary detection and wall source terms. */
#ifndef SPHSEG_PARTICLES_H
#define SPHSEG_PARTICLES_H
#include <stddef.h>
#include <stdint.h>
#include "hd.h"
#include "fields.h"

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
    uint32_t fields; /* the fields allocated, one bit per row of PART_FIELDS in its order (FLD_<X> of
                      * src/sim/stages.h): a field outside it has NULL arrays (part_alloc_fields) */
    /* the arrays, one member per row of PART_FIELDS (src/core/fields.h); an
     * array is declared there and nowhere else */
#define PART_MEMBER(member, fld, type, n, trim) type *member PART_FIELD_DIMS(n);
    PART_FIELDS(PART_MEMBER)
#undef PART_MEMBER
} particles_t;

/* The store's arrays: one per component of each field, in the table's
 * order (x[0], x[1], x[2], X0[0], ...). */
#define PART_NCOMP(member, fld, type, n, trim) +(n)
enum { PART_NARRAYS = 0 PART_FIELDS(PART_NCOMP) };
#undef PART_NCOMP

/* Every field (tests, tools), or those of fields (bit r: row r of
 * PART_FIELDS; a run's come from its stage rows, stage_store_fields): the
 * arrays of the others stay NULL, and every loop below skips them. */
void part_alloc(particles_t *p, int dim, size_t cap);
void part_alloc_fields(particles_t *p, int dim, size_t cap, uint32_t fields);
/* All of the table's fields, as a mask for part_alloc_fields. */
uint32_t part_fields_all(void);
void part_free(particles_t *p);
/* Grow the arrays to hold at least cap particles, keeping their contents. */
void part_reserve(particles_t *p, size_t cap);
/* Apply permutation: new[k] = old[perm[k]], k < n + ng, for every array. */
void part_permute(particles_t *p, const size_t *perm);
/* Keep particles keep[0..m-1] (increasing indices), in that order, at
 * [0, m); p->n = m, p->ng = 0. */
void part_compact(particles_t *p, const size_t *keep, size_t m);
/* Bytes a particle of every field of the table (the store before issue 56),
 * and of the fields p holds (its store). */
size_t part_bytes_per_particle(void);
size_t part_store_bytes(const particles_t *p);
/* The same for a field mask (part_alloc_fields), before any allocation. */
size_t part_fields_bytes(uint32_t fields);
/* The field row (its bit position in a mask) array k belongs to. */
int part_array_field(size_t k);
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
