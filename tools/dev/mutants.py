#!/usr/bin/env python3
"""Mutation test of the suite (`make test-mutants`; not part of CI).

Plants one plausible bug at a time in a scratch copy of the working tree,
builds it (a CPU build, GPU=0) and runs the suite on it (tests/run.sh with
FAIL_FAST=1: it stops at the first failing test). A mutant is killed when the
suite fails, survives when it passes. Prints one line per mutant, the kill
rate and each survivor, and writes the table as markdown to WORK/mutants.md.

The GPU tests are made to skip in the mutant runs (an nvidia-smi that lists no
GPU comes first on PATH), since the build has no CUDA backend.

  python3 -m tools.dev.mutants                  all mutants (about an hour on 2 cores)
  python3 -m tools.dev.mutants --list           the mutants, and whether each still applies
  python3 -m tools.dev.mutants --only a,b       some of them
  python3 -m tools.dev.mutants --keep-going     the whole suite per mutant (every test that kills it)

A mutant is (name, area, file, [(old, new), ...], what it does): each `old`
must occur exactly once in its file, so a mutant that no longer applies is
reported, not silently skipped. A mutant that does not build is reported and
left out of the rate (it would be killed by the compiler, not the suite).
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import time

from tools import ROOT  # noqa: E402

MUTANTS = [
    # ---- physics: flow
    ("shepard_never", "physics", "src/sim/integrate.c",
     [("every > 0 && s->step % (long)every == 0) s->be->filter(s);", "every > 0 && 0) s->be->filter(s);")],
     "the Shepard filter (3.12) is never applied"),
    ("shepard_unweighted", "physics", "src/physics/wall.h",
     [("acc[c] += sj[c] * W;\n    *wsum += W;", "acc[c] += sj[c];\n    *wsum += R(1.0);")],
     "the Shepard filter is a plain mean of the neighbours"),
    ("av_dropped", "physics", "src/physics/flow.h",
     [("if (c->alpha_av > 0) Pi = mom_av(", "if (c->alpha_av < 0) Pi = mom_av(")],
     "the artificial viscosity (3.10) is dropped"),
    ("mls_moment", "physics", "src/physics/flow.h",
     [("mo[6] += W * xi[0] * xi[1]", "mo[6] += W * xi[0] * xi[0]")],
     "Flow:stress_filter mls sums its xy moment as xx (no longer exact for a linear stress)"),
    ("shift_no_dummies", "physics", "src/physics/shift.h",
     [("const real cw = V * (R(1.0) + c->R * t2 * t2) * f, vf = V * f;",
       "const real cw = (p->kind[j] == KIND_MATERIAL) * V * (R(1.0) + c->R * t2 * t2) * f, vf = V * f;")],
     "Flow:shifting fickian's concentration sum leaves out the dummies (a grain crowding a wall is not pushed off)"),
    ("kgc_neighbour_B", "physics", "src/physics/flow.h",
     [("linalg_sym_apply(Bj, gradW, gj);", "linalg_sym_apply(Bi, gradW, gj);")],
     "Flow:gradient_correction takes i's correction for j's stress (the pair forces no longer opposite)"),
    ("kgc_adjugate", "physics", "src/physics/flow.h",
     [("adj[0] = m[1], adj[1] = m[0], adj[3] = -m[3];", "adj[0] = m[1], adj[1] = m[0], adj[3] = m[3];")],
     "Flow:gradient_correction inverts a 2D moment with the off-diagonal's sign kept"),
    ("pair_force_sign", "physics", "src/physics/momentum.h",
     [("a[0] += m_j * (T[0]", "a[0] -= m_j * (T[0]"), ("a[1] += m_j * (T[3]", "a[1] -= m_j * (T[3]"),
      ("a[2] += m_j * (T[4]", "a[2] -= m_j * (T[4]")],
     "the pair force of (3.9) has its sign flipped"),
    ("mu_s_for_mu_d", "physics", "src/physics/stress.h",
     [("return m->mu_s + (m->mu_d - m->mu_s) * gdot / den;", "return m->mu_s + (m->mu_s - m->mu_s) * gdot / den;")],
     "mu(I) (2.14) uses mu_s where mu_d belongs: a constant friction"),
    ("jaumann_sign", "physics", "src/physics/stress.h",
     [("t += W[a][c] * S[c][b] - S[a][c] * W[c][b];", "t += S[a][c] * W[c][b] - W[a][c] * S[c][b];")],
     "the Jaumann rotation terms of (C1) have the wrong sign"),
    ("bulk_modulus_third", "physics", "src/physics/stress.h",
     [("out[0] = J[0][0] + R(2.0) * G * (eps[0] - tr / R(3.0)) + K * tr;",
       "out[0] = J[0][0] + R(2.0) * G * (eps[0] - tr / R(3.0)) + K * tr / R(3.0);")],
     "K eps_v with eps_v = tr/3 in the xx component (the slip below 2.16)"),
    ("no_tension_cut", "physics", "src/physics/stress.h",
     [("    if (p <= 0) {\n        for (int c = 0; c < 6; ++c) s[c] = 0;",
       "    if (p < -1e30) {\n        for (int c = 0; c < 6; ++c) s[c] = 0;")],
     "the return mapping has no tension cut-off"),
    ("kernel_alpha_2d", "physics", "src/physics/kernel.h",
     [("return dim == 2 ? R(7.0) / (R(4.0 * M_PI) * h * h)", "return dim == 2 ? R(7.0) / (R(3.0 * M_PI) * h * h)")],
     "the 2D kernel normalisation is wrong"),
    # ---- physics: segregation
    ("eta_lost", "physics", "src/physics/seg_kern.h",
     [("* (Ci - Cj) * f * r2 / (r2 + k->eta2);", "* (Ci - Cj) * f;")],
     "the paper scheme's Laplacian (3.8) loses its eta clipping"),
    ("wall_flux_ni", "physics", "src/physics/seg_kern.h",
     [("qs += seg_wall_flux(sp, Ci, p->gdot[i], nj) * s2;", "qs += seg_wall_flux(sp, Ci, p->gdot[i], ni) * s2;")],
     "the wall flux (4.9) uses n_i instead of n_j"),
    ("c1_unused", "physics", "src/physics/seg_kern.h",
     [("if (!seg_c1_solve(&s1, k->dim, sp->ghat, gc)) gx[0] = gc[0], gx[1] = gc[1];",
       "if (!seg_c1_solve(&s1, k->dim, sp->ghat, gc)) gx[0] = gx[0], gx[1] = gx[1];")],
     "the C1 boundary gradient (App. E) is computed but unused"),
    ("mcsr_halved", "physics", "src/physics/seg_kern.h",
     [("(mcsr ? R(2.0) * fc * qs : R(0.0))", "(mcsr ? fc * qs : R(0.0))")],
     "the MCSR free-surface source (4.16) is halved"),
    ("cons_D_i", "physics", "src/physics/seg_kern.h",
     [("diff += w * (Di + Dj) * (Ci - Cj) * xlx;", "diff += w * (Di + Di) * (Ci - Cj) * xlx;")],
     "the conservative scheme uses 2 D_i for D_i + D_j"),
    ("cons_seg_sign", "physics", "src/physics/seg_kern.h",
     [("seg -= w * q * gx;", "seg += w * q * gx;")],
     "the conservative segregation flux points up"),
    ("dFdC", "physics", "src/physics/seg.h",
     [("return sp->A * (R(3.0) * sp->kappa * C * C - R(2.0) * (R(1.0) + sp->kappa) * C + R(1.0));",
       "return sp->A * (R(3.0) * sp->kappa * C * C - (R(1.0) + sp->kappa) * C + R(1.0));")],
     "dF/dC below (2.10) loses a factor 2"),
    ("kin_velocity_phase", "physics", "src/physics/kin.h",
     [("double rate = kp->gamma0 * kp->omega * cos(kp->omega * t);",
       "double rate = kp->gamma0 * kp->omega * sin(kp->omega * t);")],
     "the shear box's velocity and shear rate are a quarter period off its positions"),
    ("umbrella_angle", "physics", "src/physics/bound_kern.h",
     [("> R(0.5) * sq2 * r) {", "> R(0.7) * sq2 * r) {")],
     "the free-surface umbrella test (4.19) uses a wider cone"),
    # ---- integration
    ("midpoint_at_t_dt", "integration", "src/sim/integrate.c",
     [("be->prepare(s, s->t + 0.5 * dt, 0);", "be->prepare(s, s->t + dt, 0);")],
     "the midpoint stage is evaluated at t + dt"),
    ("save_after_predictor", "integration", "src/sim/integrate.c",
     [("    be->save_start(s);\n    be->advance(s, 0.5 * dt, 0.0);\n    be->prepare(s, s->t + 0.5 * dt, 0);",
       "    be->advance(s, 0.5 * dt, 0.0);\n    be->save_start(s);\n    be->prepare(s, s->t + 0.5 * dt, 0);")],
     "the corrector starts from the predicted state"),
    ("conc_from_current", "integration", "src/physics/step.h",
     [("if (seg_on) p->C[i] = p->C_n[i] + (creal)a * p->dCdt[i];", "if (seg_on) p->C[i] = p->C[i] + (creal)a * p->dCdt[i];")],
     "C advances from its current value, not the start of the step"),
    ("diffusion_cfl_x10", "integration", "src/sim/integrate.c",
     [("dt = fmin(dt, fdiff * sc->run.cfl_diffusion * h * h / dmax);",
       "dt = fmin(dt, 10 * fdiff * sc->run.cfl_diffusion * h * h / dmax);")],
     "the diffusion time-step bound is 10x too loose"),
    ("flow_cfl_x10", "integration", "src/sim/integrate.c",
     [("stress_dt((real)sc->run.cfl_flow,", "stress_dt((real)(10 * sc->run.cfl_flow),")],
     "the flow time-step bound (3.19) is 10x too loose"),
    # ---- walls
    ("freeslip_wall_normal", "walls", "src/physics/wall.h",
     [("real dn = R(2.0) * wn - an;", "real dn = -an;")],
     "a free-slip dummy ignores the wall's normal velocity"),
    ("noslip_no_mirror", "walls", "src/physics/wall.h",
     [("for (int a = 0; a < 3; ++a) ud[a] = R(2.0) * uw[a] - avg[a];", "for (int a = 0; a < 3; ++a) ud[a] = uw[a];")],
     "a no-slip dummy takes the wall velocity instead of the mirror (4.1)"),
    ("wall_hydrostatic_sign", "walls", "src/physics/wall.h",
     [("for (int a = 0; a < 3; ++a) sd[a] -= ws->gr[a] / ws->w;", "for (int a = 0; a < 3; ++a) sd[a] += ws->gr[a] / ws->w;")],
     "the hydrostatic term of the dummy stress (4.3) has the wrong sign"),
    ("wall_accel_sign", "walls", "src/physics/flow.h",
     [("geff[a] = c->g[a] - aw[a];", "geff[a] = c->g[a] + aw[a];")],
     "the dummy stress uses g + a_w for g - a_w"),
    ("drum_turns_backwards", "walls", "src/physics/wall.h",
     [("double th = q->omega * t, c = cos(th), s = sin(th);", "double th = -q->omega * t, c = cos(th), s = sin(th);")],
     "the drum's dummies turn against omega"),
    ("dummy_tension_kept", "walls", "src/physics/flow.h",
     [("if (stress_pressure(sd) <= 0)", "if (stress_pressure(sd) < -1e30)")],
     "the dummy stress keeps tension"),
    # ---- halo
    ("ghost_rows_unmerged", "halo", "src/cpu/nlist.c",
     [("if (s == 0 || s == c || !nlist_after", "if (1 || s == 0 || s == c || !nlist_after")],
     "a kept ghost's and an owned particle's entries are not merged by cell and rank in a followed row"),
    ("ghost_psi_stale", "halo", "src/cpu/backend_cpu.c",
     [("if (cpu_stage(s, id, c)) cpu_refresh(s, m->refresh[s->be_data && cpu_of(s)->keep][id]);",
       "if (cpu_stage(s, id, c)) cpu_refresh(s, m->refresh[s->be_data && cpu_of(s)->keep][id] & ~(id == ST_CLASSIFY ? (uint32_t)FLD_PSI : 0u));")],
     "ghost psi is not refreshed after the classification"),
    ("ghost_gdot_stale", "halo", "src/cpu/backend_cpu.c",
     [("if (cpu_stage(s, id, c)) cpu_refresh(s, m->refresh[s->be_data && cpu_of(s)->keep][id]);",
       "if (cpu_stage(s, id, c)) cpu_refresh(s, m->refresh[s->be_data && cpu_of(s)->keep][id] & ~(id == ST_FLOW ? (uint32_t)FLD_GDOT : 0u));")],
     "ghost shear rates are not refreshed before the concentration rates"),
    ("ghost_sig_stale", "halo", "src/cpu/backend_cpu.c",
     [("if (cpu_stage(s, id, c)) cpu_refresh(s, m->refresh[s->be_data && cpu_of(s)->keep][id]);",
       "if (cpu_stage(s, id, c)) cpu_refresh(s, m->refresh[s->be_data && cpu_of(s)->keep][id] & ~(id == ST_SHEPARD_STORE ? (uint32_t)FLD_SIG : 0u));")],
     "ghost stresses are not refreshed after the Shepard filter"),
    ("halo_inner_off_by_one", "halo", "mpi/halo_geom.h",
     [("if (code == HG_NOSHIFT && lo >= g->bound[g->rank] && hi < g->bound[g->rank + 1]) return n;",
       "if (code == HG_NOSHIFT && lo + 1 >= g->bound[g->rank] && hi - 1 < g->bound[g->rank + 1]) return n;")],
     "cells one column from the ghost reach are taken as inner: ghosts missing"),
    # ---- checkpoints
    ("ckpt_amax_lost", "checkpoints", "src/output/checkpoint_read.c",
     [('s->amax = ckpt_get_double(g, "Amax", 0, HUGE_VAL);', 's->amax = 0 * ckpt_get_double(g, "Amax", 0, HUGE_VAL);')],
     "a restart forgets the last |a|, so its first dt differs"),
    ("ckpt_small0_lost", "checkpoints", "src/output/checkpoint_read.c",
     [('r->small0 = ckpt_get_double(g, "SmallVolume0", -HUGE_VAL, HUGE_VAL);',
       'r->small0 = 1.000001 * ckpt_get_double(g, "SmallVolume0", -HUGE_VAL, HUGE_VAL);')],
     "a restart's conservation reference is off"),
    ("ckpt_rotation_moves", "checkpoints", "src/output/checkpoint.c",
     [("if (link(path, link_tmp) == 0) {", "if (rename(path, link_tmp) == 0) {")],
     "the rotation moves checkpoint.h5 aside instead of linking it: a kill before the next rename leaves none"),
    ("ckpt_rotation_reversed", "checkpoints", "src/output/checkpoint.c",
     [('        if (rename(tmp, path) != 0) io_write_failed("cannot rename it to %s", path);\n', ""),
      ("        if (unlink(link_tmp) != 0 && errno != ENOENT)",
       '        if (rename(tmp, path) != 0) io_write_failed("cannot rename it to %s", path);\n'
       "        if (unlink(link_tmp) != 0 && errno != ENOENT)")],
     "the rotation renames the new checkpoint first, then links it: _prev is the same file, no fallback"),
    # ---- I/O
    ("io_velocity_field", "I/O", "src/output/io.c",
     [("IO_ARRAY(io_v, p->v[c])", "IO_ARRAY(io_v, p->x[c])")],
     "snapshots write positions as Velocities"),
    ("io_no_commit", "I/O", "src/output/io.c",
     [("if (io_rank() == 0 && rename(tmp, path) != 0)", "if (io_rank() == 0 && 0 && rename(tmp, path) != 0)")],
     "a snapshot stays under its temporary name"),
    ("xdmf_time", "I/O", "src/output/io.c",
     [('fprintf(fp, "        <Time Value=\\"%.17g\\"/>\\n", time);', 'fprintf(fp, "        <Time Value=\\"%.17g\\"/>\\n", 2 * time);')],
     "the XDMF index gives each snapshot the wrong time"),
    # ---- diagnostics
    ("drift_zero", "diagnostics", "src/output/diag.c",
     [("v.drift = d->small0 != 0 ? (inside_out - d->small0) / d->small0 : inside_out;", "v.drift = 0 * inside_out;")],
     "the reported drift of sum C_i V_i is forced to 0"),
    ("drift_zero_and_leak", "diagnostics", "src/output/diag.c",
     [("v.drift = d->small0 != 0 ? (inside_out - d->small0) / d->small0 : inside_out;", "v.drift = 0 * inside_out;"),
      ("diff += w * (Di + Dj) * (Ci - Cj) * xlx;", "diff += w * (Di + Di) * (Ci - Cj) * xlx;")],
     "a real drift (2 D_i) hidden by a reported drift of 0"),
    ("small_volume_weighted", "diagnostics", "src/output/diag.c",
     [("ksum_add(&small, (double)p->C[i] * p->vol[i]);", "ksum_add(&small, (double)p->C[i] * p->vol[i] * (1 + 1e-3 * (double)(i % 2)));")],
     "sum C_i V_i is weighted wrongly"),
    ("c_min_is_max", "diagnostics", "src/output/diag.c",
     [("cmin = fmin(cmin, p->C[i]);", "cmin = fmax(cmin, p->C[i]);")],
     "the C_min column reports the largest C"),
    ("kinetic_energy_factor", "diagnostics", "src/output/diag.c",
     [("ke += 0.5 * s->sc->physics.rho * diag_mass_volume(p, i) * v2;",
       "ke += s->sc->physics.rho * diag_mass_volume(p, i) * v2;")],
     "the kinetic energy loses its factor 1/2"),
    # ---- DEM grains
    ("dem_volume_fixed", "DEM", "src/dem/dem_body.h",
     [("p->vol[a] = (real)((double)p->phi[a] / e);", "p->vol[a] = p->vol[a];")],
     "a fluid particle's volume stays V0 beside the grains (not phi / eps): the packed bed's water 28 % over hydrostatic"),
]


def locate(m):
    """[(path, old, new)] for each edit of mutant m; raises on an edit that
    does not occur exactly once in exactly one candidate file."""
    out = []
    cands = [m[2]] + sorted(set(x[2] for x in MUTANTS) - {m[2]})
    for old, new in m[3]:
        hits = [f for f in cands if open(os.path.join(ROOT, f)).read().count(old) == 1]
        if not hits or any(open(os.path.join(ROOT, f)).read().count(old) > 1 for f in cands):
            raise ValueError("mutant %s: %r does not occur exactly once" % (m[0], old[:60]))
        out.append((hits[0], old, new))
    return out


def sh(cmd, cwd, env=None, timeout=None, log=None):
    t0 = time.time()
    try:
        r = subprocess.run(cmd, cwd=cwd, env=env, shell=True, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                           text=True, timeout=timeout)
        rc, out = r.returncode, r.stdout
    except subprocess.TimeoutExpired as e:
        rc, out = 124, (e.stdout or b"").decode(errors="replace") if isinstance(e.stdout, bytes) else (e.stdout or "")
    if log:
        with open(log, "w") as f:
            f.write(out)
    return rc, out, time.time() - t0


def scratch_copy(work):
    """The working tree's tracked and untracked-not-ignored files into WORK/tree
    (mtimes kept; a fresh git index of them), plus a fake nvidia-smi listing no GPU."""
    dst = os.path.join(work, "tree")
    files = subprocess.run(["git", "ls-files", "-co", "--exclude-standard"], cwd=ROOT, capture_output=True,
                           text=True, check=True).stdout.split("\n")
    for f in filter(None, files):
        src = os.path.join(ROOT, f)
        if not os.path.isfile(src):
            continue
        os.makedirs(os.path.dirname(os.path.join(dst, f)), exist_ok=True)
        shutil.copy2(src, os.path.join(dst, f))
    # a git index of the same files: the suite's doc_links reads `git ls-files`
    # (outside a repository it fails, and would kill every mutant that got that far)
    subprocess.run(["git", "init", "-q"], cwd=dst, check=True)
    subprocess.run(["git", "add", "-A"], cwd=dst, check=True)
    fake = os.path.join(work, "nogpu")
    os.makedirs(fake, exist_ok=True)
    with open(os.path.join(fake, "nvidia-smi"), "w") as f:
        f.write("#!/bin/sh\necho 'No devices were found (tools/dev/mutants.py hides the GPU)'\nexit 6\n")
    os.chmod(os.path.join(fake, "nvidia-smi"), 0o755)
    return dst, fake


def run_mutant(m, tree, env, a, logdir):
    """Apply m in tree, build, run the suite; restore. Returns (status, detail, seconds)."""
    edits = locate(m)
    saved = {}
    for path, old, new in edits:
        full = os.path.join(tree, path)
        saved.setdefault(full, open(full).read())
        text = open(full).read()
        assert text.count(old) == 1, (m[0], path)
        with open(full, "w") as f:
            f.write(text.replace(old, new))
    t0 = time.time()
    try:
        rc, out, _ = sh("make -j%d GPU=0 all unit" % a.jobs, tree, env, 1800, os.path.join(logdir, m[0] + ".build.log"))
        if rc != 0:
            return "invalid", "does not build", time.time() - t0
        env_t = dict(env, FAIL_FAST="0" if a.keep_going else "1")
        rc, out, _ = sh("bash tests/run.sh", tree, env_t, a.timeout, os.path.join(logdir, m[0] + ".test.log"))
        fails = re.findall(r"^FAIL (\S+)", out, re.M)
        if rc == 124:
            return "killed", "timeout after %d s%s" % (a.timeout, (" (" + fails[0] + " failed first)") if fails else ""), \
                time.time() - t0
        if rc != 0:
            return "killed", ", ".join(fails) if fails else "run.sh exit %d" % rc, time.time() - t0
        last = [l for l in out.splitlines() if l.strip()][-1:]
        return "survived", last[0] if last else "", time.time() - t0
    finally:
        for full, text in saved.items():
            with open(full, "w") as f:
                f.write(text)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--list", action="store_true", help="list the mutants and check that each applies")
    ap.add_argument("--only", default=None, help="comma-separated mutant names")
    ap.add_argument("--keep-going", action="store_true", help="run the whole suite per mutant (slow)")
    ap.add_argument("--work", default="/tmp/sphseg-mutants", help="scratch directory (default %(default)s)")
    ap.add_argument("--jobs", type=int, default=2, help="make -j (default 2)")
    ap.add_argument("--threads", type=int, default=1,
                    help="OMP_NUM_THREADS of the suite (default 1: on a shared machine spinning threads cost more)")
    ap.add_argument("--timeout", type=int, default=1500, help="seconds per mutant's suite (default 1500)")
    a = ap.parse_args()
    names = [m[0] for m in MUTANTS]
    assert len(set(names)) == len(names), "duplicate mutant names"
    todo = MUTANTS
    if a.only:
        want = [n.strip() for n in a.only.split(",") if n.strip()]
        bad = [n for n in want if n not in names]
        if bad:
            ap.error("unknown mutant(s): %s" % ", ".join(bad))
        todo = [m for m in MUTANTS if m[0] in want]
    if a.list:
        ok = True
        for m in todo:
            try:
                where = ", ".join(sorted(set(p for p, _, _ in locate(m))))
                print("%-24s %-12s %-28s %s" % (m[0], m[1], where, m[4]))
            except ValueError as e:
                ok = False
                print("DOES NOT APPLY %s" % e)
        print("%d mutants" % len(todo))
        sys.exit(0 if ok else 1)
    for m in todo:
        locate(m)  # every mutant applies before anything runs
    if os.path.exists(a.work):
        shutil.rmtree(a.work)
    os.makedirs(a.work)
    logdir = os.path.join(a.work, "logs")
    os.makedirs(logdir)
    tree, fake = scratch_copy(a.work)
    env = dict(os.environ, PATH=fake + os.pathsep + os.environ["PATH"], OMP_NUM_THREADS=str(a.threads),
               OMP_WAIT_POLICY="passive")
    env.pop("REQUIRE_GPU", None)
    rc, _, sec = sh("make -j%d GPU=0 all unit" % a.jobs, tree, env, 1800, os.path.join(logdir, "baseline.build.log"))
    if rc != 0:
        sys.exit("the unmutated tree does not build: %s" % os.path.join(logdir, "baseline.build.log"))
    print("scratch copy %s built in %.0f s; %d mutants, suite %s" % (
        tree, sec, len(todo), "in full" if a.keep_going else "to the first failure"), flush=True)
    rows = []
    t_all = time.time()
    for m in todo:
        status, detail, sec = run_mutant(m, tree, env, a, logdir)
        where = ", ".join(sorted(set(p for p, _, _ in locate(m))))
        rows.append((m, where, status, detail, sec))
        print("%-8s %-24s %-12s %-24s %5.0f s  %s" % (status.upper(), m[0], m[1], where, sec, detail), flush=True)
    valid = [r for r in rows if r[2] != "invalid"]
    killed = [r for r in valid if r[2] == "killed"]
    rate = 100.0 * len(killed) / max(len(valid), 1)
    with open(os.path.join(a.work, "mutants.md"), "w") as f:
        f.write("| mutant | area | where | what | result |\n| --- | --- | --- | --- | --- |\n")
        for m, where, status, detail, sec in rows:
            f.write("| %s | %s | `%s` | %s | %s%s |\n" % (m[0], m[1], where, m[4],
                                                          "killed by " if status == "killed" else status + ": ",
                                                          detail))
    print("\nkill rate: %d of %d mutants killed (%.1f %%)%s; %.0f s; table in %s" % (
        len(killed), len(valid), rate,
        "" if len(valid) == len(rows) else ", %d that do not build left out" % (len(rows) - len(valid)),
        time.time() - t_all, os.path.join(a.work, "mutants.md")))
    for m, where, status, detail, sec in rows:
        if status == "survived":
            print("survivor: %s (%s): %s" % (m[0], where, m[4]))
    sys.exit(0)


if __name__ == "__main__":
    main()
