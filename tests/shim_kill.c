/* shim_kill.c — a test-only LD_PRELOAD library: the process kills itself
 * (SIGKILL) just before its N-th rename onto a path ending in SUFFIX, as a
 * node that dies in the middle of a checkpoint rotation does
 * (tests/test_outdir.sh). Not part of sphseg: built by that test.
 *
 *   SHIM_KILL=SUFFIX:N LD_PRELOAD=shim_kill.so sphseg ...
 *
 * SHIM_KILL=/checkpoint.h5:2 kills the run in rotation 2, after
 * checkpoint.h5 was hard-linked to checkpoint_prev.h5 and before the new
 * checkpoint is renamed over checkpoint.h5 (src/output/checkpoint.c, ckpt_commit).
 * Renames onto other paths, and those after the N-th, go through untouched.
 * sphseg calls rename(3) (nm -D: rename@GLIBC); a product that moved to
 * renameat would not be killed and the test's exit-status check fails. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int shim_on = -1;
static char shim_suffix[256];
static long shim_at, shim_seen;

static void shim_init(void)
{
    if (shim_on >= 0) return;
    shim_on = 0;
    const char *spec = getenv("SHIM_KILL"), *colon = spec ? strrchr(spec, ':') : NULL;
    if (!colon || colon == spec || (size_t)(colon - spec) >= sizeof shim_suffix) return;
    shim_at = atol(colon + 1);
    if (shim_at < 1) return;
    memcpy(shim_suffix, spec, (size_t)(colon - spec));
    shim_suffix[colon - spec] = 0;
    shim_on = 1;
}

int rename(const char *from, const char *to)
{
    shim_init();
    if (shim_on && to) {
        size_t lt = strlen(to), ls = strlen(shim_suffix);
        if (lt >= ls && strcmp(to + lt - ls, shim_suffix) == 0 && ++shim_seen == shim_at) raise(SIGKILL);
    }
    return ((int (*)(const char *, const char *))dlsym(RTLD_NEXT, "rename"))(from, to);
}
