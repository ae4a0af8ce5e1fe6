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
                                             once per n_build steps in a flowing drum
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

  /usr/bin/python3 tools/scaling_model.py [--check] [--b-net 25e9] [--png docs/parallel_model.png]
"""
import argparse
import math


def halo_terms(a, P, n_r):
    sides = 2 * (P - 1) / P
    ghosts = sides * a.depth_planes * a.plane
    nbytes = a.k_meas * ghosts * (2 * a.record + 2 * 8)
    tc = n_r / a.rate
    t_copy = 0.0 if a.cuda_aware else 2 * nbytes / a.b_pcie
    t_net = nbytes / a.b_net + sides * 4 * a.lat
    window = 0.0 if a.no_overlap else a.f_window * tc
    t_ghost = a.f_ghost * ghosts / n_r * tc
    t_build = a.t_build * n_r / a.n_build_ref / a.n_build if P > 1 else 0.0
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
    t1 = N / a.rate
    if P == 1:
        return 1.0, 0.0
    tc, th, _ = halo_terms(a, P, n_r)
    return t1 / (P * (tc + th)), th / (tc + th)


def main():
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
    ap.add_argument("--n-build", type=float, default=1000,
                    help="steps between list builds (flowing drum, docs/gpu.md)")
    ap.add_argument("--per-gpu", type=float, default=1.1e7, help="particles per GPU, weak scaling")
    ap.add_argument("--strong", type=float, nargs="+", default=[2e7, 1e8], help="total particles, strong")
    ap.add_argument("--no-overlap", action="store_true", help="refreshes not overlapped (SPHSEG_GPU_OVERLAP=0)")
    ap.add_argument("--cuda-aware", action="store_true", help="no host staging (CUDA-aware MPI, GPUDirect)")
    ap.add_argument("--check", action="store_true",
                    help="compare with the measured 2-GPU runs (docs/parallel.md) and exit")
    ap.add_argument("--png", default=None, help="chart to write")
    a = ap.parse_args()
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
