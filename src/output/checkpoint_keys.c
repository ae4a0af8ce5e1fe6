/* checkpoint_keys.c — does a restart's scene describe the checkpoint's
 * state? (see checkpoint.h, ckpt_check_scene). Both sides are the
 * used-parameters text (scene_used_text): "Section:" lines, then
 * "  key: value" lines, every key of the schema present; a list of
 * mappings (Container:walls, Container:regions) is "  key: " followed by
 * one "    - {k: v, k: v, ...}" line per entry, or "  key: []".
 *
 * Both texts are flattened into keys first (ckpt_keys_read): a plain key is
 * Section:key; a list is Section:key (its length) and, for each entry K
 * (counted from 1, as the scene's own errors count them: scene_check.c),
 * Section:key:K:k for each key k of the entry. Every key is compared on its
 * own, so that the refusal names the one that differs, once, with both
 * values whole: Container:walls:4 (hopper_right):to ([0.06, 0] in the
 * checkpoint, [0.061, 0] now). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "checkpoint.h"
#include "core/error.h"

enum ckpt_key_class { KEY_RUN = 0, KEY_MODEL = 1, KEY_STATE = 2 };

/* Run-control and model keys by name; every other key is a state key. So
 * are all of DEM's: the grains' count and places (d, placement, at, block_*)
 * make the store the checkpoint fills, and their material and coupling
 * (rho, kn, kt, e, mu, t_damp, coupling, motion) what its velocities, spins
 * and tangential springs mean and how the next DEM step reads them. */
static enum ckpt_key_class ckpt_key_class(const char *name)
{
    static const char *const run[] = {"Run:", "Output:", "Parallel:"};
    static const char *const modules[] = {"Segregation:enabled", "Segregation:scheme",
                                          "Segregation:renormalize"};
    for (size_t k = 0; k < 3; ++k)
        if (!strncmp(name, run[k], strlen(run[k]))) return KEY_RUN;
    for (size_t k = 0; k < 3; ++k)
        if (!strcmp(name, modules[k])) return KEY_STATE;
    if (!strncmp(name, "Segregation:", 12) || !strncmp(name, "Flow:", 5) || !strncmp(name, "Grains:", 7) ||
        !strncmp(name, "Outlet:", 7))
        return KEY_MODEL;
    return KEY_STATE;
}

/* One flattened key. entry: the entry's place K in its list (0: not an
 * entry's key), list: the index of its list's own key in the table; label:
 * the entry's name, for the message (walls have one, regions not). */
struct ckpt_key {
    char name[160], label[48], value[240];
    int entry;
    size_t list;
};

struct ckpt_keys {
    struct ckpt_key *k;
    size_t n, cap;
};

static struct ckpt_key *ckpt_keys_add(struct ckpt_keys *t, const char *name, int namelen, const char *value,
                                      int valuelen)
{
    if (t->n == t->cap) {
        size_t cap = t->cap ? 2 * t->cap : 256;
        struct ckpt_key *k = realloc(t->k, cap * sizeof *k);
        if (!k) error_exit(EXIT_SYSTEM, "out of memory comparing scenes");
        t->k = k, t->cap = cap;
    }
    struct ckpt_key *k = &t->k[t->n++];
    snprintf(k->name, sizeof k->name, "%.*s", namelen, name);
    snprintf(k->value, sizeof k->value, "%.*s", valuelen, value);
    k->label[0] = 0, k->entry = 0, k->list = 0;
    return k;
}

/* The length of the next "k: v" item of a flow mapping's inside at p (up to
 * the ", " at bracket depth 0 outside quotes, or the end). */
static size_t ckpt_item_len(const char *p, size_t n)
{
    int depth = 0, quoted = 0;
    for (size_t i = 0; i < n; ++i) {
        char c = p[i];
        if (quoted) {
            if (c == '\\' && i + 1 < n)
                ++i;
            else if (c == '"')
                quoted = 0;
        } else if (c == '"')
            quoted = 1;
        else if (c == '[' || c == '{')
            ++depth;
        else if (c == ']' || c == '}')
            --depth;
        else if (c == ',' && depth <= 0 && i + 1 < n && p[i + 1] == ' ')
            return i;
    }
    return n;
}

/* The entry K of the list t->k[list] from its line's mapping "{...}" (m, n
 * bytes): one key per item, named Section:key:K:item. */
static void ckpt_keys_entry(struct ckpt_keys *t, size_t list, int K, const char *m, size_t n)
{
    char name[160];
    if (n < 2 || m[0] != '{' || m[n - 1] != '}') { /* not a mapping: kept whole, under the entry's own name */
        int nl = snprintf(name, sizeof name, "%.120s:%d", t->k[list].name, K);
        struct ckpt_key *k = ckpt_keys_add(t, name, nl, m, (int)n);
        k->entry = K, k->list = list;
        return;
    }
    const char *p = m + 1, *end = m + n - 1;
    char label[48] = "";
    size_t first = t->n;
    while (p < end) {
        size_t len = ckpt_item_len(p, (size_t)(end - p)), lk = strcspn(p, ":");
        if (lk > len) lk = len;
        const char *v = p + lk + (lk < len) + (lk + 1 < len && p[lk + 1] == ' ');
        int nl =
            snprintf(name, sizeof name, "%.120s:%d:%.*s", t->k[list].name, K, (int)(lk < 30 ? lk : 30), p);
        struct ckpt_key *k = ckpt_keys_add(t, name, nl, v, (int)(p + len - v));
        k->entry = K, k->list = list;
        if (lk == 4 && !strncmp(p, "name", 4)) /* the name without its quotes (letters, digits, _) */
            snprintf(label, sizeof label, "%.*s", (int)strcspn(k->value + (k->value[0] == '"'), "\""),
                     k->value + (k->value[0] == '"'));
        p += len + 2;
    }
    for (size_t i = first; i < t->n; ++i)
        snprintf(t->k[i].label, sizeof t->k[i].label, "%s", label);
}

/* The used-parameters text flattened into t (see the top of this file). */
static void ckpt_keys_read(const char *text, struct ckpt_keys *t)
{
    char sec[64] = "";
    size_t list = (size_t)-1;
    int count = 0;
    for (const char *l = text; *l; l += strcspn(l, "\n") + (l[strcspn(l, "\n")] != 0)) {
        size_t len = strcspn(l, "\n");
        while (len && l[len - 1] == ' ')
            --len; /* "  walls: " before its entries */
        if (l[0] != ' ' && l[0] != '#' && len > 1 && len < sizeof sec && l[len - 1] == ':') {
            snprintf(sec, sizeof sec, "%.*s", (int)(len - 1), l);
            list = (size_t)-1;
        } else if (list != (size_t)-1 && len > 6 && !strncmp(l, "    - ", 6)) {
            snprintf(t->k[list].value, sizeof t->k[list].value, "%d entries", ++count);
            ckpt_keys_entry(t, list, count, l + 6, len - 6);
        } else if (sec[0] && len > 2 && !strncmp(l, "  ", 2) && l[2] != ' ') {
            size_t lk = strcspn(l + 2, ":\n");
            if (lk >= 80 || 2 + lk >= len) continue;
            char name[160];
            int nl = snprintf(name, sizeof name, "%s:%.*s", sec, (int)lk, l + 2);
            const char *v = l + 2 + lk + 1 + (3 + lk < len && l[3 + lk] == ' ');
            int vl = (int)(l + len - v);
            list = vl > 0 ? (size_t)-1 : t->n, count = 0; /* "  key:" alone: a list follows */
            ckpt_keys_add(t, name, nl, vl > 0 ? v : "[]", vl > 0 ? vl : 2);
        } else {
            list = (size_t)-1;
        }
    }
}

static const struct ckpt_key *ckpt_keys_find(const struct ckpt_keys *t, const char *name)
{
    for (size_t i = 0; i < t->n; ++i)
        if (!strcmp(t->k[i].name, name)) return &t->k[i];
    return NULL;
}

/* A key of an entry that the other side's list does not have (a shorter
 * list, or none): its list's length says it (one line, not one per key). */
static int ckpt_key_past_list(const struct ckpt_keys *mine, const struct ckpt_key *k,
                              const struct ckpt_keys *other)
{
    if (!k->entry) return 0;
    const struct ckpt_key *l = ckpt_keys_find(other, mine->k[k->list].name);
    return !l || atoi(l->value) < k->entry;
}

struct ckpt_key_diff {
    struct ckpt_keys was, now;
    char lists[3][2400];
    int count[3], left_out[3];
};

/* Append "name (A in the checkpoint, B now)" to list c, or count it as
 * left out when the list is full. */
static void ckpt_key_note(struct ckpt_key_diff *d, enum ckpt_key_class c, const struct ckpt_key *k,
                          const char *was, const char *now)
{
    char shown[256], note[800];
    const char *colon = strrchr(k->name, ':');
    if (k->entry && k->label[0]) /* Container:walls:4 (hopper_right):to */
        snprintf(shown, sizeof shown, "%.*s (%s)%s", (int)(colon - k->name), k->name, k->label, colon);
    else
        snprintf(shown, sizeof shown, "%s", k->name);
    int len = snprintf(note, sizeof note, "%s%s (%s in the checkpoint, %s now)", d->count[c] ? ", " : "",
                       shown, was, now);
    size_t used = strlen(d->lists[c]);
    d->count[c]++;
    if (d->left_out[c] || used + (size_t)len + 1 > sizeof d->lists[c] - 40)
        d->left_out[c]++;
    else
        memcpy(d->lists[c] + used, note, (size_t)len + 1);
}

/* The value a key newer than a checkpoint had in effect before it existed:
 * its default, but where a key's default changed the behaviour when it came,
 * the old behaviour's value; a list newer than the checkpoint was empty. */
static const char *ckpt_key_before(const struct ckpt_key *k)
{
    static const char *const before[][2] = {{"Segregation:limiter", "none"}};
    for (size_t j = 0; j < sizeof before / sizeof before[0]; ++j)
        if (!strcmp(k->name, before[j][0])) return before[j][1];
    if (!strcmp(k->value, "[]")) return "[]";
    return k->entry ? NULL : scene_key_default(k->name);
}

/* Compare now's key k with the checkpoint's of that name. */
static void ckpt_key_compare(struct ckpt_key_diff *d, const struct ckpt_key *k)
{
    const struct ckpt_key *w = ckpt_keys_find(&d->was, k->name);
    if (w && !strcmp(w->value, k->value)) return;
    if (!w && ckpt_key_past_list(&d->now, k, &d->was)) return;
    /* a key newer than the checkpoint: the checkpoint ran the behaviour the code
     * had before the key, which is the key's default (Material:yield
     * drucker_prager) unless ckpt_key_before names another (Segregation:limiter,
     * whose default donor came with it: the code before capped nothing) */
    const char *def = w ? NULL : ckpt_key_before(k);
    if (def && !strcmp(def, k->value)) return;
    ckpt_key_note(d, ckpt_key_class(k->name), k, w ? w->value : "(absent)", k->value);
}

/* The checkpoint's key k, which this run's scene does not have. */
static void ckpt_key_gone(struct ckpt_key_diff *d, const struct ckpt_key *k)
{
    if (ckpt_keys_find(&d->now, k->name) || ckpt_key_past_list(&d->was, k, &d->now)) return;
    ckpt_key_note(d, ckpt_key_class(k->name), k, k->value, "(absent)");
}

/* " and N more" after a full list. */
static const char *ckpt_key_more(const struct ckpt_key_diff *d, enum ckpt_key_class c, char *b, size_t n)
{
    if (!d->left_out[c]) return "";
    snprintf(b, n, ", and %d more", d->left_out[c]);
    return b;
}

void ckpt_check_scene(const char *file, const char *stored, const struct scene *sc)
{
    static struct ckpt_key_diff d; /* 7 kB of lists: not on the stack */
    memset(&d, 0, sizeof d);
    char *now = scene_used_text(sc), more[40];
    if (!now) error_exit(EXIT_SYSTEM, "out of memory comparing scenes");
    ckpt_keys_read(stored, &d.was);
    ckpt_keys_read(now, &d.now);
    free(now);
    for (size_t i = 0; i < d.now.n; ++i)
        ckpt_key_compare(&d, &d.now.k[i]);
    for (size_t i = 0; i < d.was.n; ++i)
        ckpt_key_gone(&d, &d.was.k[i]);
    free(d.was.k), free(d.now.k);
    if (d.count[KEY_STATE])
        input_error(
            "--restart %s: the scene %s describes another state than the checkpoint's: %d state-defining "
            "key(s) differ: %s%s (restart with the scene and -P options the run was started with)",
            file, sc->path, d.count[KEY_STATE], d.lists[KEY_STATE],
            ckpt_key_more(&d, KEY_STATE, more, sizeof more));
    if (d.count[KEY_MODEL])
        warning("--restart %s: %d model key(s) differ from the checkpoint's, continuing with the values now: "
                "%s%s",
                file, d.count[KEY_MODEL], d.lists[KEY_MODEL],
                ckpt_key_more(&d, KEY_MODEL, more, sizeof more));
    if (d.count[KEY_RUN])
        message("restart: %d run-control key(s) differ from the checkpoint's: %s%s", d.count[KEY_RUN],
                d.lists[KEY_RUN], ckpt_key_more(&d, KEY_RUN, more, sizeof more));
}
