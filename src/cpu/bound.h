/* bound.h — CPU driver of the HCSR boundary-particle search (paper §4.2.2):
 * classifies every particle (enum part_bclass) and sets its normal and psi~. */
#ifndef SPHSEG_BOUND_H
#define SPHSEG_BOUND_H
#include "nbr.h"
#include "physics/bound_kern.h"

typedef struct bound_work {
    unsigned char *cell_type; /* enum cell_type per cell */
    size_t *cell_mat;         /* material particles per cell */
    bound_sums *sums;         /* per particle */
    unsigned char *cls;       /* per particle, new classes */
    size_t cap_cell, cap_part;
    size_t count[6];          /* particles per class after the last call */
} bound_work;

/* Classify all particles of p (sorted by g) and fill p->bclass, p->nrm, p->psi. */
void bound_classify(bound_work *w, particles_t *p, const nbr_grid *g, const sph_ctx *k);
void bound_free(bound_work *w);

#endif
