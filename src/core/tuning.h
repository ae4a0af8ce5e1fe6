/* core/tuning.h — the tuning and diagnostics settings: the only environment
 * variables sphseg reads (README, "Tuning and diagnostics settings"). None
 * changes the answer beyond round-off; each exists to measure a saving, to
 * diagnose, or (SPHSEG_BALANCE_SKEW) to exercise a code path. They are read
 * here, once, at the first tuning_get (nowhere else: `grep -rn getenv src
 * mpi gpu` finds this file only), and tuning_log names those that are set. */
#ifndef SPHSEG_TUNING_H
#define SPHSEG_TUNING_H

typedef struct tuning {
    int gpu_profile;  /* SPHSEG_GPU_PROFILE set and not 0: time each GPU stage (default 0) */
    int gpu_team;     /* SPHSEG_GPU_TEAM: threads per particle 1, 2, 4, 8 or 16; 0: the rule (default);
                       * -1: set to something else (gpu_team_text; the GPU backend refuses it) */
    int gpu_nbr;      /* SPHSEG_GPU_NBR: the GPU's neighbour pass, 0 list, 1 list16, 2 cells, 4 tile (list16 with
                       * the flow pass staged in shared memory) (unset: by memory, gpu_setup.cu)
                       * (src/physics/grid.h GRID_NBR_*); -1: set to something else (the GPU backend refuses it) */
    int gpu_wallskip; /* SPHSEG_GPU_WALLSKIP not 0: dummies out of reach skip their wall loop (default 1) */
    int gpu_overlap;  /* SPHSEG_GPU_OVERLAP not 0: ghost refreshes overlap interior work (default 1) */
    int gpu_hostx;    /* SPHSEG_GPU_HOSTX set and not 0: list-build exchanges through the host (default 0) */
    int gpu_ipc;      /* SPHSEG_GPU_IPC not 0: CUDA IPC between the GPUs of one node (default 1) */
    int gpu_graph;    /* SPHSEG_GPU_GRAPH not 0: a step between list builds on one rank is replayed as a CUDA
                       * graph (gpu/gpu_graph.cu; default 1) */
    int gpu_bedq;     /* SPHSEG_GPU_BEDQ: the bed damping's weight once a particle before the flow pass (1) or per
                       * pair (0); -1 (unset): by the store's size (gpu/gpu_pairs.cu gpu_bed_q) */
    int gpu_spec;     /* SPHSEG_GPU_SPEC not 0: the flow pass specialised to the run's flow where one fits
                       * (gpu/gpu_pairs.cu gpu_flow_spec; default 1); 0: the general kernel, the same bits */
    int cuda_aware;   /* SPHSEG_CUDA_AWARE not 0: device buffers to MPI where it reports CUDA support (default 1) */
    int skew_rank;    /* SPHSEG_BALANCE_SKEW=R:F: the load balance counts rank R's compute time F times (the
                       * cut moves, the answer does not beyond round-off); -1: not set (default); -2: set to
                       * something else (skew_text; settings_check refuses it) */
    double skew_factor;
    int cpu_nbr;      /* SPHSEG_CPU_NBR: the CPU's neighbour pass, 0 list (or unset: the list where it fits in
                       * half the free memory, src/cpu/nlist.c), 2 cells; -1: set to something else (refused) */
    const char *skew_text; /* SPHSEG_BALANCE_SKEW as set, or NULL */
    const char *gpu_team_text; /* SPHSEG_GPU_TEAM as set, or NULL */
    const char *gpu_nbr_text;  /* SPHSEG_GPU_NBR as set, or NULL */
    const char *cpu_nbr_text;  /* SPHSEG_CPU_NBR as set, or NULL */
} tuning;

/* The settings, read from the environment at the first call. */
const tuning *tuning_get(void);
/* One log line (rank 0) naming the settings that are set, if any. */
void tuning_log(void);

#endif
