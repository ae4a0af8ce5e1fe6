/* scene_yaml.c — the scene file as a libyaml document (scene_ctx.h): the
 * file read (its size and flow nesting bounded before libyaml sees it) and
 * parsed, with node marks for line numbers; the document edited in place,
 * -P Section:key=value overrides set into it (their nodes numbered after
 * the file's, so each node's origin is known), the grain sizes' old keys
 * moved to Grains; and the edited document emitted as text for libcyaml. */
#define _POSIX_C_SOURCE 200809L
#include "scene_ctx.h"
#include "core/error.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the libyaml document ------------------------------------------------------ */

static int node_count(const struct scene_ctx *c) { return (int)(c->doc.nodes.top - c->doc.nodes.start); }

/* Where node id came from: -1 the file, i >= 0 override i, -2 a default. */
int scene_node_origin(const struct scene_ctx *c, int id)
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
yaml_node_pair_t *scene_map_pair(struct scene_ctx *c, int map, const char *key)
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
int scene_doc_add_text(struct scene_ctx *c, const char *text, char *why, size_t n)
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
int scene_doc_put(struct scene_ctx *c, const char *const *comp, int n, int val)
{
    int map = 1; /* the root */
    for (int j = 0; j < n - 1; ++j) {
        yaml_node_pair_t *p = scene_map_pair(c, map, comp[j]);
        int sub = p ? p->value : 0;
        if (!sub) {
            sub = yaml_document_add_mapping(&c->doc, NULL, YAML_BLOCK_MAPPING_STYLE);
            if (!sub || map_append(c, map, comp[j], sub)) return -1;
        }
        if (node(c, sub)->type != YAML_MAPPING_NODE) return 0;
        map = sub;
    }
    yaml_node_pair_t *p = scene_map_pair(c, map, comp[n - 1]);
    if (p) {
        p->value = val;
        return 0;
    }
    return map_append(c, map, comp[n - 1], val);
}

/* ---- reading the file ---------------------------------------------------------- */

int scene_read_text(struct scene_ctx *c)
{
    FILE *f = fopen(c->path, "rb");
    if (!f) return scene_fail(c, -1, 0, NULL, "cannot read: %s", strerror(errno));
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
    if (!t) return scene_fail(c, -1, 0, NULL, "cannot read: out of memory");
    if (bad) {
        free(t);
        return scene_fail(c, -1, 0, NULL, "cannot read: %s", strerror(eno));
    }
    t[n] = '\0';
    c->text = t;
    c->len = n;
    if (n > SCENE_MAX_BYTES)
        return scene_fail(c, -1, 0, NULL, "%zu bytes: larger than any scene file (at most %d)", n, SCENE_MAX_BYTES);
    int deep = text_too_deep(t, n);
    if (deep) return scene_fail(c, -1, deep, NULL, "not a scene: nested more than %d levels deep", SCENE_MAX_NEST);
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
    return scene_fail(c, -1, (int)line, NULL, "not valid YAML: %s%s%s", why, p->context ? " " : "",
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
        if (!m) return scene_fail(c, -1, 0, NULL, "out of memory");
        node(c, 1)->data.mapping.pairs.start[i].value = m;
    }
    return 0;
}

/* Parse the text into c->doc: one document whose root is a mapping. */
int scene_load_doc(struct scene_ctx *c)
{
    yaml_parser_t p;
    yaml_document_t extra;
    int rc = 0;
    if (!yaml_parser_initialize(&p)) return scene_fail(c, -1, 0, NULL, "out of memory");
    yaml_parser_set_input_string(&p, (const unsigned char *)c->text, c->len);
    if (!yaml_parser_load(&p, &c->doc)) {
        rc = yaml_fail(c, &p);
    } else if (!yaml_parser_load(&p, &extra)) {
        c->have_doc = 1;
        rc = yaml_fail(c, &p);
    } else {
        c->have_doc = 1;
        if (yaml_document_get_root_node(&extra))
            rc = scene_fail(c, -1, (int)extra.start_mark.line + 1, NULL, "more than one YAML document");
        yaml_document_delete(&extra);
    }
    yaml_parser_delete(&p);
    if (rc) return rc;
    yaml_node_t *root = yaml_document_get_root_node(&c->doc);
    if (!root || is_null(root)) /* nothing but blanks, comments or a null: not a scene missing a key */
        return scene_fail(c, -1, 0, NULL, "the file is empty (%s): a scene gives at least Run:t_end, Geometry:dr "
                          "and Output:dt, inputs/*.yml show the rest", c->len ? "no YAML content, only blanks, "
                          "comments or a null" : "0 bytes");
    if (root->type != YAML_MAPPING_NODE) {
        return scene_fail(c, -1, (int)root->start_mark.line + 1, NULL,
                    "not a scene: the top level must be a mapping of sections (Run:, ...)");
    }
    return empty_sections(c);
}

/* ---- -P Section:key=value overrides --------------------------------------------- */

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
        len = scene_cat(name, sizeof name, len, "%s%s", j ? ":" : "", comp[j]);
        const cyaml_schema_field_t *f = scene_field_find(fields, comp[j]);
        if (!f) return scene_fail_unknown(c, i, 0, name, fields, j == 0);
        if (j + 1 == n) break;
        if (f->value.type != CYAML_MAPPING) return scene_fail(c, i, 0, name, "not a section");
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
        return scene_fail(c, i, 0, NULL, "malformed override, expected -P Section:key=value");
    if (over_check(c, i, comp, n)) return -1;
    int val = scene_doc_add_text(c, value, why, sizeof why);
    if (!val) return scene_fail(c, i, 0, NULL, "value %s", why);
    if (scene_doc_put(c, (const char *const *)comp, n, val)) return scene_fail(c, i, 0, NULL, "out of memory");
    return 0;
}

int scene_apply_overrides(struct scene_ctx *c)
{
    c->n_file_nodes = node_count(c);
    c->first_node = malloc(((size_t)c->n_over + 1) * sizeof *c->first_node);
    if (!c->first_node) return scene_fail(c, -1, 0, NULL, "out of memory");
    for (int i = 0; i < c->n_over; ++i) {
        c->first_node[i] = node_count(c) + 1;
        if (apply_override(c, i)) return -1;
    }
    c->first_node[c->n_over] = node_count(c) + 1;
    return 0;
}

/* ---- the grain sizes' old place ------------------------------------------------ */

/* Segregation:d_small and :d_large, the grain sizes' place before the
 * Grains section, are read as Grains:d_small and :d_large with a warning
 * that names where they were; given in both places, the scene is refused.
 * The key and value nodes move as they are, so that later messages about
 * the value still name its line. */
int scene_move_grain_keys(struct scene_ctx *c)
{
    static const char *const keys[] = {"d_small", "d_large"};
    for (size_t k = 0; k < ARRAY_LEN(keys); ++k) {
        yaml_node_pair_t *sp = scene_map_pair(c, 1, "Segregation");
        int seg = sp ? sp->value : 0;
        yaml_node_pair_t *old = seg ? scene_map_pair(c, seg, keys[k]) : NULL;
        if (!old) continue;
        const int key = old->key, val = old->value;
        const int over = scene_node_origin(c, key), line = over == -1 ? node_line(c, key) : 0;
        char name[SCENE_NAME];
        snprintf(name, sizeof name, "Segregation:%s", keys[k]);
        yaml_node_pair_t *gp = scene_map_pair(c, 1, "Grains");
        int grains = gp ? gp->value : 0;
        if (grains && node(c, grains)->type != YAML_MAPPING_NODE) continue; /* the walk reports it */
        yaml_node_pair_t *dup = grains ? scene_map_pair(c, grains, keys[k]) : NULL;
        if (dup) {
            int dover = scene_node_origin(c, dup->key), dline = dover == -1 ? node_line(c, dup->key) : 0;
            char where[SCENE_NAME + 16];
            if (dover >= 0) snprintf(where, sizeof where, "-P %.*s", SCENE_NAME, c->over[dover]);
            else snprintf(where, sizeof where, "line %d", dline);
            return scene_fail(c, over, line, name, "given twice: here and as Grains:%s (%s); the grain sizes belong in the "
                        "Grains section", keys[k], where);
        }
        if (!grains) {
            grains = yaml_document_add_mapping(&c->doc, NULL, YAML_BLOCK_MAPPING_STYLE);
            if (!grains || map_append(c, 1, "Grains", grains)) return scene_fail(c, -1, 0, NULL, "out of memory");
        }
        if (!yaml_document_append_mapping_pair(&c->doc, grains, key, val)) return scene_fail(c, -1, 0, NULL, "out of memory");
        yaml_node_t *m = node(c, seg); /* the pair out of Segregation */
        yaml_node_pair_t *q = scene_map_pair(c, seg, keys[k]);
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

/* ---- the edited document as text (for libcyaml) ------------------------------- */

/* Emit doc as YAML text into b; the document is freed either way. */
int scene_doc_emit(yaml_document_t *doc, struct scene_buf *b)
{
    yaml_emitter_t em;
    if (!yaml_emitter_initialize(&em)) {
        yaml_document_delete(doc);
        return 0;
    }
    yaml_emitter_set_output(&em, scene_buf_write, b);
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

