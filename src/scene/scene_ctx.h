/* scene_ctx.h — what the scene loader's files share (private to scene.c,
 * scene_yaml.c, scene_walk.c, scene_check.c and scene_write.c; the rest of
 * the code includes scene.h only).
 *
 * One load is one struct scene_ctx: the file's text, the libyaml document
 * edited in place (overrides, moved keys, defaults), the keys the walk met
 * (for line numbers after loading) and the error buffer. The steps, in the
 * order scene.c's parse_steps runs them:
 *   scene_yaml.c   read the file, parse it, edit -P overrides into it, move
 *                  the grain sizes' old keys
 *   scene_walk.c   walk the document against the libcyaml schema: every key
 *                  and scalar checked and located
 *   scene.c        defaults edited in, libcyaml load, ranges from the key table
 *   scene_check.c  the checks across keys (geometry, container, choices)
 * scene_write.c writes the loaded scene back (used_params.yml). */
#ifndef SPHSEG_SCENE_CTX_H
#define SPHSEG_SCENE_CTX_H
#include "scene.h"

#include <cyaml/cyaml.h>
#include <yaml.h>

#include <stdarg.h>
#include <stddef.h>

#define ARRAY_LEN(a) (sizeof(a) / sizeof((a)[0]))

enum { SCENE_MAX_LEAVES = 640, SCENE_MAX_DEPTH = 4, SCENE_NAME = 64 };

/* A key the walk met: where it was set, for errors found after loading. */
struct scene_leaf {
    char name[SCENE_NAME]; /* "Section" or "Section:key" */
    int line;              /* 1-based line of the key in the file, 0 if not there */
    int over;              /* index of the -P override that set it, or -1 */
};

struct scene_ctx {
    const char *path;
    int n_over;
    char **over;
    char *text; /* the file, NUL-terminated */
    size_t len;
    yaml_document_t doc;
    int have_doc;
    int n_preset;       /* over[0..n_preset): Run:preset's keys (scene_preset.c), then the user's -P */
    const char *preset; /* the preset's name, or NULL */
    int over_owned;     /* over is an array of scene_expand_preset's (the strings are not) */
    int n_file_nodes; /* nodes 1..n_file_nodes came from the file */
    int *first_node;  /* first node of override i; [n_over]: first default node */
    struct scene_leaf leaf[SCENE_MAX_LEAVES];
    int n_leaf;
    char *err;
    size_t errlen;
    char log[256]; /* libcyaml's first error message */
};

/* A growing text (NUL-terminated); bad is set when memory ran out. */
struct scene_buf {
    char *p;
    size_t n, cap;
    int bad;
};

/* ---- scene.c: the schema from the key table, messages, the record of keys ---- */

/* The sections of the libcyaml schema (scene_keys.h), ended by a NULL key. */
extern const cyaml_schema_field_t scene_fields[];
/* The entries of Container:walls and :regions (the echo leaves keys out of them). */
extern const cyaml_schema_value_t *const scene_wall_entry, *const scene_region_entry;

/* Append printf output at offset n of out[cap]; returns the new offset. */
size_t scene_vcat(char *out, size_t cap, size_t n, const char *fmt, va_list ap);
size_t scene_cat(char *out, size_t cap, size_t n, const char *fmt, ...) __attribute__((format(printf, 4, 5)));
/* Write "WHERE: NAME: why" to c->err: WHERE is "-P ARG" for override `over`
 * >= 0, else FILE:LINE (FILE alone when line is 0); NAME may be NULL.
 * Returns -1. */
int scene_fail(struct scene_ctx *c, int over, int line, const char *name, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
/* Error about parameter `name` ("Section:key") after the walk, located where
 * the key was set (its override, or the line of the key, else of its
 * section, else 1). Returns -1. */
int scene_fail_at(struct scene_ctx *c, const char *name, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
int scene_leaf_add(struct scene_ctx *c, const char *name, int line, int over);
const struct scene_leaf *scene_leaf_find(const struct scene_ctx *c, const char *name);
/* The shortest of %.15g, %.16g, %.17g that reads back as exactly d. */
void scene_fmt_double(char *out, size_t n, double d);
/* Append size bytes to the buffer `data` (a struct scene_buf); libyaml's
 * write handler: 1 on success, 0 (and bad set) when memory ran out. */
int scene_buf_write(void *data, unsigned char *bytes, size_t size);

/* ---- scene_yaml.c: the libyaml document ----------------------------------------- */

static inline yaml_node_t *node(struct scene_ctx *c, int id) { return yaml_document_get_node(&c->doc, id); }

static inline const char *scalar(const yaml_node_t *n) { return (const char *)n->data.scalar.value; }

static inline int node_line(struct scene_ctx *c, int id)
{
    yaml_node_t *n = node(c, id);
    return n ? (int)n->start_mark.line + 1 : 1;
}

/* Where node id came from: -1 the file, i >= 0 override i, -2 a default. */
int scene_node_origin(const struct scene_ctx *c, int id);
/* The pair of mapping `map` whose key is `key`, or NULL. The pointer is valid
 * until a pair is appended to that mapping. */
yaml_node_pair_t *scene_map_pair(struct scene_ctx *c, int map, const char *key);
/* Parse `text` as YAML and add its root to the scene document; returns the
 * node id, or 0 with the reason in why. Empty text gives an empty scalar. */
int scene_doc_add_text(struct scene_ctx *c, const char *text, char *why, size_t n);
/* Set comp[0]:...:comp[n-1] to node val, creating sections as needed. A
 * section that is not a mapping is left alone: the walk reports it. */
int scene_doc_put(struct scene_ctx *c, const char *const *comp, int n, int val);
/* Emit doc as YAML text into b; the document is freed either way. */
int scene_doc_emit(yaml_document_t *doc, struct scene_buf *b);
/* The steps: the file into c->text, parsed into c->doc (a mapping at the
 * root), the -P overrides, the grain sizes' old keys moved to Grains. */
int scene_read_text(struct scene_ctx *c);
int scene_load_doc(struct scene_ctx *c);
int scene_apply_overrides(struct scene_ctx *c);
/* scene_preset.c: Run:preset (from the last -P that sets it, else the file)
 * put before the user's overrides as overrides of its own keys, less those the
 * user sets (c->n_preset of them); nothing for none or an unknown name (the
 * walk refuses that). */
int scene_expand_preset(struct scene_ctx *c);
int scene_move_grain_keys(struct scene_ctx *c);

/* ---- scene_walk.c: the document against the schema --------------------------------- */

const cyaml_schema_field_t *scene_field_find(const cyaml_schema_field_t *f, const char *key);
/* "unknown key" or "unknown section" (section != 0), listing the known ones. */
int scene_fail_unknown(struct scene_ctx *c, int over, int line, const char *name,
                       const cyaml_schema_field_t *fields, int section);
/* The whole document against scene_fields, each key recorded (scene_leaf_add). */
int scene_walk(struct scene_ctx *c);
/* Segregation:V and :D are required when Segregation:model is constant. */
int scene_require_model_keys(struct scene_ctx *c);

/* ---- scene_check.c: the checks across keys, after loading -------------------------- */

int scene_check_special(struct scene_ctx *c, struct scene *s);
int scene_check_every(struct scene_ctx *c, struct scene_segregation *g);

#endif
