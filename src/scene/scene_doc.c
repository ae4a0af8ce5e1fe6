/* scene_doc.c — the documentation of every scene key (sphseg --keys,
 * docs/keys.md), from the key table src/scene/scene_keys.h. */
#include <cyaml/cyaml.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include "scene.h"

#define ARRAY_LEN(a) (sizeof(a) / sizeof((a)[0]))
#define REQ CYAML_FLAG_DEFAULT
#define OPT CYAML_FLAG_OPTIONAL


/* the names of the enumerated keys (the guarded head of scene_keys.h), rows ignored */
#include "scene_keys_none.h"
#include "scene_keys.h"

enum { DOC_NUM, DOC_NAME, DOC_UINT, DOC_STRING, DOC_VEC, DOC_LIST };
struct scene_doc {
    const char *section, *key;
    int kind;
    const cyaml_strval_t *strs; /* DOC_NAME: the names */
    uint32_t nstrs;             /* DOC_NAME: how many; DOC_VEC: entries */
    int required;
    const char *def;
    double lo, hi;
    int open, when;
    const char *doc;
};
static const struct scene_doc scene_docs[] = {
#include "scene_keys_none.h"
#undef KF
#define KF(sec, m, st, k, req, def, lo, hi, open, when, doc) \
    {sec, #k, DOC_NUM, NULL, 0, (req) == REQ, def, lo, hi, open, when, doc},
#undef KE
#define KE(sec, m, st, k, type, strs, def, doc) \
    {sec, #k, DOC_NAME, strs, CYAML_ARRAY_LEN(strs), 0, def, 0, 0, 0, NO_RANGE, doc},
#undef KU
#define KU(sec, m, st, k, def, doc) {sec, #k, DOC_UINT, NULL, 0, 0, def, 0, 0, 0, NO_RANGE, doc},
#undef KS
#define KS(sec, m, st, k, mn, mx, def, doc) {sec, #k, DOC_STRING, NULL, 0, 0, def, 0, 0, 0, NO_RANGE, doc},
#undef KV
#define KV(sec, m, st, k, n, def, doc) {sec, #k, DOC_VEC, NULL, n, 0, def, 0, 0, 0, NO_RANGE, doc},
#undef KL
#define KL(sec, m, st, k, est, entry, max, doc) \
    {sec, #k, DOC_LIST, NULL, max, 0, NULL, 0, 0, 0, NO_RANGE, doc},
#undef EKF
#define EKF(sec, st, k, doc) {sec ":K", #k, DOC_NUM, NULL, 0, 0, NULL, 0, 0, 0, NO_RANGE, doc},
#undef EKE
#define EKE(sec, st, k, type, strs, doc) \
    {sec ":K", #k, DOC_NAME, strs, CYAML_ARRAY_LEN(strs), 0, NULL, 0, 0, 0, NO_RANGE, doc},
#undef EKU
#define EKU(sec, st, k, doc) {sec ":K", #k, DOC_UINT, NULL, 0, 0, NULL, 0, 0, 0, NO_RANGE, doc},
#undef EKS
#define EKS(sec, st, k, mn, mx, doc) {sec ":K", #k, DOC_STRING, NULL, 0, 0, NULL, 0, 0, 0, NO_RANGE, doc},
#undef EKV
#define EKV(sec, st, k, n, doc) {sec ":K", #k, DOC_VEC, NULL, n, 0, NULL, 0, 0, 0, NO_RANGE, doc},
#include "scene_keys.h"
};

void scene_keys_markdown(FILE *f)
{
    fprintf(f, "# sphseg scene keys\n\n"
               "Every key of a scene file, from the key table `src/scene/scene_keys.h` (`sphseg --keys` writes this\n"
               "file; `tests/test_keys.sh` checks it is current). Units are SI. Any key may be set on the\n"
               "command line with `-P Section:key=value`; a list is given whole. The scenes in `inputs/`\n"
               "show them in use, with comments.\n");
    const char *sec = "";
    for (size_t j = 0; j < 2 * ARRAY_LEN(scene_docs); ++j) { /* the sections, then the lists' entries */
        const struct scene_doc *d = &scene_docs[j % ARRAY_LEN(scene_docs)];
        if ((j < ARRAY_LEN(scene_docs)) == (strchr(d->section, ':') != NULL)) continue;
        if (strcmp(sec, d->section)) {
            sec = d->section;
            fprintf(f, "\n## %s\n\n| key | value | default | range | meaning |\n| --- | --- | --- | --- | --- |\n", sec);
        }
        fprintf(f, "| `%s` | ", d->key);
        switch (d->kind) {
        case DOC_NUM: fprintf(f, "number"); break;
        case DOC_UINT: fprintf(f, "whole number >= 0"); break;
        case DOC_STRING: fprintf(f, "text"); break;
        case DOC_VEC: fprintf(f, "%u numbers", d->nstrs); break;
        case DOC_LIST: fprintf(f, "list (at most %u)", d->nstrs); break;
        default:
            for (uint32_t k = 0; k < d->nstrs; ++k) fprintf(f, "%s`%s`", k ? " \\| " : "", d->strs[k].str);
        }
        fprintf(f, " | %s | ", d->required ? "required" : d->def ? d->def : "-");
        if (d->when != NO_RANGE) {
            fprintf(f, "%c%g, ", d->open & LO_OPEN ? '(' : '[', d->lo);
            if (isinf(d->hi)) fprintf(f, "inf)");
            else fprintf(f, "%g%c", d->hi, d->open & HI_OPEN ? ')' : ']');
            if (d->when != ALWAYS) fprintf(f, " (Segregation:model %s)", d->when == IF_CONSTANT ? "constant" : "shear_rate");
        } else {
            fprintf(f, "-");
        }
        fprintf(f, " | ");
        for (const char *c = d->doc; *c; ++c) fprintf(f, *c == '|' ? "\\|" : "%c", *c);
        fprintf(f, " |\n");
    }
}

