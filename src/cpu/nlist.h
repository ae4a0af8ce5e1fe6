/* nlist.h — the CPU backend's Verlet neighbour list (issue 56): each
 * particle's neighbours within 2h + skin (skin = Run:list_skin h), in the
 * order the cell scan of nbr.h meets them, as a row of indices that every
 * neighbour loop walks (src/physics/grid.h, GRID_NBR_ROWS) instead of the
 * 3^d cells of 2h, about six times the candidates in 3D.
 *
 * The CPU sorts the store by cell at every prepare (nbr_build, so that the
 * store, its checkpoints and every sum keep today's order), and the list
 * holds indices: at each sort it follows the particles (nlist_update: each
 * row moved to its particle's new index, its entries renamed through the
 * sort's permutation and put back in ascending index order, which is the
 * cell scan's order on a store without ghosts: cells in index order, each
 * cell's run in store order). Bodies skip a neighbour beyond the support
 * before anything else (r^2 >= support2), so a list that holds every
 * particle within 2h, in the scan's order, gives the scan's sums bit for bit.
 * It is built again (from the cells that the ball of 2h + skin touches,
 * grid_list_fill_reach) when a particle has moved skin/2 since the last
 * build, when the store changed outside a sort (a drain, a load balance:
 * nlist_forget), and with a halo at every prepare that makes the ghosts
 * afresh: on several ranks, when an owned particle of any rank has moved
 * skin/2 (nlist_stale) or an exact classification is due, the ghosts kept
 * in between (their rows follow the sort: nlist_follow merges a row's owned
 * and ghost entries by cell and rank); with periodic axes or DEM grains at
 * every prepare (src/cpu/backend_cpu.c, cpu_keeps_why). */
#ifndef SPHSEG_NLIST_H
#define SPHSEG_NLIST_H
#include "nbr.h"

/* The skin, in units of h, of a list built at every prepare (a run with a
 * halo): the stages between two prepares read it at the positions it was
 * built at (sim/integrate.c: every advance is followed by a prepare before
 * any neighbour loop), so it needs no skin, only a margin over the rounding
 * of r^2 against the support's square (1e-3 h: 5e-4 of 2h, far above a
 * float's 6e-8). */
#define NLIST_SKIN_FRESH 1e-3

typedef struct nlist {
    int on;                 /* 1: the list (SPHSEG_CPU_NBR unset or list, and it fits); 0: the cell scan */
    int valid;              /* the rows match the store's order */
    unsigned *nl, *nl2;     /* rows of cap entries, and the spare the next sort moves them into */
    unsigned *cnt, *cnt2;   /* entries of each row (above cap: the row overflowed; that particle scans) */
    real *xb[3], *xb2[3];   /* positions at the last build, for the skin test */
    unsigned char *wact, *wact2; /* a dummy's wall loop is due until the next build (flow_wall_reached, at
                                  * each build); a dummy not due takes flow_wall_none (the GPU's wact) */
    unsigned *inv;          /* scratch: the sort's inverse permutation */
    size_t n, cap_part;     /* particles in the rows; allocated */
    unsigned cap;           /* entries a row */
    double list2, skin;     /* (2h + skin)^2; skin, m */
    long builds, follows;   /* builds from the cells; sorts the rows followed */
} nlist;

/* Choose the form at the first call (SPHSEG_CPU_NBR, core/tuning.h; the
 * list's memory against the machine's free memory) and name it in the log. */
void nlist_init(nlist *L, const particles_t *p, double h, double dr, double skin_h);
/* After nbr_build of g (g->perm: the old index now at k): build the list,
 * or follow the sort, and set it in g->view. mode NLIST_AUTO (no halo):
 * build where a particle has moved skin/2 or the store changed, else
 * follow; NLIST_BUILD: the ghosts were made afresh; NLIST_FOLLOW: the
 * ghosts were kept (the ranks agreed on it: nlist_stale). */
enum { NLIST_AUTO, NLIST_BUILD, NLIST_FOLLOW };
void nlist_update(nlist *L, nbr_grid *g, particles_t *p, int mode);
/* Before a prepare's sort: 1 when the list cannot be followed (off, never
 * built, the store changed, or an owned particle has moved skin/2 since
 * the build), so that the ghosts must be made afresh and the list built. */
int nlist_stale(const nlist *L, const particles_t *p);
/* The store changed outside a sort (drain, load balance, restart): the next
 * update builds. */
void nlist_forget(nlist *L);
/* Dummy i's wall loop is due (flow_wall_reached at the list's build): 1
 * for every dummy without the list. */
static inline int nlist_wall_due(const nlist *L, size_t i) { return !L->on || !L->valid || L->wact[i]; }
/* Bytes a particle the list holds (0 for the cell scan). */
size_t nlist_bytes(const nlist *L);
void nlist_free(nlist *L);

#endif
