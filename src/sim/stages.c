/* stages.c — the step's stages as data, and what follows from them
 * (stages.h). */
#include "stages.h"
#include <stdio.h>
#include <string.h>
#include "sim.h"

#define STAGE_TABLE_ROWS /* stage_table.h: the rows too */
#include "stage_table.h"
const int stage_table_n = (int)(sizeof stage_table / sizeof stage_table[0]);

/* The hooks in the order a run can call them: two half steps (each rates
 * followed by the DEM grains' coupling, src/sim/integrate.c), the filter,
 * a window's close with its two midpoint stages; then round again. Every
 * reader a run can meet after a writer is in it. A writer that only some
 * runs call (the filter's store) could close a field early for the others;
 * in this table none stands between another writer and its first reader,
 * and tests/test_stages.c holds the derived refreshes to the lists worked
 * out by hand. */
static const int cycle[] = {HOOK_RATES,   HOOK_DEM,       HOOK_SAVE,      HOOK_ADVANCE, HOOK_PREPARE,
                            HOOK_RATES,   HOOK_DEM,       HOOK_ADVANCE,   HOOK_PREPARE, HOOK_FILTER,
                            HOOK_PREPARE, HOOK_CONC_BEGIN, HOOK_CONC_STEP, HOOK_CONC_STEP};
enum { NCYCLE = (int)(sizeof cycle / sizeof cycle[0]) };

unsigned stage_flags(const struct sim *s)
{
    unsigned f = 0;
    if (s->flow_on) f |= SF_FLOW;
    if (s->seg_on) f |= SF_SEG;
    if (s->win.on) f |= SF_WIN;
    if (s->seg_on && s->seg.scheme == SEG_SCHEME_CONSERVATIVE && s->seg.renorm) f |= SF_RENORM;
    if (s->hcsr) f |= SF_HCSR;
    if (s->shift.kind != SHIFT_OFF) f |= SF_SHIFT;
    if (s->flow_on && s->flow.kgc) f |= SF_KGC;
    if (s->dem) f |= SF_DEM;
    if (s->dem && s->dem->coupling == DEM_TWO_WAY) f |= SF_DEM2;
    if (s->flow_on && s->flow.contact) f |= SF_CONTACT;
    return f;
}

static int row_on(const stage *r, unsigned flags)
{
    return (r->when & flags) == r->when && !(r->unless & flags);
}

int stage_runs(unsigned flags, int id)
{
    for (int k = 0; k < stage_table_n; ++k)
        if (stage_table[k].id == id && row_on(&stage_table[k], flags)) return 1;
    return 0;
}

int stage_plan(int hook, unsigned flags, const stage **rows)
{
    int n = 0;
    for (int k = 0; k < stage_table_n; ++k) {
        const stage *r = &stage_table[k];
        if (!(r->hooks & H(hook)) || !row_on(r, flags)) continue;
        int seen = 0;
        for (int q = 0; q < n; ++q) seen |= rows[q]->id == r->id;
        if (!seen) rows[n++] = r;
    }
    return n;
}

/* What stage id reads of ghosts, and writes, under flags (all its rows). */
static uint32_t id_halo(int id, unsigned flags)
{
    uint32_t m = 0;
    for (int k = 0; k < stage_table_n; ++k)
        if (stage_table[k].id == id && row_on(&stage_table[k], flags)) m |= stage_table[k].halo;
    return m;
}

static uint32_t id_writes(int id, unsigned flags, int *range, int *from_owner)
{
    uint32_t m = 0;
    for (int k = 0; k < stage_table_n; ++k) {
        const stage *r = &stage_table[k];
        if (r->id != id || !row_on(r, flags)) continue;
        m |= r->writes;
        if (range) *range = r->range;
        if (from_owner) *from_owner = r->from_owner;
    }
    return m;
}

uint32_t stage_store_fields(unsigned flags)
{
    uint32_t m = STAGE_STORE_BASE | stage_ghost_fields(flags);
    for (int k = 0; k < stage_table_n; ++k) {
        const stage *r = &stage_table[k];
        if (row_on(r, flags)) m |= r->halo | r->writes | r->reads;
    }
    if (!POS_REMAINDER) m &= ~(uint32_t)FLD_XR;
    return m;
}

uint32_t stage_ghost_fields(unsigned flags)
{
    uint32_t m = FLD_X | FLD_ID | FLD_KIND;
    for (int k = 0; k < stage_table_n; ++k) {
        const stage *r = &stage_table[k];
        if (!row_on(r, flags)) continue;
        m |= r->halo;
        if (r->from_owner) m |= r->writes;
    }
    return m;
}

/* The cycle unrolled into stage ids: seq[0..n-1]. */
static int unroll(unsigned flags, int *seq)
{
    int n = 0;
    for (int c = 0; c < NCYCLE; ++c) {
        const stage *rows[ST_N];
        int m = stage_plan(cycle[c], flags, rows);
        for (int q = 0; q < m; ++q) seq[n++] = rows[q]->id;
    }
    return n;
}

/* Walk on from position at of seq (once round): the fields of `want` that
 * a stage reads of a ghost before a stage writes them again (a later
 * writer that leaves them stale in the ghosts owes its own refresh) or the
 * ghosts are made afresh (ST_EXCHANGE, unless keep). */
static uint32_t needed_after(const int *seq, int n, int at, uint32_t want, unsigned flags, int keep)
{
    uint32_t need = 0, open = want;
    for (int q = 1; q <= n && open; ++q) {
        int id = seq[(at + q) % n];
        if (id == ST_EXCHANGE && !keep) break;
        uint32_t r = id_halo(id, flags) & open;
        need |= r;
        open &= ~(r | id_writes(id, flags, NULL, NULL));
    }
    return need;
}

uint32_t stage_refresh_after(int id, unsigned flags, int keep)
{
    int range = RANGE_OWNED, fo = 0;
    uint32_t w = id_writes(id, flags, &range, &fo), m = 0;
    if (fo) return w;
    if (!w || range == RANGE_ALL) return 0;
    int seq[ST_N * NCYCLE], n = unroll(flags, seq);
    for (int at = 0; at < n; ++at) /* every place the cycle runs it */
        if (seq[at] == id) m |= needed_after(seq, n, at, w, flags, keep);
    return m;
}

uint32_t stage_moving_fields(unsigned flags)
{
    int seq[ST_N * NCYCLE], n = unroll(flags, seq);
    uint32_t m = 0;
    for (int at = 0; at < n; ++at) {
        int id = seq[at];
        if (id != ST_PLACE && id != ST_ADVANCE && id != ST_ADVANCE_C && id != ST_ADVANCE_GSUM) continue;
        m |= needed_after(seq, n, at, id_writes(id, flags, NULL, NULL), flags, 1);
    }
    return m;
}

const stage_sched *stage_schedule(unsigned flags)
{
    enum { NF = SF_ALL + 1 }; /* ten flags */
    static stage_sched memo[NF];
    static int done[NF];
    flags &= NF - 1;
    stage_sched *m = &memo[flags];
    if (done[flags]) return m;
    for (int h = 0; h < HOOK_N; ++h) {
        const stage *rows[ST_N];
        m->n[h] = stage_plan(h, flags, rows);
        for (int k = 0; k < m->n[h]; ++k) m->ids[h][k] = rows[k]->id;
    }
    for (int keep = 0; keep < 2; ++keep)
        for (int id = 0; id < ST_N; ++id) m->refresh[keep][id] = stage_refresh_after(id, flags, keep);
    m->moving = stage_moving_fields(flags);
    m->ghost = stage_ghost_fields(flags);
    done[flags] = 1;
    return m;
}

/* Each field's bit, component count and what a trimmed 2D list keeps of
 * it, in the table's order: the store's arrays are its components in turn. */
static const struct {
    uint32_t bit;
    int n, keep2d;
    const char *name;
} stage_fields[] = {
#define STAGE_FIELD(member, fld, type, n, trim) {FLD_##fld, n, PART_FIELD_KEEP2D(trim, n), #member},
    PART_FIELDS(STAGE_FIELD)
#undef STAGE_FIELD
};
_Static_assert(sizeof stage_fields / sizeof stage_fields[0] == FLD_NFIELDS, "one bit per field");
_Static_assert(FLD_NFIELDS <= 31, "the field bits are an int enum and a uint32_t mask");
/* a VEC row is a 3-vector, a SYM row a symmetric tensor of 6 */
#define STAGE_TRIM_OK(member, fld, type, n, trim) &&PART_FIELD_KEEP2D(trim, n) > 0
_Static_assert(1 PART_FIELDS(STAGE_TRIM_OK), "a VEC field has 3 components, a SYM field 6");
#undef STAGE_TRIM_OK

int stage_arrays(const particles_t *p, uint32_t f, int trim2d, void **ptrs)
{
    const int trim = trim2d && p->dim == 2;
    int n = 0;
    for (size_t i = 0, k = 0; i < FLD_NFIELDS; k += (size_t)stage_fields[i].n, ++i)
        if (f & stage_fields[i].bit)
            for (int d = 0; d < (trim ? stage_fields[i].keep2d : stage_fields[i].n); ++d)
                ptrs[n++] = part_array_get(p, k + (size_t)d);
    return n;
}

const char *stage_fields_str(uint32_t f, char *buf, size_t len)
{
    size_t o = 0;
    buf[0] = 0;
    for (int k = 0; k < FLD_NFIELDS; ++k) {
        if (!(f & stage_fields[k].bit)) continue;
        o += (size_t)snprintf(buf + o, o < len ? len - o : 0, "%s%s", o ? ", " : "", stage_fields[k].name);
    }
    return buf;
}
