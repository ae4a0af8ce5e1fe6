/* scene.c — the scene file: load, -P overrides, defaults, validation and the
 * used-parameters echo (scene.h, DESIGN.md "Errors").
 *
 * The file is parsed by libyaml into a document, whose node marks give line
 * numbers. -P overrides and then defaults are edited into that document. A
 * walk checks every key and scalar against the libcyaml schema below (unknown,
 * duplicate and missing keys, numbers, enums), so each error names FILE:LINE
 * (or the -P argument) and Section:key. The edited document is emitted and
 * libcyaml loads it into struct scene; range checks follow.
 *
 * The walk checks scalars itself because libcyaml 1.3.1 accepts "1.74mm" as
 * 1.74 and "2abc" as 2, and its own errors carry no file line. The schema is
 * the one list of sections and keys; the used-parameters echo walks it too.
 *
 * This file holds what comes from the key table (the schema, the defaults,
 * the ranges), the messages and the record of where each key was set, the
 * libcyaml load and the steps in order (parse_steps); the steps themselves
 * are in scene_yaml.c, scene_walk.c and scene_check.c (scene_ctx.h), the
 * echo in scene_write.c. */
#define _POSIX_C_SOURCE 200809L
#include "scene_ctx.h"
#include "core/error.h"

#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- schema: every section and key, its type and whether it is required ---- */

#define OPT CYAML_FLAG_OPTIONAL
#define REQ CYAML_FLAG_DEFAULT
/* Key names equal member names, so one macro argument gives both. */
#define FLT(st, key, flags) CYAML_FIELD_FLOAT(#key, flags, struct st, key)
#define ENM(st, key, strs)                                                                                   \
    CYAML_FIELD_ENUM(#key, OPT | CYAML_FLAG_STRICT, struct st, key, strs, CYAML_ARRAY_LEN(strs))
#define SEC(key, member, fields) CYAML_FIELD_MAPPING(key, OPT, struct scene, member, fields)

static const cyaml_schema_value_t gravity_entry = {CYAML_VALUE_FLOAT(CYAML_FLAG_DEFAULT, double)};

/* The schema from the key table (scene_keys.h): one array of fields per
 * list entry and per section, then the sections. */
#define ENTRY(name, st, title) static const cyaml_schema_field_t name##_fields[] = {
#define END_ENTRY(name, st)                                                                                   \
    CYAML_FIELD_END                                                                                            \
    }                                                                                                          \
    ;                                                                                                          \
    static const cyaml_schema_value_t name##_entry = {                                                         \
        CYAML_VALUE_MAPPING(CYAML_FLAG_DEFAULT, struct st, name##_fields)};
#define SECTION(sec, m, st) static const cyaml_schema_field_t m##_fields[] = {
#define END_SECTION(m)                                                                                        \
    CYAML_FIELD_END                                                                                            \
    }                                                                                                          \
    ;
#define KF(sec, m, st, k, req, def, lo, hi, open, when, doc) CYAML_FIELD_FLOAT(#k, req, struct st, k),
#define KE(sec, m, st, k, type, strs, def, doc) ENM(st, k, strs),
#define KU(sec, m, st, k, def, doc) CYAML_FIELD_UINT(#k, OPT, struct st, k),
#define KS(sec, m, st, k, mn, mx, def, doc) CYAML_FIELD_STRING_PTR(#k, OPT, struct st, k, mn, mx),
#define KV(sec, m, st, k, n, def, doc) CYAML_FIELD_SEQUENCE_FIXED(#k, OPT, struct st, k, &gravity_entry, n),
#define KL(sec, m, st, k, est, entry, max, doc) \
    CYAML_FIELD_SEQUENCE(#k, OPT | CYAML_FLAG_POINTER, struct st, k, &entry, 0, max),
#define EKF(sec, st, k, doc) CYAML_FIELD_FLOAT(#k, OPT, struct st, k),
#define EKE(sec, st, k, type, strs, doc) ENM(st, k, strs),
#define EKU(sec, st, k, doc) CYAML_FIELD_UINT(#k, OPT, struct st, k),
#define EKS(sec, st, k, mn, mx, doc) CYAML_FIELD_STRING_PTR(#k, OPT, struct st, k, mn, mx),
#define EKV(sec, st, k, n, doc) CYAML_FIELD_SEQUENCE_FIXED(#k, OPT, struct st, k, &gravity_entry, n),
#include "scene_keys.h"

const cyaml_schema_field_t scene_fields[] = {
#include "scene_keys_none.h"
#undef SECTION
#define SECTION(sec, m, st) SEC(sec, m, m##_fields),
#include "scene_keys.h"
    CYAML_FIELD_END,
};

static const cyaml_schema_value_t scene_schema = {
    CYAML_VALUE_MAPPING(CYAML_FLAG_POINTER, struct scene, scene_fields)};

/* ---- defaults (as YAML text, edited into the document when a key is absent) - */

struct scene_default {
    const char *section, *key, *value;
};

/* The keys with a default (value NULL: none; add_defaults skips them). */
static const struct scene_default scene_defaults[] = {
#include "scene_keys_none.h"
#undef KF
#define KF(sec, m, st, k, req, def, lo, hi, open, when, doc) {sec, #k, def},
#undef KE
#define KE(sec, m, st, k, type, strs, def, doc) {sec, #k, def},
#undef KU
#define KU(sec, m, st, k, def, doc) {sec, #k, def},
#undef KS
#define KS(sec, m, st, k, mn, mx, def, doc) {sec, #k, def},
#undef KV
#define KV(sec, m, st, k, n, def, doc) {sec, #k, def},
#include "scene_keys.h"
};

/* ---- ranges of the double parameters ----------------------------------------- */

struct scene_range {
    const char *name; /* Section:key */
    size_t offset;    /* of the double in struct scene */
    double lo, hi;
    int open, when;
};

/* The numbers with a range (when NO_RANGE: none; check_ranges skips them). */
static const struct scene_range scene_ranges[] = {
#include "scene_keys_none.h"
#undef KF
#define KF(sec, m, st, k, req, def, lo, hi, open, when, doc) {sec ":" #k, offsetof(struct scene, m.k), lo, hi, open, when},
#include "scene_keys.h"
};

/* The list entries the echo writes with keys left out (scene_write.c). */
const cyaml_schema_value_t *const scene_wall_entry = &cwall_entry, *const scene_region_entry = &region_entry;

/* What struct scene keeps of the walk: scene_key_line, scene_key_where. */
struct scene_keys {
    int n_over, n_leaf;
    char **over; /* where each override came from: "-P ARG", or "Run:preset NAME (ARG)" */
    struct scene_leaf leaf[];
};

/* ---- messages and the record of keys ------------------------------------------- */

/* Append printf output at offset n of out[cap]; returns the new offset. */
size_t scene_vcat(char *out, size_t cap, size_t n, const char *fmt, va_list ap)
{
    if (n >= cap) return n;
    int k = vsnprintf(out + n, cap - n, fmt, ap);
    return k < 0 ? n : n + (size_t)k;
}

size_t scene_cat(char *out, size_t cap, size_t n, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    n = scene_vcat(out, cap, n, fmt, ap);
    va_end(ap);
    return n;
}

/* Write "WHERE: NAME: why" to c->err: WHERE is "-P ARG" for override `over`
 * >= 0, else FILE:LINE (FILE alone when line is 0); NAME may be NULL. Control
 * characters become spaces so the message is one line. Returns -1. */
static int vfail(struct scene_ctx *c, int over, int line, const char *name, const char *fmt, va_list ap)
{
    char *e = c->err;
    size_t cap = c->errlen, n = 0;
    if (!e || cap == 0) return -1;
    if (over >= 0 && over < c->n_preset)
        n = scene_cat(e, cap, n, "Run:preset %s (%s): ", c->preset, c->over[over]);
    else if (over >= 0)
        n = scene_cat(e, cap, n, "-P %s: ", c->over[over]);
    else if (line > 0)
        n = scene_cat(e, cap, n, "%s:%d: ", c->path, line);
    else
        n = scene_cat(e, cap, n, "%s: ", c->path);
    if (name) n = scene_cat(e, cap, n, "%s: ", name);
    scene_vcat(e, cap, n, fmt, ap);
    for (char *p = e; *p; ++p)
        if (iscntrl((unsigned char)*p)) *p = ' ';
    return -1;
}

int scene_fail(struct scene_ctx *c, int over, int line, const char *name, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vfail(c, over, line, name, fmt, ap);
    va_end(ap);
    return -1;
}

int scene_leaf_add(struct scene_ctx *c, const char *name, int line, int over)
{
    if (c->n_leaf == SCENE_MAX_LEAVES) return scene_fail(c, -1, line, name, "too many keys");
    struct scene_leaf *l = &c->leaf[c->n_leaf++];
    snprintf(l->name, sizeof l->name, "%.63s", name);
    l->line = line;
    l->over = over;
    return 0;
}

static const struct scene_leaf *leaf_in(const struct scene_leaf *leaf, int n, const char *name)
{
    for (int i = 0; i < n; ++i)
        if (strcmp(leaf[i].name, name) == 0) return &leaf[i];
    return NULL;
}

const struct scene_leaf *scene_leaf_find(const struct scene_ctx *c, const char *name)
{
    return leaf_in(c->leaf, c->n_leaf, name);
}

/* Where parameter `name` ("Section:key") was set: the override (or -1), and
 * the line of its key in the file, else of its section, else 1. */
static void leaf_resolve(const struct scene_leaf *leaf, int n, const char *name, int *over, int *line)
{
    char sec[SCENE_NAME];
    const struct scene_leaf *l = leaf_in(leaf, n, name);
    *over = l ? l->over : -1;
    *line = l ? l->line : 0;
    if (*line > 0) return;
    snprintf(sec, sizeof sec, "%.*s", (int)strcspn(name, ":"), name);
    l = leaf_in(leaf, n, sec);
    *line = l && l->line > 0 ? l->line : 1;
}

/* Error about parameter `name` ("Section:key") after the walk, located by
 * leaf_resolve. */
int scene_fail_at(struct scene_ctx *c, const char *name, const char *fmt, ...)
{
    int over, line;
    leaf_resolve(c->leaf, c->n_leaf, name, &over, &line);
    va_list ap;
    va_start(ap, fmt);
    vfail(c, over, line, name, fmt, ap);
    va_end(ap);
    return -1;
}

/* The shortest of %.15g, %.16g, %.17g that reads back as exactly d. */
void scene_fmt_double(char *out, size_t n, double d)
{
    for (int prec = 15; prec <= 17; ++prec) {
        snprintf(out, n, "%.*g", prec, d);
        if (strtod(out, NULL) == d) return;
    }
}

int scene_buf_write(void *data, unsigned char *bytes, size_t size)
{
    struct scene_buf *b = data;
    if (b->n + size + 1 > b->cap) {
        size_t cap = 2 * (b->n + size + 1);
        char *p = realloc(b->p, cap);
        if (!p) {
            b->bad = 1;
            return 0;
        }
        b->p = p;
        b->cap = cap;
    }
    memcpy(b->p + b->n, bytes, size);
    b->n += size;
    b->p[b->n] = '\0';
    return 1;
}

/* ---- defaults, the libcyaml load, ranges ------------------------------------------ */

/* The keys with a default the walk did not meet, edited into the document. */
const char *scene_key_default(const char *name)
{
    for (size_t i = 0; i < ARRAY_LEN(scene_defaults); ++i) {
        const struct scene_default *d = &scene_defaults[i];
        size_t ls = strlen(d->section);
        if (!strncmp(name, d->section, ls) && name[ls] == ':' && !strcmp(name + ls + 1, d->key)) return d->value;
    }
    return NULL;
}

static int add_defaults(struct scene_ctx *c)
{
    char name[SCENE_NAME], why[160];
    for (size_t i = 0; i < ARRAY_LEN(scene_defaults); ++i) {
        const struct scene_default *d = &scene_defaults[i];
        if (!d->value) continue; /* required, or no default */
        snprintf(name, sizeof name, "%s:%s", d->section, d->key);
        if (scene_leaf_find(c, name)) continue;
        const char *comp[2] = {d->section, d->key};
        int val = scene_doc_add_text(c, d->value, why, sizeof why);
        if (!val || scene_doc_put(c, comp, 2, val)) return scene_fail(c, -1, 0, name, "default %s", why);
    }
    return 0;
}

/* libcyaml's log: its first error, for the message of a failed load. */
static void cyaml_log_capture(cyaml_log_t level, void *ctx, const char *fmt, va_list args)
{
    struct scene_ctx *c = ctx;
    if (level < CYAML_LOG_ERROR || c->log[0]) return; /* keep the first error */
    vsnprintf(c->log, sizeof c->log, fmt, args);
    c->log[strcspn(c->log, "\n")] = '\0';
}

/* The edited document emitted as text and loaded by libcyaml into s. */
static int load_struct(struct scene_ctx *c, struct scene *s)
{
    struct scene_buf b = {0};
    int ok = scene_doc_emit(&c->doc, &b);
    c->have_doc = 0;
    if (!ok) {
        free(b.p);
        return scene_fail(c, -1, 0, NULL, "internal error: cannot emit the edited scene");
    }
    cyaml_config_t cfg = {.log_fn = cyaml_log_capture,
                          .log_ctx = c,
                          .mem_fn = cyaml_mem, /* realloc/free: free() releases it */
                          .log_level = CYAML_LOG_ERROR,
                          .flags = CYAML_CFG_DEFAULT};
    struct scene *tmp = NULL;
    cyaml_err_t e =
        cyaml_load_data((const uint8_t *)b.p, b.n, &cfg, &scene_schema, (cyaml_data_t **)&tmp, NULL);
    free(b.p);
    if (e != CYAML_OK)
        return scene_fail(c, -1, 0, NULL, "libcyaml: %s%s%s", cyaml_strerror(e), c->log[0] ? ": " : "", c->log);
    *s = *tmp;
    free(tmp);
    return 0;
}

/* Every number with a range in the key table against it. */
static int check_ranges(struct scene_ctx *c, const struct scene *s)
{
    char got[32], lo[32], hi[32];
    int constant = s->segregation.model == SEG_MODEL_CONSTANT;
    for (size_t i = 0; i < ARRAY_LEN(scene_ranges); ++i) {
        const struct scene_range *r = &scene_ranges[i];
        if (r->when == NO_RANGE || (r->when == IF_CONSTANT && !constant) || (r->when == IF_SHEAR_RATE && constant))
            continue;
        if (r->when != ALWAYS && !s->segregation.enabled) continue;
        double v;
        memcpy(&v, (const char *)s + r->offset, sizeof v);
        scene_fmt_double(got, sizeof got, v);
        if (!isfinite(v)) return scene_fail_at(c, r->name, "not a finite number: %s", got);
        int lo_ok = r->open & LO_OPEN ? v > r->lo : v >= r->lo;
        int hi_ok = r->open & HI_OPEN ? v < r->hi : v <= r->hi;
        if (lo_ok && hi_ok) continue;
        scene_fmt_double(lo, sizeof lo, r->lo);
        scene_fmt_double(hi, sizeof hi, r->hi);
        if (isinf(r->hi))
            return scene_fail_at(c, r->name, "must be %s %s, got %s", r->open & LO_OPEN ? ">" : ">=", lo, got);
        return scene_fail_at(c, r->name, "must be in %c%s, %s%c, got %s", r->open & LO_OPEN ? '(' : '[', lo, hi,
                       r->open & HI_OPEN ? ')' : ']', got);
    }
    return 0;
}

/* ---- public API ----------------------------------------------------------------------- */

/* Copy the walk's record of keys into s->keys. */
static int keys_keep(struct scene_ctx *c, struct scene *s)
{
    struct scene_keys *k = calloc(1, sizeof *k + (size_t)c->n_leaf * sizeof k->leaf[0]);
    if (!k) return -1;
    s->keys = k;
    k->n_leaf = c->n_leaf;
    memcpy(k->leaf, c->leaf, (size_t)c->n_leaf * sizeof k->leaf[0]);
    k->over = calloc((size_t)c->n_over + 1, sizeof *k->over);
    if (!k->over) return -1;
    for (; k->n_over < c->n_over; ++k->n_over) { /* where each was set, as messages name it */
        char w[320];
        if (k->n_over < c->n_preset)
            snprintf(w, sizeof w, "Run:preset %s (%s)", c->preset, c->over[k->n_over]);
        else
            snprintf(w, sizeof w, "-P %s", c->over[k->n_over]);
        if (!(k->over[k->n_over] = strdup(w))) return -1;
    }
    return 0;
}

/* The steps of a load, in order; the first that fails ends it. */
static int parse_steps(struct scene_ctx *c, struct scene *s)
{
    if (scene_read_text(c) || scene_load_doc(c) || scene_expand_preset(c) || scene_apply_overrides(c) ||
        scene_move_grain_keys(c) ||
        scene_walk(c) || scene_require_model_keys(c) || add_defaults(c) || load_struct(c, s))
        return -1;
    if (!scene_leaf_find(c, "Output:diag_dt")) s->output.diag_dt = s->output.dt / 20;
    if (check_ranges(c, s) || scene_check_special(c, s) || scene_check_every(c, &s->segregation)) return -1;
    s->path = strdup(c->path);
    if (!s->path || keys_keep(c, s)) return scene_fail(c, -1, 0, NULL, "out of memory");
    s->text = c->text;
    c->text = NULL;
    return 0;
}

int scene_parse(struct scene *s, const char *path, int n_over, char **over, char *err, size_t errlen)
{
    struct scene_ctx *c = calloc(1, sizeof *c);
    memset(s, 0, sizeof *s);
    if (err && errlen) err[0] = '\0';
    if (!c) {
        if (err && errlen) snprintf(err, errlen, "out of memory");
        return -1;
    }
    c->path = path ? path : "(no scene file)";
    c->n_over = over ? n_over : 0;
    c->over = over;
    c->err = err;
    c->errlen = errlen;
    int rc = path ? parse_steps(c, s) : scene_fail(c, -1, 0, NULL, "no scene file given");
    if (c->have_doc) yaml_document_delete(&c->doc);
    free(c->first_node);
    free(c->text);
    if (c->over_owned) free(c->over);
    free(c);
    if (rc) scene_free(s);
    return rc ? -1 : 0;
}

int scene_load(struct scene *s, const char *path, int n_over, char **over)
{
    char err[SCENE_ERRLEN];
    if (scene_parse(s, path, n_over, over, err, sizeof err)) input_error("%s", err);
    return 0;
}
/* Where Section:key was set: the override index (or -1) and the file line. */
static void key_origin(const struct scene *s, const char *section, const char *key, int *over, int *line)
{
    char name[2 * SCENE_NAME];
    const struct scene_keys *k = s->keys;
    snprintf(name, sizeof name, "%s:%s", section, key);
    leaf_resolve(k ? k->leaf : NULL, k ? k->n_leaf : 0, name, over, line);
}

int scene_key_line(const struct scene *s, const char *section, const char *key)
{
    int over, line;
    key_origin(s, section, key, &over, &line);
    return line;
}

const char *scene_key_where(const struct scene *s, const char *section, const char *key, char *buf, size_t n)
{
    int over, line;
    const struct scene_keys *k = s->keys;
    key_origin(s, section, key, &over, &line);
    if (k && over >= 0 && over < k->n_over)
        snprintf(buf, n, "%s", k->over[over]);
    else
        snprintf(buf, n, "%s:%d", s->path ? s->path : "(no scene file)", line);
    return buf;
}

int scene_key_overridden(const struct scene *s, const char *section, const char *key)
{
    int over, line;
    const struct scene_keys *k = s->keys;
    key_origin(s, section, key, &over, &line);
    return k && over >= 0 && over < k->n_over;
}

/* A container's box: the walls' ends and cylinders, the regions' shapes
 * (a fill below its level, as high as that). */
void scene_container_box(const struct scene_container *k, double lo[2], double hi[2])
{
    for (int a = 0; a < 2; ++a) lo[a] = INFINITY, hi[a] = -INFINITY;
    for (unsigned i = 0; i < k->walls_count; ++i) {
        const struct scene_wall *w = &k->walls[i];
        if (w->shape == CWALL_ENDS) continue;
        for (int a = 0; a < 2; ++a) {
            double l = w->shape == CWALL_CYLINDER ? w->centre[a] - w->radius : fmin(w->from[a], w->to[a]);
            double h = w->shape == CWALL_CYLINDER ? w->centre[a] + w->radius : fmax(w->from[a], w->to[a]);
            lo[a] = fmin(lo[a], l), hi[a] = fmax(hi[a], h);
        }
    }
    for (unsigned r = 0; r < k->regions_count; ++r) {
        const struct scene_region *g = &k->regions[r];
        if (g->shape == REGION_BOX)
            for (int a = 0; a < 2; ++a) lo[a] = fmin(lo[a], g->lo[a]), hi[a] = fmax(hi[a], g->hi[a]);
        else if (g->shape == REGION_SECTOR)
            for (int a = 0; a < 2; ++a)
                lo[a] = fmin(lo[a], g->centre[a] - g->r_out), hi[a] = fmax(hi[a], g->centre[a] + g->r_out);
        else if (g->shape == REGION_COLUMN)
            lo[0] = fmin(lo[0], g->centre[0] - g->r_out), hi[0] = fmax(hi[0], g->centre[0] + g->r_out),
            hi[1] = fmax(hi[1], g->level);
        else
            hi[1] = fmax(hi[1], g->level);
    }
}

void scene_extent(const struct scene *s, double ext[3])
{
    const struct scene_geometry *g = &s->geometry;
    int d3 = g->dim == 3;
    if (g->type == GEOM_DRUM) {
        ext[0] = ext[1] = 2 * g->radius, ext[2] = d3 ? g->length : 0;
    } else if (g->type == GEOM_CONTAINER) {
        double lo[2], hi[2];
        scene_container_box(&s->container, lo, hi);
        for (int a = 0; a < 2; ++a) ext[a] = hi[a] > lo[a] ? hi[a] - lo[a] : 0;
        if (g->periodic & PERIODIC_X) ext[0] = fmax(ext[0], g->width);
        if (g->periodic & PERIODIC_Y) ext[1] = fmax(ext[1], g->height);
        ext[2] = d3 ? g->depth : 0;
    } else {
        ext[0] = g->width + (g->type == GEOM_COLUMN ? g->runout : 0), ext[1] = g->height;
        ext[2] = d3 ? g->depth : 0;
    }
}

void scene_free(struct scene *s)
{
    if (!s) return;
    if (s->keys) {
        for (int i = 0; i < s->keys->n_over; ++i)
            free(s->keys->over[i]);
        free(s->keys->over);
        free(s->keys);
    }
    for (unsigned i = 0; i < s->container.walls_count; ++i) free(s->container.walls[i].name);
    free(s->container.walls);
    free(s->container.regions);
    free(s->run.backend);
    free(s->segregation.every);
    free(s->path);
    free(s->text);
    memset(s, 0, sizeof *s);
}
