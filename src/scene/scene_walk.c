/* scene_walk.c — the scene document against the libcyaml schema (scene_ctx.h):
 * every key known, none twice, every required one present, every scalar of
 * its type (numbers whole and finite, integers, enum names), lists of their
 * length, lists of mappings (Container:walls) entry by entry as
 * Container:walls:K:key. Each key met is recorded (scene_leaf_add) with the
 * line or the override that set it, for errors found after loading.
 *
 * The walk checks scalars itself because libcyaml 1.3.1 accepts "1.74mm" as
 * 1.74 and "2abc" as 2, and its own errors carry no file line. */
#define _POSIX_C_SOURCE 200809L
#include "scene_ctx.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* ---- the schema's keys ------------------------------------------------------------ */

const cyaml_schema_field_t *scene_field_find(const cyaml_schema_field_t *f, const char *key)
{
    for (; f->key; ++f)
        if (strcmp(f->key, key) == 0) return f;
    return NULL;
}

int scene_fail_unknown(struct scene_ctx *c, int over, int line, const char *name,
                        const cyaml_schema_field_t *fields, int section)
{
    char known[512];
    size_t n = 0;
    known[0] = '\0';
    for (; fields->key; ++fields)
        n = scene_cat(known, sizeof known, n, "%s%s", n ? ", " : "", fields->key);
    return scene_fail(c, over, line, name, "unknown %s (known: %s)", section ? "section" : "key", known);
}

/* ---- the walk: the document against the schema ----------------------------------- */

/* Write a reason into why[n]; returns -1. */
static int why_set(char *why, size_t n, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static int why_set(char *why, size_t n, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    scene_vcat(why, n, 0, fmt, ap);
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
    size_t k = scene_cat(why, n, 0, "expected one of ");
    for (uint32_t i = 0; i < v->enumeration.count; ++i) {
        if (strcmp(s, v->enumeration.strings[i].str) == 0) return 0;
        k = scene_cat(why, n, k, "%s%s", i ? "|" : "", v->enumeration.strings[i].str);
    }
    scene_cat(why, n, k, ", got '%.40s'", s);
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
    scene_cat(name, sizeof name, 0, "%s%s%s", prefix, prefix[0] ? ":" : "", f->key);
    if (!(f->value.flags & CYAML_FLAG_OPTIONAL)) return scene_fail(c, -1, line, name, "required key missing");
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
        return scene_fail(c, over, line, name, "expected a list of %u numbers", v->sequence.max);
    long count = (long)(n->data.sequence.items.top - n->data.sequence.items.start);
    if (count != (long)v->sequence.max)
        return scene_fail(c, over, line, name, "expected %u entries, got %ld", v->sequence.max, count);
    for (long i = 0; i < count; ++i) {
        yaml_node_t *e = node(c, n->data.sequence.items.start[i]);
        if (scalar_check(e, v->sequence.entry, why, sizeof why))
            return scene_fail(c, over, line, name, "entry %ld: %s", i + 1, why);
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
    if (n->type != YAML_SEQUENCE_NODE) return scene_fail(c, over, line, name, "expected a list of mappings");
    long count = (long)(n->data.sequence.items.top - n->data.sequence.items.start);
    if (count > (long)v->sequence.max)
        return scene_fail(c, over, line, name, "at most %u entries, got %ld", v->sequence.max, count);
    for (long i = 0; i < count; ++i) {
        int e = node(c, val)->data.sequence.items.start[i];
        int eline = scene_node_origin(c, e) == -1 ? node_line(c, e) : 0;
        snprintf(item, sizeof item, "%.40s:%ld", name, i + 1);
        if (scene_leaf_add(c, item, eline, scene_node_origin(c, e))) return -1;
        if (node(c, e)->type != YAML_MAPPING_NODE)
            return scene_fail(c, over, eline ? eline : line, item, "expected a mapping of keys");
        if (walk_map(c, e, v->sequence.entry->mapping.fields, item, eline > 0 ? eline : line)) return -1;
    }
    return 0;
}

/* The value node val of key node key, named "Section:key". */
static int walk_value(struct scene_ctx *c, int key, int val, const cyaml_schema_value_t *v, const char *name)
{
    char why[160];
    int over = scene_node_origin(c, val);
    int line = scene_node_origin(c, key) == -1 ? node_line(c, key) : 0;
    yaml_node_t *n = node(c, val);
    if (scene_leaf_add(c, name, line, over)) return -1;
    if (v->type == CYAML_MAPPING) {
        if (n->type != YAML_MAPPING_NODE) return scene_fail(c, over, line, name, "expected %s", type_word(v));
        return walk_map(c, val, v->mapping.fields, name, line > 0 ? line : 1);
    }
    if (v->type == CYAML_SEQUENCE_FIXED) return walk_seq(c, n, v, over, line, name);
    if (v->type == CYAML_SEQUENCE) return walk_list(c, val, v, over, line, name);
    if (scalar_check(n, v, why, sizeof why)) return scene_fail(c, over, line, name, "%s", why);
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
        int over = scene_node_origin(c, p->key), kline = over == -1 ? node_line(c, p->key) : 0;
        if (k->type != YAML_SCALAR_NODE)
            return scene_fail(c, over, kline, prefix[0] ? prefix : NULL, "keys must be plain names");
        snprintf(name, sizeof name, "%s%s%.40s", prefix, prefix[0] ? ":" : "", scalar(k));
        const cyaml_schema_field_t *f = scene_field_find(fields, scalar(k));
        if (!f) return scene_fail_unknown(c, over, kline, name, fields, !prefix[0]);
        uint64_t bit = (uint64_t)1 << (f - fields);
        if (seen & bit) return scene_fail(c, over, kline, name, "duplicate key");
        seen |= bit;
        if (walk_value(c, p->key, p->value, &f->value, name)) return -1;
    }
    for (const cyaml_schema_field_t *f = fields; f->key; ++f)
        if (!(seen >> (f - fields) & 1) && require_absent(c, f, prefix, line)) return -1;
    return 0;
}

/* Segregation:V and :D are required when Segregation:model is constant. */
int scene_require_model_keys(struct scene_ctx *c)
{
    static const char *const keys[] = {"Segregation:V", "Segregation:D"};
    const char *model = "constant";
    yaml_node_pair_t *sec = scene_map_pair(c, 1, "Segregation");
    yaml_node_pair_t *mp = sec ? scene_map_pair(c, sec->value, "model") : NULL;
    yaml_node_pair_t *en = sec ? scene_map_pair(c, sec->value, "enabled") : NULL;
    if (mp) model = scalar(node(c, mp->value));
    if (strcmp(model, "constant") != 0) return 0;
    if (en && !strcmp(scalar(node(c, en->value)), "off")) return 0; /* not solved */
    for (size_t i = 0; i < ARRAY_LEN(keys); ++i) {
        if (scene_leaf_find(c, keys[i])) continue;
        const struct scene_leaf *l = scene_leaf_find(c, "Segregation");
        return scene_fail(c, -1, l && l->line > 0 ? l->line : 1, keys[i],
                    "required key missing (Segregation:model is constant)");
    }
    return 0;
}

int scene_walk(struct scene_ctx *c) { return walk_map(c, 1, scene_fields, "", 1); }
