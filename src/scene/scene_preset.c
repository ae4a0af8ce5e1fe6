/* scene_preset.c — Run:preset, named groups of keys (docs/guide.md, "Presets").
 * A preset stands for the -P overrides of its keys, put before the user's
 * own: its values replace the scene file's and the defaults, and a key the
 * user gives with -P keeps the user's value. The sets are measured ones:
 *   paper      the paper's method (§3, Table 1): docs/method.md, "The
 *              paper's settings";
 *   converged  the drum scenes' flow (riemann with bed damping, the
 *              corrected gradient, Fickian shifting) at E 0.1 MPa, chi 0.2:
 *              within 0.9 % (surface speed) and 0.1 % (segregation index) of
 *              the converged drum at dr 0.5 mm;
 *   fast       the same at E 30 kPa with Run:integrator leapfrog: within
 *              1.9 % and 1.7 % at dr 0.5 mm, 0.76 GPU-hours a revolution of
 *              the 1.6e6 3D drum, a quarter of converged's (one H200;
 *              docs/performance.md, "Time to solution"; the rows of
 *              docs/data/gpu/time_to_solution_pair.csv, which
 *              `python3 -m tools.studies.time_to_solution plan` reads). */
#include <stdlib.h>
#include <string.h>
#include "scene_ctx.h"

#define SCENE_FLOW "Flow:stabilization=riemann", "Flow:bed_damping=1", "Flow:gradient_correction=on", \
                   "Flow:shifting=fickian", "Segregation:every=auto", "Run:cfl_flow=0.2"
static const char *const paper[] = {"Flow:stabilization=monaghan", "Flow:alpha_av=0.1", "Flow:shepard_every=30",
                                    "Flow:stress_filter=shepard", "Flow:gradient_correction=off", "Flow:shifting=off",
                                    "Material:yield=drucker_prager", "Material:E=1e7", "Run:cfl_flow=0.1",
                                    "Segregation:scheme=paper", "Segregation:every=1", NULL};
static const char *const converged[] = {SCENE_FLOW, "Material:E=1e5", NULL};
static const char *const fast[] = {SCENE_FLOW, "Material:E=3e4", "Run:integrator=leapfrog", NULL};

/* Indexed by enum run_preset (scene.h); the names are run_presets' (scene_keys.h). */
static const struct {
    const char *name;
    const char *const *keys;
} presets[] = {{"none", NULL}, {"paper", paper}, {"converged", converged}, {"fast", fast}};

const char *scene_preset_name(int preset)
{
    return preset >= 0 && preset < (int)(sizeof presets / sizeof presets[0]) ? presets[preset].name : "?";
}

const char *const *scene_preset_keys(int preset)
{
    return preset >= 0 && preset < (int)(sizeof presets / sizeof presets[0]) ? presets[preset].keys : NULL;
}

/* The name override i (or the file) gives Run:preset, or NULL. */
static const char *preset_named(struct scene_ctx *c)
{
    for (int i = c->n_over - 1; i >= 0; --i) /* the last -P wins, as for any key */
        if (!strncmp(c->over[i], "Run:preset=", 11)) return c->over[i] + 11;
    yaml_node_pair_t *run = scene_map_pair(c, 1, "Run");
    yaml_node_t *r = run ? yaml_document_get_node(&c->doc, run->value) : NULL;
    if (!r || r->type != YAML_MAPPING_NODE) return NULL;
    yaml_node_pair_t *p = scene_map_pair(c, run->value, "preset");
    yaml_node_t *v = p ? yaml_document_get_node(&c->doc, p->value) : NULL;
    return v && v->type == YAML_SCALAR_NODE ? (const char *)v->data.scalar.value : NULL;
}

/* Whether a user's -P sets the key of "Section:key=value" kv. */
static int user_sets(const struct scene_ctx *c, const char *kv)
{
    size_t n = (size_t)(strchr(kv, '=') - kv);
    for (int i = c->n_preset; i < c->n_over; ++i)
        if (!strncmp(c->over[i], kv, n) && c->over[i][n] == '=') return 1;
    return 0;
}

int scene_expand_preset(struct scene_ctx *c)
{
    const char *name = preset_named(c);
    const char *const *keys = NULL;
    for (size_t k = 0; name && k < sizeof presets / sizeof presets[0]; ++k)
        if (!strcmp(name, presets[k].name)) keys = presets[k].keys;
    if (!keys) return 0; /* none, absent, or a name the walk will refuse */
    int n = 0;
    while (keys[n]) ++n;
    char **all = malloc(((size_t)n + (size_t)c->n_over + 1) * sizeof *all);
    if (!all) return scene_fail(c, -1, 0, NULL, "out of memory");
    int m = 0;
    for (int k = 0; k < n; ++k)
        if (!user_sets(c, keys[k])) all[m++] = (char *)keys[k];
    c->n_preset = m;
    memcpy(all + m, c->over, (size_t)c->n_over * sizeof *all);
    c->over = all; /* owned here: scene_ctx_free frees the array, not the strings */
    c->over_owned = 1;
    c->n_over += m;
    c->preset = name;
    return 0;
}
