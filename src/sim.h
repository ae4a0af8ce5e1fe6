/* sim.h — the state of one run and the backend seam. A backend owns where
 * the particle arrays live and runs the per-step stages; the driver
 * (src/main.c) and time integration (src/integrate.c) call it only through
 * struct backend. The CPU backend (src/backend_cpu.c) runs OpenMP loops over
 * the shared bodies of src/physics/; the CUDA backend (gpu/) plugs in here. */
#ifndef SPHSEG_SIM_H
#define SPHSEG_SIM_H
#include "bound.h"
#include "nbr.h"
#include "particles.h"
#include "physics/kin.h"
#include "physics/seg_kern.h"
#include "scene.h"

struct sim;

struct backend {
    const char *name;
    /* Place particles at time t (prescribed kinematics), rebuild the sorted
     * cell list and, if classify and the scheme needs it, classify boundary
     * particles (classes, normals and psi~ otherwise travel with the
     * particles from the last classification); classify == 2 classifies
     * whatever the scheme (snapshots show boundary classes and normals).
     * The conservative scheme's renormalisation L is computed here too,
     * when classify is set: once per step, like the classification. */
    void (*prepare)(struct sim *s, double t, int classify);
    /* dC/dt of every material particle into p.dCdt. */
    void (*conc_rates)(struct sim *s);
    /* C = C_n + a dC/dt for material particles; a in seconds. */
    void (*advance)(struct sim *s, double a);
    /* Copy C into C_n (start of a step). */
    void (*save_start)(struct sim *s);
    void (*finish)(struct sim *s);
};

typedef struct sim {
    const struct scene *sc;
    const struct backend *be;
    particles_t p;
    nbr_grid grid;
    bound_work bw;
    seg_ctx seg;
    kin_params kin;
    int hcsr;          /* scheme needs the boundary classification */
    double t;          /* simulated time, s */
    long step;
    double dt;         /* last time step, s */
    size_t n_material; /* local material particles */
} sim_t;

/* Build the particles of the scene at t = 0 (src/setup.c). Exits with status
 * 2 if the resolution needs more memory than the machine has. */
void setup_particles(sim_t *s);
/* Fill the physics contexts from the scene. */
void setup_contexts(sim_t *s);

const struct backend *backend_cpu(void);

/* One predictor–corrector step (3.17–3.18) of length dt (src/integrate.c). */
void integrate_step(sim_t *s, double dt);
/* The stable time step (s): bounds by diffusion, segregation, kinematics. */
double integrate_dt(const sim_t *s);

#endif
