#!/usr/bin/env python3
"""Predicted parallel efficiency of sphseg's slab decomposition on P GPUs
(1 to 512), from the halo volume the code sends and the machine's rates.

Per rank and step (docs/parallel.md, "Scaling model"):
  T_comp = N_r / R                                  R: one GPU's particle-steps/s
  ghosts = sides * depth_planes * plane             a slab's faces: 2 (P - 1) / P on average
                                                    (the end slabs have one);
                                                    depth 4h = 6 dr at h = 1.5 dr
  bytes  = k_meas * ghosts * (2 * rec + 2 * 8)      two ghost builds per step (predictor,
                                                    corrector) of rec bytes, two γ̇
                                                    refreshes; k_meas: measured / counted
  T_halo = bytes / B_net + 2 * bytes / B_pcie       MPI transfer, device<->pinned-host
           + msgs * lat + 4 * log2(P) * lat         staging; point-to-point and the four
                                                    small allreduces of a step (dt bounds,
                                                    lattice origin)
  weak    E_w(P) = T_comp / (T_comp + T_halo)       (N_r fixed; one GPU has no halo)
  strong  E_s(P) = T(1) / (P T(P))                  (N fixed; slabs >= depth_planes thick)
No overlap of halo and interior work is assumed (the code does not overlap yet).

  /usr/bin/python3 tools/scaling_model.py [--rate 9.9e7] [--png docs/parallel_model.png]
"""
import argparse
import math


def halo_time(a, P, sides):
    ghosts = sides * a.depth_planes * a.plane
    nbytes = a.k_meas * ghosts * (2 * a.record + 2 * 8)
    msgs = sides * 2 * 4  # per side: 2 ghost builds + 2 refreshes, each a count and a data message
    t = nbytes / a.bw_net + 2 * nbytes / a.bw_pcie + msgs * a.latency
    return t + 4 * math.log2(max(P, 1)) * a.latency, nbytes


def weak(a, P):
    tc = a.per_gpu / a.rate
    th, nb = halo_time(a, P, 2 * (P - 1) / P)
    return tc / (tc + th), th / (tc + th), nb


def strong(a, N, P):
    nr = N / P
    if P > 1 and nr / a.plane < a.depth_planes:
        return math.nan, math.nan  # slabs thinner than the ghost depth: not allowed
    t1 = N / a.rate
    th, _ = halo_time(a, P, 2 * (P - 1) / P)
    tp = nr / a.rate + th
    return t1 / (P * tp), th / tp


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rate", type=float, default=9.9e7,
                    help="one GPU's particle-steps/s (default: 3D drum, 9.3e5 particles, H100, measured)")
    ap.add_argument("--plane", type=float, default=28500,
                    help="particles per dr-thick plane of the slab's cross-section (default: the 3D drum of "
                         "R = 35 mm, fill 0.42, at dr = 0.25 mm: 25 900 material + 2 600 ring dummies)")
    ap.add_argument("--depth-planes", type=float, default=6, help="ghost depth in planes (4h/dr = 6)")
    ap.add_argument("--record", type=float, default=186,
                    help="bytes of one ghost (the drum's ghost arrays, src/main.c parallel_ghost_arrays)")
    ap.add_argument("--k-meas", type=float, default=1.15,
                    help="measured bytes / counted bytes (CPU weak sweep, docs/parallel.md)")
    ap.add_argument("--bw-net", type=float, default=25e9, help="MPI bandwidth per direction, B/s (assumed)")
    ap.add_argument("--bw-pcie", type=float, default=25e9, help="device-host copy bandwidth, B/s (assumed)")
    ap.add_argument("--latency", type=float, default=3e-6, help="MPI message latency, s (assumed)")
    ap.add_argument("--per-gpu", type=float, default=1e7, help="particles per GPU, weak scaling")
    ap.add_argument("--strong", type=float, nargs="+", default=[2e7, 1e8], help="total particles, strong")
    ap.add_argument("--png", default=None, help="chart to write")
    a = ap.parse_args()
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
        ax.plot(Ps, res["weak"], "o-", label="weak, %.0e particles/GPU" % a.per_gpu)
        for n in a.strong:
            ax.plot(Ps, res[n], "s--", label="strong, %.0e particles" % n)
        ax.axhline(0.9, color="0.6", lw=0.8, ls=":")
        ax.set_xscale("log", base=2)
        ax.set_xticks(Ps)
        ax.set_xticklabels([str(p) for p in Ps])
        ax.set_ylim(0, 1.05)
        ax.set_xlabel("GPUs P")
        ax.set_ylabel("predicted parallel efficiency")
        ax.set_title("slab model: R = %.2g p-s/s, %.0f B/ghost, net %.0f GB/s" % (a.rate, a.record, a.bw_net / 1e9),
                     fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(a.png, dpi=120)
        print("\nwrote " + a.png)


if __name__ == "__main__":
    main()
