#!/usr/bin/env bash
# test_own_scene.sh BINARY [PAGE] — docs/own_scene.md (or PAGE) runs as written.
# Every ```bash block of the page runs, in order, in a scratch folder that looks
# like the repository root (build -> BINARY's folder, inputs, tools; python3 ->
# $PYTHON), each with bash -e -o pipefail; a block that exits non-zero fails the
# test and stops it. A ```text block right after a bash block is what that block
# prints: each of its lines must appear in the block's output (stdout and
# stderr). Then the facts the page states, checked independently of it:
#   - fill = (H + R)/2R: the page's area share for fill 0.35 is the formula's, and
#     the run's material count is the lattice's own (sites r <= R - dr/2, y <= H);
#   - the mixed start has uniform C (diagnostics row 0 and snapshot 0), the layered
#     one C 0 below and 1 above y = -R + split (H + R), site by site in count;
#   - the hopper's gate opened and grains left through the outlet, sum C V conserved;
#   - the restart continued the run to the page's t_end;
#   - the runner itself: a block with a misspelt key fails.
# Prints PASS/FAIL per check; exits 1 on any FAIL.
set -u
bin=${1:?usage: $0 BINARY [PAGE]}
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/.." && pwd)
page=${2:-$root/docs/own_scene.md}
. "$here/testlib.sh" # $tmp (removed at exit), $fail, check NAME CONDITION
PY=${PYTHON:-/usr/bin/python3}
work=$tmp/work
mkdir -p "$work" "$tmp/bin" "$tmp/blocks"
ln -s "$(cd "$(dirname "$bin")" && pwd)" "$work/build"
ln -s "$root/inputs" "$work/inputs"
ln -s "$root/tools" "$work/tools"
ln -s "$PY" "$tmp/bin/python3"
export PATH="$tmp/bin:$PATH" OMP_NUM_THREADS=1 PYTHONDONTWRITEBYTECODE=1
# Open MPI as root (containers, CI) and two ranks on a small machine
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1

# blocks/NNN.sh, NNN.line (its first line in the page), NNN.txt (the text block after it)
"$PY" - "$page" "$tmp/blocks" <<'EOF'
import re, sys
lines = open(sys.argv[1]).read().split("\n")
out, k, i, last = sys.argv[2], 0, 0, None
while i < len(lines):
    m = re.match(r"^```(\w*)\s*$", lines[i])
    if not m:
        if lines[i].strip():
            last = None  # prose between a bash block and a text block: not its output
        i += 1
        continue
    j = i + 1
    while j < len(lines) and lines[j].rstrip() != "```":
        j += 1
    body = "\n".join(lines[i + 1:j]) + "\n"
    if m.group(1) == "bash":
        k += 1
        open("%s/%03d.sh" % (out, k), "w").write(body)
        open("%s/%03d.line" % (out, k), "w").write(str(i + 1))
        last = k
    elif m.group(1) == "text" and last is not None:
        open("%s/%03d.txt" % (out, last), "w").write(body)
        last = None
    else:
        last = None
    i = j + 1
print(k, "bash blocks")
EOF
nblocks=$(ls "$tmp/blocks"/*.sh 2>/dev/null | wc -l)
check "the page has bash blocks ($nblocks)" '[ "$nblocks" -ge 10 ]' || exit 1

run_block() { # SCRIPT LOG: runs one block in the scratch root
    (cd "$work" && bash -e -o pipefail "$1") >"$2" 2>&1
}

t0=$SECONDS
for sh in "$tmp/blocks"/*.sh; do
    n=$(basename "$sh" .sh)
    line=$(cat "$tmp/blocks/$n.line")
    log="$tmp/blocks/$n.log"
    if ! check "block $n (page line $line) exits 0" 'run_block "$sh" "$log"'; then
        sed 's/^/    | /' "$sh"
        tail -n 15 "$log" | sed 's/^/    > /'
        exit 1
    fi
    if [ -f "$tmp/blocks/$n.txt" ]; then
        missing=$(while IFS= read -r want; do
            [ -n "$want" ] && ! grep -qF -- "$want" "$log" && echo "$want"
        done <"$tmp/blocks/$n.txt")
        check "block $n prints what the page shows" '[ -z "$missing" ]' || {
            echo "    not printed:"; echo "$missing" | sed 's/^/      /'
            echo "    printed:"; tail -n 10 "$log" | sed 's/^/      /'; }
    fi
done
echo "    (the blocks ran in $((SECONDS - t0)) s)"

# The facts, from the runs the blocks made (their folders are named in the page).
"$PY" - "$work" "$page" <<'EOF'
import csv, math, os, re, sys
import h5py
import numpy as np
work, page = sys.argv[1], open(sys.argv[2]).read()
bad = 0
def check(name, ok, detail=""):
    global bad
    print("%s %s%s" % ("PASS" if ok else "FAIL", name, "" if ok else ": " + detail))
    bad |= not ok
def row0(run):
    return next(csv.DictReader(open(os.path.join(work, "out", run, "diagnostics.csv"))))
def rows(run):
    return list(csv.DictReader(open(os.path.join(work, "out", run, "diagnostics.csv"))))
def lattice(R, dr, fill, split=None):
    """The drum's material sites by the page's rule: ((i + 1/2) dr, (j + 1/2) dr)
    with r <= R - dr/2 and y <= H = (2 fill - 1) R; with split, those above
    y = -R + split (H + R) too."""
    H = (2 * fill - 1) * R
    c = (np.arange(-int(R / dr) - 2, int(R / dr) + 2) + 0.5) * dr
    x, y = np.meshgrid(c, c)
    mat = (np.hypot(x, y) <= R - 0.5 * dr) & (y <= H)
    if split is None:
        return int(mat.sum())
    return int(mat.sum()), int((mat & (y > -R + split * (H + R))).sum())

# fill: the area share of the flat-surfaced segment, as the page states it
h = 2 * 0.35 - 1
area = (math.pi - math.acos(h) + h * math.sqrt(1 - h * h)) / math.pi
stated = "%.1f %%" % (100 * area)
check("fill 0.35 fills %s of the area (formula), as the page says" % stated,
      re.search(r"0\.35 fills %s" % re.escape(stated), page) is not None)
n = int(row0("my_drum_count")["n_material"])
check("the drum's material count %d is the lattice's below H = (2 fill - 1) R" % n,
      n == lattice(0.05, 0.001, 0.35), "lattice %d" % lattice(0.05, 0.001, 0.35))
share = "%.1f%%" % (100 * n * 1e-6 / (math.pi * 0.05 ** 2))
check("the page states the counted share %s" % share, share in page)

# mixed start: C uniform at C_below = C_above = 0.3
r = row0("my_drum_count")
check("mixed start: C_min = C_max = 0.3 in diagnostics row 0",
      float(r["C_min"]) == 0.3 and float(r["C_max"]) == 0.3, "%s %s" % (r["C_min"], r["C_max"]))
with h5py.File(os.path.join(work, "out", "my_drum", "snapshot_00000.h5"), "r") as f:
    kind, C = f["Particles/Kind"][:], f["Particles/Concentration"][:]
check("mixed start: every material particle of snapshot 0 has C = 0.3",
      np.all(C[kind == 0] == 0.3), "C in [%g, %g]" % (C[kind == 0].min(), C[kind == 0].max()))
# layered: C 0 below the split, 1 above, as many above as the lattice puts there
r = row0("my_drum_layered")
nm, above = lattice(0.05, 0.001, 0.35, split=0.5)
small = float(r["small_volume"]) / 1e-6
check("layered start: C from 0 to 1, %d of %d particles above y = -R + split (H + R)" % (above, nm),
      r["C_min"] == "0" and r["C_max"] == "1" and abs(small - above) < 1e-6 and int(r["n_material"]) == nm,
      "C %s-%s, small %.3f particles, n %s" % (r["C_min"], r["C_max"], small, r["n_material"]))
check("the container drum holds the same particles",
      int(row0("my_drum_container")["n_material"]) == n)

# hopper: the gate held, then grains left through the outlet; sum C V of inside + outflow conserved
d = rows("my_hopper")
before = [x for x in d if float(x["time"]) <= 0.02]
check("hopper: nothing leaves before the gate opens (t <= 0.02 s)",
      all(x["n_outflow"] == "0" for x in before) and len(before) > 1)
check("hopper: grains leave through the outlet after it opens",
      int(d[-1]["n_outflow"]) > 0 and int(d[-1]["n_material"]) + int(d[-1]["n_outflow"]) == int(d[0]["n_material"]),
      "out %s, inside %s, start %s" % (d[-1]["n_outflow"], d[-1]["n_material"], d[0]["n_material"]))
check("hopper: sum C V of inside and outflow conserved",
      max(abs(float(x["small_volume_drift"])) for x in d) < 1e-10)

# two ranks: the same drum
check("two ranks hold the drum's particles",
      row0("my_drum_2ranks")["n_material"] == row0("my_drum")["n_material"])
# restart: continued in its folder to the page's t_end, without a second header
d = rows("my_drum")
check("the restart reached t = 0.5 s in out/my_drum", abs(float(d[-1]["time"]) - 0.5) < 1e-9, d[-1]["time"])
steps = [int(x["step"]) for x in d]
check("out/my_drum's rows run on in order across the restart", steps == sorted(steps) and len(set(steps)) == len(steps))
sys.exit(bad)
EOF
[ $? -eq 0 ] || fail=1

# The runner fails a broken block: the first sphseg block with a misspelt key.
first=$(grep -l 'build/sphseg' "$tmp/blocks"/*.sh | head -n 1)
sed 's/Geometry:dr=/Geometry:drr=/' "$first" >"$tmp/broken.sh"
check "a block with a misspelt key (Geometry:drr) fails" '! grep -q drr "$first" && grep -q drr "$tmp/broken.sh" && ! run_block "$tmp/broken.sh" "$tmp/broken.log"'
exit $fail
