#!/usr/bin/env python3
"""What a restart refuses (issue 19, defects 5, 6, 7; issue 33, defects 3,
4): every refusal is exit status 2 and one "sphseg: error: --restart ..."
line, in bounded time, on 1, 2 and 3 ranks; never exit 0 on a damaged file,
1, a crash or a hang.

- foreign scenes: a checkpoint restarted with another dr, or the drum's
  with the shear box scene and the reverse, is refused naming each
  state-defining key that differs; run-control keys may differ and are
  listed; model keys are a warning; a key newer than the checkpoint
  (Material:yield, issue 30) is the checkpoint's state at its default and
  refused at another value;
- damaged files: a few hundred byte-fuzzed mutants of a checkpoint (bytes
  changed, cut short, extended) are refused by the checksum before HDF5
  reads them;
- crafted files (changed with h5py, then sealed again with the documented
  checksum, so that only the reader's checks stand between them and the
  run): NaN time, NumRanks 0, Kind 255, missing, retyped and reshaped
  datasets, absurd counts... each refused with a located reason;
- several ranks: a bad row that only the last rank reads (Kind 255 in the
  last particle), and a byte-damaged file, end every rank with one line
  from rank 0 within the time limit, on 2 and 3 ranks;
- the seal checks itself (issue 33, defect 3): one bit flipped in
  checkpoint_prev.h5's seal step (3 -> 11, past checkpoint.h5's 6) no longer
  wins over checkpoint.h5, and the warning says why it was passed over; the
  same flip in checkpoint.h5 gives checkpoint_prev.h5 with a reason; a flip
  in any other seal word (format, size, sum, step, time, check, reserved) is
  refused alone and passed over beside a good checkpoint.h5; legacy seals
  (check word 0) are taken, but one whose step disagrees with /Header is
  refused, and a legacy checkpoint.h5 older than checkpoint_prev.h5 says so;
- files without a seal (issue 55, defect 3): a snapshot is refused as a
  snapshot of sphseg VERSION (the version written whole), a checkpoint's HDF5
  part alone as a checkpoint without its checksum block, one whose seal is
  overwritten as damaged, a text file as no HDF5 file;
- FIFOs (issue 33, defect 4): --restart FIFO, and a DIR whose checkpoint.h5
  is a FIFO, exit 2 with one line at once on 1 and 3 ranks, not blocked in
  open() (a run past 60 s is a failure; the test then opens the FIFO for
  writing so that the blocked ranks end); a FIFO checkpoint_prev.h5 beside a
  good checkpoint.h5 is passed over.

    /usr/bin/python3 -m tests.test_restart_guard --sphseg build/sphseg --work DIR [--mutants 300]
"""
import argparse
import concurrent.futures
import os
import random
import shutil
import subprocess
import sys
import time

import h5py
import numpy as np

from tests.ckpt_seal import reseal  # noqa: E402

MPI = ["mpirun", "--oversubscribe", "--allow-run-as-root"]
SHEAR, DRUM = "inputs/shearbox_2d.yml", "inputs/drum_2d_EV.yml"
FAILS = []


def check(name, ok, detail=""):
    print(("PASS " if ok else "FAIL ") + name)
    if not ok:
        FAILS.append(name)
        if detail:
            print("    " + detail.strip().replace("\n", "\n    ")[-1500:])


def run(cmd, timeout=120):
    t0 = time.time()
    env = dict(os.environ, OMP_NUM_THREADS="1")
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, errors="replace", timeout=timeout, env=env)
        return p.returncode, p.stdout, p.stderr, time.time() - t0
    except subprocess.TimeoutExpired as e:  # its output comes undecoded
        text = [x.decode(errors="replace") if isinstance(x, bytes) else x or "" for x in (e.stdout, e.stderr)]
        return "timeout", text[0], text[1], time.time() - t0


def refused(res, what, limit=60):
    rc, out, err, dt = res
    lines = [l for l in err.splitlines() if l.startswith("sphseg: error")]
    ok = rc == 2 and len(lines) == 1 and "--restart" in lines[0] and dt < limit
    return ok, f"{what}: rc {rc}, {dt:.1f} s, stderr:\n{err}\n{out[-300:]}"


def make_checkpoint(sp, work, name, scene, np_, extra):
    out = os.path.join(work, name)
    cmd = ([] if np_ == 1 else MPI + ["-np", str(np_)]) + [sp, scene, "-o", out] + extra
    rc, o, e, _ = run(cmd)
    if rc != 0 or not os.path.exists(out + "/checkpoint.h5"):
        sys.exit(f"cannot make {name}: rc {rc}\n{e}")
    return out + "/checkpoint.h5"


def restart(sp, work, ck, scene=SHEAR, np_=1, extra=(), timeout=120):
    out = os.path.join(work, "r_%d" % random.randrange(1 << 30))
    cmd = ([] if np_ == 1 else MPI + ["-np", str(np_)]) + [sp, scene, "-o", out, "--restart", ck]
    return run(cmd + list(extra), timeout)


# ---- crafted mutants: (name, function(h5py.File), expected words) ----------

def set_attr(path, value, dtype=None):
    grp, _, name = path.rpartition("/")

    def f(h):
        g = h[grp] if grp else h
        del g.attrs[name]
        if dtype is None:
            g.attrs[name] = value
        else:
            g.attrs.create(name, value, dtype=dtype)
    return f


def replace_dataset(path, make):
    def f(h):
        old = h[path][()]
        del h[path]
        h[path] = make(old)
    return f


def set_row(path, row, value):
    def f(h):
        d = h[path]
        a = d[()]
        a[row] = value
        d[...] = a
    return f


def kind_name(h):
    return [k for k in sorted(h["Particles"]) if k != "RankCounts" and h["Particles"][k].dtype.itemsize == 1][0]


def crafted():
    nan_bits = np.uint64(0x7FF8000000000000)
    return [
        ("Time = NaN", set_attr("Header/Time", np.float64("nan")), "Time = nan is out of range"),
        ("Time < 0", set_attr("Header/Time", -1.0), "Time = -1 is out of range"),
        ("Dt = inf", set_attr("Header/Dt", np.float64("inf")), "Dt = inf"),
        ("Step < 0", set_attr("Header/Step", np.int64(-5)), "Step = -5"),
        ("NumRanks = 0", set_attr("Header/NumRanks", np.int64(0)), "NumRanks = 0"),
        ("NumPart_Total = 1e15", set_attr("Header/NumPart_Total", np.int64(10**15)), "NumPart_Total"),
        ("Dimension = 7", set_attr("Header/Dimension", np.int64(7)), "Dimension = 7"),
        ("Checkpoint format 1", set_attr("Header/Checkpoint", np.int64(1)), "Checkpoint = 1"),
        ("Time as a string", set_attr("Header/Time", "0.5"), "attribute Time is not a scalar"),
        ("Time as int32", set_attr("Header/Time", 1, dtype="<i4"), "attribute Time is not a scalar"),
        ("Code other", set_attr("Header/Code", "other"), "Code is 'other'"),
        ("Precision single", set_attr("Header/Precision", "single"), "single-precision build"),
        ("no /Header", lambda h: h.__delitem__("Header"), "no group /Header"),
        ("/Particles a dataset", lambda h: (h.__delitem__("Particles"), h.create_dataset("Particles", data=[1])),
         "/Particles is not a group"),
        ("dataset 05 missing", lambda h: h["Particles"].__delitem__("05"), "dataset 05 missing"),
        ("dataset 05 as floats", replace_dataset("Particles/05", lambda a: a.view("<f8")), "dataset 05 does not hold"),
        ("dataset 05 short", replace_dataset("Particles/05", lambda a: a[:-1]), "dataset 05 has the wrong shape"),
        ("dataset 05 2D", replace_dataset("Particles/05", lambda a: a.reshape(-1, 1)), "dataset 05 has the wrong shape"),
        ("RankCounts sum", set_row("Particles/RankCounts", 0, 7), "RankCounts sum to"),
        ("Kind 255", lambda h: set_row("Particles/" + kind_name(h), 3, 255)(h), "is out of range (kind 255"),
        ("x NaN", set_row("Particles/00", 5, nan_bits), "non-finite position"),
        ("Outputs Count 1e9", set_attr("Outputs/Count", np.int64(10**9)), "Count = 1000000000"),
        ("Outputs Times NaN", set_row("Outputs/Times", 0, np.nan), "/Outputs row 0"),
        ("Warned 7", set_attr("Diagnostics/Warned", np.int64(7)), "Warned = 7"),
        ("Scene dr changed", lambda h: set_attr("Header/Scene", h["Header"].attrs["Scene"].replace(
            "  dr: 0.00348", "  dr: 0.005"))(h), "Geometry:dr (0.005 in the checkpoint, 0.00348 now)"),
    ]


def mutate_bytes(src, dst, rng):
    data = bytearray(open(src, "rb").read())
    kind = rng.random()
    if kind < 0.08:
        data = data[: rng.randrange(len(data))]
    elif kind < 0.12:
        data += bytes(rng.randrange(256) for _ in range(rng.randrange(1, 64)))
    else:
        for _ in range(rng.randrange(1, 5)):
            data[rng.randrange(len(data))] ^= rng.randrange(1, 256)
    open(dst, "wb").write(data)


# ---- issue 33: the seal's own words; FIFOs ---------------------------------

SEAL_WORDS = ["magic", "format", "size", "sum", "step", "time", "check", "reserved"]


def seal_word(path, name):
    with open(path, "rb") as f:
        f.seek(8 * SEAL_WORDS.index(name))
        return int.from_bytes(f.read(8), "little")


def flip_seal(path, name, bit):
    """Flip one bit of a seal word in place."""
    k = 8 * SEAL_WORDS.index(name) + bit // 8
    with open(path, "r+b") as f:
        f.seek(k)
        b = f.read(1)[0] ^ (1 << (bit % 8))
        f.seek(k)
        f.write(bytes([b]))


def pair(work, name, src, legacy=False):
    """A directory holding copies of src's checkpoint.h5 and checkpoint_prev.h5
    (legacy: both sealed as before the check existed, check word 0)."""
    d = os.path.join(work, name)
    os.makedirs(d)
    for f in ("checkpoint.h5", "checkpoint_prev.h5"):
        shutil.copy(os.path.join(src, f), d)
        if legacy:
            reseal(os.path.join(d, f), legacy=True)
    return d


def took(res, path):
    """The restart ran (exit 0) from path; the warnings it gave."""
    rc, out, err, dt = res
    warns = [l for l in err.splitlines() if l.startswith("sphseg: warning: --restart")]
    return rc == 0 and f"restart from {path}: step" in out, warns, f"rc {rc}, {dt:.1f} s\n{err}\n{out[-400:]}"


def without_line(work, drum, name, line):
    """A copy of checkpoint drum, resealed, whose stored scene lacks line (a
    checkpoint written before that key existed); whether the line was there."""
    old = os.path.join(work, name)
    shutil.copy(drum, old)
    with h5py.File(old, "r+") as h:
        text = h["Header"].attrs["Scene"]
        set_attr("Header/Scene", text.replace(line, ""))(h)
    reseal(old)
    return old, line in text


def test_key_newer(sp, work, drum):
    """A checkpoint written before a key existed (issue 30: Material:yield): its
    scene text lacks the key; at the key's default (the behaviour the code had)
    it restarts, at another value it is refused naming the key (a state key) or
    continues with a warning naming it (a model key: Flow:stabilization)."""
    old, ok = without_line(work, drum, "before_yield.h5", "  yield: drucker_prager\n")
    more = ["-P", "Geometry:dr=0.004", "-P", "Run:max_steps=3", "-P", "Output:checkpoint_dt=1"]
    rc, out, err, _ = restart(sp, work, old, DRUM, extra=more)
    check("a checkpoint from before Material:yield restarts as drucker_prager (its default)",
          ok and rc == 0 and "Material:yield" not in out + err, f"rc {rc}\n{err}\n{out[-400:]}")
    ok, why = refused(restart(sp, work, old, DRUM, extra=more + ["-P", "Material:yield=mu_I"]), "mu_I")
    check("... and is refused as mu_I, naming Material:yield",
          ok and "Material:yield ((absent) in the checkpoint, mu_I now)" in why, why)
    # Segregation:limiter came with a default (donor) that is not what the code did before it (none)
    old, ok = without_line(work, drum, "before_limiter.h5", "  limiter: donor\n")
    rc, out, err, _ = restart(sp, work, old, DRUM, extra=more)
    check("a checkpoint from before Segregation:limiter restarted at its default (donor) says the key changed "
          "(the code before capped nothing)",
          ok and "Segregation:limiter ((absent) in the checkpoint, donor now)" in out + err, f"rc {rc}\n{err}\n{out[-400:]}")
    rc, out, err, _ = restart(sp, work, old, DRUM, extra=more + ["-P", "Segregation:limiter=none"])
    check("... and restarted with limiter none (the old behaviour) says nothing of it",
          rc == 0 and "Segregation:limiter" not in out + err, f"rc {rc}\n{err}\n{out[-400:]}")
    # Flow:stabilization came with its default monaghan (the code before it), but the drum scene now sets
    # riemann: a run of it from before the key continues under riemann, with the warning that says so
    old, ok = without_line(work, drum, "before_stabilization.h5", "  stabilization: riemann\n")
    rc, out, err, _ = restart(sp, work, old, DRUM, extra=more)
    check("a checkpoint from before Flow:stabilization restarted with the drum scene (riemann) warns that the model "
          "key changed", ok and rc == 0 and "Flow:stabilization ((absent) in the checkpoint, riemann now)" in err,
          f"rc {rc}\n{err}\n{out[-400:]}")
    rc, out, err, _ = restart(sp, work, old, DRUM, extra=more + ["-P", "Flow:stabilization=monaghan"])
    check("... and restarted with monaghan (the code before the key) says nothing of it",
          rc == 0 and "Flow:stabilization" not in out + err, f"rc {rc}\n{err}\n{out[-400:]}")


def test_seal_flips(sp, work, src, run_ok):
    """Defect 3: a flipped seal step chooses no checkpoint; every reason is said."""
    cur, prev = seal_word(src + "/checkpoint.h5", "step"), seal_word(src + "/checkpoint_prev.h5", "step")
    up = cur.bit_length()  # prev's step with this bit set passes checkpoint.h5's
    d = pair(work, "flip_prev", src)
    flip_seal(d + "/checkpoint_prev.h5", "step", up)
    ok, warns, why = took(restart(sp, work, d, extra=run_ok), d + "/checkpoint.h5")
    check(f"seal: checkpoint_prev.h5's step flipped ({prev} -> {prev ^ 1 << up}, past {cur}): checkpoint.h5 "
          "taken, the warning says why checkpoint_prev.h5 was passed over", ok and len(warns) == 1 and
          "checkpoint_prev.h5: damaged: its checksum block is corrupted" in warns[0], why)
    d = pair(work, "flip_cur", src)
    flip_seal(d + "/checkpoint.h5", "step", up)
    ok, warns, why = took(restart(sp, work, d, extra=run_ok), d + "/checkpoint_prev.h5")
    check("seal: checkpoint.h5's step flipped: checkpoint_prev.h5 taken, with the reason",
          ok and len(warns) == 1 and "checkpoint.h5: damaged: its checksum block is corrupted" in warns[0]
          and "taking checkpoint_prev.h5" in warns[0], why)


def test_seal_legacy(sp, work, src, run_ok):
    """Legacy seals (check 0): taken; /Header's step stands behind their step."""
    cur, prev = seal_word(src + "/checkpoint.h5", "step"), seal_word(src + "/checkpoint_prev.h5", "step")
    d = pair(work, "legacy", src, legacy=True)
    ok, warns, why = took(restart(sp, work, d, extra=run_ok), d + "/checkpoint.h5")
    check("seal: legacy seals (check 0) are taken: checkpoint.h5, no warning", ok and not warns, why)
    d = pair(work, "legacy_flip_prev", src, legacy=True)
    flip_seal(d + "/checkpoint_prev.h5", "step", cur.bit_length())
    ok, why = refused(restart(sp, work, d, extra=run_ok), "legacy prev flipped")
    check("seal: a legacy checkpoint_prev.h5 whose seal step is flipped past checkpoint.h5's: refused, "
          "its seal and /Header disagree", ok and f"says step {prev ^ 1 << cur.bit_length()}" in why
          and f"/Header says step {prev}" in why, why)
    low = cur.bit_length() - 1  # clearing checkpoint.h5's top bit puts it below checkpoint_prev.h5's step
    d = pair(work, "legacy_flip_cur", src, legacy=True)
    flip_seal(d + "/checkpoint.h5", "step", low)
    ok, warns, why = took(restart(sp, work, d, extra=run_ok), d + "/checkpoint_prev.h5")
    check(f"seal: a legacy checkpoint.h5 whose step reads {cur ^ 1 << low} < {prev}: checkpoint_prev.h5 taken, "
          "the warning says checkpoint.h5 is older", cur ^ 1 << low < prev and ok and len(warns) == 1 and
          f"checkpoint.h5: step {cur ^ 1 << low}, older than checkpoint_prev.h5 (step {prev})" in warns[0], why)


def test_seal_words(sp, work, src, run_ok):
    """A bit flipped in each seal word: refused alone, passed over beside a good checkpoint.h5."""
    jobs = []
    for k, name in enumerate(SEAL_WORDS[1:]):
        bit = (5 + 11 * k) % 64  # a different bit in each word
        one = os.path.join(work, f"word_{name}.h5")
        shutil.copy(src + "/checkpoint.h5", one)
        flip_seal(one, name, bit)
        d = pair(work, f"word_{name}", src)
        flip_seal(d + "/checkpoint_prev.h5", name, bit)
        jobs.append((name, bit, one, d))

    def one_job(j):
        name, bit, one, d = j
        return refused(restart(sp, work, one, extra=run_ok, timeout=60), name), took(
            restart(sp, work, d, extra=run_ok, timeout=60), d + "/checkpoint.h5")
    with concurrent.futures.ThreadPoolExecutor(2) as ex:
        res = list(ex.map(one_job, jobs))
    # the user block past the seal: written as zero and covered by neither the seal's check nor the
    # checksum (a flip there was taken until the reader checked it; the byte fuzz met one at byte 474)
    pad = os.path.join(work, "userblock_pad.h5")
    shutil.copy(src + "/checkpoint.h5", pad)
    with open(pad, "r+b") as f:
        f.seek(474)
        f.write(bytes([0x20]))
    ok, why = refused(restart(sp, work, pad, extra=run_ok, timeout=60), "user block")
    check("seal: a byte of the user block past the seal set: refused alone",
          ok and "user block past the checksum block is not blank" in why, why)
    for (name, bit, one, d), ((ok1, why1), (ok2, warns, why2)) in zip(jobs, res):
        check(f"seal: {name} word, bit {bit} flipped: refused alone (checksum block corrupted)",
              ok1 and "damaged: its checksum block is corrupted" in why1, why1)
        check(f"seal: {name} word, bit {bit} flipped in checkpoint_prev.h5: passed over, saying why",
              ok2 and len(warns) == 1 and "checkpoint_prev.h5: damaged: its checksum block" in warns[0], why2)


def restart_fifo(sp, work, target, fifo, np_=1, extra=(), timeout=60):
    """restart(), but a run blocked past timeout on fifo is released (the FIFO
    opened for writing and closed: the blocked open returns) and then killed,
    so that no rank is left behind; its result is then "timeout"."""
    out = os.path.join(work, "r_%d" % random.randrange(1 << 30))
    cmd = ([] if np_ == 1 else MPI + ["-np", str(np_)]) + [sp, SHEAR, "-o", out, "--restart", target] + list(extra)
    t0 = time.time()
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, errors="replace",
                         start_new_session=True, env=dict(os.environ, OMP_NUM_THREADS="1"))
    try:
        o, e = p.communicate(timeout=timeout)
        return p.returncode, o, e, time.time() - t0
    except subprocess.TimeoutExpired:
        try:
            os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
        except OSError:
            pass
        try:
            o, e = p.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, 9)
            o, e = p.communicate()
        return "timeout", o, e, time.time() - t0


def test_fifos(sp, work, src, run_ok):
    """Defect 4: a FIFO given to --restart, or named checkpoint.h5 in its
    directory, is refused at once: no rank waits in open() for a writer."""
    fifo = os.path.join(work, "fifo.h5")
    os.mkfifo(fifo)
    d = os.path.join(work, "fifo_dir")
    os.makedirs(d)
    os.mkfifo(d + "/checkpoint.h5")
    for n in (1, 3):
        ok, why = refused(restart_fifo(sp, work, fifo, fifo, n, run_ok), f"FIFO, {n} rank(s)")
        check(f"--restart FIFO on {n} rank(s): exit 2, one line, not a regular file",
              ok and "not a regular file" in why, why)
        ok, why = refused(restart_fifo(sp, work, d, d + "/checkpoint.h5", n, run_ok), f"DIR/FIFO, {n} rank(s)")
        check(f"--restart DIR whose checkpoint.h5 is a FIFO, {n} rank(s): exit 2, one line",
              ok and "checkpoint.h5: not a regular file" in why, why)
    d = pair(work, "fifo_prev", src)
    os.remove(d + "/checkpoint_prev.h5")
    os.mkfifo(d + "/checkpoint_prev.h5")
    ok, warns, why = took(restart_fifo(sp, work, d, d + "/checkpoint_prev.h5", 1, run_ok), d + "/checkpoint.h5")
    check("--restart DIR whose checkpoint_prev.h5 is a FIFO: checkpoint.h5 taken, the FIFO passed over",
          ok and len(warns) == 1 and "checkpoint_prev.h5: not a regular file" in warns[0], why)


def test_not_checkpoints(sp, work, src, run_ok):
    """Issue 55, defect 3: a file without a seal is said for what it is, with the
    version that wrote it as written (a snapshot was 'a checkpoint of sphseg 0.1'
    from sphseg 0.1.0): a snapshot; a checkpoint's HDF5 part alone (as before the
    seal: its version and format); a checkpoint whose seal is overwritten
    (damaged: HDF5 reads none of it); not HDF5 at all."""
    version = run([sp, "--version"])[1].split()[-1]
    snap = os.path.join(src, "snapshot_00001.h5")
    with h5py.File(snap, "r") as h:
        step, t = int(h["Header"].attrs["Step"]), float(h["Header"].attrs["Time"])
    ok, why = refused(restart(sp, work, snap, extra=run_ok), "snapshot")
    check(f"a snapshot: refused as a snapshot of sphseg {version} (step {step}), not a checkpoint",
          ok and f"not a sphseg checkpoint: a snapshot of sphseg {version} (step {step}, t = {t:.9g} s)" in why
          and "holds no run state" in why and "sphseg 0.1)" not in why, why)
    bare = os.path.join(work, "unsealed.h5")
    with h5py.File(src + "/checkpoint.h5", "r") as a, h5py.File(bare, "w") as b:
        for k in a:
            a.copy(k, b)
        fmt = int(a["Header"].attrs["Checkpoint"])
    ok, why = refused(restart(sp, work, bare, extra=run_ok), "unsealed")
    check(f"a checkpoint's HDF5 part without its seal: a checkpoint of sphseg {version} (format {fmt}) without "
          "its checksum block", ok and f"a checkpoint of sphseg {version} (format {fmt}, step" in why
          and "without its checksum block" in why, why)
    over = os.path.join(work, "seal_overwritten.h5")
    shutil.copy(src + "/checkpoint.h5", over)
    with open(over, "r+b") as f:
        f.write(b"\0" * 64)
    ok, why = refused(restart(sp, work, over, extra=run_ok), "seal zeroed")
    check("a checkpoint whose seal is overwritten: damaged, checksum block missing",
          ok and "damaged: its checksum block is missing or overwritten" in why, why)
    ok, why = refused(restart(sp, work, os.path.join(src, "used_params.yml"), extra=run_ok), "yml")
    check("a text file: not a sphseg checkpoint, not an HDF5 file",
          ok and "not a sphseg checkpoint (no checksum block, and not an HDF5 file)" in why, why)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sphseg", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--mutants", type=int, default=300)
    a = ap.parse_args()
    sp, work = os.path.abspath(a.sphseg), a.work
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    random.seed(19)
    small = ["-P", "Geometry:dr=0.00348", "-P", "Run:t_end=1", "-P", "Output:dt=0.5", "-P", "Output:checkpoint_dt=0.5"]
    ck = {n: make_checkpoint(sp, work, f"shear{n}", SHEAR, n, small) for n in (1, 2, 3)}
    drum = make_checkpoint(sp, work, "drum", DRUM, 1, ["-P", "Geometry:dr=0.004", "-P", "Run:max_steps=2",
                                                       "-P", "Output:checkpoint_dt=1"])
    base = ["-P", "Geometry:dr=0.00348", "-P", "Output:dt=0.5", "-P", "Output:checkpoint_dt=0.5"]

    # defect 5: another scene's state
    ok, why = refused(restart(sp, work, ck[1], extra=["-P", "Geometry:dr=0.003", "-P", "Run:t_end=2"]), "dr")
    check("another dr: refused naming Geometry:dr", ok and "Geometry:dr (0.00348 in the checkpoint, 0.003 now)"
          in why and "1 state-defining key(s)" in why, why)
    ok, why = refused(restart(sp, work, drum, SHEAR, extra=["-P", "Run:t_end=2"]), "drum -> shear box")
    check("the drum's checkpoint with the shear-box scene: refused naming each key",
          ok and "Geometry:type (drum in the checkpoint, shearbox now)" in why and "Kinematics:velocity" in why, why)
    ok, why = refused(restart(sp, work, ck[1], DRUM, extra=base), "shear box -> drum")
    check("the shear box's checkpoint with the drum scene: refused", ok and "Geometry:type" in why, why)
    rc, out, err, _ = restart(sp, work, ck[1], extra=base + ["-P", "Run:t_end=1.5", "-P", "Segregation:D=2e-7"])
    check("run-control keys listed, model keys a warning, the run goes on",
          rc == 0 and "run-control key(s) differ" in out and "Run:t_end (1 in the checkpoint, 1.5 now)" in out
          and "Segregation:D" in err and "model key(s) differ" in err, out[-800:] + err)
    test_key_newer(sp, work, drum)

    # defect 6: crafted, resealed
    for name, fn, words in crafted():
        path = os.path.join(work, "crafted.h5")
        shutil.copy(ck[1], path)
        with h5py.File(path, "r+") as h:
            fn(h)
        reseal(path)
        ok, why = refused(restart(sp, work, path, extra=base + ["-P", "Run:t_end=1.5"]), name)
        check(f"crafted: {name}: exit 2, one line", ok and words in why, why + f"\n(expected: {words})")

    # defect 6: byte fuzz, two at a time
    rng = random.Random(1919)
    paths = []
    for k in range(a.mutants):
        p = os.path.join(work, f"mutant_{k:04d}.h5")
        mutate_bytes(ck[1], p, rng)
        paths.append(p)
    t0 = time.time()
    with concurrent.futures.ThreadPoolExecutor(2) as ex:
        res = list(ex.map(lambda p: refused(restart(sp, work, p, extra=base + ["-P", "Run:t_end=1.5"], timeout=60),
                                            p), paths))
    bad = [why for ok, why in res if not ok]
    check(f"byte fuzz: {a.mutants} mutants, each exit 2 with one line ({time.time() - t0:.0f} s)", not bad,
          "\n".join(bad[:3]))

    # defect 7: several ranks, an error only one rank sees, and a damaged file
    for n in (2, 3):
        path = os.path.join(work, f"lastrow{n}.h5")
        shutil.copy(ck[n], path)
        with h5py.File(path, "r+") as h:
            set_row("Particles/" + kind_name(h), -1, 255)(h)
        reseal(path)
        ok, why = refused(restart(sp, work, path, np_=n, extra=base + ["-P", "Run:t_end=1.5"], timeout=90),
                          f"{n} ranks", limit=30)
        check(f"{n} ranks: Kind 255 in the last rank's rows: every rank ends, one line from rank 0, < 30 s",
              ok and f"rank {n - 1}: --restart" in why, why)
        path = os.path.join(work, f"bytes{n}.h5")
        mutate_bytes(ck[n], path, random.Random(n))
        ok, why = refused(restart(sp, work, path, np_=n, extra=base + ["-P", "Run:t_end=1.5"], timeout=90),
                          f"{n} ranks damaged", limit=30)
        check(f"{n} ranks: a byte-damaged checkpoint: exit 2, one line, < 30 s", ok, why)

    # issue 33: the seal checks itself (defect 3); FIFOs (defect 4)
    run_ok = base + ["-P", "Run:t_end=1.5"]
    src = os.path.dirname(ck[1])
    test_seal_flips(sp, work, src, run_ok)
    test_seal_legacy(sp, work, src, run_ok)
    test_seal_words(sp, work, src, run_ok)
    test_fifos(sp, work, src, run_ok)
    test_not_checkpoints(sp, work, src, run_ok)
    print(f"{len(FAILS)} failed")
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
