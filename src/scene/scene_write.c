/* scene_write.c — the loaded scene written back as YAML: every key of the
 * schema with the value used, defaults included (scene_used_text), into
 * OUTDIR/used_params.yml (scene_write_used), the Scene attribute of the
 * snapshots and checkpoints, and the restart's key check (checkpoint_keys.c).
 * Numbers round-trip exactly. */
#define _POSIX_C_SOURCE 200809L
#include "scene_ctx.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void buf_add(struct scene_buf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void buf_add(struct scene_buf *b, const char *fmt, ...)
{
    char tmp[256];
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    if (k < 0 || (size_t)k >= sizeof tmp)
        b->bad = 1;
    else
        scene_buf_write(b, (unsigned char *)tmp, (size_t)k);
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
static void put_value(struct scene_buf *b, const cyaml_schema_value_t *v, const char *p)
{
    char num[32];
    double d;
    const char *str;
    switch (v->type) {
    case CYAML_FLOAT:
        memcpy(&d, p, sizeof d);
        scene_fmt_double(num, sizeof num, d);
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
static void put_list(struct scene_buf *b, const cyaml_schema_field_t *f, const char *base)
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
            if (e == scene_wall_entry && !strcmp(g->key, "open_at") && !((const struct scene_wall *)(const void *)it)->gate)
                continue;
            if (e == scene_region_entry && !strcmp(g->key, "floor") &&
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
    struct scene_buf b = {0};
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

