#!/usr/bin/env python3
"""Predicted parallel efficiency of sphseg's GPU slab decomposition on P GPUs
(1 to 512), from the halo the code sends and rates measured on 1 and 2 GPUs.

Per rank and step (docs/parallel.md, "Scaling model"), for the GPU path as
built (gpu/backend_gpu.cu: ghosts kept between list builds, refreshed at
every stage with device packing, staged through pinned host memory, and
overlapped with interior work):
  T_comp  = N_r / R                          R: one GPU's particle-steps/s
  ghosts  = sides * depth_planes * plane     a slab's faces: 2 (P - 1) / P on average;
                                             depth 3 cells of 2h = 9 dr at h = 1.5 dr
  bytes   = k_meas * ghosts * (2 rec + 2 * 8)   two refreshes of x, u, sigma, C (rec
                                             bytes each) and two of the shear rate
  T_copy  = 2 bytes / B_pcie                 device -> pinned host -> device, on the
                                             compute stream: exposed (0 with --cuda-aware)
  T_net   = bytes / B_net + msgs * lat       MPI; hidden behind interior work up to
  window  = f_window * T_comp                the interior flow and concentration rates
  T_ghost = f_ghost * ghosts / N_r * T_comp  stages that run on ghosts too (walls, L,
                                             coefficients, the list) and the split passes
  T_build = t_build * (N_r / n_build_ref) / n_build   the host exchange at a list build
                                             (measured seconds per n_build_ref particles),
                                             once per n_build steps:
  n_build = skin h / (2 v dt) - 2            the list is rebuilt once D + 2 d > skin/2
                                             (gpu/backend_gpu.cu), D the largest
                                             displacement since the build, d = v dt
                                             the last step's; --n-build overrides it
  R(skin) = R(0.1) * L(0.1) / L(skin)        a step reads every list entry: its cost
                                             follows the list length L ~ (2 + skin)^dim
  T_red   = 4 log2(P) lat                    the step's small allreduces
  T_halo  = T_copy + max(0, T_net - window) + T_ghost + T_build + T_red
  weak    E_w(P) = T_comp / (T_comp + T_halo)   (N_r fixed; one GPU has no halo)
  strong  E_s(P) = T(1) / (P T(P))              (N fixed; slabs >= 3 cells thick)
--no-overlap: window = 0 (SPHSEG_GPU_OVERLAP=0).

Defaults are the measurements of docs/parallel.md (two H200 of one host, 3D
drum at dr = 0.25 mm): R = 9.1e7, 27 100 particles per dr plane, 225 B per
ghost and step sent (k_meas = 1.0), B_pcie = 38 GB/s and B_net = 3.8 GB/s
(intra-node MPI through host memory) from the exposed halo time with and
without overlap, t_build = 1.5 s per 1.1e7 particles. --b-net 25e9 --lat 3e-6
model an InfiniBand cluster (assumed, not measured here).

  /usr/bin/python3 tools/scaling_model.py [--check] [--check-skin] [--check-device] [--b-net 25e9]
      [--png docs/parallel_model.png]
  (fast settings, list-build exchange through the host: --dt 2.504e-5 --rate 3.077e8 --t-build 0.94;
   on the device, gpu/gpu_exchange.cuh: --dt 2.504e-5 --rate 3.04e8 --t-build 0.029)
"""
import argparse
import math


def list_len(skin, dim=3):
    """Relative length of a neighbour list reaching 2h + skin h."""
    return (2.0 + skin) ** dim


def n_build(a):
    """Steps between list builds: the skin over twice a step's largest displacement v dt, less 2."""
    if a.n_build is not None:
        return a.n_build
    return max(1.0, a.skin * a.h / (2 * a.v_max * a.dt) - 2)


def rate_at(a):
    """One GPU's rate at Run:list_skin a.skin, from its measured rate at a.rate_skin."""
    return a.rate * list_len(a.rate_skin) / list_len(a.skin)


def halo_terms(a, P, n_r):
    sides = 2 * (P - 1) / P
    ghosts = sides * a.depth_planes * a.plane
    nbytes = a.k_meas * ghosts * (2 * a.record + 2 * 8)
    tc = n_r / rate_at(a)
    t_copy = 0.0 if a.cuda_aware else 2 * nbytes / a.b_pcie
    t_net = nbytes / a.b_net + sides * 4 * a.lat
    window = 0.0 if a.no_overlap else a.f_window * tc
    t_ghost = a.f_ghost * ghosts / n_r * tc
    t_build = a.t_build * n_r / a.n_build_ref / n_build(a) if P > 1 else 0.0
    t_red = 4 * math.log2(max(P, 1)) * a.lat
    th = t_copy + max(0.0, t_net - window) + t_ghost + t_build + t_red
    return tc, th, nbytes


def weak(a, P):
    if P == 1:
        return 1.0, 0.0, 0.0
    tc, th, nb = halo_terms(a, P, a.per_gpu)
    return tc / (tc + th), th / (tc + th), nb


def strong(a, N, P):
    n_r = N / P
    if P > 1 and n_r / a.plane < a.depth_planes:
        return math.nan, math.nan  # slabs thinner than the ghost depth: not allowed
    t1 = N / rate_at(a)
    if P == 1:
        return 1.0, 0.0
    tc, th, _ = halo_terms(a, P, n_r)
    return t1 / (P * (tc + th)), th / (tc + th)


# 3D drum, 1.12e7 particles, fast settings (dt 2.504e-5 s), single build, 200 steps, 2 H200:
# skin -> (list builds in 200 steps, 1-GPU rate, 2-GPU strong rate, exposed halo s on 2 GPUs)
SKIN_RUNS = {0.1: (12, 3.0770e8, 2.2768e8, 5.617), 0.25: (5, 2.3854e8, 2.9961e8, 2.320),
             0.5: (2, 1.7164e8, 2.9386e8, 0.726), 1.0: (1, 1.1584e8, 2.1475e8, 0.233)}


def check_skin(a):
    """The model's list builds and rates against the skin runs (docs/parallel_data/skin_h200x2.txt)."""
    N, steps = 1.1236e7, 200
    a.dt, a.rate, a.rate_skin, a.n_build = 2.504e-5, 3.077e8, 0.1, None
    a.t_build = 0.47 * 2  # exposed seconds per list build at N/2 a rank (5.62 s / 12), per 1.1e7 particles
    print("| skin | builds in 200 steps: model, measured | 1-GPU rate: model, measured | "
          "2-GPU strong E_s vs 1 GPU at 0.1: model, measured |")
    print("|---:|---|---|---|")
    for skin, (nb, r1, r2, _) in SKIN_RUNS.items():
        a.skin = skin
        nbm = 1 + math.floor(steps / n_build(a))  # the first build, then one per n_build steps
        t1 = N / a.rate  # one GPU at the best skin measured (0.1)
        tc, th, _ = halo_terms(a, 2, N / 2)
        print("| %.2g | %d, %d | %.3g, %.3g | %.2f, %.2f |" % (
            skin, nbm, nb, rate_at(a), r1, t1 / (2 * (tc + th)), r2 / (2 * a.rate)))


# The exchange at a list build on the device (gpu/gpu_exchange.cuh), two H200, 3D drum at dr 0.25 mm, single,
# skin 0.1, 200 steps (docs/parallel_data/device_exchange_h200x2.txt): settings -> (dt, 1-GPU rate, seconds per
# build exchange at 1.1e7 a rank, measured weak E_w, measured strong E_s at 1.12e7, or None)
DEVICE_RUNS = {"fast": (2.504e-5, 3.0416e8, 0.345 / 12, 0.923, 0.868),
               "Table 1": (3.958e-7, 3.2199e8, 0.082, 0.937, None)}


def check_device(a):
    """The model, with the device exchange's measured cost per build, against the 2-GPU runs at both
    settings: the builds' frequency from dt and the flow speed (n_build), their cost from t_build."""
    print("| settings | steps between builds (model) | weak E_w: model, measured | strong E_s (1.12e7): model, measured |")
    print("|---|---:|---|---|")
    for name, (dt, rate, tb, ew, es) in DEVICE_RUNS.items():
        a.dt, a.rate, a.rate_skin, a.skin, a.n_build, a.t_build, a.n_build_ref = dt, rate, 0.1, 0.1, None, tb, 1.1e7
        a.per_gpu = 1.1e7
        mw = weak(a, 2)[0]
        ms = strong(a, 1.1236e7, 2)[0]
        print("| %s | %.0f | %.3f, %.3f | %.3f, %s |" % (name, n_build(a), mw, ew, ms, "%.3f" % es if es else "—"))


def plot_skin(a, png):
    """Measured rates against the skin on 1 and 2 GPUs, beside the model (check_skin's settings)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    N = 1.1236e7
    a.dt, a.rate, a.rate_skin, a.n_build, a.t_build = 2.504e-5, 3.077e8, 0.1, None, 0.94
    sk = sorted(SKIN_RUNS)
    fine = [0.05 + 0.01 * k for k in range(100)]
    m1, m2 = [], []
    for x in fine:
        a.skin = x
        tc, th, _ = halo_terms(a, 2, N / 2)
        m1.append(rate_at(a))
        m2.append(N / (tc + th))
    fig, ax = plt.subplots(figsize=(6.5, 4))
    ax.plot(sk, [SKIN_RUNS[x][1] for x in sk], "o", color="C0", label="1 GPU, measured")
    ax.plot(sk, [SKIN_RUNS[x][2] for x in sk], "s", color="C1", label="2 GPUs (strong), measured")
    ax.plot(fine, m1, "-", color="C0", lw=1, label="1 GPU, model: list length (2 + skin)^3")
    ax.plot(fine, m2, "--", color="C1", lw=1, label="2 GPUs, model: + host exchange per list build")
    for x in sk:
        ax.annotate("%d builds" % SKIN_RUNS[x][0], (x, SKIN_RUNS[x][2]), textcoords="offset points",
                    xytext=(4, 6), fontsize=7)
    ax.set_xlabel("Run:list_skin (units of h)")
    ax.set_ylabel("particle-steps/s")
    ax.set_title("3D drum, 1.12e7 particles, fast settings, single build, 200 steps, 2 H200", fontsize=9)
    ax.set_ylim(0, 3.6e8)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    print("wrote " + png)


def model_for(settings, **over):
    """The model's parameters (the defaults) at a named set of settings of the job scripts
    (jobs/common.sh: "scene", Table 1's in the drum; "fast"), with the device exchange's
    measured build cost (DEVICE_RUNS); over: any parameter by name."""
    a = parser().parse_args([])
    dt, rate, tb, _, _ = DEVICE_RUNS["fast" if settings == "fast" else "Table 1"]
    a.dt, a.rate, a.t_build = dt, rate, tb
    for k, v in over.items():
        setattr(a, k, v)
    return a


def parser():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rate", type=float, default=9.1e7,
                    help="one GPU's particle-steps/s (default: 3D drum, 1.1e7 particles, H200, measured, final code)")
    ap.add_argument("--plane", type=float, default=27100,
                    help="particles per dr-thick plane of the slab's cross-section (default: the 3D drum of "
                         "R = 35 mm, fill 0.42, at dr = 0.25 mm; measured: 244 143 ghosts in 9 planes)")
    ap.add_argument("--depth-planes", type=float, default=9, help="ghost depth in dr planes (3 cells of 2h = 9 dr)")
    ap.add_argument("--record", type=float, default=104,
                    help="bytes of one ghost refresh (x, u: 3 reals each, sigma: 6, C: 1; backend_gpu.cu moving_fields)")
    ap.add_argument("--k-meas", type=float, default=1.0,
                    help="measured / counted bytes (54.92 MB per rank and step measured, 54.7 counted)")
    ap.add_argument("--b-net", type=float, default=3.8e9,
                    help="MPI bandwidth per direction, B/s (default: measured between two ranks of one host "
                         "through host memory; an InfiniBand NDR/HDR cluster: 25e9, assumed)")
    ap.add_argument("--b-pcie", type=float, default=38e9, help="device<->pinned host copy bandwidth, B/s (measured)")
    ap.add_argument("--lat", type=float, default=3e-6, help="MPI message latency, s (assumed)")
    ap.add_argument("--f-window", type=float, default=0.48,
                    help="share of a step's compute the refreshes overlap (the flow rates: 48 %% of the step, "
                         "docs/gpu.md profile)")
    ap.add_argument("--f-ghost", type=float, default=1.0,
                    help="cost of a ghost in units of an owned particle's step (fitted to the 2-GPU runs)")
    ap.add_argument("--t-build", type=float, default=1.5, help="host exchange at a list build, s (measured)")
    ap.add_argument("--n-build-ref", type=float, default=1.1e7, help="particles per rank of --t-build")
    ap.add_argument("--n-build", type=float, default=None,
                    help="steps between list builds; default from --skin, --h, --v-max, --dt")
    ap.add_argument("--skin", type=float, default=0.1, help="Run:list_skin, in units of h (default 0.1)")
    ap.add_argument("--rate-skin", type=float, default=0.1, help="the skin at which --rate was measured")
    ap.add_argument("--h", type=float, default=3.75e-4, help="smoothing length, m (3D drum at dr = 0.25 mm)")
    ap.add_argument("--dt", type=float, default=3.958e-7,
                    help="time step, s (default: Table 1, E 10 MPa, chi 0.1: about 1 280 steps between builds; "
                         "the fast settings E 10 kPa, chi 0.2: 2.504e-5, docs/gpu.md)")
    ap.add_argument("--v-max", type=float, default=0.037,
                    help="largest particle speed, m/s (default: from the measured build interval, 18.2 steps at "
                         "skin 0.1 and dt 2.504e-5 s: docs/parallel_data/skin_h200x2.txt)")
    ap.add_argument("--check-device", action="store_true",
                    help="compare with the 2-GPU runs whose list-build exchange runs on the device (both settings) "
                         "and exit")
    ap.add_argument("--check-skin", action="store_true",
                    help="compare with the measured skin runs (1 and 2 H200, fast settings) and exit")
    ap.add_argument("--per-gpu", type=float, default=1.1e7, help="particles per GPU, weak scaling")
    ap.add_argument("--strong", type=float, nargs="+", default=[2e7, 1e8], help="total particles, strong")
    ap.add_argument("--no-overlap", action="store_true", help="refreshes not overlapped (SPHSEG_GPU_OVERLAP=0)")
    ap.add_argument("--cuda-aware", action="store_true", help="no host staging (CUDA-aware MPI, GPUDirect)")
    ap.add_argument("--check", action="store_true",
                    help="compare with the measured 2-GPU runs (docs/parallel.md) and exit")
    ap.add_argument("--png", default=None, help="chart to write")
    ap.add_argument("--skin-png", default=None, help="chart of the skin runs beside the model, to write")
    return ap


def main():
    a = parser().parse_args()
    if a.check_device:
        check_device(a)
        return
    if a.check_skin or a.skin_png:
        if a.check_skin:
            check_skin(a)
        if a.skin_png:
            plot_skin(a, a.skin_png)
        return
    if a.check:  # the model at the measured points, build term off (no list build inside the timed steps)
        a.n_build = math.inf
        rate = a.rate
        a.rate = 7.7e7  # commit df38609, before the early loads (docs/parallel.md)
        for label, no_ov, meas in (("weak, overlap", False, 0.950), ("weak, no overlap", True, 0.885)):
            a.no_overlap = no_ov
            e, h, nb = weak(a, 2)
            print("R = %.2g %-17s P = 2: model E_w %.3f (halo share %.3f, %.1f MB/step), measured %.3f" % (
                a.rate, label, e, h, nb / 1e6, meas))
        a.no_overlap = False
        print("R = %.2g %-17s P = 2: model E_s %.3f, measured %.3f" % (a.rate, "strong 2e7", strong(a, 1.99e7, 2)[0], 0.954))
        a.rate = rate  # the final code
        print("R = %.2g %-17s P = 2: model E_w %.3f, measured %.3f" % (a.rate, "weak, overlap", weak(a, 2)[0], 0.947))
        print("R = %.2g %-17s P = 2: model E_s %.3f, measured %.3f" % (a.rate, "strong 2e7", strong(a, 1.99e7, 2)[0], 0.945))
        return
    Ps = [1, 2, 4, 8, 16, 32, 64, 128, 256, 512]
    print("| P | weak E_w | weak halo share | MB/rank/step | " +
          " | ".join("strong E_s (N=%.0e) | halo share" % n for n in a.strong) + " |")
    print("|---:" * (4 + 2 * len(a.strong)) + "|")
    res = {"weak": [], **{n: [] for n in a.strong}}
    for P in Ps:
        ew, hw, nb = weak(a, P)
        res["weak"].append(ew)
        cells = ["%d" % P, "%.3f" % ew, "%.3f" % hw, "%.1f" % (nb / 1e6)]
        for n in a.strong:
            es, hs = strong(a, n, P)
            res[n].append(es)
            cells += ["%.3f" % es if es == es else "—", "%.3f" % hs if hs == hs else "—"]
        print("| " + " | ".join(cells) + " |")
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(6.5, 4))
        ax.plot(Ps, res["weak"], "o-", label="weak, %.1e particles/GPU" % a.per_gpu)
        for n in a.strong:
            ax.plot(Ps, res[n], "s--", label="strong, %.0e particles" % n)
        ax.plot([2, 2], [0.947, 0.945], "k*", ms=9, label="measured, 2 H200 (weak, strong 2e7)")
        ax.axhline(0.9, color="0.6", lw=0.8, ls=":")
        ax.set_xscale("log", base=2)
        ax.set_xticks(Ps)
        ax.set_xticklabels([str(p) for p in Ps])
        ax.set_ylim(0, 1.05)
        ax.set_xlabel("GPUs P")
        ax.set_ylabel("predicted parallel efficiency")
        ax.set_title("GPU slab model: R = %.2g p-s/s, net %.1f GB/s, PCIe %.0f GB/s%s" % (
            a.rate, a.b_net / 1e9, a.b_pcie / 1e9, ", no overlap" if a.no_overlap else ""), fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(a.png, dpi=120)
        print("\nwrote " + a.png)


if __name__ == "__main__":
    main()
