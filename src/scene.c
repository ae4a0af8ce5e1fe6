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
 * the one list of sections and keys; the used-parameters echo walks it too. */
#define _POSIX_C_SOURCE 200809L
#include "scene.h"
#include "error.h"

#include <cyaml/cyaml.h>
#include <yaml.h>

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#define ARRAY_LEN(a) (sizeof(a) / sizeof((a)[0]))

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
#define KE(sec, m, st, k, strs, def, doc) ENM(st, k, strs),
#define KU(sec, m, st, k, def, doc) CYAML_FIELD_UINT(#k, OPT, struct st, k),
#define KS(sec, m, st, k, mn, mx, def, doc) CYAML_FIELD_STRING_PTR(#k, OPT, struct st, k, mn, mx),
#define KV(sec, m, st, k, n, def, doc) CYAML_FIELD_SEQUENCE_FIXED(#k, OPT, struct st, k, &gravity_entry, n),
#define KL(sec, m, st, k, entry, max, doc) \
    CYAML_FIELD_SEQUENCE(#k, OPT | CYAML_FLAG_POINTER, struct st, k, &entry, 0, max),
#define EKF(sec, st, k, doc) CYAML_FIELD_FLOAT(#k, OPT, struct st, k),
#define EKE(sec, st, k, strs, doc) ENM(st, k, strs),
#define EKU(sec, st, k, doc) CYAML_FIELD_UINT(#k, OPT, struct st, k),
#define EKS(sec, st, k, mn, mx, doc) CYAML_FIELD_STRING_PTR(#k, OPT, struct st, k, mn, mx),
#define EKV(sec, st, k, n, doc) CYAML_FIELD_SEQUENCE_FIXED(#k, OPT, struct st, k, &gravity_entry, n),
#include "scene_keys.h"
#undef ENTRY
#undef END_ENTRY
#undef SECTION
#undef END_SECTION
#define ENTRY(name, st, title)
#define END_ENTRY(name, st)
#define END_SECTION(m)
#undef KF
#undef KE
#undef KU
#undef KS
#undef KV
#undef KL
#undef EKF
#undef EKE
#undef EKU
#undef EKS
#undef EKV
#define EKF(sec, st, k, doc)
#define EKE(sec, st, k, strs, doc)
#define EKU(sec, st, k, doc)
#define EKS(sec, st, k, mn, mx, doc)
#define EKV(sec, st, k, n, doc)

static const cyaml_schema_field_t scene_fields[] = {
#define SECTION(sec, m, st) SEC(sec, m, m##_fields),
#define KF(sec, m, st, k, req, def, lo, hi, open, when, doc)
#define KE(sec, m, st, k, strs, def, doc)
#define KU(sec, m, st, k, def, doc)
#define KS(sec, m, st, k, mn, mx, def, doc)
#define KV(sec, m, st, k, n, def, doc)
#define KL(sec, m, st, k, entry, max, doc)
#include "scene_keys.h"
#undef SECTION
    CYAML_FIELD_END,
};
#define SECTION(sec, m, st)

static const cyaml_schema_value_t scene_schema = {
    CYAML_VALUE_MAPPING(CYAML_FLAG_POINTER, struct scene, scene_fields)};

/* ---- defaults (as YAML text, edited into the document when a key is absent) - */

struct scene_default {
    const char *section, *key, *value;
};

/* The keys with a default (value NULL: none; add_defaults skips them). */
static const struct scene_default scene_defaults[] = {
#undef KF
#undef KE
#undef KU
#undef KS
#undef KV
#define KF(sec, m, st, k, req, def, lo, hi, open, when, doc) {sec, #k, def},
#define KE(sec, m, st, k, strs, def, doc) {sec, #k, def},
#define KU(sec, m, st, k, def, doc) {sec, #k, def},
#define KS(sec, m, st, k, mn, mx, def, doc) {sec, #k, def},
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
#undef KF
#undef KE
#undef KU
#undef KS
#undef KV
#define KF(sec, m, st, k, req, def, lo, hi, open, when, doc) {sec ":" #k, offsetof(struct scene, m.k), lo, hi, open, when},
#define KE(sec, m, st, k, strs, def, doc)
#define KU(sec, m, st, k, def, doc)
#define KS(sec, m, st, k, mn, mx, def, doc)
#define KV(sec, m, st, k, n, def, doc)
#include "scene_keys.h"
};

/* ---- parse context and error messages ------------------------------------------ */

enum { SCENE_MAX_LEAVES = 640, SCENE_MAX_DEPTH = 4, SCENE_NAME = 64 };

/* A key the walk met: where it was set, for errors found after loading. */
struct scene_leaf {
    char name[SCENE_NAME]; /* "Section" or "Section:key" */
    int line;              /* 1-based line of the key in the file, 0 if not there */
    int over;              /* index of the -P override that set it, or -1 */
};

/* What struct scene keeps of the walk: scene_key_line, scene_key_where. */
struct scene_keys {
    int n_over, n_leaf;
    char **over; /* copies of the -P arguments */
    struct scene_leaf leaf[];
};

struct scene_ctx {
    const char *path;
    int n_over;
    char **over;
    char *text; /* the file, NUL-terminated */
    size_t len;
    yaml_document_t doc;
    int have_doc;
    int n_file_nodes; /* nodes 1..n_file_nodes came from the file */
    int *first_node;  /* first node of override i; [n_over]: first default node */
    struct scene_leaf leaf[SCENE_MAX_LEAVES];
    int n_leaf;
    char *err;
    size_t errlen;
    char log[256]; /* libcyaml's first error message */
};

/* Append printf output at offset n of out[cap]; returns the new offset. */
static size_t vcat(char *out, size_t cap, size_t n, const char *fmt, va_list ap)
{
    if (n >= cap) return n;
    int k = vsnprintf(out + n, cap - n, fmt, ap);
    return k < 0 ? n : n + (size_t)k;
}

static size_t cat(char *out, size_t cap, size_t n, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static size_t cat(char *out, size_t cap, size_t n, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    n = vcat(out, cap, n, fmt, ap);
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
    if (over >= 0)
        n = cat(e, cap, n, "-P %s: ", c->over[over]);
    else if (line > 0)
        n = cat(e, cap, n, "%s:%d: ", c->path, line);
    else
        n = cat(e, cap, n, "%s: ", c->path);
    if (name) n = cat(e, cap, n, "%s: ", name);
    vcat(e, cap, n, fmt, ap);
    for (char *p = e; *p; ++p)
        if (iscntrl((unsigned char)*p)) *p = ' ';
    return -1;
}

static int fail(struct scene_ctx *c, int over, int line, const char *name, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
static int fail(struct scene_ctx *c, int over, int line, const char *name, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vfail(c, over, line, name, fmt, ap);
    va_end(ap);
    return -1;
}

static int leaf_add(struct scene_ctx *c, const char *name, int line, int over)
{
    if (c->n_leaf == SCENE_MAX_LEAVES) return fail(c, -1, line, name, "too many keys");
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

static const struct scene_leaf *leaf_find(const struct scene_ctx *c, const char *name)
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

/* Error about parameter `name` ("Section:key") after loading, located by
 * leaf_resolve. */
static int fail_at(struct scene_ctx *c, const char *name, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int fail_at(struct scene_ctx *c, const char *name, const char *fmt, ...)
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
static void fmt_double(char *out, size_t n, double d)
{
    for (int prec = 15; prec <= 17; ++prec) {
        snprintf(out, n, "%.*g", prec, d);
        if (strtod(out, NULL) == d) return;
    }
}

/* ---- the libyaml document ------------------------------------------------------ */

static yaml_node_t *node(struct scene_ctx *c, int id) { return yaml_document_get_node(&c->doc, id); }

static const char *scalar(const yaml_node_t *n) { return (const char *)n->data.scalar.value; }

static int node_count(const struct scene_ctx *c) { return (int)(c->doc.nodes.top - c->doc.nodes.start); }

static int node_line(struct scene_ctx *c, int id)
{
    yaml_node_t *n = node(c, id);
    return n ? (int)n->start_mark.line + 1 : 1;
}

/* Where node id came from: -1 the file, i >= 0 override i, -2 a default. */
static int node_origin(const struct scene_ctx *c, int id)
{
    if (id <= c->n_file_nodes || !c->first_node) return -1;
    for (int i = c->n_over; i >= 0; --i)
        if (id >= c->first_node[i]) return i == c->n_over ? -2 : i;
    return -1;
}

static int is_null(const yaml_node_t *n)
{
    static const char *const nulls[] = {"", "~", "null", "Null", "NULL"};
    if (n->type != YAML_SCALAR_NODE || n->data.scalar.style != YAML_PLAIN_SCALAR_STYLE) return 0;
    for (size_t i = 0; i < ARRAY_LEN(nulls); ++i)
        if (strcmp(scalar(n), nulls[i]) == 0) return 1;
    return 0;
}

/* The pair of mapping `map` whose key is `key`, or NULL. The pointer is valid
 * until a pair is appended to that mapping. */
static yaml_node_pair_t *map_pair(struct scene_ctx *c, int map, const char *key)
{
    yaml_node_t *m = node(c, map);
    if (!m || m->type != YAML_MAPPING_NODE) return NULL;
    for (yaml_node_pair_t *p = m->data.mapping.pairs.start; p < m->data.mapping.pairs.top; ++p) {
        yaml_node_t *k = node(c, p->key);
        if (k && k->type == YAML_SCALAR_NODE && strcmp(scalar(k), key) == 0) return p;
    }
    return NULL;
}

static int map_append(struct scene_ctx *c, int map, const char *key, int val)
{
    int k = yaml_document_add_scalar(&c->doc, NULL, (yaml_char_t *)key, -1, YAML_PLAIN_SCALAR_STYLE);
    return k && yaml_document_append_mapping_pair(&c->doc, map, k, val) ? 0 : -1;
}

/* Copy node id of src (and what it holds) into dst; returns the new id or 0. */
static int node_copy(yaml_document_t *dst, yaml_document_t *src, int id, int depth)
{
    yaml_node_t *n = yaml_document_get_node(src, id);
    if (!n || depth > 8) return 0;
    if (n->type == YAML_SCALAR_NODE)
        return yaml_document_add_scalar(dst, n->tag, n->data.scalar.value, (int)n->data.scalar.length,
                                        n->data.scalar.style);
    if (n->type == YAML_SEQUENCE_NODE) {
        int out = yaml_document_add_sequence(dst, n->tag, n->data.sequence.style);
        for (yaml_node_item_t *it = n->data.sequence.items.start; out && it < n->data.sequence.items.top;
             ++it) {
            int k = node_copy(dst, src, *it, depth + 1);
            if (!k || !yaml_document_append_sequence_item(dst, out, k)) return 0;
        }
        return out;
    }
    int out = yaml_document_add_mapping(dst, n->tag, n->data.mapping.style);
    for (yaml_node_pair_t *p = n->data.mapping.pairs.start; out && p < n->data.mapping.pairs.top; ++p) {
        int k = node_copy(dst, src, p->key, depth + 1), v = node_copy(dst, src, p->value, depth + 1);
        if (!k || !v || !yaml_document_append_mapping_pair(dst, out, k, v)) return 0;
    }
    return out;
}

/* Scene files are a few kB of shallow YAML; libyaml takes quadratic time
 * over deep flow nesting ([[[...]]] 200 000 levels: minutes), so deeper
 * nesting or a larger file is refused before it parses. */
enum { SCENE_MAX_NEST = 64, SCENE_MAX_BYTES = 1 << 20 };

/* The line where flow nesting ([ and { outside quotes and comments) first
 * passes SCENE_MAX_NEST, or 0. */
static int text_too_deep(const char *t, size_t n)
{
    int depth = 0, line = 1, quote = 0, comment = 0;
    for (size_t i = 0; i < n; ++i) {
        char ch = t[i];
        if (ch == '\n') line++, comment = 0;
        if (comment) continue;
        if (quote) {
            if (quote == '"' && ch == '\\' && i + 1 < n) ++i;
            else if (ch == quote) quote = 0;
        } else if (ch == '\'' || ch == '"') {
            quote = ch;
        } else if (ch == '#' && (i == 0 || t[i - 1] == ' ' || t[i - 1] == '\t' || t[i - 1] == '\n')) {
            comment = 1;
        } else if ((ch == '[' || ch == '{') && ++depth > SCENE_MAX_NEST) {
            return line;
        } else if ((ch == ']' || ch == '}') && depth > 0) {
            depth--;
        }
    }
    return 0;
}

/* Parse `text` as YAML and add its root to the scene document; returns the
 * node id, or 0 with the reason in why. Empty text gives an empty scalar. */
static int doc_add_text(struct scene_ctx *c, const char *text, char *why, size_t n)
{
    yaml_parser_t p;
    yaml_document_t v;
    int id = 0;
    if (text_too_deep(text, strlen(text)))
        return snprintf(why, n, "is nested more than %d levels deep", SCENE_MAX_NEST), 0;
    snprintf(why, n, "cannot be stored: out of memory");
    if (!yaml_parser_initialize(&p)) return 0;
    yaml_parser_set_input_string(&p, (const unsigned char *)text, strlen(text));
    if (!yaml_parser_load(&p, &v)) {
        snprintf(why, n, "is not valid YAML: %s", p.problem ? p.problem : "parse error");
    } else {
        if (yaml_document_get_root_node(&v))
            id = node_copy(&c->doc, &v, 1, 0);
        else
            id = yaml_document_add_scalar(&c->doc, NULL, (yaml_char_t *)"", 0, YAML_PLAIN_SCALAR_STYLE);
        if (!id) snprintf(why, n, "is nested too deeply");
        yaml_document_delete(&v);
    }
    yaml_parser_delete(&p);
    return id;
}

/* Set comp[0]:...:comp[n-1] to node val, creating sections as needed. A
 * section that is not a mapping is left alone: the walk reports it. */
static int doc_put(struct scene_ctx *c, const char *const *comp, int n, int val)
{
    int map = 1; /* the root */
    for (int j = 0; j < n - 1; ++j) {
        yaml_node_pair_t *p = map_pair(c, map, comp[j]);
        int sub = p ? p->value : 0;
        if (!sub) {
            sub = yaml_document_add_mapping(&c->doc, NULL, YAML_BLOCK_MAPPING_STYLE);
            if (!sub || map_append(c, map, comp[j], sub)) return -1;
        }
        if (node(c, sub)->type != YAML_MAPPING_NODE) return 0;
        map = sub;
    }
    yaml_node_pair_t *p = map_pair(c, map, comp[n - 1]);
    if (p) {
        p->value = val;
        return 0;
    }
    return map_append(c, map, comp[n - 1], val);
}

/* ---- reading the file ---------------------------------------------------------- */

static int read_text(struct scene_ctx *c)
{
    FILE *f = fopen(c->path, "rb");
    if (!f) return fail(c, -1, 0, NULL, "cannot read: %s", strerror(errno));
    size_t cap = 4096, n = 0;
    char *t = malloc(cap);
    while (t) {
        size_t got = fread(t + n, 1, cap - n - 1, f);
        n += got;
        if (got == 0) break;
        if (n + 1 == cap) {
            char *bigger = realloc(t, cap *= 2);
            if (!bigger) free(t);
            t = bigger;
        }
    }
    int eno = errno, bad = ferror(f);
    fclose(f);
    if (!t) return fail(c, -1, 0, NULL, "cannot read: out of memory");
    if (bad) {
        free(t);
        return fail(c, -1, 0, NULL, "cannot read: %s", strerror(eno));
    }
    t[n] = '\0';
    c->text = t;
    c->len = n;
    if (n > SCENE_MAX_BYTES)
        return fail(c, -1, 0, NULL, "%zu bytes: larger than any scene file (at most %d)", n, SCENE_MAX_BYTES);
    int deep = text_too_deep(t, n);
    if (deep) return fail(c, -1, deep, NULL, "not a scene: nested more than %d levels deep", SCENE_MAX_NEST);
    return 0;
}

static int yaml_fail(struct scene_ctx *c, const yaml_parser_t *p)
{
    size_t line = p->problem_mark.line + 1;
    if (p->error == YAML_READER_ERROR) { /* located by byte offset only */
        line = 1;
        for (size_t i = 0; i < p->problem_offset && i < c->len; ++i)
            line += c->text[i] == '\n';
    }
    const char *why = p->problem ? p->problem : "parse error";
    return fail(c, -1, (int)line, NULL, "not valid YAML: %s%s%s", why, p->context ? " " : "",
                p->context ? p->context : "");
}

/* Sections written with no keys ("Physics:" alone) become empty mappings. */
static int empty_sections(struct scene_ctx *c)
{
    yaml_node_t *root = node(c, 1);
    int n = (int)(root->data.mapping.pairs.top - root->data.mapping.pairs.start);
    for (int i = 0; i < n; ++i) {
        yaml_node_pair_t *p = node(c, 1)->data.mapping.pairs.start + i;
        if (!is_null(node(c, p->value))) continue;
        int m = yaml_document_add_mapping(&c->doc, NULL, YAML_BLOCK_MAPPING_STYLE);
        if (!m) return fail(c, -1, 0, NULL, "out of memory");
        node(c, 1)->data.mapping.pairs.start[i].value = m;
    }
    return 0;
}

/* Parse the text into c->doc: one document whose root is a mapping. */
static int load_doc(struct scene_ctx *c)
{
    yaml_parser_t p;
    yaml_document_t extra;
    int rc = 0;
    if (!yaml_parser_initialize(&p)) return fail(c, -1, 0, NULL, "out of memory");
    yaml_parser_set_input_string(&p, (const unsigned char *)c->text, c->len);
    if (!yaml_parser_load(&p, &c->doc)) {
        rc = yaml_fail(c, &p);
    } else if (!yaml_parser_load(&p, &extra)) {
        c->have_doc = 1;
        rc = yaml_fail(c, &p);
    } else {
        c->have_doc = 1;
        if (yaml_document_get_root_node(&extra))
            rc = fail(c, -1, (int)extra.start_mark.line + 1, NULL, "more than one YAML document");
        yaml_document_delete(&extra);
    }
    yaml_parser_delete(&p);
    if (rc) return rc;
    yaml_node_t *root = yaml_document_get_root_node(&c->doc);
    if (!root) { /* an empty file: start an empty mapping in a fresh document */
        yaml_document_delete(&c->doc);
        if (!yaml_document_initialize(&c->doc, NULL, NULL, NULL, 1, 1) ||
            !yaml_document_add_mapping(&c->doc, NULL, YAML_BLOCK_MAPPING_STYLE))
            return fail(c, -1, 0, NULL, "out of memory");
    } else if (root->type != YAML_MAPPING_NODE) {
        return fail(c, -1, (int)root->start_mark.line + 1, NULL,
                    "not a scene: the top level must be a mapping of sections (Run:, ...)");
    }
    return empty_sections(c);
}

/* ---- -P Section:key=value overrides --------------------------------------------- */

static const cyaml_schema_field_t *field_find(const cyaml_schema_field_t *f, const char *key)
{
    for (; f->key; ++f)
        if (strcmp(f->key, key) == 0) return f;
    return NULL;
}

static int fail_unknown(struct scene_ctx *c, int over, int line, const char *name,
                        const cyaml_schema_field_t *fields, int section)
{
    char known[512];
    size_t n = 0;
    known[0] = '\0';
    for (; fields->key; ++fields)
        n = cat(known, sizeof known, n, "%s%s", n ? ", " : "", fields->key);
    return fail(c, over, line, name, "unknown %s (known: %s)", section ? "section" : "key", known);
}

/* Split "A:b=value" (in buf) into path components; 0 if malformed. */
static int over_split(const char *arg, char *buf, size_t n, char **comp, int *ncomp, const char **value)
{
    const char *eq = strchr(arg, '=');
    if (!eq || (size_t)(eq - arg) >= n) return 0;
    memcpy(buf, arg, (size_t)(eq - arg));
    buf[eq - arg] = '\0';
    *value = eq + 1;
    *ncomp = 0;
    for (char *s = buf; s; ++*ncomp) {
        if (*ncomp == SCENE_MAX_DEPTH) return 0;
        comp[*ncomp] = s;
        s = strchr(s, ':');
        if (s) *s++ = '\0';
    }
    for (int i = 0; i < *ncomp; ++i)
        if (!comp[i][0]) return 0;
    return *ncomp >= 2;
}

/* Check an override's path against the schema. */
static int over_check(struct scene_ctx *c, int i, char *const *comp, int n)
{
    const cyaml_schema_field_t *fields = scene_fields;
    if (n == 2 && !strcmp(comp[0], "Segregation") && (!strcmp(comp[1], "d_small") || !strcmp(comp[1], "d_large")))
        return 0; /* the grain sizes' old place: move_grain_keys */
    char name[256];
    size_t len = 0;
    for (int j = 0; j < n; ++j) {
        len = cat(name, sizeof name, len, "%s%s", j ? ":" : "", comp[j]);
        const cyaml_schema_field_t *f = field_find(fields, comp[j]);
        if (!f) return fail_unknown(c, i, 0, name, fields, j == 0);
        if (j + 1 == n) break;
        if (f->value.type != CYAML_MAPPING) return fail(c, i, 0, name, "not a section");
        fields = f->value.mapping.fields;
    }
    return 0;
}

static int apply_override(struct scene_ctx *c, int i)
{
    char buf[256], *comp[SCENE_MAX_DEPTH], why[160];
    const char *value;
    int n;
    if (!over_split(c->over[i], buf, sizeof buf, comp, &n, &value))
        return fail(c, i, 0, NULL, "malformed override, expected -P Section:key=value");
    if (over_check(c, i, comp, n)) return -1;
    int val = doc_add_text(c, value, why, sizeof why);
    if (!val) return fail(c, i, 0, NULL, "value %s", why);
    if (doc_put(c, (const char *const *)comp, n, val)) return fail(c, i, 0, NULL, "out of memory");
    return 0;
}

static int apply_overrides(struct scene_ctx *c)
{
    c->n_file_nodes = node_count(c);
    c->first_node = malloc(((size_t)c->n_over + 1) * sizeof *c->first_node);
    if (!c->first_node) return fail(c, -1, 0, NULL, "out of memory");
    for (int i = 0; i < c->n_over; ++i) {
        c->first_node[i] = node_count(c) + 1;
        if (apply_override(c, i)) return -1;
    }
    c->first_node[c->n_over] = node_count(c) + 1;
    return 0;
}

/* ---- the walk: the document against the schema ----------------------------------- */

/* Write a reason into why[n]; returns -1. */
static int why_set(char *why, size_t n, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int why_set(char *why, size_t n, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vcat(why, n, 0, fmt, ap);
    va_end(ap);
    return -1;
}

static int float_check(const char *s, char *why, size_t n)
{
    const char *t = s + (*s == '+' || *s == '-');
    if (strcasecmp(t, ".inf") == 0 || (t == s && strcasecmp(s, ".nan") == 0))
        return why_set(why, n, "not a finite number: %s", s);
    char *end = NULL;
    double d = *s && !isspace((unsigned char)*s) ? strtod(s, &end) : 0;
    if (!end || end == s || *end) return why_set(why, n, "expected a number, got '%.40s'", s);
    if (!isfinite(d)) return why_set(why, n, "not a finite number: %.40s", s);
    return 0;
}

static int uint_check(const char *s, char *why, size_t n)
{
    char *end;
    errno = 0;
    unsigned long long u = strtoull(s, &end, 10);
    if (!isdigit((unsigned char)*s) || *end || errno || u > 0xffffffffULL)
        return why_set(why, n, "expected a non-negative integer, got '%.40s'", s);
    return 0;
}

static int enum_check(const char *s, const cyaml_schema_value_t *v, char *why, size_t n)
{
    size_t k = cat(why, n, 0, "expected one of ");
    for (uint32_t i = 0; i < v->enumeration.count; ++i) {
        if (strcmp(s, v->enumeration.strings[i].str) == 0) return 0;
        k = cat(why, n, k, "%s%s", i ? "|" : "", v->enumeration.strings[i].str);
    }
    cat(why, n, k, ", got '%.40s'", s);
    return -1;
}

static const char *type_word(const cyaml_schema_value_t *v)
{
    switch (v->type) {
    case CYAML_FLOAT:
        return "a number";
    case CYAML_UINT:
        return "a non-negative integer";
    case CYAML_ENUM:
        return "a name";
    case CYAML_MAPPING:
        return "a section (a mapping of keys)";
    case CYAML_SEQUENCE_FIXED:
    case CYAML_SEQUENCE:
        return "a list";
    default:
        return "a string";
    }
}

/* A scalar against its schema value; 0 if fine, else -1 with why. */
static int scalar_check(const yaml_node_t *n, const cyaml_schema_value_t *v, char *why, size_t len)
{
    static const char *const kinds[] = {"nothing", "a scalar", "a list", "a mapping"};
    if (n->type != YAML_SCALAR_NODE)
        return why_set(why, len, "expected %s, got %s", type_word(v), kinds[n->type]);
    switch (v->type) {
    case CYAML_FLOAT:
        return float_check(scalar(n), why, len);
    case CYAML_UINT:
        return uint_check(scalar(n), why, len);
    case CYAML_ENUM:
        return enum_check(scalar(n), v, why, len);
    case CYAML_STRING:
        return 0;
    default:
        return why_set(why, len, "unsupported schema type");
    }
}

static int walk_map(struct scene_ctx *c, int map, const cyaml_schema_field_t *fields, const char *prefix,
                    int line);

/* Field f (under prefix) is absent: fail at line if it, or a key of it when
 * it is a whole section, is required. */
static int require_absent(struct scene_ctx *c, const cyaml_schema_field_t *f, const char *prefix, int line)
{
    char name[SCENE_NAME];
    cat(name, sizeof name, 0, "%s%s%s", prefix, prefix[0] ? ":" : "", f->key);
    if (!(f->value.flags & CYAML_FLAG_OPTIONAL)) return fail(c, -1, line, name, "required key missing");
    if (f->value.type != CYAML_MAPPING) return 0;
    for (const cyaml_schema_field_t *g = f->value.mapping.fields; g->key; ++g)
        if (require_absent(c, g, name, line)) return -1;
    return 0;
}

static int walk_seq(struct scene_ctx *c, yaml_node_t *n, const cyaml_schema_value_t *v, int over, int line,
                    const char *name)
{
    char why[160];
    if (n->type != YAML_SEQUENCE_NODE)
        return fail(c, over, line, name, "expected a list of %u numbers", v->sequence.max);
    long count = (long)(n->data.sequence.items.top - n->data.sequence.items.start);
    if (count != (long)v->sequence.max)
        return fail(c, over, line, name, "expected %u entries, got %ld", v->sequence.max, count);
    for (long i = 0; i < count; ++i) {
        yaml_node_t *e = node(c, n->data.sequence.items.start[i]);
        if (scalar_check(e, v->sequence.entry, why, sizeof why))
            return fail(c, over, line, name, "entry %ld: %s", i + 1, why);
    }
    return 0;
}

/* A list of mappings (Container:walls): each entry, named name:K (K from 1),
 * against the entry's fields. */
static int walk_list(struct scene_ctx *c, int val, const cyaml_schema_value_t *v, int over, int line,
                     const char *name)
{
    char item[SCENE_NAME + 24];
    yaml_node_t *n = node(c, val);
    if (n->type != YAML_SEQUENCE_NODE) return fail(c, over, line, name, "expected a list of mappings");
    long count = (long)(n->data.sequence.items.top - n->data.sequence.items.start);
    if (count > (long)v->sequence.max)
        return fail(c, over, line, name, "at most %u entries, got %ld", v->sequence.max, count);
    for (long i = 0; i < count; ++i) {
        int e = node(c, val)->data.sequence.items.start[i];
        int eline = node_origin(c, e) == -1 ? node_line(c, e) : 0;
        snprintf(item, sizeof item, "%.40s:%ld", name, i + 1);
        if (leaf_add(c, item, eline, node_origin(c, e))) return -1;
        if (node(c, e)->type != YAML_MAPPING_NODE)
            return fail(c, over, eline ? eline : line, item, "expected a mapping of keys");
        if (walk_map(c, e, v->sequence.entry->mapping.fields, item, eline > 0 ? eline : line)) return -1;
    }
    return 0;
}

/* The value node val of key node key, named "Section:key". */
static int walk_value(struct scene_ctx *c, int key, int val, const cyaml_schema_value_t *v, const char *name)
{
    char why[160];
    int over = node_origin(c, val);
    int line = node_origin(c, key) == -1 ? node_line(c, key) : 0;
    yaml_node_t *n = node(c, val);
    if (leaf_add(c, name, line, over)) return -1;
    if (v->type == CYAML_MAPPING) {
        if (n->type != YAML_MAPPING_NODE) return fail(c, over, line, name, "expected %s", type_word(v));
        return walk_map(c, val, v->mapping.fields, name, line > 0 ? line : 1);
    }
    if (v->type == CYAML_SEQUENCE_FIXED) return walk_seq(c, n, v, over, line, name);
    if (v->type == CYAML_SEQUENCE) return walk_list(c, val, v, over, line, name);
    if (scalar_check(n, v, why, sizeof why)) return fail(c, over, line, name, "%s", why);
    return 0;
}

/* Mapping node map against fields; prefix names it ("" for the root), line is
 * where a missing required key is reported. */
static int walk_map(struct scene_ctx *c, int map, const cyaml_schema_field_t *fields, const char *prefix,
                    int line)
{
    char name[SCENE_NAME];
    uint64_t seen = 0;
    yaml_node_t *m = node(c, map);
    for (yaml_node_pair_t *p = m->data.mapping.pairs.start; p < m->data.mapping.pairs.top; ++p) {
        yaml_node_t *k = node(c, p->key);
        int over = node_origin(c, p->key), kline = over == -1 ? node_line(c, p->key) : 0;
        if (k->type != YAML_SCALAR_NODE)
            return fail(c, over, kline, prefix[0] ? prefix : NULL, "keys must be plain names");
        snprintf(name, sizeof name, "%s%s%.40s", prefix, prefix[0] ? ":" : "", scalar(k));
        const cyaml_schema_field_t *f = field_find(fields, scalar(k));
        if (!f) return fail_unknown(c, over, kline, name, fields, !prefix[0]);
        uint64_t bit = (uint64_t)1 << (f - fields);
        if (seen & bit) return fail(c, over, kline, name, "duplicate key");
        seen |= bit;
        if (walk_value(c, p->key, p->value, &f->value, name)) return -1;
    }
    for (const cyaml_schema_field_t *f = fields; f->key; ++f)
        if (!(seen >> (f - fields) & 1) && require_absent(c, f, prefix, line)) return -1;
    return 0;
}

/* Segregation:V and :D are required when Segregation:model is constant. */
static int require_model_keys(struct scene_ctx *c)
{
    static const char *const keys[] = {"Segregation:V", "Segregation:D"};
    const char *model = "constant";
    yaml_node_pair_t *sec = map_pair(c, 1, "Segregation");
    yaml_node_pair_t *mp = sec ? map_pair(c, sec->value, "model") : NULL;
    yaml_node_pair_t *en = sec ? map_pair(c, sec->value, "enabled") : NULL;
    if (mp) model = scalar(node(c, mp->value));
    if (strcmp(model, "constant") != 0) return 0;
    if (en && !strcmp(scalar(node(c, en->value)), "off")) return 0; /* not solved */
    for (size_t i = 0; i < ARRAY_LEN(keys); ++i) {
        if (leaf_find(c, keys[i])) continue;
        const struct scene_leaf *l = leaf_find(c, "Segregation");
        return fail(c, -1, l && l->line > 0 ? l->line : 1, keys[i],
                    "required key missing (Segregation:model is constant)");
    }
    return 0;
}

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
        if (leaf_find(c, name)) continue;
        const char *comp[2] = {d->section, d->key};
        int val = doc_add_text(c, d->value, why, sizeof why);
        if (!val || doc_put(c, comp, 2, val)) return fail(c, -1, 0, name, "default %s", why);
    }
    return 0;
}

/* ---- loading with libcyaml ---------------------------------------------------------- */

struct buf {
    char *p;
    size_t n, cap;
    int bad;
};

static int buf_write(void *data, unsigned char *bytes, size_t size)
{
    struct buf *b = data;
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

/* Emit doc as YAML text into b; the document is freed either way. */
static int doc_emit(yaml_document_t *doc, struct buf *b)
{
    yaml_emitter_t em;
    if (!yaml_emitter_initialize(&em)) {
        yaml_document_delete(doc);
        return 0;
    }
    yaml_emitter_set_output(&em, buf_write, b);
    yaml_emitter_set_width(&em, -1);
    yaml_emitter_set_unicode(&em, 1);
    int ok = yaml_emitter_open(&em);
    if (ok)
        ok = yaml_emitter_dump(&em, doc); /* frees doc */
    else
        yaml_document_delete(doc);
    ok = ok && yaml_emitter_close(&em) && yaml_emitter_flush(&em);
    yaml_emitter_delete(&em);
    return ok && !b->bad;
}

static void cyaml_log_capture(cyaml_log_t level, void *ctx, const char *fmt, va_list args)
{
    struct scene_ctx *c = ctx;
    if (level < CYAML_LOG_ERROR || c->log[0]) return; /* keep the first error */
    vsnprintf(c->log, sizeof c->log, fmt, args);
    c->log[strcspn(c->log, "\n")] = '\0';
}

static int load_struct(struct scene_ctx *c, struct scene *s)
{
    struct buf b = {0};
    int ok = doc_emit(&c->doc, &b);
    c->have_doc = 0;
    if (!ok) {
        free(b.p);
        return fail(c, -1, 0, NULL, "internal error: cannot emit the edited scene");
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
        return fail(c, -1, 0, NULL, "libcyaml: %s%s%s", cyaml_strerror(e), c->log[0] ? ": " : "", c->log);
    *s = *tmp;
    free(tmp);
    return 0;
}

/* ---- validation ----------------------------------------------------------------------- */

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
        fmt_double(got, sizeof got, v);
        if (!isfinite(v)) return fail_at(c, r->name, "not a finite number: %s", got);
        int lo_ok = r->open & LO_OPEN ? v > r->lo : v >= r->lo;
        int hi_ok = r->open & HI_OPEN ? v < r->hi : v <= r->hi;
        if (lo_ok && hi_ok) continue;
        fmt_double(lo, sizeof lo, r->lo);
        fmt_double(hi, sizeof hi, r->hi);
        if (isinf(r->hi))
            return fail_at(c, r->name, "must be %s %s, got %s", r->open & LO_OPEN ? ">" : ">=", lo, got);
        return fail_at(c, r->name, "must be in %c%s, %s%c, got %s", r->open & LO_OPEN ? '(' : '[', lo, hi,
                       r->open & HI_OPEN ? ')' : ']', got);
    }
    return 0;
}

static int check_geometry(struct scene_ctx *c, const struct scene_geometry *g)
{
    char a[32], b[32];
    if (g->dim == 3 && g->type == GEOM_SHEARBOX)
        return fail_at(c, "Geometry:dim", "3D is supported for Geometry:type column or drum only (use 2)");
    if (g->dim != 2 && g->dim != 3) return fail_at(c, "Geometry:dim", "must be 2 or 3, got %u", g->dim);
    if (g->dim == 3 && g->type == GEOM_DRUM && g->length < 4 * g->dr) {
        fmt_double(a, sizeof a, 4 * g->dr);
        fmt_double(b, sizeof b, g->length);
        return fail_at(c, "Geometry:length", "must be >= 4*dr = %s, got %s", a, b);
    }
    if (g->dim == 3 && g->type == GEOM_COLUMN && g->depth < 4 * g->dr) {
        fmt_double(a, sizeof a, 4 * g->dr);
        fmt_double(b, sizeof b, g->depth);
        return fail_at(c, "Geometry:depth", "must be >= 4*dr = %s, got %s", a, b);
    }
    if (g->periodic != PERIODIC_NONE && g->type != GEOM_COLUMN && g->type != GEOM_CONTAINER)
        return fail_at(c, "Geometry:periodic", "needs Geometry:type column or container (the walls of a %s are fixed)",
                       g->type == GEOM_DRUM ? "drum" : "shear box");
    if ((g->periodic & PERIODIC_Z) && g->dim != 3)
        return fail_at(c, "Geometry:periodic", "z needs Geometry:dim 3");
    if ((g->periodic & PERIODIC_Y) && g->type != GEOM_CONTAINER)
        return fail_at(c, "Geometry:periodic", "y needs Geometry:type container (a column has a base across y)");
    /* a period must hold the ghost layers of both sides (mpi/halo.h): 3 cells
     * of 2h each way on the GPU, so 6 supports; shorter would need images of
     * images */
    for (int d = 0; d < 3; ++d) {
        double len = d == 0 ? g->width : d == 1 ? g->height : g->depth;
        double need = SCENE_PERIOD_SUPPORTS * 2 * g->h_factor * g->dr;
        if (!(g->periodic & (1u << d)) || len >= need) continue;
        return fail_at(c, d == 0 ? "Geometry:width" : d == 1 ? "Geometry:height" : "Geometry:depth",
                       "a periodic axis needs a period of at least %d supports 2h = %.4g m, got %.4g",
                       SCENE_PERIOD_SUPPORTS, need, len);
    }
    if (g->type == GEOM_CONTAINER) return 0; /* its walls and regions: check_container */
    if (g->type == GEOM_DRUM) {
        fmt_double(a, sizeof a, 8 * g->dr);
        fmt_double(b, sizeof b, g->radius);
        if (g->radius < 8 * g->dr) return fail_at(c, "Geometry:radius", "must be >= 8*dr = %s, got %s", a, b);
        return 0;
    }
    fmt_double(a, sizeof a, 4 * g->dr);
    fmt_double(b, sizeof b, g->width);
    if (g->width < 4 * g->dr) return fail_at(c, "Geometry:width", "must be >= 4*dr = %s, got %s", a, b);
    fmt_double(b, sizeof b, g->height);
    if (g->height < 4 * g->dr) return fail_at(c, "Geometry:height", "must be >= 4*dr = %s, got %s", a, b);
    return 0;
}

/* Segregation:every: "auto" (every_k = 0) or a whole number of flow steps
 * from 1 to SCENE_EVERY_MAX. */
static int check_every(struct scene_ctx *c, struct scene_segregation *g)
{
    const char *e = g->every ? g->every : "";
    if (!strcmp(e, "auto")) {
        g->every_k = 0;
        return 0;
    }
    char *end;
    errno = 0;
    long k = strtol(e, &end, 10);
    if (!*e || *end || errno || k < 1 || k > SCENE_EVERY_MAX)
        return fail_at(c, "Segregation:every", "expected auto or a whole number of flow steps from 1 to %d, got "
                       "'%.40s'", SCENE_EVERY_MAX, e);
    g->every_k = (unsigned)k;
    return 0;
}

/* Container:walls and :regions (Geometry:type container): each entry on
 * its own, located as Container:walls:K:key; what needs the lattice
 * (overlapping regions, a region beyond the walls) is found by the builder
 * (setup_container.c). Sets each wall's gate flag and default name. */
static int check_container(struct scene_ctx *c, struct scene *s)
{
    struct scene_container *k = &s->container;
    char nm[SCENE_NAME + 40];
    const double dr = s->geometry.dr;
    if (s->geometry.type != GEOM_CONTAINER) {
        if (k->walls_count) return fail_at(c, "Container:walls", "needs Geometry:type container");
        if (k->regions_count) return fail_at(c, "Container:regions", "needs Geometry:type container");
        return 0;
    }
    if (!k->walls_count) return fail_at(c, "Container:walls", "Geometry:type container needs at least one wall");
    if (!k->regions_count)
        return fail_at(c, "Container:regions", "Geometry:type container needs at least one region of material");
    for (unsigned i = 0; i < k->walls_count; ++i) {
        struct scene_wall *w = &k->walls[i];
#define AT(key) (snprintf(nm, sizeof nm, "Container:walls:%u%s%s", i + 1, *(key) ? ":" : "", key), nm)
        const double *v = w->velocity;
        for (int a = 0; a < 2; ++a)
            if (!isfinite(w->from[a]) || !isfinite(w->to[a]) || !isfinite(w->centre[a]))
                return fail_at(c, AT(""), "a coordinate is not finite");
        if (!isfinite(w->radius) || !isfinite(w->rpm) || !isfinite(w->open_at) || !isfinite(v[0]) ||
            !isfinite(v[1]) || !isfinite(v[2]))
            return fail_at(c, AT(""), "a value is not finite");
        if (w->shape == CWALL_SEGMENT && hypot(w->to[0] - w->from[0], w->to[1] - w->from[1]) < 2 * dr)
            return fail_at(c, AT("to"), "a segment must be at least 2 dr long (from and to too close)");
        if (w->shape == CWALL_CYLINDER && w->material == CWALL_INSIDE && !(w->radius >= 8 * dr))
            return fail_at(c, AT("radius"), "must be >= 8 dr = %.4g m, got %.4g", 8 * dr, w->radius);
        /* a post: its dummies fill it, so it may be small; but a radius under 2 dr
         * is not resolved by the lattice around it */
        if (w->shape == CWALL_CYLINDER && w->material == CWALL_OUTSIDE && !(w->radius >= 2 * dr))
            return fail_at(c, AT("radius"), "a post (material outside) must be >= 2 dr = %.4g m, got %.4g", 2 * dr,
                           w->radius);
        if (w->shape != CWALL_CYLINDER && w->material == CWALL_OUTSIDE)
            return fail_at(c, AT("material"), "outside: only a cylinder (a post) has its material outside");
        if (w->motion == CWALL_TURNING && w->shape == CWALL_SEGMENT)
            return fail_at(c, AT("motion"), "only a cylinder turns (about its own axis), or a 3D container's ends");
        if (w->shape == CWALL_ENDS && s->geometry.dim != 3)
            return fail_at(c, AT("shape"), "ends: the end walls of a 3D container (Geometry:dim 3)");
        for (unsigned j = 0; j < i && w->shape == CWALL_ENDS; ++j)
            if (k->walls[j].shape == CWALL_ENDS) return fail_at(c, AT("shape"), "ends given twice (also wall %u)", j + 1);
        if (w->motion != CWALL_TURNING && w->rpm != 0) return fail_at(c, AT("rpm"), "needs motion turning");
        if (!(w->rpm >= 0)) return fail_at(c, AT("rpm"), "must be >= 0, got %.4g", w->rpm);
        if (w->motion != CWALL_TRANSLATING && (v[0] != 0 || v[1] != 0 || v[2] != 0))
            return fail_at(c, AT("velocity"), "needs motion translating");
        if (s->geometry.dim == 2 && v[2] != 0) return fail_at(c, AT("velocity"), "z entry must be 0 in 2D");
        w->gate = leaf_find(c, AT("open_at")) != NULL;
        if (w->gate && !(w->open_at >= 0))
            return fail_at(c, AT("open_at"), "a gate opens at t >= 0, got %.4g", w->open_at);
        if (w->gate && w->shape != CWALL_SEGMENT) return fail_at(c, AT("open_at"), "only a segment can be a gate");
        if (w->priority > 100) return fail_at(c, AT("priority"), "must be <= 100, got %u", w->priority);
        if (!w->name) {
            char def[16];
            snprintf(def, sizeof def, "wall%u", i + 1);
            if (!(w->name = strdup(def))) return fail(c, -1, 0, NULL, "out of memory");
        }
        for (const char *q = w->name; *q; ++q)
            if (!isalnum((unsigned char)*q) && *q != '_')
                return fail_at(c, AT("name"), "letters, digits and _ only, got '%.32s'", w->name);
        for (unsigned j = 0; j < i; ++j)
            if (!strcmp(k->walls[j].name, w->name))
                return fail_at(c, AT("name"), "'%s' names wall %u already", w->name, j + 1);
        if (s->geometry.dim == 3 && (!strcmp(w->name, "end_lo") || !strcmp(w->name, "end_hi")))
            return fail_at(c, AT("name"), "'%s' is the name of an end wall of a 3D container", w->name);
#undef AT
    }
    for (unsigned i = 0; i < k->regions_count; ++i) {
        const struct scene_region *r = &k->regions[i];
#define AT(key) (snprintf(nm, sizeof nm, "Container:regions:%u%s%s", i + 1, *(key) ? ":" : "", key), nm)
        const double vals[] = {r->lo[0], r->lo[1], r->hi[0], r->hi[1], r->centre[0], r->centre[1], r->r_in,
                               r->r_out, r->from_deg, r->to_deg, r->level, r->C};
        for (size_t q = 0; q < ARRAY_LEN(vals); ++q)
            if (!isfinite(vals[q])) return fail_at(c, AT(""), "a value is not finite");
        if (!(r->C >= 0 && r->C <= 1)) return fail_at(c, AT("C"), "must be in [0, 1], got %.4g", r->C);
        if (r->shape == REGION_BOX && !(r->lo[0] < r->hi[0] && r->lo[1] < r->hi[1]))
            return fail_at(c, AT("hi"), "must lie above and right of lo");
        if (r->shape == REGION_SECTOR && !(r->r_in >= 0 && r->r_in < r->r_out))
            return fail_at(c, AT("r_out"), "needs 0 <= r_in < r_out, got r_in %.4g, r_out %.4g", r->r_in, r->r_out);
        ((struct scene_region *)r)->has_floor = leaf_find(c, AT("floor")) != NULL;
        if (r->has_floor && !(r->floor < r->level))
            return fail_at(c, AT("floor"), "must lie below level, got floor %.4g, level %.4g", r->floor, r->level);
        if (r->shape == REGION_SECTOR && r->from_deg == r->to_deg)
            return fail_at(c, AT("to_deg"), "an empty sector: from_deg equals to_deg");
        if (r->shape == REGION_COLUMN && s->geometry.dim != 3)
            return fail_at(c, AT("shape"), "column: an upright column of a 3D container (Geometry:dim 3)");
        if (r->shape == REGION_COLUMN && !(r->r_out > 0))
            return fail_at(c, AT("r_out"), "a column's radius must be > 0, got %.4g", r->r_out);
#undef AT
    }
    for (unsigned i = 0; i < k->walls_count; ++i)
        if (k->walls[i].shape == CWALL_ENDS && (s->geometry.periodic & PERIODIC_Z))
            return fail_at(c, "Geometry:periodic", "z: a container periodic along z has no end walls (Container:walls:%u "
                           "is of shape ends)", i + 1);
    if (s->geometry.dim == 3 && s->geometry.depth < 4 * dr)
        return fail_at(c, "Geometry:depth", "must be >= 4*dr = %.4g, got %.4g", 4 * dr, s->geometry.depth);
    if (s->geometry.dim == 3 && k->walls_count > SCENE_WALLS_MAX)
        return fail_at(c, "Container:walls", "at most %d walls", SCENE_WALLS_MAX);
    return 0;
}

static int check_special(struct scene_ctx *c, struct scene *s)
{
    const double *g = s->physics.gravity;
    const char *backend = s->run.backend ? s->run.backend : "";
    if (check_geometry(c, &s->geometry) || check_container(c, s)) return -1;
    if (!(s->material.mu_s <= s->material.mu_d))
        return fail_at(c, "Material:mu_d", "must be >= Material:mu_s");
    int box = s->geometry.type == GEOM_SHEARBOX, vel = s->kinematics.velocity;
    if (vel == KIN_OSCILLATORY_SHEAR && !box && s->geometry.type != GEOM_CONTAINER)
        return fail_at(c, "Kinematics:velocity", "oscillatory_shear needs Geometry:type shearbox or container");
    if (vel == KIN_COMPUTED && box)
        return fail_at(c, "Kinematics:velocity",
                       "computed needs Geometry:type column or drum (the shear box's walls are prescribed)");
    if (!s->segregation.enabled && vel != KIN_COMPUTED)
        return fail_at(c, "Segregation:enabled", "off with prescribed velocity leaves nothing to solve");
    if (!(s->grains.d_small < s->grains.d_large))
        return fail_at(c, "Grains:d_large", "must be larger than Grains:d_small");
    for (int k = 0; k < 3; ++k)
        if (!isfinite(g[k])) return fail_at(c, "Physics:gravity", "entry %d is not finite", k + 1);
    if (g[0] == 0 && g[1] == 0 && g[2] == 0) return fail_at(c, "Physics:gravity", "must not be all zero");
    const double *wv = s->walls.velocity;
    for (int k = 0; k < 3; ++k)
        if (!isfinite(wv[k])) return fail_at(c, "Walls:velocity", "entry %d is not finite", k + 1);
    if (s->geometry.dim == 2 && wv[2] != 0)
        return fail_at(c, "Walls:velocity", "z entry must be 0 in 2D (the x-y plane)");
    if ((wv[0] != 0 || wv[1] != 0 || wv[2] != 0) && s->geometry.type != GEOM_COLUMN)
        return fail_at(c, "Walls:velocity", "a translating container needs Geometry:type column");
    if (s->geometry.dim == 2 && g[2] != 0)
        return fail_at(c, "Physics:gravity", "z entry must be 0 in 2D (the x-y plane)");
    if (s->geometry.runout > 0) {
        const struct scene_geometry *g = &s->geometry;
        double need = (ceil(2.0 * g->h_factor - 1e-9) + 1) * g->dr;
        if (g->type != GEOM_COLUMN || vel != KIN_COMPUTED)
            return fail_at(c, "Geometry:runout", "needs Geometry:type column and Kinematics:velocity computed");
        if (g->periodic & PERIODIC_X) return fail_at(c, "Geometry:runout", "needs walls along x (Geometry:periodic)");
        if (g->runout < need)
            return fail_at(c, "Geometry:runout", "must be 0 or at least the gate's thickness plus dr, %.4g m, got %.4g",
                           need, g->runout);
        if (g->outlet_width > 0)
            return fail_at(c, "Geometry:outlet_width", "an opening in a base with a runout is not supported");
    }
    if (s->geometry.lid && (s->geometry.type != GEOM_COLUMN || s->geometry.runout > 0))
        return fail_at(c, "Geometry:lid", "needs Geometry:type column without a runout");
    if (s->geometry.outlet_width > 0 && s->geometry.type != GEOM_COLUMN)
        return fail_at(c, "Geometry:outlet_width", "needs Geometry:type column (an opening in its base)");
    if (s->geometry.outlet_width > 0 &&
        !(s->geometry.outlet_width <= s->geometry.width - 2 * s->geometry.dr &&
          (s->geometry.dim == 2 || s->geometry.outlet_width <= s->geometry.depth - 2 * s->geometry.dr)))
        return fail_at(c, "Geometry:outlet_width", "%.4g m leaves less than 2 dr of base beside the opening",
                       s->geometry.outlet_width);
    if (s->outlet.enabled &&
        ((s->geometry.type != GEOM_COLUMN && s->geometry.type != GEOM_CONTAINER) || vel != KIN_COMPUTED))
        return fail_at(c, "Outlet:enabled", "needs Geometry:type column or container and Kinematics:velocity computed");
    if (s->outlet.enabled && s->geometry.type == GEOM_COLUMN && !(s->outlet.below <= 0))
        return fail_at(c, "Outlet:below", "must be at or below the base, y <= 0 (the plane would cut the material "
                       "at the start), got %.4g", s->outlet.below);
    if (s->geometry.periodic != PERIODIC_NONE && vel != KIN_COMPUTED)
        return fail_at(c, "Geometry:periodic", "needs Kinematics:velocity computed");
    if ((s->geometry.periodic & PERIODIC_Y) && s->initial.stress == INIT_STRESS_GEOSTATIC)
        return fail_at(c, "Initial:stress", "geostatic needs a free surface above the material; a container periodic "
                       "along y has none (Geometry:periodic)");
    if (strcmp(backend, "cpu") != 0 && strcmp(backend, "gpu") != 0 && strcmp(backend, "auto") != 0)
        return fail_at(c, "Run:backend", "expected auto, cpu or gpu, got '%.40s'", backend);
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
    for (; k->n_over < c->n_over; ++k->n_over)
        if (!(k->over[k->n_over] = strdup(c->over[k->n_over]))) return -1;
    return 0;
}

/* Segregation:d_small and :d_large, the grain sizes' place before the
 * Grains section, are read as Grains:d_small and :d_large with a warning
 * that names where they were; given in both places, the scene is refused.
 * The key and value nodes move as they are, so that later messages about
 * the value still name its line. */
static int move_grain_keys(struct scene_ctx *c)
{
    static const char *const keys[] = {"d_small", "d_large"};
    for (size_t k = 0; k < ARRAY_LEN(keys); ++k) {
        yaml_node_pair_t *sp = map_pair(c, 1, "Segregation");
        int seg = sp ? sp->value : 0;
        yaml_node_pair_t *old = seg ? map_pair(c, seg, keys[k]) : NULL;
        if (!old) continue;
        const int key = old->key, val = old->value;
        const int over = node_origin(c, key), line = over == -1 ? node_line(c, key) : 0;
        char name[SCENE_NAME];
        snprintf(name, sizeof name, "Segregation:%s", keys[k]);
        yaml_node_pair_t *gp = map_pair(c, 1, "Grains");
        int grains = gp ? gp->value : 0;
        if (grains && node(c, grains)->type != YAML_MAPPING_NODE) continue; /* the walk reports it */
        yaml_node_pair_t *dup = grains ? map_pair(c, grains, keys[k]) : NULL;
        if (dup) {
            int dover = node_origin(c, dup->key), dline = dover == -1 ? node_line(c, dup->key) : 0;
            char where[SCENE_NAME + 16];
            if (dover >= 0) snprintf(where, sizeof where, "-P %.*s", SCENE_NAME, c->over[dover]);
            else snprintf(where, sizeof where, "line %d", dline);
            return fail(c, over, line, name, "given twice: here and as Grains:%s (%s); the grain sizes belong in the "
                        "Grains section", keys[k], where);
        }
        if (!grains) {
            grains = yaml_document_add_mapping(&c->doc, NULL, YAML_BLOCK_MAPPING_STYLE);
            if (!grains || map_append(c, 1, "Grains", grains)) return fail(c, -1, 0, NULL, "out of memory");
        }
        if (!yaml_document_append_mapping_pair(&c->doc, grains, key, val)) return fail(c, -1, 0, NULL, "out of memory");
        yaml_node_t *m = node(c, seg); /* the pair out of Segregation */
        yaml_node_pair_t *q = map_pair(c, seg, keys[k]);
        memmove(q, q + 1, (size_t)(m->data.mapping.pairs.top - q - 1) * sizeof *q);
        m->data.mapping.pairs.top--;
        if (over >= 0)
            warning("-P %s: Segregation:%s is read as Grains:%s (the grain sizes have a section of their own, which "
                    "the flow's mu(I) reads too)", c->over[over], keys[k], keys[k]);
        else
            warning("%s:%d: Segregation:%s is read as Grains:%s (the grain sizes have a section of their own, which "
                    "the flow's mu(I) reads too): move it there", c->path, line, keys[k], keys[k]);
    }
    return 0;
}

static int parse_steps(struct scene_ctx *c, struct scene *s)
{
    if (read_text(c) || load_doc(c) || apply_overrides(c) || move_grain_keys(c) ||
        walk_map(c, 1, scene_fields, "", 1) ||
        require_model_keys(c) || add_defaults(c) || load_struct(c, s))
        return -1;
    if (!leaf_find(c, "Output:diag_dt")) s->output.diag_dt = s->output.dt / 20;
    if (check_ranges(c, s) || check_special(c, s) || check_every(c, &s->segregation)) return -1;
    s->path = strdup(c->path);
    if (!s->path || keys_keep(c, s)) return fail(c, -1, 0, NULL, "out of memory");
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
    int rc = path ? parse_steps(c, s) : fail(c, -1, 0, NULL, "no scene file given");
    if (c->have_doc) yaml_document_delete(&c->doc);
    free(c->first_node);
    free(c->text);
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

static void buf_add(struct buf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void buf_add(struct buf *b, const char *fmt, ...)
{
    char tmp[256];
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    if (k < 0 || (size_t)k >= sizeof tmp)
        b->bad = 1;
    else
        buf_write(b, (unsigned char *)tmp, (size_t)k);
}

/* An unsigned (or enum) value of `size` bytes at p. */
static uint64_t read_uint(const char *p, uint32_t size)
{
    uint8_t u8;
    uint16_t u16;
    uint32_t u32;
    uint64_t u64;
    if (size == 1) {
        memcpy(&u8, p, 1);
        return u8;
    }
    if (size == 2) {
        memcpy(&u16, p, 2);
        return u16;
    }
    if (size == 4) {
        memcpy(&u32, p, 4);
        return u32;
    }
    memcpy(&u64, p, sizeof u64);
    return u64;
}

/* One value as YAML: numbers round-trip exactly, strings double-quoted. */
static void put_value(struct buf *b, const cyaml_schema_value_t *v, const char *p)
{
    char num[32];
    double d;
    const char *str;
    switch (v->type) {
    case CYAML_FLOAT:
        memcpy(&d, p, sizeof d);
        fmt_double(num, sizeof num, d);
        buf_add(b, "%s", num);
        break;
    case CYAML_UINT:
        buf_add(b, "%llu", (unsigned long long)read_uint(p, v->data_size));
        break;
    case CYAML_ENUM:
        for (uint32_t i = 0; i < v->enumeration.count; ++i)
            if ((uint64_t)v->enumeration.strings[i].val == read_uint(p, v->data_size))
                buf_add(b, "%s", v->enumeration.strings[i].str);
        break;
    case CYAML_STRING:
        memcpy(&str, p, sizeof str);
        buf_add(b, "\"");
        for (; str && *str; ++str)
            buf_add(b, *str == '"' || *str == '\\' ? "\\%c" : "%c", *str);
        buf_add(b, "\"");
        break;
    case CYAML_SEQUENCE_FIXED:
        for (uint32_t i = 0; i < v->sequence.max; ++i) {
            buf_add(b, i ? ", " : "[");
            put_value(b, v->sequence.entry, p + i * v->sequence.entry->data_size);
        }
        buf_add(b, "]");
        break;
    default:
        b->bad = 1;
    }
}

/* A list of mappings (field f of the section at base) as a block list of
 * flow mappings, every key with its value but an absent name, the open_at
 * of a wall that is not a gate and an absent floor; [] when empty. */
static void put_list(struct buf *b, const cyaml_schema_field_t *f, const char *base)
{
    const char *items;
    memcpy(&items, base + f->data_offset, sizeof items);
    uint64_t count = read_uint(base + f->count_offset, f->count_size);
    if (!count) buf_add(b, "[]");
    const cyaml_schema_value_t *e = f->value.sequence.entry;
    for (uint64_t i = 0; i < count; ++i) {
        const char *it = items + i * e->data_size;
        buf_add(b, "\n    - {");
        int first = 1;
        for (const cyaml_schema_field_t *g = e->mapping.fields; g->key; ++g) {
            const char *str;
            if (g->value.type == CYAML_STRING && (memcpy(&str, it + g->data_offset, sizeof str), !str)) continue;
            if (e == &cwall_entry && !strcmp(g->key, "open_at") && !((const struct scene_wall *)(const void *)it)->gate)
                continue;
            if (e == &region_entry && !strcmp(g->key, "floor") &&
                !((const struct scene_region *)(const void *)it)->has_floor)
                continue;
            buf_add(b, "%s%s: ", first ? "" : ", ", g->key);
            put_value(b, &g->value, it + g->data_offset);
            first = 0;
        }
        buf_add(b, "}");
    }
}

char *scene_used_text(const struct scene *s)
{
    struct buf b = {0};
    buf_add(&b, "# sphseg: every parameter with the value used, defaults included\n");
    for (const cyaml_schema_field_t *sec = scene_fields; sec->key; ++sec) {
        buf_add(&b, "%s:\n", sec->key);
        for (const cyaml_schema_field_t *f = sec->value.mapping.fields; f->key; ++f) {
            const char *base = (const char *)s + sec->data_offset;
            buf_add(&b, "  %s: ", f->key);
            if (f->value.type == CYAML_SEQUENCE)
                put_list(&b, f, base);
            else
                put_value(&b, &f->value, base + f->data_offset);
            buf_add(&b, "\n");
        }
    }
    if (b.bad) {
        free(b.p);
        return NULL;
    }
    return b.p;
}

int scene_write_used(const struct scene *s, const char *file)
{
    char *text = scene_used_text(s);
    size_t n = strlen(file) + 5;
    char *tmp = malloc(n);
    int ok = text && tmp;
    FILE *f = NULL;
    if (ok) {
        snprintf(tmp, n, "%s.tmp", file);
        f = fopen(tmp, "w");
        ok = f && fputs(text, f) >= 0;
        if (f) ok = (fclose(f) == 0) && ok;
        if (ok) ok = rename(tmp, file) == 0;
        if (!ok && f) remove(tmp);
    }
    free(tmp);
    free(text);
    return ok ? 0 : -1;
}

int scene_key_line(const struct scene *s, const char *section, const char *key)
{
    char name[2 * SCENE_NAME];
    int over, line;
    const struct scene_keys *k = s->keys;
    snprintf(name, sizeof name, "%s:%s", section, key);
    leaf_resolve(k ? k->leaf : NULL, k ? k->n_leaf : 0, name, &over, &line);
    return line;
}

const char *scene_key_where(const struct scene *s, const char *section, const char *key, char *buf, size_t n)
{
    char name[2 * SCENE_NAME];
    int over, line;
    const struct scene_keys *k = s->keys;
    snprintf(name, sizeof name, "%s:%s", section, key);
    leaf_resolve(k ? k->leaf : NULL, k ? k->n_leaf : 0, name, &over, &line);
    if (k && over >= 0 && over < k->n_over)
        snprintf(buf, n, "-P %s", k->over[over]);
    else
        snprintf(buf, n, "%s:%d", s->path ? s->path : "(no scene file)", line);
    return buf;
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
