/* halo.h — the slab decomposition of a multi-rank run: which rank owns a
 * particle, particle migration, ghost (halo) particles and their refresh,
 * and the load balance of the slab bounds (DESIGN.md "Parallel model").
 *
 * Space is cut by the global cell lattice of edge 2h that one rank holding
 * every particle would use for its cell list (its origin is the particles'
 * lower corner, as grid_fit sets it, reduced over ranks at every exchange).
 * Along the slab axis rank r owns the lattice columns [bound[r], bound[r+1]);
 * or (Parallel:method metis) METIS assigns coarse cells of the lattice to
 * ranks. Either way a rank's domain is a union of lattice cells.
 * Each rank holds its own particles at [0, n) of its store and ghost copies
 * of its neighbours' particles in the `depth` columns next to its slab at
 * [n, n + ng). depth is 2 on the CPU: the HCSR classification of a particle
 * reads the cell types of the cells next to its own, which read their
 * neighbours, so two columns of ghosts make every owned particle's class
 * exact without an exchange between the classification stages; every other
 * stage reads one support. A backend that keeps its ghosts between
 * neighbour list builds asks for 3 (halo_set_depth; struct
 * backend.ghost_depth): the GPU, and the CPU but with DEM grains.
 * A rank exchanges with its neighbours: the ranks owning a lattice cell
 * within depth cells of one of its own (slabs at least depth columns wide:
 * the two next slabs).
 *
 * Per prepare (CPU): at a list build (and at every prepare with periodic
 * axes or DEM grains) halo_exchange (migrate, then fresh ghosts carrying the
 * arrays the scene's stages read), else halo_refresh of the moving fields
 * and halo_reorigin; the cell sort, halo_sorted (follow the ghosts and the
 * send lists through the sort); then halo_refresh of a few arrays after the
 * stages that change what neighbours read (src/cpu/backend_cpu.c). The GPU
 * backend exchanges only at its list builds and
 * refreshes with device-packed byte segments (halo_post_bytes) in between.
 * One rank uses none of this (sim_t.halo is NULL), unless an axis is
 * periodic: the images across a period are ghosts of the rank itself
 * (halo_set_periodic). */
#ifndef SPHSEG_HALO_H
#define SPHSEG_HALO_H
#include <stddef.h>
#include "../src/core/particles.h"
#include "halo_geom.h"

enum { HALO_MAX_ARRAYS = 64, HALO_DEPTH = 2 };
/* Shift codes: (s0 + 1) + 3 (s1 + 1) + 9 (s2 + 1) for a shift of s_d in
 * {-1, 0, 1} periods along axis d; 26 - code is the opposite shift. */
enum { HALO_NOSHIFT = HG_NOSHIFT, HALO_NCODES = HG_NCODES };
enum halo_method { HALO_SLABS = 0, HALO_METIS = 1 };

typedef struct halo {
    int rank, size;
    int dim, axis;         /* slab axis (0 x, 1 y, 2 z) */
    int method;            /* enum halo_method */
    int depth;             /* ghost lattice cells on each side (HALO_DEPTH) */
    real support;          /* lattice cell edge 2h, m */
    real origin[3];        /* lattice origin of the last exchange, m */
    real corner[3];        /* the particles' lower corner over all ranks at the last exchange
                            * (origin = corner - 1e-6 2h off periodic axes), m: a backend that bins
                            * into cells of another edge e takes corner - 1e-6 e, as grid_fit does
                            * on one rank, so that every rank count bins alike */
    long *bound;           /* slabs: size + 1 column bounds; bound[0] and bound[size] open */
    /* METIS: the coarse grid of blk^dim lattice cells per vertex, its owners */
    int blk, cg_n[3];
    int *part;             /* rank owning each coarse cell */
    /* Channels: a neighbour rank and a shift. Channel k sends to rank nb[k]
     * the images, moved by shift nbs[k] (a code: halo_shift_of) times the
     * periods, of the particles that lie near that rank's domain so moved,
     * and receives from it the images it sends this rank. Without periodic
     * axes every channel is a plain neighbour (shift code HALO_NOSHIFT, no
     * self); with them a rank may also be its own neighbour, and a rank may
     * be a neighbour through several shifts. Ascending by rank, then code. */
    int nnb, *nb, *nbs;
    /* Periodic axes (halo_set_periodic): bit d of per; the period along d
     * is [plo[d], plo[d] + plen[d]). Along a periodic axis the lattice
     * origin stays at plo - (depth + 1) 2h, so that images of depth cells
     * stay at positive columns. */
    int per;
    real plo[3], plen[3];
    int img[HALO_NCODES], nimg; /* the shift codes of the images: shifts along periodic axes only */
    int arr[HALO_MAX_ARRAYS], narr; /* arrays a ghost carries (part_array index) */
    size_t **send, *nsend, *cap_send; /* per neighbour: owned particles ghosted to it */
    size_t *nrecv;                    /* per neighbour: ghosts from it */
    size_t *recv, cap_recv;           /* store index of each ghost, in neighbour order */
    size_t *inv, cap_inv;             /* scratch: inverse permutation, keep list */
    char *buf[2];
    size_t cap_buf[2];
    double wall_comm;      /* wall seconds spent in exchanges and refreshes */
    double wall_wait;      /* of which in MPI waits (transfer, and waiting for slower ranks) */
    double wall_exposed;   /* seconds the computation stood still for the halo: set by a backend
                            * that overlaps (the GPU: measured on the device timeline), with
                            * exposed_measured = 1; otherwise all of wall_comm */
    int exposed_measured;
    long long migrated;    /* particles this rank sent to a neighbour, in total */
    long recut_checks;     /* load-balance checks past the threshold (src/run.c), and */
    long recuts;           /* those that moved the bounds; */
    double recut_s;        /* their wall seconds: the state to the host, the re-cut, back, prepared */
    long long bytes;       /* bytes this rank sent to its neighbours (migration, ghosts, refreshes) */
    long long messages;    /* point-to-point sends of this rank, counts included */
    long gen;              /* bumped whenever the channels are set (on every rank at once) */
    void *req;             /* MPI requests of a posted byte exchange (halo_post_bytes) */
    int nreq;
    size_t cap_req;
} halo_t;

/* Set up for particles of dimension dim on a lattice of edge support;
 * method: HALO_SLABS or HALO_METIS; axis (slabs): 0, 1, 2, or -1 for the
 * longest extent of the particles (chosen in halo_decompose).
 * arr[0..narr-1]: the arrays ghosts carry. */
void halo_init(halo_t *h, int dim, real support, int method, int axis, const int *arr, int narr);
/* Ghosts `depth` lattice cells deep (default HALO_DEPTH = 2, where they are
 * made afresh at every prepare; a backend whose neighbour lists reach 2h +
 * skin and are kept for many steps with their ghosts needs 3); METIS coarse
 * cells as wide. Before halo_decompose. */
void halo_set_depth(halo_t *h, int depth);
/* Periodic axes: bit d of mask makes axis d periodic with the period
 * [lo[d], lo[d] + len[d]). After halo_set_depth, before halo_decompose or
 * halo_restore. Owned particles are wrapped into the period at every
 * exchange (x with xr, and x_n by the same shift); every owned particle
 * within depth cells of a domain across a period boundary is sent there
 * as an image (positions shifted by the period), on one rank too: the
 * same ghost machinery, refreshes included, so no neighbour loop knows
 * about periods. Each period must be longer than 2 depth cells
 * (SCENE_PERIOD_SUPPORTS). */
void halo_set_periodic(halo_t *h, int mask, const real lo[3], const real len[3]);
/* The owned particles back into the period along every periodic axis (x
 * with xr, and x_n by the same shift); every exchange does it first. For a
 * host copy about to be written (the GPU's, whose device store wraps only
 * at its exchanges). */
void halo_wrap(const halo_t *h, particles_t *p);
/* The shift (-1, 0 or 1 periods per axis) of a shift code. */
void halo_shift_of(int code, int s[3]);
/* The displacement, m, of the images received on channel k from their
 * owners' positions (zero on a plain neighbour's channel). halo_exchange
 * and halo_refresh add it to x (and x_n) of those ghosts; a backend that
 * unpacks its own refreshes (the GPU) adds it itself. */
void halo_image_shift(const halo_t *h, int k, double s[3]);
/* Collective. Whatever rank holds which particles, cut the domain so that
 * each rank holds an equal share of the particles — slabs (every slab at
 * least depth columns wide; exit 2 if the domain is too short for the rank
 * count), or METIS parts of the graph of coarse cells (blk^dim lattice
 * cells, vertex weight its particle count, edges to the 3^dim - 1 cells
 * around) — and send every particle to its owner. Drops ghosts. */
void halo_decompose(halo_t *h, particles_t *p);
/* Take over a decomposition saved by a run on the same rank count (a
 * checkpoint): slab bounds (size + 1), or METIS coarse-grid size cg and
 * owners part; each rank must hold its own particles already. */
void halo_restore(halo_t *h, int method, int axis, const long *bound, const int cg[3], const int *part);
/* Collective. The lattice origin from the particles' lower corner; the
 * particles that left the slab to the neighbour that owns them; then fresh
 * ghosts from both neighbours at [n, n + ng). */
void halo_exchange(halo_t *h, particles_t *p);
/* After the cell sort permuted the store (perm[k] = old index now at k,
 * over n + ng particles): follow the send lists and the ghosts. */
void halo_sorted(halo_t *h, const size_t *perm, size_t n);
/* Collective. Copy arrays arr[0..narr-1] of the owners into their ghosts. */
void halo_refresh(halo_t *h, particles_t *p, const int *arr, int narr);
/* Collective. cost: this rank's measured compute seconds over the last
 * interval. If the largest cost exceeds the mean by more than threshold
 * (a fraction), move the slab bounds so that each rank's predicted cost
 * (particle count per column times its rank's cost per particle) is equal,
 * send the particles to their new owners (ghosts dropped; prepare again)
 * and return 1; else return 0. The decision is logged. */
int halo_balance(halo_t *h, particles_t *p, double cost, double threshold);
/* halo_balance in two halves, for a backend whose host copy of the
 * particles must be brought up to date first, and only when it is needed:
 * halo_imbalance (collective) returns max/mean - 1 of the ranks' costs;
 * halo_recut (collective, same arguments) re-cuts and moves particles as
 * halo_balance does when imb > threshold, and returns whether any moved. */
double halo_imbalance(halo_t *h, double cost);
int halo_recut(halo_t *h, particles_t *p, double cost, double imb, double threshold);
/* Collective among neighbours. Post the exchange of one byte segment per
 * neighbour: send + soff[k] .. send + soff[k + 1] to neighbour k, and
 * receive neighbour k's into recv + roff[k] .. recv + roff[k + 1] (both
 * sides know the sizes: a refresh of the ghost lists; every offset a
 * multiple of 8). The buffers may be device memory where
 * halo_cuda_aware(). halo_wait_bytes completes it; nothing else may be
 * posted in between. */
void halo_post_bytes(halo_t *h, const char *send, const size_t *soff, char *recv, const size_t *roff);
void halo_wait_bytes(halo_t *h);
/* Collective among neighbours. A record of `bytes` bytes to every
 * neighbour k with on[k] (all with on NULL; on must be the same on both
 * ends of a channel) from send + k bytes, and one from each into recv + k
 * bytes: descriptors of a transfer that does not go through MPI (the GPU's
 * CUDA IPC channels), blocking. */
void halo_swap_small(halo_t *h, const void *send, void *recv, size_t bytes, const int *on);
/* 1 if the MPI library reports CUDA-aware point-to-point transfers
 * (Open MPI's MPIX_Query_cuda_support) and SPHSEG_CUDA_AWARE is not 0
 * (core/tuning.h). */
int halo_cuda_aware(void);
/* The decisions' view of h (halo_geom.h), pointing at h's arrays; a device
 * copy points its arrays at device memory instead. */
void halo_geom_of(const halo_t *h, halo_geom *g);
/* Collective. The lattice origin from the owned particles' lower corner
 * over all ranks, as halo_exchange takes it: a backend that keeps its
 * ghosts bins at each sort on the lattice one rank would (the CPU). */
void halo_reorigin(halo_t *h, const particles_t *p);
/* Collective. The lattice origin from every rank's lower corner lo (this
 * rank's owned particles; periodic axes keep theirs): what halo_exchange
 * does first, for a backend that reduces its particles itself. */
void halo_set_origin(halo_t *h, const real lo[3]);
/* Collective among neighbours. Send n[k] to neighbour k and receive its
 * count into got[k], for every channel: the sizes of an exchange that
 * halo_post_bytes then carries (the GPU's device exchange). */
void halo_swap_counts(halo_t *h, const size_t *n, size_t *got);
/* The lattice column of coordinate x along axis d. */
long halo_column(const halo_t *h, int d, real x);
/* The rank owning lattice cell c (coordinates from the current origin). */
int halo_owner(const halo_t *h, const long c[3]);
void halo_free(halo_t *h);

#endif
