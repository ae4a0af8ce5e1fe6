/* core/particles.c — the structure-of-arrays particle store (see particles.h).
 * Every per-particle array is one component of a row of PART_FIELDS
 * (src/core/fields.h), and part_arrays[] is made from that table;
 * allocation, release, permutation, packing and the memory estimate all
 * loop over it, so a new field is one row of the table. */
#include "particles.h"
#include "error.h"
#include <stdlib.h>
#include <string.h>
#include "omp_shim.h"

struct part_array {
    size_t offset; /* offsetof(particles_t, <pointer member>) */
    size_t size;   /* bytes per element */
};

#define PART_ARRAY_COMP(comp, type) {offsetof(particles_t, comp), sizeof(type)},
#define PART_ARRAY_ROW(member, fld, type, n, trim) PART_FIELD_EACH(n, PART_ARRAY_COMP, member, type)
static const struct part_array part_arrays[] = {PART_FIELDS(PART_ARRAY_ROW)};
#undef PART_ARRAY_ROW
#undef PART_ARRAY_COMP

/* Each row's component count, in order: array k's row is the row whose
 * components cover k (part_array_field). */
#define PART_ROW_N(member, fld, type, n, trim) n,
static const int part_row_n[] = {PART_FIELDS(PART_ROW_N)};
#undef PART_ROW_N
enum { PART_NFIELDS = (int)(sizeof part_row_n / sizeof part_row_n[0]) };
_Static_assert(PART_NFIELDS <= 32, "a field mask is a uint32_t");

int part_array_field(size_t k)
{
    int r = 0;
    for (size_t c = (size_t)part_row_n[0]; c <= k; c += (size_t)part_row_n[++r]) {}
    return r;
}

uint32_t part_fields_all(void) { return PART_NFIELDS == 32 ? 0xffffffffu : (1u << PART_NFIELDS) - 1; }

/* The table makes every array member of particles_t and the list alike; past
 * the counts at its head, particles_t holds those pointers and nothing
 * else, one after another (a member added outside the table fails here). */
_Static_assert(sizeof part_arrays / sizeof part_arrays[0] == PART_NARRAYS, "one entry per array");
_Static_assert(sizeof(particles_t) == offsetof(particles_t, x) + PART_NARRAYS * sizeof(void *),
               "particles_t holds a member outside PART_FIELDS (src/core/fields.h)");

/* Read / write the pointer member described by a. memcpy keeps this free of
 * type punning (the member is real *, int64_t * or uint8_t *). */
static void *part_get(const particles_t *p, const struct part_array *a)
{
    void *ptr;
    memcpy(&ptr, (const char *)p + a->offset, sizeof ptr);
    return ptr;
}

static void part_set(particles_t *p, const struct part_array *a, void *ptr)
{
    memcpy((char *)p + a->offset, &ptr, sizeof ptr);
}

/* Below this many particles the store's loops run on one thread. */
#define PART_PAR_MIN 4096

/* Zero elements [a, b) of every array on all threads, in the static slices
 * the particle loops use: the first touch of a fresh page places it on the
 * NUMA node of the thread that will work on it. */
static void part_touch(particles_t *p, size_t a, size_t b)
{
#pragma omp parallel if (b - a >= PART_PAR_MIN)
    {
        const size_t T = (size_t)omp_get_num_threads(), t = (size_t)omp_get_thread_num();
        const size_t k0 = a + (b - a) * t / T, k1 = a + (b - a) * (t + 1) / T;
        for (size_t k = 0; k < PART_NARRAYS; k++) {
            size_t es = part_arrays[k].size;
            char *a = part_get(p, &part_arrays[k]);
            if (a) memset(a + k0 * es, 0, (k1 - k0) * es);
        }
    }
}

void part_alloc_fields(particles_t *p, int dim, size_t cap, uint32_t fields)
{
    memset(p, 0, sizeof *p);
    p->dim = dim;
    p->n = 0;
    p->cap = cap;
    p->fields = fields & part_fields_all();
    size_t nalloc = cap > 0 ? cap : 1; /* calloc(0) may return NULL */
    for (size_t k = 0; k < PART_NARRAYS; k++) {
        if (!(p->fields >> part_array_field(k) & 1)) continue; /* not this run's: NULL */
        void *buf = calloc(nalloc, part_arrays[k].size); /* fresh large blocks: pages untouched */
        if (!buf)
            error_exit(1, "out of memory allocating %zu particles (%zu bytes each)", cap, part_store_bytes(p));
        part_set(p, &part_arrays[k], buf);
    }
    part_touch(p, 0, nalloc);
}

void part_alloc(particles_t *p, int dim, size_t cap) { part_alloc_fields(p, dim, cap, part_fields_all()); }

void part_free(particles_t *p)
{
    for (size_t k = 0; k < PART_NARRAYS; k++)
        free(part_get(p, &part_arrays[k]));
    memset(p, 0, sizeof *p);
}

/* part_gather's loop for elements of type T */
#define PART_GATHER_AS(T)                                                                                     \
    do {                                                                                                       \
        T *d = dst;                                                                                            \
        const T *s = src;                                                                                      \
        for (size_t k = k0; k < k1; k++) d[k] = s[perm[k]];                                                    \
    } while (0)

/* dst[k] = src[perm[k]], k in [k0, k1), for elements of esize bytes. */
static void part_gather(void *dst, const void *src, const size_t *perm, size_t k0, size_t k1, size_t esize)
{
    switch (esize) {
    case 8:
        PART_GATHER_AS(uint64_t);
        break;
    case 4:
        PART_GATHER_AS(uint32_t);
        break;
    case 1:
        PART_GATHER_AS(uint8_t);
        break;
    default:
        for (size_t k = k0; k < k1; k++)
            memcpy((char *)dst + k * esize, (const char *)src + perm[k] * esize, esize);
    }
}
#undef PART_GATHER_AS

/* Gather every array through perm into its first m entries. Parallel over
 * particles: thread t gathers and stores back the same static slice of every
 * array, so each page stays with the thread that first touched it
 * (part_alloc). Two scratch buffers alternate, so that storing array k-1
 * back and gathering array k share one barrier: the gather reads array k,
 * which no thread writes in that phase. */
static void part_gather_all(particles_t *p, const size_t *perm, size_t m)
{
    if (m == 0) return;
    size_t emax = 1;
    for (size_t k = 0; k < PART_NARRAYS; k++)
        if (part_arrays[k].size > emax) emax = part_arrays[k].size;
    char *buf = malloc(2 * m * emax);
    if (!buf) error_exit(1, "out of memory permuting %zu particles", m);
    char *scr[2] = {buf, buf + m * emax};
#pragma omp parallel if (m >= PART_PAR_MIN)
    {
        const size_t T = (size_t)omp_get_num_threads(), t = (size_t)omp_get_thread_num();
        const size_t k0 = m * t / T, k1 = m * (t + 1) / T;
        for (size_t k = 0; k <= PART_NARRAYS; k++) {
            char *prev = k > 0 ? part_get(p, &part_arrays[k - 1]) : NULL;
            const void *cur = k < PART_NARRAYS ? part_get(p, &part_arrays[k]) : NULL;
            if (prev) { /* array k-1 back from its buffer */
                size_t es = part_arrays[k - 1].size;
                memcpy(prev + k0 * es, scr[(k - 1) % 2] + k0 * es, (k1 - k0) * es);
            }
            if (cur) part_gather(scr[k % 2], cur, perm, k0, k1, part_arrays[k].size);
            if (prev || cur) {
#pragma omp barrier
            }
        }
    }
    free(buf);
}

void part_permute(particles_t *p, const size_t *perm) { part_gather_all(p, perm, p->n + p->ng); }

void part_compact(particles_t *p, const size_t *keep, size_t m)
{
    part_gather_all(p, keep, m);
    p->n = m;
    p->ng = 0;
}

void part_reserve(particles_t *p, size_t cap)
{
    if (cap <= p->cap) return;
    for (size_t k = 0; k < PART_NARRAYS; k++) {
        if (!part_get(p, &part_arrays[k])) continue; /* not this run's */
        void *buf = realloc(part_get(p, &part_arrays[k]), cap * part_arrays[k].size);
        if (!buf) error_exit(1, "out of memory growing the particle store to %zu particles", cap);
        part_set(p, &part_arrays[k], buf);
    }
    part_touch(p, p->cap, cap);
    p->cap = cap;
}

int part_array_find(const particles_t *p, const void *ptr)
{
    if (!ptr) return -1; /* a field the store does not hold */
    for (size_t k = 0; k < PART_NARRAYS; k++)
        if (part_get(p, &part_arrays[k]) == ptr) return (int)k;
    return -1;
}

size_t part_record_bytes(const int *arr, int narr)
{
    size_t b = 0;
    for (int a = 0; a < narr; a++)
        b += part_arrays[arr[a]].size;
    return b;
}

void part_pack(const particles_t *p, const size_t *idx, size_t m, const int *arr, int narr, char *buf)
{
    size_t rec = part_record_bytes(arr, narr);
    for (int a = 0, off = 0; a < narr; off += (int)part_arrays[arr[a]].size, a++) {
        size_t es = part_arrays[arr[a]].size;
        const char *src = part_get(p, &part_arrays[arr[a]]);
        for (size_t k = 0; k < m; k++)
            memcpy(buf + k * rec + (size_t)off, src + (idx ? idx[k] : k) * es, es);
    }
}

void part_unpack(particles_t *p, const size_t *idx, size_t at, size_t m, const int *arr, int narr,
                 const char *buf)
{
    size_t rec = part_record_bytes(arr, narr);
    for (int a = 0, off = 0; a < narr; off += (int)part_arrays[arr[a]].size, a++) {
        size_t es = part_arrays[arr[a]].size;
        char *dst = part_get(p, &part_arrays[arr[a]]);
        for (size_t k = 0; k < m; k++)
            memcpy(dst + (idx ? idx[k] : at + k) * es, buf + k * rec + (size_t)off, es);
    }
}

size_t part_narrays(void) { return PART_NARRAYS; }
size_t part_array_esize(size_t k) { return part_arrays[k].size; }
void *part_array_get(const particles_t *p, size_t k) { return part_get(p, &part_arrays[k]); }
void part_array_set(particles_t *p, size_t k, void *ptr) { part_set(p, &part_arrays[k], ptr); }

size_t part_fields_bytes(uint32_t fields)
{
    size_t b = 0;
    for (size_t k = 0; k < PART_NARRAYS; k++)
        if (fields >> part_array_field(k) & 1) b += part_arrays[k].size;
    return b;
}

size_t part_bytes_per_particle(void) { return part_fields_bytes(part_fields_all()); }

size_t part_store_bytes(const particles_t *p) { return part_fields_bytes(p->fields); }
