/* sim.h — the state of one run and the backend seam. A backend owns where
 * the particle arrays live and runs the per-step stages; the driver
 * (src/main.c, src/run.c) and time integration (src/sim/integrate.c) call it only through
 * struct backend. The CPU backend (src/cpu/backend_cpu.c) runs OpenMP loops over
 * the shared bodies of src/physics/; the CUDA backend (gpu/) plugs in here. */
#ifndef SPHSEG_SIM_H
#define SPHSEG_SIM_H
#include "mpi/halo.h"
#include "core/particles.h"
#include "dem/dem.h"
#include "physics/flow.h"
#include "physics/kin.h"
#include "physics/seg_kern.h"
#include "physics/shift.h"
#include "physics/step.h"
#include "scene/scene.h"

struct sim;

struct backend {
    const char *name;
    /* Place particles at time t and rebuild the sorted cell list. Prescribed
     * velocity: every particle from kin_state. Computed flow: the material
     * stays where the integrator put it and the dummies follow the walls
     * (wall_motion); after the sort the dummies' velocity and stress are
     * extrapolated from the material (flow_wall, §4.1). If classify and the
     * scheme needs it, classify boundary particles (classes, normals and
     * psi~ otherwise travel with the particles from the last
     * classification); classify == 2 classifies whatever the scheme
     * (snapshots show boundary classes and normals). The conservative
     * scheme's renormalisation L is computed when classify is set: once per
     * step, like the classification, at these positions; here, or for the
     * owned particles in the next rates' flow pass (then s->renorm_due is
     * set until that pass), but before the concentration rates read it. */
    void (*prepare)(struct sim *s, double t, int classify);
    /* Rates of every solved equation at the current state: with computed
     * flow acc, dsig and gdot (flow_rates; s->amax is set); then, with
     * segregation on, dC/dt into p.dCdt (which reads gdot). */
    void (*rates)(struct sim *s);
    /* X = X_n + a dX/dt for the solved fields of material particles (C
     * unless it advances in windows; and x, u, sigma with the return mapping
     * when the flow is computed); a in seconds. w > 0 (windows): add w times
     * the last rates' shear rate to each material particle's gsum. */
    void (*advance)(struct sim *s, double a, double w);
    /* Concentration windows (s->win, integrate_conc): the state is prepared
     * at the window's end (and classified when the scheme needs it).
     * conc_begin turns gsum into the window's mean shear rate (length T),
     * over the owned particles and their ghosts, computes the conservative
     * scheme's L at these positions when it is on, and gives the local
     * STEP_D and STEP_WAVE bounds at that shear rate (the rest 0).
     * conc_step is one midpoint step of C alone, of length a, with the
     * segregation coefficients at that mean shear rate; the last one of a
     * window clears gsum for the next. */
    void (*conc_begin)(struct sim *s, double T, double out[STEP_NBOUNDS]);
    void (*conc_step)(struct sim *s, double a, int last);
    /* Copy the solved fields into their start-of-step copies. */
    void (*save_start)(struct sim *s);
    /* Shepard filter of the material stress (3.12), then the dummies again. */
    void (*filter)(struct sim *s);
    /* Local maxima over material particles of what bounds the time step
     * (enum STEP_D..STEP_ACC, physics/step.h); STEP_ACC is the largest
     * |acceleration| of the last rate evaluation. */
    void (*bounds)(struct sim *s, double out[STEP_NBOUNDS]);
    /* The lowest local index of a material particle in a blow-up state
     * (step_guard at s->t), or -1. */
    long (*check)(struct sim *s);
    /* Bring the host arrays s->p up to date with the backend's copy (before
     * output, diagnostics and error reports; a no-op on the CPU). */
    void (*to_host)(struct sim *s);
    void (*finish)(struct sim *s);
    /* The host arrays s->p were changed (a load balance moved particles
     * between ranks): take them over; prepare follows. A no-op on the CPU. */
    void (*from_host)(struct sim *s);
    /* Ghost depth in lattice cells of 2h that the backend needs on several
     * ranks (mpi/halo.h): 3, where the neighbour lists and the ghosts are
     * kept between builds while particles move up to a skin (the GPU; the
     * CPU but for ghost_depth_fresh below). */
    int ghost_depth;
    /* Drop the neighbour lists kept between prepares, so that the next
     * prepare builds them afresh (the GPU's Verlet lists); NULL where every
     * prepare sorts anyway (the CPU). At every load-balance check
     * (Parallel:balance_every), on any rank count, as a re-cut does on
     * several: the lists' order, so the sums' bits, follow the builds. */
    void (*relist)(struct sim *s);
    /* The DEM grains (s->dem; called only when it is not NULL; src/dem/dem.h).
     * dem_couple: the coupling at the fluid's state of the rates just
     * evaluated (time t): the fluid fraction at the fluid particles, the
     * fluid's velocity and fraction at the grains, the interaction forces,
     * and with DEM:coupling two_way the fluid's source added to acc and dsig
     * before the advance that uses them. dem_advance: the grains from t over
     * the fluid step dt in DEM steps. The CPU runs src/dem/dem.c on s->p;
     * the GPU the same bodies (src/dem/dem_body.h) on its device copies
     * (gpu/gpu_dem.cu), and its to_host brings the grains up too. */
    void (*dem_couple)(struct sim *s, double t);
    void (*dem_advance)(struct sim *s, double t, double dt);
    /* A step begins (integrate_step), its end the next check: the GPU holds
     * the step's launches until then and replays them as one CUDA graph
     * (gpu/gpu_graph.cu); NULL on the CPU. */
    void (*step_begin)(struct sim *s);
    /* The ghost depth of a run whose ghosts this backend makes afresh at
     * every prepare: the CPU's runs with DEM grains (src/dem/dem_halo.c
     * divides the grains at every coupling), 2 = HALO_DEPTH; 0 where the
     * backend keeps its ghosts in every run (the GPU). */
    int ghost_depth_fresh;
};

/* The concentration equation in windows of K flow steps (Segregation:every,
 * integrate.c): the flow steps alone, each material particle integrates its
 * shear rate (gsum), and when the window closes C takes one midpoint step
 * of the window's length with the window's mean shear rate. */
typedef struct conc_window {
    int on;         /* computed flow with segregation and Segregation:every != 1 */
    unsigned every; /* Segregation:every: K, or 0 for auto */
    long k, K;      /* flow steps in the open window; its length in steps (set at its first) */
    double T;       /* the open window's length so far, s */
    long windows, substeps; /* closed so far; their midpoint steps (> windows when C needed more) */
} conc_window;

typedef struct sim {
    const struct scene *sc;
    const struct backend *be;
    void *be_data;     /* the backend's own state (the CPU's cell list, the GPU's device arrays), or NULL */
    particles_t p;     /* owned particles [0, p.n), ghosts [p.n, p.n + p.ng) */
    halo_t *halo;      /* slab decomposition and ghosts (mpi/halo.h); NULL on one rank */
    seg_ctx seg;
    kin_params kin;
    flow_ctx flow;
    shift_ctx shift;   /* particle shifting (Flow:shifting; physics/shift.h) */
    const char *wall_name[WALL_PRIM_MAX]; /* the name of each wall primitive of flow.w (setup.c builders) */
    step_ctx step_c;   /* time-step bounds and blow-up guard */
    int flow_on;       /* Kinematics:velocity computed: momentum and stress solved */
    int seg_on;        /* Segregation:enabled: the concentration equation solved */
    int hcsr;          /* scheme needs the boundary classification */
    double surface_y;  /* initial free-surface height, m (geostatic stress) */
    double amax;       /* largest |acceleration| of the last rate evaluation, m/s^2 (CPU) */
    int renorm_due;    /* the owned particles' L are due in the next flow rates (set by prepare) */
    int shift_due;     /* this step's shift (ST_SHIFT) comes with the next flow rates, not in
                        * save_start (Run:integrator leapfrog, integrate.c step_lf) */
    int kgc_skip;      /* the next prepare leaves B (ST_KGC) alone: no flow rates read it
                        * before another prepare makes it (leapfrog's end-of-step prepare) */
    conc_window win;   /* the concentration's windows (integrate.c) */
    double t;          /* simulated time, s */
    long step;
    double dt;         /* last time step, s */
    size_t n_material; /* material particles (set by setup; all ranks together) */
    long long out_n;   /* Outlet: material particles that left the run through it, on this rank */
    double out_cv;     /* Outlet: their sum C_i V_i (diagnostics: inside plus outflow is conserved) */
    dem_t *dem;        /* the DEM grains (DEM:d > 0; src/dem/dem.h), or NULL */
    unsigned gate;     /* bit k: the dummies of gate primitive k (flow.w.prim[k].open_at >= 0) are still in the store */
} sim_t;

/* Build the particles of the scene at t = 0 (src/sim/setup.c). Exits with status
 * 2 if the resolution needs more memory than the machine has. */
void setup_particles(sim_t *s);
/* The 1-based id of the wall primitive called `name` ("base", "gate", "drum", ...), 0 if none. */
int wall_named(const sim_t *s, const char *name);
/* The container's wall primitives into buf[n], "ID NAME" each, comma
 * separated ("1 base, 2 xlo, 3 xhi"); long: with each one's shape, slip and
 * motion, for the log. Returns buf. */
char *wall_list(const sim_t *s, int longer, char *buf, size_t n);
/* Fill the physics contexts from the scene. */
void setup_contexts(sim_t *s);

const struct backend *backend_cpu(void);
/* The CUDA backend (gpu/backend_gpu.cu), when built with SPHSEG_CUDA:
 * gpu_devices() is the number of usable devices (0 without a driver or GPU);
 * backend_gpu(local_rank) selects device local_rank modulo that number. */
int gpu_devices(void);
const struct backend *backend_gpu(int local_rank);

/* One predictor–corrector step (3.17–3.18) of length dt (src/sim/integrate.c). */
void integrate_step(sim_t *s, double dt);
/* The stable time step (s): bounds by diffusion, segregation, kinematics;
 * with concentration windows it also fixes the next window's length. */
double integrate_dt(sim_t *s);
/* Concentration windows: set s->win from the scene (after setup_contexts). */
void integrate_conc_init(sim_t *s);
/* The largest K that Segregation:every auto gives. */
int integrate_conc_auto_max(void);
/* Close the open window (C at s->t) if it has its K steps, or if force and
 * it holds any step; returns whether C was advanced. */
int integrate_conc(sim_t *s, int force);

#endif
