# issue 30: the rows of docs/data/gpu/time_to_solution_pair.csv from the runs here (README.md): each setting's
# GPU-hours per revolution (time_to_solution run, single build, one H100) and its 2D EV drum errors (double build),
# the means over t = 3, 4, 5 s of the mid-chord's largest speed and of the segregation index, against the pair's
# dr 0.25-mm, E 0.1-MPa run (call2/k025e5.ana) and, for comparison, against the reference of
# docs/data/gpu/time_to_solution_riemann.csv (riemann + bed damping at dr 0.125 mm).
# python3 docs/data/stabilization/pair_default/tts_rows.py  (from the repository root)
import csv
import os
import re

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", "..", "..", ".."))
DAMP = os.path.join(ROOT, "docs", "data", "stabilization", "bed_noise", "damping")
OLD_REF = os.path.join(ROOT, "docs", "data", "stabilization", "dr_dependence", "ref0125", "ref.ana")
ROW = re.compile(r"^\s+(\d+\.\d+)\s+[\d.]+°\s+[\d.]+ dr\s+([\d.]+) cm/s\s+([-\d.]+) ")


def rows_of(lines):
    out = {}
    for l in lines:
        m = ROW.match(l)
        if m:
            out[float(m.group(1))] = (float(m.group(2)), float(m.group(3)))
    return out


def tail_blocks():
    """The .ana rows printed in call1/output_tail.txt, by tag (the files of those runs did not come back)."""
    blocks, tag = {}, None
    for l in open(os.path.join(HERE, "call1", "output_tail.txt")):
        m = re.match(r"== \S+/(\w+)\.ana", l)
        if m:
            tag = m.group(1)
            blocks[tag] = []
        elif tag:
            blocks[tag].append(l)
    return {t: rows_of(b) for t, b in blocks.items()}


def means(rows):
    ts = (3.0, 4.0, 5.0)
    if not all(t in rows for t in ts):
        return None
    return sum(rows[t][0] for t in ts) / 3, sum(rows[t][1] for t in ts) / 3


def hours():
    h = {}
    for l in open(os.path.join(HERE, "call1", "output_tail.txt")):
        m = re.match(r"(\w+): ([\d.]+) GPU-hours per revolution", l)
        if m:
            h[m.group(1)] = float(m.group(2))
    return h


def main():
    tb, H = tail_blocks(), hours()
    ana = lambda p: rows_of(open(p).readlines())
    ref = means(ana(os.path.join(HERE, "call2", "k025e5.ana")))
    old = means(ana(OLD_REF))
    src_ref = "docs/data/stabilization/pair_default/call2/k025e5.ana (the pair, dr 0.25 mm, E 0.1 MPa, chi 0.2, double)"
    cases = [  # label, E, hours, how the hours were had, errors' rows, their source
        ("riemann + bed damping (the scenes until now), dr 0.5 mm, E 0.1 MPa, cfl 0.2, single", 1e5,
         H["p05e4"] * 10 ** 0.5, "p05e4 (E 10 kPa) times sqrt(10): the rate at 10 kPa, the step of 0.1 MPa",
         ana(os.path.join(DAMP, "b05e5a1_10s.ana")), "docs/data/stabilization/bed_noise/damping/b05e5a1_10s.ana"),
        ("riemann + bed damping (the scenes until now), dr 0.25 mm, E 10 kPa, cfl 0.2, single", 1e4, H["p025e4"],
         "p025e4", ana(os.path.join(DAMP, "b025e4a1t.ana")), "docs/data/stabilization/bed_noise/damping/b025e4a1t.ana"),
        ("riemann + bed damping (the scenes until now), dr 0.2 mm, E 0.1 MPa, cfl 0.2, single", 1e5, 50.48,
         "docs/data/stabilization/bed_noise/damping/tts_dr02_h100.txt (an earlier call, one H100)",
         ana(os.path.join(DAMP, "b02e5a1.ana")), "docs/data/stabilization/bed_noise/damping/b02e5a1.ana"),
        ("the pair (the drum scenes), dr 0.5 mm, E 10 kPa, cfl 0.2, single", 1e4, H["k05e4"], "k05e4", tb["k05e4"],
         "call1/output_tail.txt k05e4"),
        ("the pair (the drum scenes), dr 0.5 mm, E 30 kPa, cfl 0.2, single", 3e4, H["k05e3"], "k05e3", tb["k05e3"],
         "call1/output_tail.txt k05e3"),
        ("the pair (the drum scenes), dr 0.5 mm, E 0.1 MPa, cfl 0.2, single", 1e5, H["k05e5"], "k05e5", tb["k05e5"],
         "call1/output_tail.txt k05e5"),
        ("the pair (the drum scenes), dr 0.25 mm, E 10 kPa, cfl 0.2, single", 1e4, H["k025e4"], "k025e4",
         ana(os.path.join(HERE, "call1", "k025e4.ana")), "call1/k025e4.ana"),
        ("the pair (the drum scenes), dr 0.25 mm, E 0.1 MPa, cfl 0.2, single (the reference's setting)", 1e5,
         H["k025e5"], "k025e5", ana(os.path.join(HERE, "call2", "k025e5.ana")), "call2/k025e5.ana"),
    ]
    out = os.path.join(ROOT, "docs", "data", "gpu", "time_to_solution_pair.csv")
    with open(out, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(("label", "E_Pa", "alpha_av", "cfl_flow", "every", "gpu_hours_per_rev", "speed_err", "seg_err",
                    "t_s", "source"))
        for label, E, h, hsrc, rows, esrc in cases:
            m = means(rows)
            se, ge = m[0] / ref[0] - 1, m[1] / ref[1] - 1
            so, go = m[0] / old[0] - 1, m[1] / old[1] - 1
            w.writerow((label, E, "", 0.2, "auto", "%.4g" % h, "%.4f" % se, "%.4f" % ge, "3-5",
                        "hours: %s (docs/data/stabilization/pair_default/call1/output_tail.txt unless named); "
                        "error: %s against %s; means of t = 3-5 s: %.3f vs %.3f cm/s, %.4f vs %.4f; against "
                        "riemann + bed damping at dr 0.125 mm (docs/data/stabilization/dr_dependence/ref0125/"
                        "ref.ana): %+.1f %%, %+.1f %%" % (hsrc, esrc, src_ref, m[0], ref[0], m[1], ref[1],
                                                           100 * so, 100 * go)))
            print("%-100s %7.3g h  speed %+5.1f %%  seg %+5.1f %%   (old ref: %+5.1f %%, %+5.1f %%)"
                  % (label, h, 100 * se, 100 * ge, 100 * so, 100 * go))
    print("wrote", out)


if __name__ == "__main__":
    main()
