/* dem/dem.h — DEM grains in the SPH fluid (issue 58; Markauskas et al. 2016):
 * the grains' own store, their contacts and sub-cycled motion, and the
 * coupling with the fluid's particles. A room between the scene and the
 * simulation (docs/architecture.md, "DEM grains"): the integrator
 * (src/sim/integrate.c) calls dem_couple after each evaluation of the fluid's
 * rates and dem_advance after each fluid step; the bodies are
 * src/physics/dem.h. A scene without grains has no dem_t (NULL). */
#ifndef SPHSEG_DEM_DEM_H
#define SPHSEG_DEM_DEM_H
#include <stddef.h>
#include <stdint.h>
#include "core/particles.h"
#include "physics/grid.h"
#include "physics/dem.h"
#include "physics/wall.h"
#include "scene/scene.h"

struct halo; /* mpi/halo.h */

enum { DEM_CMAX = 16 }; /* contacts a grain keeps (12 touch a sphere in the densest packing; walls add 3) */
/* The DEM step is the contact time over this (usual DEM practice: 20 to 50
 * steps a contact). A numerical choice, measured by tests/test_dem.c: the
 * head-on restitution's error against the clamped spring-dashpot is 1.6 %
 * at e = 0.7 with 20 steps, 0.7 % with 50 (first order). */
enum { DEM_STEPS_PER_CONTACT = 50 };

typedef struct dem {
    dem_params c;
    int coupling, motion; /* enum dem_coupling, enum dem_motion */
    size_t n;             /* grains held: owned at [0, no), ghosts at [no, n) */
    size_t no;            /* the grains this rank owns (moves, and writes the contacts of) */
    size_t ntot;          /* the run's grains, on all ranks */
    size_t cap;           /* the per-grain arrays' room, grains */
    /* Several ranks (dem_halo.c): split is 1 once the grains are divided as
     * the fluid is. Each rank owns the grains whose centre lies in its
     * domain (the halo's lattice cells) and holds ghosts, copies of other
     * ranks' grains within DEM_REACH of its domain, at [no, n): those from
     * rank r at [no + goff[r], no + goff[r + 1]), in that rank's order.
     * slist[soff[r] .. soff[r + 1]) are the owned grains whose ghosts rank r
     * holds. split 0: this rank holds every grain (no = n = ntot), one
     * rank, and every rank until the first coupling divides them. */
    int split, nrank;
    size_t *soff, *slist, scap, *goff;
    size_t *scnt, *gcnt;  /* of slist's entries for rank r and of the ghosts from r, the first scnt[r] and
                           * gcnt[r] are the contact tier: within the contact reach, refreshed each DEM step */
    long long migrated;   /* grains this rank sent to a new owner (this run's, for the end report) */
    long long exchanges;  /* exchanges this run (the end report), and couplings that only refreshed */
    long long refreshes;
    /* What the last exchange was made for (dem_exchange_due): the slab bounds and lattice origin,
     * the owned grains' centres; due: an exchange at the next coupling (set by a checkpoint) */
    long *bound0;
    real origin0[3];
    double *x0[3];
    size_t x0cap;
    int due;
    double *x[3], *v[3], *w[3]; /* centre (m), velocity (m/s), angular velocity (rad/s) */
    double *fint[3];      /* the interaction force of eq. (23) at the last coupling, N */
    double *fd[3];        /* its drag part, Di Felice's F_D of eq. (19), at the last coupling, N */
    double *uf[3], *eps;  /* fluid velocity (eq. 20's interpolation) and fluid fraction (20) at each grain */
    double *snorm;        /* sum_a V_a W_ai, the denominator of eq. (14) */
    int64_t *id;          /* grain IDs 0..n-1 */
    int *ncon;            /* contacts of each grain */
    int64_t *cid;         /* [n][DEM_CMAX] partner: a grain's ID, or -1 - k for wall primitive k */
    double *cxi;          /* [n][DEM_CMAX][3] the tangential springs' elongation (the history), m */
    int *ncon2;           /* the spare lists a DEM step writes while it reads the last step's */
    int64_t *cid2;
    double *cxi2;
    double V, m, I;       /* a grain's volume (m^3), mass (kg), moment of inertia (kg m^2) */
    double dt;            /* the DEM step: the contact time / DEM_STEPS_PER_CONTACT, s */
    long steps;           /* DEM steps taken by the run, restarts included (the end report) */
    double rho_f, nu, K, h; /* the fluid's density, kinematic viscosity, bulk modulus; the kernel's h */
    double g[3], t_damp;
    double exch[3];       /* the momentum the fluid gave the grains so far, int sum_i F_int dt, N s (split:
                           * each DEM step's sum over the ranks' grains, the same on every rank) */
    double *eps_f;        /* the fluid fraction at each fluid particle (15-16), owned and ghosts, the last coupling's */
    double *deps_f;       /* its rate following the fluid particle, 1/s */
    size_t eps_cap;
    size_t nown;          /* the owned fluid particles at the last coupling (p->n) */
    double *gsum;         /* [n][5] a grain's sums over the fluid, partial then over all ranks (dem_grain_partial) */
    /* the coupling's cell grid (cells of at least 2h and d): grains and fluid particles by cell */
    double lo[3], cell;
    int nc[3];
    int per;              /* the fluid's periodic axes (wall_geom.periodic, bit a: axis a), from dem_couple/advance */
    double plen[3];       /* their periods from 0, m: minimum images, grains wrapped into [0, plen) */
    size_t *gstart, *gidx, *fstart, *fidx, ncell_cap, fidx_cap;
} dem_t;

/* The grains of the scene (sc->dem.on), at rest, or NULL when it has none.
 * h: the fluid's smoothing length; rho_f, nu, K: its density, kinematic
 * viscosity and bulk modulus; g: gravity. */
dem_t *dem_create(const struct scene *sc, double h, double rho_f, double nu, double K, const double g[3]);
void dem_free(dem_t *d);
/* n grains at the origin, at rest, eps 1 (dem_create's first step; tests);
 * then d->c (d, rho, kn, kt, mu) and dem_derive(d, e) for mass, damping
 * and the DEM step from the restitution e. */
dem_t *dem_alloc(size_t n);
void dem_derive(dem_t *d, double e);

/* The coupling at the fluid's present state p (after its rates): the fluid
 * fraction at the fluid particles (15-16) and at the grains (20), the fluid
 * velocity at the grains, the interaction forces (19-23); two_way: the
 * source (14), -eps grad p and div(eps tau) and the superficial density's
 * pressure rate added to the fluid's acc and dsig. t: the time of p.
 * g: the flow pass's neighbour walk of p (the source's pair term walks a
 * fluid particle's neighbours there, ghosts included). Collective on
 * several ranks (h the fluid's halo): the grains are divided as the fluid
 * is (dem_exchange when due, else every ghost refreshed); a grain's sums
 * over the fluid are each rank's partials, added at its owner in rank
 * order (dem_sums_home), and the owned grains' forces go to their ghosts
 * (dem_refresh) before the source reads them. */
void dem_couple(dem_t *d, particles_t *p, const grid_view *g, const wall_geom *w, double t, double visc_norm,
                const struct halo *h);

/* The grains from t to t + dt in steps of at most d->dt: contacts with
 * each other and the walls w, gravity (3-4), the interaction force (23)
 * with the drag at the present grain velocity. */
void dem_advance(dem_t *d, const wall_geom *w, double t, double dt);

/* The pieces of dem_couple and dem_advance that a backend running the
 * bodies of dem_body.h elsewhere (gpu/gpu_dem.cu) shares with them: the
 * periods of w into d (not the grains' wrap); the grid's cell, origin and
 * cell counts from the bounding box lo, hi of what it bins (the periodic
 * axes from d->per, d->plen); the DEM steps of a fluid step dt; the report
 * (exit 3) of grain i's contact list overflowing. */
void dem_period_set(dem_t *d, const wall_geom *w);
void dem_grid_fit(dem_t *d, const double lo[3], const double hi[3]);
long dem_substeps(const dem_t *d, double dt);
void dem_overflow_exit(size_t i);

/* The grains' state that a checkpoint carries (src/output/checkpoint.c,
 * /DEM): every array a later step reads before it writes it, and those the
 * snapshots show. Centre, velocity and spin (a rigid body's state too: its
 * centre and velocity are the grains' means, its spin every grain's w, its
 * inertia tensor made from the positions at each DEM step), IDs, and the
 * contact lists of the last DEM step with their tangential springs (ncon,
 * cid, cxi: the next step's history; the spare lists ncon2, cid2, cxi2 are
 * written before they are read). The coupling's results (fint, fd, uf, eps,
 * snorm) are made again at the next coupling before a step reads them; they
 * are carried so that the restored dem_t is the saved one. The scalars
 * beside them: exch and steps (attributes). Not carried: the fluid
 * fraction at the fluid particles (eps_f, deps_f), the grid and gsum,
 * each written at a coupling before it is read; the parameters, from the
 * scene (its DEM keys must match the checkpoint's). */
typedef struct dem_state_array {
    const char *name; /* the dataset's name in /DEM */
    void *a;          /* d->n * per elements */
    size_t esize;     /* bytes an element: 8 or 4 */
    size_t per;       /* elements a grain */
    int is_double;    /* 1: doubles, 0: signed integers */
} dem_state_array;
enum { DEM_STATE_NARRAYS = 24 };
/* The k-th array of d's state (k < DEM_STATE_NARRAYS), pointing at d's arrays. */
dem_state_array dem_state_get(dem_t *d, size_t k);
/* NULL when d's state is one a run can continue from (finite values,
 * contact counts within DEM_CMAX, partners a grain's ID 0..n-1 or one of
 * nwalls wall primitives, IDs 0..n-1 in order), else why (in why[len]). */
const char *dem_state_check(const dem_t *d, int nwalls, char *why, size_t len);

/* The kinetic energy (translation and rotation) of the grains this rank
 * owns, J. */
double dem_kinetic_energy(const dem_t *d);

/* ---- the grains divided among the ranks (dem_halo.c) ---- */
/* Collective (several ranks, h the fluid's halo). The first call keeps
 * this rank's own grains of the replicated store; every call sends each owned grain that left
 * the domain to its new owner with its whole state, contact lists and
 * springs included, orders the owned by ID, then makes the ghosts: a
 * copy of each owned grain's centre, velocity and spin for every other
 * rank owning a lattice cell within DEM_REACH cells of it (a periodic
 * image's owner too), so that every grain within 2h of a rank's fluid,
 * owned or ghost, and every contact partner of its grains are there. */
void dem_exchange(dem_t *d, const struct halo *h);
/* Collective when split (else 1: the first call divides). Whether the
 * next coupling must exchange: the fluid's slabs moved (bounds or lattice
 * origin; METIS parts: always), a checkpoint was written since (so that a
 * restart exchanges where the straight run does: the same bits), or on any
 * rank an owned grain moved h / 2 or more since the last exchange (maxdisp,
 * m: dem_max_shift's, or a backend's own). Until then the reach's cell of
 * room (2h) holds what each grain and its neighbours may move, and a
 * coupling refreshes every ghost's centre, velocity and spin instead
 * (dem_refresh DEM_SEND_GHOSTS). */
int dem_exchange_due(dem_t *d, const struct halo *h, double maxdisp);
/* The largest distance an owned grain moved since the last exchange, m. */
double dem_max_shift(const dem_t *d);
/* The owned grains (split) whose centre h gives to another rank now: those
 * dem_exchange would send away (their centres must be current). */
size_t dem_migrating(const dem_t *d, const struct halo *h);
enum { DEM_SEND_MOTION = 0, DEM_SEND_COUPLING = 1, DEM_SEND_GHOSTS = 2 };
/* Collective when split (else nothing). The owners' values into the
 * ghosts: DEM_SEND_MOTION centre, velocity and spin (each DEM step) of the
 * contact tier, the ghosts within d and a cell of room of an owned grain
 * (the others, held for the fluid's fraction, are not read before the next
 * exchange); DEM_SEND_COUPLING the coupling's results (fint, fd, uf, eps,
 * snorm) of every ghost; DEM_SEND_GHOSTS centre, velocity and spin of
 * every ghost (a coupling without an exchange). */
void dem_refresh(dem_t *d, int what);
/* The refresh in pieces, for a backend that packs its own rows (the GPU):
 * the owned grains whose rows it sends, in the order dem_refresh_swap
 * takes them (sidx, returns their count), and the ghosts the received rows
 * go to (ridx, *nrecv of them); sidx holds soff[nrank], ridx n - no. Then,
 * collective, send[ns][k] to the ghosts' ranks and recv[nrecv][k] back
 * (k: 11 for DEM_SEND_COUPLING, else 9: dem_refresh's rows). */
size_t dem_refresh_lists(const dem_t *d, int what, size_t *sidx, size_t *ridx, size_t *nrecv);
void dem_refresh_swap(const dem_t *d, int what, int k, const double *send, double *recv);
/* Collective when split. The grains' partial sums over each rank's fluid
 * (gsum, 5 a grain, owned and ghosts) added at their owners, over the
 * ranks in rank order, into the owned rows. */
void dem_sums_home(dem_t *d);
/* Collective when split. Of every grain of the run (the ranks' owned, in
 * ID order), for output and checkpoints:
 * d itself when not split, else a new store (dem_whole_free). */
dem_t *dem_whole(dem_t *d);
void dem_whole_free(const dem_t *d, dem_t *whole);
/* Collective. The run's grains' kinetic energy, J, and exchanged momentum, N s. */
void dem_totals(const dem_t *d, double *ke, double exch[3]);
/* Collective when split (else nothing): ex[m][3], each DEM step's
 * momentum exchanged with this rank's grains, summed over the ranks in
 * rank order (one reduction for the fluid step), then added to exch step
 * by step: each step's total the same on every rank and on any timing. */
void dem_exch_steps(dem_t *d, double *ex, long m);
/* Collective when split: x[0..k) (k <= 16) summed over the ranks in rank order. */
void dem_sum_ranks(const dem_t *d, double *x, int k);
/* Room for m grains in every per-grain array (their values kept). */
void dem_reserve(dem_t *d, size_t m);
/* Every per-grain array of d (the one list that allocation, growth, release
 * and migration read): its pointer in dem_t and its bytes a grain. The first
 * DEM_NMIG travel with a migrating grain (the rest are scratch a step
 * rewrites). */
typedef struct dem_arr {
    void **a;
    size_t bytes;
} dem_arr;
enum { DEM_NARR = 28, DEM_NMIG = 24 };
void dem_arrays(dem_t *d, dem_arr t[DEM_NARR]);

/* The normal force the walls w carry from grain i now (overlap and
 * velocity as they are), N. */
double dem_wall_load(const dem_t *d, const wall_geom *w, size_t i);

#endif
