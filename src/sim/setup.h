/* setup.h — what the builders of the initial particles share (setup.c, the
 * built-in containers; setup_container.c, a container described in the
 * scene). Internal to setup*.c; the rest of the code calls setup_contexts
 * and setup_particles (sim.h). */
#ifndef SPHSEG_SETUP_H
#define SPHSEG_SETUP_H
#include "sim.h"

/* Allocate this rank's share of the scene's n particles, the fields of the
 * run (stage_store_fields: the others stay NULL; exit 2 if they would not
 * fit); particle k of the scene (its ID) is then placed with
 * setup_put, which keeps it if it is in this rank's share. */
void setup_alloc(sim_t *s, int dim, size_t n);
void setup_put(particles_t *p, size_t k, double x, double y, double z, int kind, double vol, double C);
/* Particle k's wall id (a dummy placed for a primitive that claims none by
 * position), if it is in this rank's share. */
void setup_put_wall(particles_t *p, size_t k, int id);
/* This rank's particles once the scene's first k are placed. */
size_t setup_count(size_t k);

/* Append a wall primitive (s->flow.w) called name, with the box's
 * translation when Walls:velocity is set and the slip `slip` (enum
 * wall_slip; Walls:mu_w where coulomb); wall_plane also places it. */
wall_prim *wall_add_prim(sim_t *s, const char *name, int shape, int slip, int bound, int claim);
wall_prim *wall_plane(sim_t *s, const char *name, int slip, int bound, int claim, double px, double py, double pz,
                      double nx, double ny, double nz);

/* Geometry:type container (setup_container.c): its wall primitives from
 * Container:walls, then its particles on the lattice. */
void container_walls(sim_t *s);
void container_place(sim_t *s);

#endif
