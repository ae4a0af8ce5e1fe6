/* core/tuning.c — the tuning and diagnostics settings read from the
 * environment, once (core/tuning.h). */
#include "tuning.h"
#include <stdlib.h>
#include <string.h>
#include "error.h"

/* The settings' names, and their values as read (NULL: not set). */
enum { T_PROFILE, T_TEAM, T_NBR, T_WALLSKIP, T_OVERLAP, T_HOSTX, T_IPC, T_CUDA_AWARE, T_SKEW, T_CPU_NBR, T_GRAPH, T_BEDQ, T_SPEC, T_N };
static const char *const tuning_names[T_N] = {"SPHSEG_GPU_PROFILE", "SPHSEG_GPU_TEAM",  "SPHSEG_GPU_NBR", "SPHSEG_GPU_WALLSKIP",
                                              "SPHSEG_GPU_OVERLAP", "SPHSEG_GPU_HOSTX", "SPHSEG_GPU_IPC",
                                              "SPHSEG_CUDA_AWARE", "SPHSEG_BALANCE_SKEW", "SPHSEG_CPU_NBR",
                                              "SPHSEG_GPU_GRAPH", "SPHSEG_GPU_BEDQ", "SPHSEG_GPU_SPEC"};
static const char *tuning_raw[T_N];

/* Set and not empty. */
static int is_set(const char *e) { return e && *e; }
/* Set to exactly "0" (an empty value keeps the default). */
static int is_zero(const char *e) { return e && !strcmp(e, "0"); }

static int team_of(const char *e)
{
    if (!is_set(e)) return 0;
    char *end;
    long t = strtol(e, &end, 10);
    return *end || (t != 1 && t != 2 && t != 4 && t != 8 && t != 16) ? -1 : (int)t;
}

/* "list" 0 (or not set), "list16" 1, "cells" 2; else -1. */
static int nbr_of(const char *e)
{
    if (!is_set(e) || !strcmp(e, "list")) return 0;
    return !strcmp(e, "list16") ? 1 : !strcmp(e, "cells") ? 2 : !strcmp(e, "tile") ? 4 : -1;
}

/* "list" 0 (or not set), "cells" 2; else -1. */
static int cpu_nbr_of(const char *e)
{
    if (!is_set(e) || !strcmp(e, "list")) return 0;
    return !strcmp(e, "cells") ? 2 : -1;
}

/* "R:F", R a rank >= 0 and F a finite factor > 0; else *rank = -2. */
static void skew_of(const char *e, int *rank, double *factor)
{
    *rank = -1, *factor = 1;
    if (!is_set(e)) return;
    char *end, *end2 = NULL;
    long r = strtol(e, &end, 10);
    double f = *end == ':' ? strtod(end + 1, &end2) : 0;
    if (end == e || *end != ':' || end2 == end + 1 || *end2 || r < 0 || r > 1L << 30 || !(f > 0 && f < 1e30))
        *rank = -2;
    else
        *rank = (int)r, *factor = f;
}

const tuning *tuning_get(void)
{
    static tuning t;
    static int read;
    if (read) return &t;
    for (int k = 0; k < T_N; ++k) tuning_raw[k] = getenv(tuning_names[k]);
    const char *const *r = tuning_raw;
    t = (tuning){.gpu_profile = is_set(r[T_PROFILE]) && !is_zero(r[T_PROFILE]),
                 .gpu_team = team_of(r[T_TEAM]),
                 .gpu_nbr = nbr_of(r[T_NBR]),
                 .gpu_wallskip = !is_zero(r[T_WALLSKIP]),
                 .gpu_overlap = !is_zero(r[T_OVERLAP]),
                 .gpu_hostx = is_set(r[T_HOSTX]) && !is_zero(r[T_HOSTX]),
                 .gpu_ipc = !is_zero(r[T_IPC]),
                 .gpu_graph = !is_zero(r[T_GRAPH]),
                 .gpu_bedq = !is_set(r[T_BEDQ]) ? -1 : !is_zero(r[T_BEDQ]),
                 .gpu_spec = !is_zero(r[T_SPEC]),
                 .cuda_aware = !is_zero(r[T_CUDA_AWARE]),
                 .gpu_team_text = is_set(r[T_TEAM]) ? r[T_TEAM] : NULL,
                 .gpu_nbr_text = is_set(r[T_NBR]) ? r[T_NBR] : NULL,
                 .cpu_nbr = cpu_nbr_of(r[T_CPU_NBR]),
                 .cpu_nbr_text = is_set(r[T_CPU_NBR]) ? r[T_CPU_NBR] : NULL,
                 .skew_text = is_set(r[T_SKEW]) ? r[T_SKEW] : NULL};
    skew_of(r[T_SKEW], &t.skew_rank, &t.skew_factor);
    read = 1;
    return &t;
}

void tuning_log(void)
{
    tuning_get();
    char line[1024] = "";
    size_t used = 0;
    for (int k = 0; k < T_N; ++k)
        if (tuning_raw[k] && used + 100 < sizeof line)
            used += (size_t)snprintf(line + used, sizeof line - used, "%s%s=%.64s", used ? ", " : "",
                                     tuning_names[k], tuning_raw[k]);
    if (used) message("tuning: %s (README, \"Tuning and diagnostics settings\")", line);
}
