"""CPU against GPU backend, and the GPU run to run (issue "GPU backend").

Every scene in inputs/ (and variants that reach the paths the scenes leave
out: the HCSR classification of the paper scheme, the 3D column, the CI-sized
3D drum, the Shepard filter) runs N steps with --backend cpu and twice with
--backend gpu, double precision, and the last snapshots are compared:

  equivalence:  every field of the GPU run equals the CPU run's to round-off:
                max |gpu - cpu| <= TOL * max |cpu| per field (TOL = 1e-8;
                both backends evaluate the same src/physics bodies on the same
                particle order, the GPU contracting a*b + c into fused
                multiply-adds, so they differ by round-off that a few tens of
                steps of a granular flow amplify to ~1e-13; a wrong stage gives
                differences of order one), and the boundary classes agree
                exactly. The paper scheme (HCSR with C1 gradients) is looser,
                TOL_C1 = 1e-4: its boundary solves amplify round-off, so much
                that a CPU build with -ffp-contract=fast differs from the
                default CPU build by 3.6e-6 in C after the same 40 shear-box
                steps (measured; the GPU differs by the same 3.6e-6);
  determinism:  the two GPU runs are bit-identical (every dataset): the
                first replays its steps as CUDA graphs (gpu/gpu_graph.cu)
                and reads the bed damping's weights made once a particle
                (SPHSEG_GPU_BEDQ=1, which these small stores leave off by
                default: gpu_bed_q), the second launches every kernel
                directly (SPHSEG_GPU_GRAPH=0), computes the weights per
                pair (SPHSEG_GPU_BEDQ=0) and runs the general flow pass
                where the first runs the one specialised to the drum
                scenes' flow (SPHSEG_GPU_SPEC=0); the drum scenes of one rank must
                have held steps as graphs (its "gpu graphs:" line).

Scenes with DEM grains (issue 58; src/dem/dem_body.h run by src/dem/dem.c and
gpu/gpu_dem.cu) compare their /DEM group too: the grains' centres,
velocities, spins (times d/2, on the velocities' scale), and the fluid's
fraction and velocity at them, within TOL_DEM of each field's largest
value (the grains' sums over the fluid and the rigid body's and exchanged
momentum's sums over the grains run in another order on the GPU; 1e-8, as
the fluid's), and bit for bit GPU run to run. The periodic DEM scenes run
at a period of 19 dr, the GPU's 6 supports (src/settings_check.c).

Exits 77 (skipped) where the build has no CUDA backend or no GPU is visible.
"""
import argparse
import os
import subprocess
import sys

import h5py
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
from tools.analysis import snap  # noqa: E402

INPUTS = os.path.join(HERE, "..", "inputs")
TOL = 1e-8
TOL_C1 = 1e-4
TOL_DEM = 1e-8

# DEM grains at CI size (the periodic scenes widened to 19 dr, 6 supports, for the GPU's ghosts)
P19 = 0.10127
DEM_POROUS = ["Material:eta=0.1", "Material:E=30000", "Initial:pressure=2000", "Run:integrator=leapfrog",
              "Geometry:width=%g" % P19, "Geometry:depth=%g" % P19, "Geometry:height=%g" % P19,
              "Container:regions=[{shape: fill, level: %g, C: 0}]" % P19, "DEM:block_n=[19, 4, 19]"]
DEM_BLOCK = ["Geometry:width=%g" % P19, "Geometry:depth=%g" % P19,
             "Container:walls=[{name: base, from: [0, 0], to: [%g, 0]}]" % P19,
             "Container:regions=[{shape: fill, level: 0.09594, C: 0}]", "DEM:block_n=[19, 4, 19]",
             "DEM:block_origin=[0.002665, 0.046, 0.002665]", "DEM:t_damp=0.03", "Run:integrator=leapfrog"]
# a rigid body that turns (no periodic axis): the grains' drag differs, so it has a torque
DEM_RIGID = ["DEM:coupling=two_way", "DEM:motion=rigid", "DEM:placement=block", "DEM:block_n=[3, 2, 2]",
             "DEM:block_spacing=0.008", "DEM:block_origin=[0.02, 0.06, 0.024]"]
# free grains that meet: layers 1 um apart on the base, the lowest touching it
DEM_PILE = ["DEM:d=0.004", "DEM:coupling=two_way", "DEM:placement=block", "DEM:block_n=[6, 3, 6]",
            "DEM:block_spacing=0.004001", "DEM:block_origin=[0.02, 0.002, 0.02]"]

# name, scene, steps, overrides
from tests.containers import (CHANNEL, CHUTE, CHUTE_3D, CHUTE_AS_CONTAINER, COLLAPSE, FILM, HOPPER, HOPPER_3D,  # noqa: E402
                        PLAIN, SILO, pick_cases)

CASES = [
    ("shearbox", "shearbox_2d.yml", 40, []),
    ("shearbox_paper", "shearbox_2d.yml", 40, ["Segregation:scheme=paper"]),
    # the donor limiter where it caps: small grains sinking through large at Pe = 200
    # (tests/validate_bounds.py), and the same without it
    ("column_bounds", "shearbox_2d.yml", 60, ["Kinematics:velocity=rest", "Segregation:V=0.0023",
                                              "Segregation:D=1e-6", "Initial:C_below=0", "Initial:C_above=1",
                                              "Geometry:dr=0.00348", "Geometry:width=0.02175"]),
    ("column_bounds_none", "shearbox_2d.yml", 60, ["Kinematics:velocity=rest", "Segregation:V=0.0023",
                                                   "Segregation:D=1e-6", "Initial:C_below=0",
                                                   "Initial:C_above=1", "Geometry:dr=0.00348",
                                                   "Geometry:width=0.02175", "Segregation:limiter=none"]),
    ("column", "column_2d.yml", 60, []),
    ("column_3d", "column_2d.yml", 30, ["Geometry:dim=3", "Geometry:dr=0.005", "Geometry:width=0.05",
                                        "Geometry:depth=0.05", "Geometry:height=0.1",
                                        "Physics:gravity=[0, -9.81, 0]"]),
    # the drum scenes as they ship (riemann, bed damping, the corrected gradient and fickian shifting)
    ("drum_EV", "drum_2d_EV.yml", 60, ["Flow:shepard_every=20", "Segregation:every=1"]),
    ("drum_EV_win", "drum_2d_EV.yml", 60, ["Flow:shepard_every=20", "Segregation:every=7"]),
    # Flow:stabilization (physics/momentum.h): the Riemann dissipation (the drum and chute scenes' own, in the
    # cases above at E 10 MPa) and pressure diffusion, delta-SPH
    # plain riemann, without the bed damping the drum scenes set (drum_EV_bed has it)
    ("drum_EV_riemann", "drum_2d_EV.yml", 300, ["Flow:stabilization=riemann", "Flow:bed_damping=0", "Material:E=1e5"] + PLAIN +
     ["Flow:shepard_every=20", "Segregation:every=7"]),
    ("drum_EV_bed", "drum_2d_EV.yml", 300, ["Flow:stabilization=riemann", "Flow:bed_damping=1", "Material:E=1e5"] + PLAIN +
     ["Flow:shepard_every=20", "Segregation:every=7"]),
    ("drum_EV_delta", "drum_2d_EV.yml", 300, ["Flow:stabilization=delta", "Material:E=1e5"] + PLAIN +
     ["Flow:shepard_every=20", "Segregation:every=7"]),
    ("drum_EN", "drum_2d_EN.yml", 60, ["Segregation:every=10"]),
    # Flow:stress_filter mls (flow.h flow_shepard_team): the first-order filter, its 3x3 and 4x4 solves
    ("drum_EV_mls", "drum_2d_EV.yml", 300, ["Flow:stress_filter=mls", "Material:E=1e5"] + PLAIN +
     ["Flow:shepard_every=20", "Segregation:every=7"]),
    ("drum_3d_mls", "drum_3d.yml", 40, ["Geometry:dr=0.0025", "Geometry:radius=0.02", "Geometry:length=0.025",
                                        "Material:E=1e5", "Walls:rpm=15", "Flow:shepard_every=20",
                                        "Segregation:every=8", "Flow:stress_filter=mls"] + PLAIN),
    # Flow:gradient_correction (flow.h flow_kgc_team, flow_rates_team): B of the owned and the ghosts in
    # prepare, and the corrected velocity gradient and stress divergence, in 2D and 3D
    ("drum_EV_kgc", "drum_2d_EV.yml", 300, ["Flow:gradient_correction=on", "Flow:shifting=off", "Material:E=1e5",
                                            "Flow:shepard_every=20", "Segregation:every=7"]),
    ("drum_3d_kgc", "drum_3d.yml", 40, ["Geometry:dr=0.0025", "Geometry:radius=0.02", "Geometry:length=0.025",
                                        "Material:E=1e5", "Walls:rpm=15", "Flow:shepard_every=20",
                                        "Segregation:every=8", "Flow:gradient_correction=on", "Flow:shifting=off"]),
    # the paper's path: its scheme and its Flow:stabilization monaghan (the drum scenes set riemann)
    ("drum_EV_paper", "drum_2d_EV.yml", 40, ["Segregation:scheme=paper", "Geometry:dr=0.001",
                                             "Segregation:every=1", "Flow:stabilization=monaghan"] + PLAIN),
    ("drum_EV_paper_win", "drum_2d_EV.yml", 40, ["Segregation:scheme=paper", "Geometry:dr=0.001",
                                                 "Segregation:every=6", "Flow:stabilization=monaghan"] + PLAIN),
    ("drum_3d", "drum_3d.yml", 40, ["Geometry:dr=0.0025", "Geometry:radius=0.02", "Geometry:length=0.025",
                                    "Material:E=1e5", "Walls:rpm=15", "Flow:shepard_every=20",
                                    "Segregation:every=8"]),
    # periodic axes (mpi/halo.h: images as ghosts of the rank itself): a layer
    # sliding down a 40-degree incline across the period boundary, 2D and 3D
    ("chute", "column_2d.yml", 400, CHUTE),
    # the tensorial mu(I) yield (Material:yield mu_I, stress.h) on the chute scene that uses it
    ("chute_mu_I", "chute_2d.yml", 400, []),
    # Material:mu_law partial (Barker & Gray 2017, stress.h stress_mu): the layer from rest, below I_N1,
    # and the drum, whose bed and layer's base sit below it
    ("chute_partial", "chute_2d.yml", 400, ["Material:mu_law=partial"]),
    ("drum_EV_partial", "drum_2d_EV.yml", 60, ["Material:mu_law=partial"] + PLAIN),
    # a gate lifted at t = 0.01 s (Geometry:runout, Walls:gate_open): a column collapse
    ("collapse", "column_2d.yml", 1500, COLLAPSE),
    # Walls:coulomb_force particles (flow.h flow_contact_team, ST_CONTACT): the Coulomb floor's friction on the
    # particles, under monaghan (the glass-bead collapse) and under riemann with the corrected gradient (a layer
    # on a Coulomb base, periodic along x)
    ("collapse_contact", "collapse_2d_glass.yml", 1500, ["Geometry:dr=0.002", "Walls:slip=coulomb",
                                                         "Walls:mu_w=0.4621", "Walls:coulomb_force=particles"]),
    ("chute_contact", "chute_2d.yml", 400, ["Walls:slip=coulomb", "Walls:mu_w=0.3", "Walls:coulomb_force=particles",
                                            "Flow:gradient_correction=on", "Material:mu_s=0.7", "Material:mu_d=0.9"]),
    # an outlet under a silo's opening: the device store shrinks (run_guard.c run_drain)
    ("silo", "column_2d.yml", 5000, SILO),
    # the Newtonian fluid (Material:model newtonian): a film down the incline, tests/validate_film.py
    ("film", "column_2d.yml", 400, FILM),
    ("channel", "column_2d.yml", 400, CHANNEL),
    ("chute_3d", "column_2d.yml", 60, CHUTE_3D),
    # a container described as data (Geometry:type container): a gated hopper that discharges
    ("hopper", "hopper_2d.yml", 2400, HOPPER),
    ("hopper_3d", "hopper_2d.yml", 40, HOPPER_3D),
    ("chute_container", "column_2d.yml", 400, CHUTE + CHUTE_AS_CONTAINER),
    # a post in a cell periodic along x and y: Stokes flow through a lattice of cylinders
    ("cylinders", "cylinders_2d.yml", 400, ["Geometry:dr=0.0005"]),
    # particle shifting (Flow:shifting, ST_SHIFT in save_start) with the background pressure left out
    # of the momentum, and shifting on a granular drum with a free surface
    ("cylinders_shift", "cylinders_2d.yml", 400, ["Geometry:dr=0.0005", "Flow:shifting=fickian",
                                                  "Flow:background_pressure=excluded"]),
    ("drum_EV_shift", "drum_2d_EV.yml", 60, ["Flow:shepard_every=20", "Segregation:every=1",
                                             "Flow:shifting=fickian", "Flow:gradient_correction=off"]),
    # a larger Verlet skin (Run:list_skin; the CPU ignores it): fewer list builds, longer
    # lists, and on a periodic axis images kept longer; the same answer to round-off
    ("drum_3d_skin", "drum_3d.yml", 40, ["Geometry:dr=0.0025", "Geometry:radius=0.02", "Geometry:length=0.025",
                                         "Material:E=1e5", "Walls:rpm=15", "Flow:shepard_every=20",
                                         "Segregation:every=8", "Run:list_skin=0.5"]),
    ("chute_skin", "column_2d.yml", 400, CHUTE + ["Run:list_skin=1"]),
    # DEM grains (issue 58): one grain one way (the scene as it ships) and two ways; a fixed porous block
    # (periodic xyz, 1444 grains); a rigid block settling (periodic xz: it translates); a rigid body that
    # turns; free grains in contact with each other and the base (sub-cycled DEM steps)
    ("dem_settling", "dem_settling.yml", 60, []),
    ("dem_settling_2way", "dem_settling.yml", 60, ["DEM:coupling=two_way"]),
    ("dem_porous", "dem_porous_flow.yml", 40, DEM_POROUS),
    ("dem_block", "dem_block_settling.yml", 40, DEM_BLOCK),
    ("dem_rigid_turn", "dem_settling.yml", 60, DEM_RIGID),
    ("dem_pile", "dem_settling.yml", 60, DEM_PILE),
]
# (Segregation:every = 1: C with the flow in every step; K > 1: in windows of
# K steps, closed 5-9 times in these runs, the last one left open at
# max_steps, src/sim/integrate.c)


def run(sphseg, scene, out, backend, steps, over, env=None):
    cmd = [sphseg, os.path.join(INPUTS, scene), "-o", out, "--backend", backend,
           "-P", "Run:max_steps=%d" % steps, "-P", "Run:progress_s=1e9", "-P", "Output:dt=1e3"]
    cmd += sum([["-P", o] for o in over], [])
    return subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ, **(env or {})))


def graph_line(r):
    """The run's "gpu graphs:" line and the steps it held as graphs (0: none)."""
    for line in (r.stdout + r.stderr).splitlines():
        if "gpu graphs:" in line:
            return line.split("gpu graphs:")[1].strip(), int(line.split("gpu graphs:")[1].split()[0])
    return "no graph line", 0


def last(out):
    return snap.read_snapshot(snap.list_snapshots(out)[-1])


def last_dem(out):
    """The last snapshot's /DEM datasets, or None (no grains)."""
    with h5py.File(snap.list_snapshots(out)[-1], "r") as f:
        return {k: f["DEM"][k][()] for k in f["DEM"]} if "DEM" in f else None


def dem_difference(c, g):
    """max over the grains' fields of max|gpu - cpu| / max|cpu| (the spins
    times d/2 on the velocities' scale)."""
    worst = 0.0
    for name in ("Coordinates", "Velocities", "AngularVelocities", "FluidFraction", "FluidVelocity"):
        a, b = np.asarray(c[name], dtype=float), np.asarray(g[name], dtype=float)
        ref = a
        if name == "AngularVelocities":
            r = 0.5 * np.asarray(c["Diameter"], dtype=float)[:, None]
            a, b, ref = a * r, b * r, np.asarray(c["Velocities"], dtype=float)
        scale = max(float(np.max(np.abs(ref))) if ref.size else 0.0, 1e-300)
        worst = max(worst, float(np.max(np.abs(b - a))) / scale if a.size else 0.0)
    return worst


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sphseg", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--cases", default=None, help="NAME,NAME: only these cases")
    a = ap.parse_args()
    cases = pick_cases(ap, CASES, a.cases)
    probe = run(a.sphseg, "shearbox_2d.yml", os.path.join(a.work, "probe"), "gpu", 1, [])
    if probe.returncode == 2 and "--backend gpu" in probe.stderr:
        print("skipped: " + probe.stderr.strip())
        sys.exit(77)
    ok = True
    for name, scene, steps, over in cases:
        res, dem = {}, {}
        for tag, backend, env in (("cpu", "cpu", None), ("gpu", "gpu", {"SPHSEG_GPU_BEDQ": "1"}),
                                  ("gpu2", "gpu", {"SPHSEG_GPU_GRAPH": "0", "SPHSEG_GPU_BEDQ": "0",
                                                   "SPHSEG_GPU_SPEC": "0"})):
            out = os.path.join(a.work, name + "_" + tag)
            r = run(a.sphseg, scene, out, backend, steps, over, env)
            if r.returncode != 0:
                print(r.stderr)
                sys.exit("FAIL %s: sphseg --backend %s exited with %d" % (name, backend, r.returncode))
            res[tag] = last(out)
            dem[tag] = last_dem(out)
            if tag == "gpu":
                graphs, held = graph_line(r)
        c, g, g2 = res["cpu"], res["gpu"], res["gpu2"]
        worst = snap.max_field_difference(c, g)
        same_ids = np.array_equal(c["ParticleIDs"], g["ParticleIDs"])
        cls_diff = int(np.sum(c["BoundaryClass"] != g["BoundaryClass"]))
        tol = TOL_C1 if "Segregation:scheme=paper" in over else TOL
        good = same_ids and worst <= tol and cls_diff == 0 and c["Step"] == g["Step"] == steps
        print("%s %-14s %3d steps, t = %.6g s: max field difference %.2e of its scale (tol %.0e), "
              "%d class differences" % ("ok  " if good else "FAIL", name, steps, c["Time"], worst, tol, cls_diff))
        ok &= good
        keys = [k for k in g if k != "path"]
        differ = [k for k in keys if not np.array_equal(np.asarray(g[k]), np.asarray(g2[k]))]
        print("%s %-14s GPU run to run, graphs, weights once a particle, specialised pass against direct, general: %s" % (
            "ok  " if not differ else "FAIL", name, "bit-identical" if not differ else "differ in " + ", ".join(differ)))
        ok &= not differ
        must = name.startswith("drum") and "paper" not in name  # one rank, computed flow, no HCSR builds
        print("%s %-14s %s" % ("FAIL" if must and held == 0 else "ok  ", name, graphs))
        ok &= not (must and held == 0)
        if dem["cpu"] is not None:
            dc, dg, dg2 = dem["cpu"], dem["gpu"], dem["gpu2"]
            dworst = dem_difference(dc, dg) if dg is not None else float("inf")
            dgood = dg is not None and np.array_equal(dc["ParticleIDs"], dg["ParticleIDs"]) and dworst <= TOL_DEM
            print("%s %-14s %d grains: max grain field difference %.2e of its scale (tol %.0e)" % (
                "ok  " if dgood else "FAIL", name, len(dc["ParticleIDs"]), dworst, TOL_DEM))
            ok &= dgood
            ddiffer = [k for k in dg if dg2 is None or not np.array_equal(dg[k], dg2[k])]
            print("%s %-14s GPU grains run to run: %s" % ("ok  " if not ddiffer else "FAIL", name,
                                                          "bit-identical" if not ddiffer else "differ in " + ", ".join(ddiffer)))
            ok &= not ddiffer
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
