/* checkpoint_keys.c — does a restart's scene describe the checkpoint's
 * state? (see checkpoint.h, ckpt_check_scene). Both sides are the
 * used-parameters text (scene_used_text): "Section:" lines, then
 * "  key: value" lines, every key of the schema present. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "checkpoint.h"
#include "core/error.h"

enum ckpt_key_class { KEY_RUN = 0, KEY_MODEL = 1, KEY_STATE = 2 };

static enum ckpt_key_class ckpt_key_class(const char *name)
{
    static const char *const run[] = {"Run:", "Output:", "Parallel:"};
    static const char *const modules[] = {"Segregation:enabled", "Segregation:scheme", "Segregation:renormalize"};
    for (size_t k = 0; k < 3; ++k)
        if (!strncmp(name, run[k], strlen(run[k]))) return KEY_RUN;
    for (size_t k = 0; k < 3; ++k)
        if (!strcmp(name, modules[k])) return KEY_STATE;
    if (!strncmp(name, "Segregation:", 12) || !strncmp(name, "Flow:", 5) || !strncmp(name, "Grains:", 7) ||
        !strncmp(name, "Outlet:", 7))
        return KEY_MODEL;
    return KEY_STATE;
}

/* The value of Section:key in a used-parameters text, into val; 0 if absent. */
static int ckpt_key_value(const char *text, const char *name, char *val, size_t n)
{
    const char *colon = strchr(name, ':');
    size_t ls = (size_t)(colon - name), lk = strlen(colon + 1);
    int in = 0;
    for (const char *l = text; *l; l += strcspn(l, "\n") + (l[strcspn(l, "\n")] != 0)) {
        size_t len = strcspn(l, "\n");
        if (l[0] != ' ' && l[0] != '#') in = len == ls + 1 && !strncmp(l, name, ls) && l[ls] == ':';
        else if (in && len > lk + 4 && !strncmp(l, "  ", 2) && !strncmp(l + 2, colon + 1, lk) && l[2 + lk] == ':') {
            snprintf(val, n, "%.*s", (int)(len - lk - 4), l + lk + 4);
            return 1;
        }
    }
    return 0;
}

/* Append "Section:key (A in the checkpoint, B now)" to list. */
static void ckpt_key_note(char *list, size_t n, const char *name, const char *was, const char *now)
{
    size_t used = strlen(list);
    if (used + 8 >= n) return;
    snprintf(list + used, n - used, "%s%s (%.60s in the checkpoint, %.60s now)", used ? ", " : "", name, was, now);
}

/* Every Section:key of text, one call of fn per key. */
static void ckpt_key_each(const char *text, void (*fn)(const char *name, void *ctx), void *ctx)
{
    char sec[64] = "", name[160];
    for (const char *l = text; *l; l += strcspn(l, "\n") + (l[strcspn(l, "\n")] != 0)) {
        size_t len = strcspn(l, "\n"), lk = strcspn(l + 2, ":\n");
        if (l[0] != ' ' && l[0] != '#' && len > 1 && len < sizeof sec && l[len - 1] == ':')
            snprintf(sec, sizeof sec, "%.*s", (int)(len - 1), l);
        else if (sec[0] && len > 2 && !strncmp(l, "  ", 2) && lk < 80) {
            snprintf(name, sizeof name, "%s:%.*s", sec, (int)lk, l + 2);
            fn(name, ctx);
        }
    }
}

struct ckpt_key_diff {
    const char *stored, *now;
    char lists[3][2000];
    int count[3];
};

/* The value a key newer than a checkpoint had in effect before it existed:
 * its default, but where a key's default changed the behaviour when it came,
 * the old behaviour's value. */
static const char *ckpt_key_before(const char *name)
{
    static const char *const before[][2] = {{"Segregation:limiter", "none"}};
    for (size_t k = 0; k < sizeof before / sizeof before[0]; ++k)
        if (!strcmp(name, before[k][0])) return before[k][1];
    return scene_key_default(name);
}

static void ckpt_key_compare(const char *name, void *ctx)
{
    struct ckpt_key_diff *d = ctx;
    char was[200] = "(absent)", now[200] = "(absent)";
    int in_was = ckpt_key_value(d->stored, name, was, sizeof was);
    int in_now = ckpt_key_value(d->now, name, now, sizeof now);
    if (in_was == in_now && (!in_was || !strcmp(was, now))) return;
    /* a key newer than the checkpoint: the checkpoint ran the behaviour the code
     * had before the key, which is the key's default (Material:yield
     * drucker_prager) unless ckpt_key_before names another (Segregation:limiter,
     * whose default donor came with it: the code before capped nothing) */
    const char *def = in_now && !in_was ? ckpt_key_before(name) : NULL;
    if (def && !strcmp(def, now)) return;
    enum ckpt_key_class c = ckpt_key_class(name);
    d->count[c]++;
    ckpt_key_note(d->lists[c], sizeof d->lists[c], name, was, now);
}

static void ckpt_key_absent_now(const char *name, void *ctx)
{
    struct ckpt_key_diff *d = ctx;
    char v[200];
    if (!ckpt_key_value(d->now, name, v, sizeof v)) ckpt_key_compare(name, ctx);
}

void ckpt_check_scene(const char *file, const char *stored, const struct scene *sc)
{
    struct ckpt_key_diff d = {stored, scene_used_text(sc), {"", "", ""}, {0, 0, 0}};
    if (!d.now) error_exit(EXIT_SYSTEM, "out of memory comparing scenes");
    ckpt_key_each(d.now, ckpt_key_compare, &d);
    ckpt_key_each(stored, ckpt_key_absent_now, &d);
    free((char *)d.now);
    if (d.count[KEY_STATE])
        input_error("--restart %s: the scene %s describes another state than the checkpoint's: %d state-defining "
                    "key(s) differ: %s (restart with the scene and -P options the run was started with)",
                    file, sc->path, d.count[KEY_STATE], d.lists[KEY_STATE]);
    if (d.count[KEY_MODEL])
        warning("--restart %s: %d model key(s) differ from the checkpoint's, continuing with the values now: %s",
                file, d.count[KEY_MODEL], d.lists[KEY_MODEL]);
    if (d.count[KEY_RUN])
        message("restart: %d run-control key(s) differ from the checkpoint's: %s", d.count[KEY_RUN],
                d.lists[KEY_RUN]);
}
