/* stages.h — the step's stages, declared once as data (docs/architecture.md,
 * "One step"): for each stage the hook that runs it, the body, when it runs,
 * the particles it runs on, what it reads of other ranks' particles (ghosts)
 * and what it writes. From this one table come
 *  - the order in which a backend's hook runs its stages (stage_plan; the CPU
 *    backend runs its hooks from it, the GPU backend fuses and overlaps some
 *    of them and checks its order against it: gpu/README.md);
 *  - the arrays a ghost carries (stage_ghost_fields, halo_init's list);
 *  - the halo refresh after a stage (stage_refresh_after), and the fields a
 *    backend that keeps its ghosts between list builds refreshes when the
 *    particles move (stage_moving_fields: the GPU's).
 * A new term in the step is an id and a row in src/sim/stage_table.h, its
 * body in src/physics/, and its case in each backend (docs/architecture.md). */
#ifndef SPHSEG_STAGES_H
#define SPHSEG_STAGES_H
#include <stdint.h>
#include "core/particles.h"

/* Fields of the store, as bits: FLD_<FLD> for each row of PART_FIELDS
 * (src/core/fields.h), in its order (a field may be several arrays: x is 3). */
#define STAGE_FIELD_POS(member, fld, type, n, trim) FLD_POS_##fld,
enum stage_field_pos { PART_FIELDS(STAGE_FIELD_POS) FLD_NFIELDS };
#undef STAGE_FIELD_POS
#define STAGE_FIELD_BIT(member, fld, type, n, trim) FLD_##fld = 1u << FLD_POS_##fld,
enum stage_field {
    PART_FIELDS(STAGE_FIELD_BIT)              /* then the unions: */
    FLD_SEGC = FLD_SEGV | FLD_SEGQ | FLD_SEGD /* the segregation coefficients V, Q, D */
};
#undef STAGE_FIELD_BIT

/* What the run solves, as bits: a stage runs when all of its `when` bits
 * are set and none of its `unless` bits. */
enum stage_flag {
    SF_FLOW = 1u << 0,   /* computed flow (Kinematics:velocity computed) */
    SF_SEG = 1u << 1,    /* the concentration equation */
    SF_WIN = 1u << 2,    /* concentration windows (Segregation:every > 1 or auto) */
    SF_RENORM = 1u << 3, /* the conservative scheme with renormalisation */
    SF_HCSR = 1u << 4,   /* a scheme that classifies every step (paper, direct) */
    SF_SHIFT = 1u << 5,  /* particle shifting (Flow:shifting fickian) */
    SF_KGC = 1u << 6,    /* the corrected kernel gradient (Flow:gradient_correction on) */
    SF_DEM = 1u << 7,    /* DEM grains (DEM:d > 0; src/dem/) */
    SF_DEM2 = 1u << 8,   /* their coupling two ways (DEM:coupling two_way) */
    SF_CONTACT = 1u << 9, /* the Coulomb walls' friction on the particles (Walls:coulomb_force particles) */
    SF_ALL = (1u << 10) - 1
};

/* HOOK_DEM: struct backend's dem_couple, after each rates (src/sim/sim.h). */
enum stage_hook { HOOK_PREPARE, HOOK_RATES, HOOK_SAVE, HOOK_ADVANCE, HOOK_CONC_BEGIN, HOOK_CONC_STEP, HOOK_FILTER,
                  HOOK_DEM, HOOK_N };

/* The particles a stage runs on: the owned ones, or the owned and the
 * ghosts (each ghost from its own support here). */
enum stage_range { RANGE_OWNED, RANGE_ALL };


typedef struct stage {
    int id;                /* enum stage_id (stage_table.h) */
    unsigned hooks;        /* bits 1 << enum stage_hook */
    const char *body;
    unsigned when, unless; /* enum stage_flag */
    int range;             /* enum stage_range */
    uint32_t halo;   /* what it reads of a ghost that the ghost's owner must supply (enum stage_field) */
    uint32_t writes; /* what it writes */
    int from_owner;  /* the ghosts' results are replaced by their owners' (a refresh after it) */
    uint32_t reads;  /* what it reads of the particle itself beyond halo (stage_store_fields) */
} stage;

/* The stage ids and the table's rows: src/sim/stage_table.h, one file. */
#include "stage_table.h"

/* The table, in step order within each hook. */
extern const stage stage_table[];
extern const int stage_table_n;

/* The flags of a run. */
struct sim;
unsigned stage_flags(const struct sim *s);

/* The stages hook h runs under flags, in order, one row per stage (the
 * first), into rows[] (at most ST_N); returns how many. */
int stage_plan(int hook, unsigned flags, const stage **rows);
/* Whether stage id runs under flags (a row of it is on): how a backend that
 * fuses stages into one pass (ST_ADVANCE with ST_ADVANCE_C) learns what the
 * pass does, instead of deciding it from the run's state. */
int stage_runs(unsigned flags, int id);

/* What the driver, the snapshots (io_fields[]) and the diagnostics read
 * in every run, whatever stage runs: the snapshot's fields, and x_n (the
 * blow-up guard's step length, a periodic wrap). */
#define STAGE_STORE_BASE                                                                                     \
    (FLD_X | FLD_V | FLD_VOL | FLD_C | FLD_GDOT | FLD_SIG | FLD_NRM | FLD_PSI | FLD_KIND | FLD_BCLASS |      \
     FLD_WALL | FLD_ID | FLD_XN)

/* The fields a run under flags allocates (issue 56): STAGE_STORE_BASE and
 * every field a running row reads (halo, reads) or writes; xr only in the
 * single build (POS_REMAINDER, core/hd.h: 0 and never read in double).
 * The rest stay NULL in the store (part_alloc_fields) and on the device. */
uint32_t stage_store_fields(unsigned flags);

/* The fields a ghost carries: those some running stage reads of a ghost,
 * those refreshed from the owners, and x, id, kind (the halo's own). */
uint32_t stage_ghost_fields(unsigned flags);

/* The fields to refresh in the ghosts after stage id (of RANGE_OWNED): its
 * writes that a later stage reads of a ghost before any stage writes them
 * again or the ghosts are made afresh (ST_EXCHANGE; keep = 1: a backend
 * that keeps its ghosts between list builds, whose exchanges this leaves
 * out); all its writes with from_owner; none for RANGE_ALL. The later
 * stages are those of a cycle of hooks that holds every order a run can
 * call them in (two half steps, the filter, a window's close and two of its
 * midpoint stages: stages.c says what that holds). */
uint32_t stage_refresh_after(int id, unsigned flags, int keep);

/* For a backend that keeps its ghosts (keep = 1): the fields that the
 * stages from ST_SAVE to ST_PLACE change and that the ghosts need before
 * anything refreshes them; refreshed when the particles have moved. */
uint32_t stage_moving_fields(unsigned flags);

/* All of the above for one run's flags, worked out once (the hooks run
 * from it every step): each hook's stage ids in order, the refresh after
 * each stage ([keep][id]), the moving and the ghost fields. */
typedef struct stage_sched {
    int n[HOOK_N];
    int ids[HOOK_N][ST_N];
    uint32_t refresh[2][ST_N];
    uint32_t moving, ghost;
} stage_sched;
const stage_sched *stage_schedule(unsigned flags);

/* The arrays of the fields as pointers of p (host or device: the same
 * members), in the store's order (part_array_get); trim2d leaves out of a
 * 2D store what the table's trim column says: the z components of the
 * vectors (x, v, normal, ...) and the xz, yz stresses. Returns how many
 * (at most PART_NARRAYS). */
int stage_arrays(const particles_t *p, uint32_t fields, int trim2d, void **ptrs);

/* "x, v, sig" for messages and tests: the fields' member names. */
const char *stage_fields_str(uint32_t fields, char *buf, size_t len);

#endif
