#!/usr/bin/env python3
"""Predicted parallel efficiency of sphseg's GPU slab decomposition on P GPUs
(1 to 512), from the halo the code sends, rates measured on 1 and 2 GPUs and a
few parameters fitted to the 2-GPU runs (docs/parallel.md, "Scaling model").

Per step on the slowest rank (gpu/backend_gpu.cu: ghosts kept between list
builds, refreshed with device packing and overlapped with interior work;
gpu/gpu_exchange.cu: the exchange at a list build on the device;
gpu/gpu_ipc.cu: CUDA IPC between the GPUs of one node):
  faces     a slab has two neighbours: P = 2 one face; 2 < P <= G (--gpus-per-node)
            two faces inside the node; P > G the slowest rank has one face inside
            the node and one to the next node
  ghosts_f  = depth_planes * plane            per face (3 cells of 2h = 9 dr planes)
  T_comp    = N_r / R                         R: one GPU's particle-steps/s
  bytes_f   = ghosts_f * bytes_ghost          what a face's refreshes send a step:
                                              2 refreshes of x, v, sigma (12 reals:
                                              48 B single, 96 B double; the single
                                              build's position remainder xr is not
                                              sent) + the Shepard store's sigma every
                                              30 steps
  copies    = s_copy * 2 bytes_f / B_pcie     staged faces only (device -> pinned host
                                              -> device): the exposed share s_copy
  T_xfer    = bytes_f / B_face                B_face: B_shm (staged, MPI through host
                                              memory), B_d2d (CUDA IPC over NVLink),
                                              B_net (to another node); the faces in
                                              parallel, hidden behind
  window    = f_window * T_comp               the interior flow rates
  T_refresh = sum(copies) + max(0, max(T_xfer) - window)
  T_ghost   = f_ghost * ghosts / R            the stages that also run on ghosts
  t_build   = f_build * T_comp                one exchange at a list build: the
              + sum(2 rec_b ghosts_f / B_pcie) device work on the rank's store,
              + max(rec_b ghosts_f / B_face)   the staging copies (not hidden), the
              + t_sync                         transfer of the new ghosts (rec_b bytes
                                               each: 115 single, 211 double) and the
                                               fixed synchronisations
  n_build   = skin h / (2 v dt) - 2           steps between builds: a list is rebuilt
                                              once D + 2 d > skin/2 (D the largest
                                              displacement since the build, d = v dt)
  R(skin)   = R(s0) * L(s0) / L(skin)         the list length L ~ (2 + skin)^3
  T_red     = 4 log2(P) lat                   the step's small allreduces
  T_halo    = T_refresh + T_ghost + t_build / n_build + T_red
  weak      E_w(P) = T_comp / (T_comp + T_halo)       (N_r fixed)
  strong    E_s(P) = T(1) / (P T(P))                  (N fixed; slabs >= 9 planes)

Fitted (FIT, worked out at import from MEASURED by fit()): f_build, B_shm and t_sync
to the logged seconds of the build exchanges of four single-build fast runs (staged
and IPC, weak and strong); s_copy and f_ghost to the efficiencies of two of them
(staged weak, IPC weak). Measured elsewhere: B_pcie 38 GB/s, f_window 0.48
(docs/gpu.md profile), the ghost count (244 143 in 9 planes), R (each run's 1-GPU
rate). Assumed, not measured here: B_d2d 100 GB/s (NVLink, NV18: 450 GB/s nominal
per direction), B_net 25 GB/s between nodes (InfiniBand HDR200/NDR), lat 3 us.
--check-device prints the model against every 2-GPU run, fitted and out of sample.

  /usr/bin/python3 -m tools.bench.scaling_model --check-device
  /usr/bin/python3 -m tools.bench.scaling_model --settings fast|table1 [--precision single|double]
      [--intra ipc|staged] [--gpus-per-node 8] [--b-net 25e9] [--cuda-aware] [--png docs/data/parallel/parallel_model.png]
  /usr/bin/python3 -m tools.bench.scaling_model [--check] [--check-skin] [--skin-png PNG]
"""
import argparse
import math

# ---- what the code sends (gpu/gpu_halo.cu, src/sim/stages.c, src/core/fields.h) ----------------------------------
# The drum runs with concentration windows (Segregation:every auto), so a refresh when the particles moved carries
# stage_moving_fields = x, v, sig (tests/test_stages.c): 3 + 3 + 6 reals. Two such refreshes a step (two prepares),
# and sig (6 reals) after the Shepard store every Flow:shepard_every = 30 steps; the windows' C and gsum once a
# window (left out: under 1 %). A ghost made at a build carries stage_ghost_fields = x, v, vol, C (double), gsum,
# nrm, psi, sig, L, id (int64), kind, bclass, wall (uint8): 24 reals + 16 + 3 bytes. xr (the single build's
# position remainder) is in neither list: only migrants carry it (all arrays).
REAL = {"single": 4, "double": 8}


def bytes_per_ghost(precision, shepard_every=30):
    es = REAL[precision]
    return 2 * 12 * es + 6 * es / shepard_every


def build_record(precision):
    return 24 * REAL[precision] + 16 + 3


# ---- the measured 2-GPU runs -------------------------------------------------------------------------------------
# Two NVIDIA H200 of one host (NV18), Open MPI 4.1.6 (not CUDA-aware), 3D drum at dr 0.25 mm, 200 steps, one rank per
# GPU, the exchange at a list build on the device. Strong: 11 236 258 particles (length 0.1 m); weak: 22 087 058 on
# two GPUs (0.2 m). Each row: the 1-GPU rate of the same call (R1), the 2-GPU rate (R2), list builds, seconds of
# the build exchanges and of exposed halo (rank 0's log line), the stepping wall, and the role in the fit:
# "fit" (efficiency and build time fitted), "build" (build time fitted, efficiency out of sample), "check".
DX, IPC, IPC2 = ("docs/data/parallel/device_exchange_h200x2.txt", "docs/data/parallel/ipc_h200x2.txt",
                 "docs/data/parallel/ipc_h200x2_run2.txt")
MEASURED = [
    # key, settings, precision, transport, mode, skin, R1, R2, builds, build_s, exposed_s, wall_s, role, file
    ("fast single staged weak", "fast", "single", "staged", "weak", 0.1, 3.0416e8, 5.6126e8, 12, 0.345, 0.602, 8.302, "fit", DX),
    ("fast single staged strong", "fast", "single", "staged", "strong", 0.1, 3.0416e8, 5.2764e8, 12, 0.233, 0.494, 4.443, "build", DX),
    ("fast single staged weak (rerun)", "fast", "single", "staged", "weak", 0.1, 3.0555e8, 5.6025e8, 12, 0.348, 0.606, 8.377, "check", IPC),
    ("fast single IPC weak", "fast", "single", "ipc", "weak", 0.1, 3.0555e8, 5.8083e8, 12, 0.261, 0.239, 7.989, "fit", IPC),
    ("fast single IPC strong", "fast", "single", "ipc", "strong", 0.1, 3.0555e8, 5.6135e8, 12, 0.158, 0.146, 4.241, "build", IPC),
    ("fast single IPC strong (run 2)", "fast", "single", "ipc", "strong", 0.1, 3.0486e8, 5.6116e8, 12, 0.152, 0.145, 4.219, "check", IPC2),
    ("fast double staged weak", "fast", "double", "staged", "weak", 0.1, 1.9993e8, 3.6874e8, 12, 0.511, 1.006, 12.472, "check", DX),
    ("fast double staged strong", "fast", "double", "staged", "strong", 0.1, 1.9993e8, 3.4559e8, 12, 0.351, 0.856, 6.733, "check", DX),
    ("fast double IPC weak", "fast", "double", "ipc", "weak", 0.1, 1.9986e8, 3.8576e8, 12, 0.367, 0.356, 11.977, "check", IPC),
    ("fast double IPC strong (run 2)", "fast", "double", "ipc", "strong", 0.1, 1.9788e8, 3.7070e8, 12, 0.210, 0.218, 6.408, "check", IPC2),
    ("Table 1 single staged weak", "table1", "single", "staged", "weak", 0.1, 3.2199e8, 6.0332e8, 1, 0.082, 0.250, 7.669, "check", DX),
    ("fast single staged weak, skin 0.25", "fast", "single", "staged", "weak", 0.25, 2.3555e8, 4.4299e8, 5, 0.199, 0.397, 10.349, "check", DX),
    ("fast single staged strong, skin 0.25", "fast", "single", "staged", "strong", 0.25, 2.3555e8, 4.2123e8, 5, 0.144, 0.359, 5.521, "check", DX),
]
N_STRONG, N_WEAK2, STEPS = 11236258, 22087058, 200
DT = {"fast": 2.504e-5, "table1": 3.958e-7}  # docs/gpu.md: E 10 kPa, chi 0.2 / Table 1, E 10 MPa, chi 0.1
RATE = {("fast", "single"): 3.0555e8, ("fast", "double"): 1.9986e8,  # 1 GPU, ipc_h200x2.txt
        ("table1", "single"): 3.2199e8, ("table1", "double"): None}  # device_exchange_h200x2.txt; double not run


def measured_eff(m):
    """The run's efficiency: weak (R2/2)/R1, strong R2/(2 R1) (the same particles on 1 and 2 GPUs)."""
    return m[7] / (2 * m[6])


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


def faces(a, P):
    """The slowest rank's faces and how each goes: 'ipc', 'staged' (intra-node MPI through host memory) or 'net'."""
    if P <= 1:
        return []
    intra = a.intra if a.gpus_per_node > 1 else "net"
    if P == 2:
        return [intra] if a.gpus_per_node >= 2 else ["net"]
    if P <= a.gpus_per_node:
        return [intra, intra]
    return [intra, "net"] if a.gpus_per_node > 1 else ["net", "net"]


def face_bw(a, f):
    return {"ipc": a.b_d2d, "staged": a.b_shm, "net": a.b_net}[f]


def staged(a, f):
    """A face whose bytes go through pinned host memory (not IPC, not a CUDA-aware network)."""
    return f == "staged" or (f == "net" and not a.cuda_aware)


def build_time(a, P, n_r, tc=None):
    """Seconds of one exchange at a list build on the slowest rank (the device exchange); --t-build: a measured
    host exchange instead, seconds per --n-build-ref particles."""
    if P <= 1:
        return 0.0
    if a.t_build is not None:
        return a.t_build * n_r / a.n_build_ref
    tc = n_r / rate_at(a) if tc is None else tc
    fs = faces(a, P)
    gb = a.depth_planes * a.plane * a.record_build
    copies = sum(2 * gb / a.b_pcie for f in fs if staged(a, f))
    xfer = max(gb / face_bw(a, f) + (a.lat if f != "ipc" else 0.0) for f in fs)
    return a.f_build * tc + copies + xfer + a.t_sync


def halo_terms(a, P, n_r):
    """(T_comp, T_halo, bytes a step) of the slowest rank, and its parts."""
    tc = n_r / rate_at(a)
    fs = faces(a, P)
    gf = a.depth_planes * a.plane
    bf = gf * a.bytes_ghost
    parts = dict(copies=0.0, exposed_xfer=0.0, ghost=0.0, build=0.0, red=0.0)
    if fs:
        parts["copies"] = sum(a.s_copy * 2 * bf / a.b_pcie for f in fs if staged(a, f))
        window = 0.0 if a.no_overlap else a.f_window * tc
        xfer = max(bf / face_bw(a, f) + (4 * a.lat if f != "ipc" else 0.0) for f in fs)
        parts["exposed_xfer"] = max(0.0, xfer - window)
        parts["ghost"] = a.f_ghost * gf * len(fs) / rate_at(a)
        parts["build"] = build_time(a, P, n_r, tc) / n_build(a)
        parts["red"] = 4 * math.log2(P) * a.lat
    th = sum(parts.values())
    return tc, th, bf * len(fs), parts


def weak(a, P):
    if P == 1:
        return 1.0, 0.0, 0.0
    tc, th, nb, _ = halo_terms(a, P, a.per_gpu)
    return tc / (tc + th), th / (tc + th), nb


def strong(a, N, P):
    n_r = N / P
    if P > 1 and n_r / a.plane < a.depth_planes:
        return math.nan, math.nan  # slabs thinner than the ghost depth: not allowed
    if P == 1:
        return 1.0, 0.0
    tc, th, _, _ = halo_terms(a, P, n_r)
    return (N / rate_at(a)) / (P * (tc + th)), th / (tc + th)


# ---- the fit -------------------------------------------------------------------------------------------------------
def run_args(m, **over):
    """The model's parameters at measured run m (its settings, precision, transport, skin, 1-GPU rate)."""
    a = parser().parse_args([])
    a.dt, a.precision, a.intra, a.skin, a.rate_skin, a.rate = DT[m[1]], m[2], m[3], m[5], m[5], m[6]
    a.bytes_ghost, a.record_build = bytes_per_ghost(m[2]), build_record(m[2])
    a.gpus_per_node = 2
    for k, v in over.items():
        setattr(a, k, v)
    return a


def run_nr(m):
    return (N_WEAK2 if m[4] == "weak" else N_STRONG) / 2


def fit(over=None):
    """f_build, B_shm, t_sync by least squares on the build exchanges' seconds of the runs with role fit or
    build (four single-build fast runs: staged and IPC, weak and strong); then s_copy and f_ghost so that the
    model gives the efficiency of the two 'fit' runs (staged weak, IPC weak) exactly."""
    import numpy as np
    over = over or {}
    rows, rhs = [], []
    for m in MEASURED:
        if m[12] not in ("fit", "build"):
            continue
        a = run_args(m, **over)
        n_r = run_nr(m)
        tc = n_r / a.rate
        gb = a.depth_planes * a.plane * a.record_build
        if m[3] == "staged":  # f_build tc + 2 gb / B_pcie + gb / B_shm + t_sync
            rows.append([tc, gb, 1.0])
            rhs.append(m[9] / m[8] - 2 * gb / a.b_pcie)
        else:  # f_build tc + gb / B_d2d + t_sync
            rows.append([tc, 0.0, 1.0])
            rhs.append(m[9] / m[8] - gb / a.b_d2d)
    (f_build, inv_bshm, t_sync), *_ = np.linalg.lstsq(np.array(rows), np.array(rhs), rcond=None)
    p = dict(f_build=float(f_build), b_shm=float(1 / inv_bshm), t_sync=float(t_sync))
    # efficiencies: T_halo measured = tc (1/E - 1) = s_copy * C + f_ghost * G + the rest (s_copy = f_ghost = 0)
    A, b = [], []
    for m in MEASURED:
        if m[12] != "fit":
            continue
        a = run_args(m, s_copy=0.0, f_ghost=0.0, **p, **over)
        tc, th0, _, _ = halo_terms(a, 2, run_nr(m))
        C = 2 * a.depth_planes * a.plane * a.bytes_ghost / a.b_pcie if m[3] == "staged" else 0.0
        G = a.depth_planes * a.plane / a.rate
        A.append([C, G])
        b.append(tc * (1 / measured_eff(m) - 1) - th0)
    s_copy, f_ghost = np.linalg.solve(np.array(A), np.array(b))
    p.update(s_copy=float(s_copy), f_ghost=float(f_ghost))
    return p


def check_device(a_cli):
    """The model against every measured 2-GPU run: efficiency and seconds per build exchange."""
    print("Fitted (tools/bench/scaling_model.py fit(), from MEASURED): f_build %.3f, B_shm %.2f GB/s, t_sync %.1f ms, "
          "s_copy %.3f, f_ghost %.3f" % (FIT["f_build"], FIT["b_shm"] / 1e9, FIT["t_sync"] * 1e3, FIT["s_copy"],
                                          FIT["f_ghost"]))
    print("Assumed: B_d2d %.0f GB/s (IPC); measured elsewhere: B_pcie %.0f GB/s, f_window %.2f\n" % (
        a_cli.b_d2d / 1e9, a_cli.b_pcie / 1e9, a_cli.f_window))
    print("| run (2 H200, one node) | role | steps/build model (measured) | s per build exchange: model, measured | "
          "E: model, measured | error | halo s/step: model, measured (exposed) |")
    print("|---|---|---:|---|---|---:|---|")
    errs = {"fit": [], "build": [], "check": []}
    for m in MEASURED:
        a = run_args(m, b_d2d=a_cli.b_d2d, b_pcie=a_cli.b_pcie, f_window=a_cli.f_window)
        n_r = run_nr(m)
        tc, th, _, parts = halo_terms(a, 2, n_r)
        e_mod, e_meas = tc / (tc + th), measured_eff(m)
        tb = build_time(a, 2, n_r, tc)
        role = {"fit": "fitted (E and build)", "build": "build fitted, E out of sample",
                "check": "out of sample"}[m[12]]
        errs[m[12]].append(e_mod - e_meas)
        print("| %s | %s | %.0f (%.1f) | %.1f ms, %.1f ms | %.3f, %.3f | %+.3f | %.2f, %.2f |" % (
            m[0], role, n_build(a), STEPS / m[8], tb * 1e3, m[9] / m[8] * 1e3, e_mod, e_meas, e_mod - e_meas,
            th * 1e3, m[10] / STEPS * 1e3))
    oos = errs["build"] + errs["check"]
    print("\nEfficiency error, model - measured: fitted runs %s; out of sample (%d runs): mean %+.3f, "
          "mean |error| %.3f, largest %+.3f" % (", ".join("%+.3f" % e for e in errs["fit"]), len(oos),
                                                sum(oos) / len(oos), sum(abs(e) for e in oos) / len(oos),
                                                max(oos, key=abs)))
    print("(halo s/step measured: the log's exposed halo on the device timeline over 200 steps; the model's also "
          "holds the ghosts' own work, which the timeline does not count)")


# ---- the skin runs (list-build exchange through the host) ---------------------------------------------------------
# 3D drum, 1.12e7 particles, fast settings (dt 2.504e-5 s), single build, 200 steps, 2 H200:
# skin -> (list builds in 200 steps, 1-GPU rate, 2-GPU strong rate, exposed halo s on 2 GPUs)
SKIN_RUNS = {0.1: (12, 3.0770e8, 2.2768e8, 5.617), 0.25: (5, 2.3854e8, 2.9961e8, 2.320),
             0.5: (2, 1.7164e8, 2.9386e8, 0.726), 1.0: (1, 1.1584e8, 2.1475e8, 0.233)}


def skin_args():
    a = parser().parse_args([])
    a.dt, a.rate, a.rate_skin, a.n_build, a.intra = DT["fast"], 3.077e8, 0.1, None, "staged"
    a.gpus_per_node = 2
    a.t_build = 0.47 * 2  # the host exchange: 5.62 s / 12 builds at N/2 a rank, per 1.1e7 particles
    return finish(a)


def check_skin(_a):
    """The model's list builds and rates against the skin runs (docs/data/parallel/skin_h200x2.txt)."""
    N = 1.1236e7
    a = skin_args()
    print("| skin | builds in 200 steps: model, measured | 1-GPU rate: model, measured | "
          "2-GPU strong E_s vs 1 GPU at 0.1: model, measured |")
    print("|---:|---|---|---|")
    for skin, (nb, r1, r2, _) in SKIN_RUNS.items():
        a.skin = skin
        nbm = 1 + math.floor(STEPS / n_build(a))  # the first build, then one per n_build steps
        t1 = N / a.rate  # one GPU at the best skin measured (0.1)
        tc, th, _, _ = halo_terms(a, 2, N / 2)
        print("| %.2g | %d, %d | %.3g, %.3g | %.2f, %.2f |" % (
            skin, nbm, nb, rate_at(a), r1, t1 / (2 * (tc + th)), r2 / (2 * a.rate)))


def plot_skin(_a, png):
    """Measured rates against the skin on 1 and 2 GPUs, beside the model (check_skin's settings)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    N = 1.1236e7
    a = skin_args()
    sk = sorted(SKIN_RUNS)
    fine = [0.05 + 0.01 * k for k in range(100)]
    m1, m2 = [], []
    for x in fine:
        a.skin = x
        tc, th, _, _ = halo_terms(a, 2, N / 2)
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


# ---- projections ---------------------------------------------------------------------------------------------------
def model_for(settings, **over):
    """The model's parameters at a named set of settings of the job scripts (jobs/common.sh: "scene", Table 1's
    in the drum, or "table1"; "fast"), single build, CUDA IPC inside a node; over: any parameter by name."""
    a = parser().parse_args([])
    key = "fast" if settings == "fast" else "table1"
    a.settings = key
    a.dt, a.rate = DT[key], RATE[(key, "single")]
    for k, v in over.items():
        setattr(a, k, v)
    finish(a)
    return a


def finish(a):
    """Fill the parameters that follow from others (settings, precision) unless given."""
    if a.dt is None:
        a.dt = DT[a.settings]
    if a.rate is None:
        a.rate = RATE[(a.settings, a.precision)]
        if a.rate is None:
            raise SystemExit("scaling_model: no measured 1-GPU rate for %s, %s: give --rate" % (a.settings, a.precision))
    if a.bytes_ghost is None:
        a.bytes_ghost = bytes_per_ghost(a.precision)
    if a.record_build is None:
        a.record_build = build_record(a.precision)
    return a


PS = [1, 2, 4, 8, 16, 32, 64, 128, 256, 512]


def projection(a):
    print("%s settings (dt %.4g s, %.0f steps between builds), %s build, R = %.4g particle-steps/s, %d GPUs a node "
          "(%s inside, %s between nodes at %.0f GB/s)" % (
              "fast" if a.settings == "fast" else "Table 1", a.dt, n_build(a), a.precision, rate_at(a),
              a.gpus_per_node, "CUDA IPC" if a.intra == "ipc" else "MPI staged through host memory",
              "CUDA-aware MPI" if a.cuda_aware else "MPI staged through host memory", a.b_net / 1e9))
    print("\n| P | faces of the slowest rank | weak E_w | weak halo share | MB/rank/step | " +
          " | ".join("strong E_s (N=%.3g) | halo share" % n for n in a.strong) + " |")
    print("|---:|---" + "|---:" * (3 + 2 * len(a.strong)) + "|")
    res = {"weak": [], **{n: [] for n in a.strong}}
    for P in PS:
        ew, hw, nb = weak(a, P)
        res["weak"].append(ew)
        cells = ["%d" % P, " + ".join(faces(a, P)) or "—", "%.3f" % ew, "%.3f" % hw, "%.1f" % (nb / 1e6)]
        for n in a.strong:
            es, hs = strong(a, n, P)
            res[n].append(es)
            cells += ["%.3f" % es if es == es else "—", "%.3f" % hs if hs == hs else "—"]
        print("| " + " | ".join(cells) + " |")
    return res


def plot_projection(curves, png, a):
    """curves: {settings label: (args, result of projection)}; the measured 2-GPU points beside them."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axs = plt.subplots(1, 2, figsize=(12, 4.4), sharey=True)
    for k, (label, (b, res)) in enumerate(curves.items()):
        ax = axs[k]
        ax.plot(PS, res["weak"], "o-", color="C0", label="weak, model, %.1e particles/GPU" % b.per_gpu)
        for j, n in enumerate(b.strong):
            ax.plot(PS, res[n], "s--", color="C%d" % (1 + j), label="strong, model, %.3g particles" % n)
        for m in MEASURED:  # the single-build runs at these settings and skin 0.1
            if m[1] != b.settings or m[2] != "single" or m[5] != 0.1 or "rerun" in m[0] or "run 2" in m[0]:
                continue
            mk = {"weak": "*", "strong": "P"}[m[4]]
            col = "k" if m[3] == "ipc" else "0.55"
            ax.plot([2], [measured_eff(m)], mk, color=col, ms=10, ls="none",
                    label="measured, 2 H200 of one node, %s %s (%s)" % (
                        m[4], "1.12e7" if m[4] == "strong" else "1.1e7/GPU",
                        "CUDA IPC" if m[3] == "ipc" else "staged via host"))
        ax.axvline(b.gpus_per_node, color="0.7", lw=0.8, ls="-.")
        ax.text(b.gpus_per_node * 1.05, 1.0, "one node (%d GPUs)" % b.gpus_per_node, fontsize=7, color="0.4")
        ax.axhline(0.9, color="0.6", lw=0.8, ls=":")
        ax.set_xscale("log", base=2)
        ax.set_xticks(PS)
        ax.set_xticklabels([str(p) for p in PS])
        ax.set_ylim(0, 1.05)
        ax.set_xlabel("GPUs P")
        ax.set_title("%s: R = %.3g p-s/s, %.0f steps/build" % (label, rate_at(b), n_build(b)), fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="lower left", framealpha=0.7)
    axs[0].set_ylabel("parallel efficiency (model: projected)")
    fig.suptitle("GPU slab model (fitted on 2 H200 of one node): IPC inside a node, %s between nodes at %.0f GB/s "
                 "(assumed)" % ("CUDA-aware MPI" if a.cuda_aware else "MPI staged via host", a.b_net / 1e9), fontsize=9)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    print("\nwrote " + png)


def parser():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--settings", choices=["fast", "table1"], default="fast",
                    help="fast (E 10 kPa, alpha 3.162, chi 0.2) or Table 1's; sets --dt and --rate unless given")
    ap.add_argument("--both", action="store_true", help="the projection at both settings (one table each)")
    ap.add_argument("--precision", choices=["single", "double"], default="single",
                    help="the build: the bytes a ghost sends and the 1-GPU rate")
    ap.add_argument("--rate", type=float, default=None,
                    help="one GPU's particle-steps/s (default: measured on an H200 at 1.1e7 particles, skin 0.1: "
                         "fast 3.0555e8 single, 1.9986e8 double; Table 1 3.2199e8 single)")
    ap.add_argument("--plane", type=float, default=27100,
                    help="particles per dr-thick plane of the slab's cross-section (the 3D drum of R = 35 mm, "
                         "fill 0.42, at dr = 0.25 mm: 244 143 ghosts in 9 planes, measured)")
    ap.add_argument("--depth-planes", type=float, default=9, help="ghost depth in dr planes (3 cells of 2h = 9 dr)")
    ap.add_argument("--bytes-ghost", type=float, default=None,
                    help="bytes a ghost's refreshes send a step (default from --precision: 96.8 single, 193.6 double)")
    ap.add_argument("--record-build", type=float, default=None,
                    help="bytes of a ghost made at a list build (default from --precision: 115 single, 211 double)")
    ap.add_argument("--intra", choices=["ipc", "staged"], default="ipc",
                    help="transport between GPUs of one node: CUDA IPC (default) or MPI staged through host memory "
                         "(SPHSEG_GPU_IPC=0)")
    ap.add_argument("--gpus-per-node", type=int, default=8,
                    help="GPUs of one node (default 8): for P <= G every face goes by --intra, for P > G the slowest "
                         "rank has one face to another node")
    ap.add_argument("--b-net", type=float, default=25e9,
                    help="network bandwidth between nodes per direction, B/s (default 25e9: InfiniBand HDR200/NDR, "
                         "assumed, not measured here)")
    ap.add_argument("--b-shm", type=float, default=FIT_DEFAULT["b_shm"],
                    help="MPI between ranks of one node through host memory, B/s (fitted to the build exchanges)")
    ap.add_argument("--b-d2d", type=float, default=100e9,
                    help="CUDA IPC device to device over NVLink, B/s (assumed, not measured; NV18 nominal 450e9)")
    ap.add_argument("--b-pcie", type=float, default=38e9, help="device<->pinned host copy bandwidth, B/s (measured)")
    ap.add_argument("--s-copy", type=float, default=FIT_DEFAULT["s_copy"],
                    help="exposed share of the staging copies (fitted)")
    ap.add_argument("--lat", type=float, default=3e-6, help="MPI message latency, s (assumed)")
    ap.add_argument("--f-window", type=float, default=0.48,
                    help="share of a step's compute the refreshes overlap (the flow rates: 48 %% of the step, "
                         "docs/gpu.md profile)")
    ap.add_argument("--f-ghost", type=float, default=FIT_DEFAULT["f_ghost"],
                    help="cost of a ghost in units of an owned particle's step (fitted)")
    ap.add_argument("--f-build", type=float, default=FIT_DEFAULT["f_build"],
                    help="device work of a build exchange in units of a step's compute (fitted)")
    ap.add_argument("--t-sync", type=float, default=FIT_DEFAULT["t_sync"],
                    help="fixed seconds of a build exchange (its synchronisations; fitted)")
    ap.add_argument("--t-build", type=float, default=None,
                    help="a measured exchange at a list build, s per --n-build-ref particles, instead of the device "
                         "exchange's model (the host exchange: 0.94)")
    ap.add_argument("--n-build-ref", type=float, default=1.1e7, help="particles per rank of --t-build")
    ap.add_argument("--n-build", type=float, default=None,
                    help="steps between list builds; default from --skin, --h, --v-max, --dt")
    ap.add_argument("--skin", type=float, default=0.1, help="Run:list_skin, in units of h (default 0.1)")
    ap.add_argument("--rate-skin", type=float, default=0.1, help="the skin at which --rate was measured")
    ap.add_argument("--h", type=float, default=3.75e-4, help="smoothing length, m (3D drum at dr = 0.25 mm)")
    ap.add_argument("--dt", type=float, default=None,
                    help="time step, s (default from --settings: fast 2.504e-5, Table 1 3.958e-7, docs/gpu.md)")
    ap.add_argument("--v-max", type=float, default=0.037,
                    help="largest particle speed, m/s (default: from the measured build interval, 18.2 steps at "
                         "skin 0.1 and dt 2.504e-5 s: docs/data/parallel/skin_h200x2.txt)")
    ap.add_argument("--check-device", action="store_true",
                    help="the model against every measured 2-GPU run (fitted and out of sample) and exit")
    ap.add_argument("--check-skin", action="store_true",
                    help="compare with the measured skin runs (1 and 2 H200, fast settings, host exchange) and exit")
    ap.add_argument("--per-gpu", type=float, default=1.1e7, help="particles per GPU, weak scaling")
    ap.add_argument("--strong", type=float, nargs="+", default=[1.1236e7, 1e8],
                    help="total particles, strong (default: the measured drum of length 0.1 m, and 1e8)")
    ap.add_argument("--no-overlap", action="store_true", help="refreshes not overlapped (SPHSEG_GPU_OVERLAP=0)")
    ap.add_argument("--cuda-aware", action="store_true",
                    help="no host staging between nodes (CUDA-aware MPI, GPUDirect RDMA; never run here)")
    ap.add_argument("--check", action="store_true",
                    help="compare with the 2-GPU runs of the older code (Table 1, no list builds; docs/parallel.md)")
    ap.add_argument("--png", default=None, help="chart of the projection at both settings, to write")
    ap.add_argument("--skin-png", default=None, help="chart of the skin runs beside the model, to write")
    return ap


def check_old(a):
    """The older code's 2-GPU runs (double build, Table 1, no windows: 225 B per ghost and step, staged, no list
    build in the timed steps) against the refitted model."""
    a.settings, a.precision, a.intra, a.gpus_per_node = "table1", "double", "staged", 2
    a.dt, a.n_build, a.bytes_ghost, a.rate = DT["table1"], math.inf, 225.0, 7.7e7
    finish(a)
    for rate, runs in ((7.7e7, (("weak, overlap", False, 0.950), ("weak, no overlap", True, 0.885))),
                       (9.1e7, (("weak, overlap", False, 0.947),))):
        a.rate = rate  # 7.7e7: commit df38609, before the early loads; 9.1e7: 1f0bd6d (docs/parallel.md)
        for label, no_ov, meas in runs:
            a.no_overlap = no_ov
            e, h, nb = weak(a, 2)
            print("R = %.2g %-17s P = 2: model E_w %.3f (halo share %.3f, %.1f MB/step), measured %.3f" % (
                a.rate, label, e, h, nb / 1e6, meas))
        a.no_overlap = False
        meas = 0.954 if rate == 7.7e7 else 0.945
        print("R = %.2g %-17s P = 2: model E_s %.3f, measured %.3f" % (a.rate, "strong 2e7", strong(a, 1.99e7, 2)[0], meas))


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
    if a.check:
        check_old(a)
        return
    given = dict(vars(a))
    if a.both or a.png:
        curves = {}
        for key, label in (("fast", "fast settings"), ("table1", "Table 1 settings")):
            b = argparse.Namespace(**given)
            b.settings = key
            if key != a.settings:
                b.dt = b.rate = None
            finish(b)
            curves[label] = (b, projection(b))
            print()
        if a.png:
            plot_projection(curves, a.png, a)
        return
    projection(finish(a))


FIT_DEFAULT = dict(f_build=0.0, b_shm=3.8e9, t_sync=0.0, s_copy=1.0, f_ghost=1.0)  # placeholders for fit() itself
FIT = fit()
FIT_DEFAULT.update(FIT)

if __name__ == "__main__":
    main()
