#!/usr/bin/env bash
# Run:preset (src/scene/scene_preset.c): a named group of keys set as -P
# overrides before the user's own.
#  - each preset's keys reach used_params.yml with its values, over the scene
#    file's (drum_2d_EV.yml sets Material:E 1e7 and Run:cfl_flow 0.1);
#  - a -P of the same key wins, before or after -P Run:preset;
#  - Run:preset in the scene file works as on the command line;
#  - an unknown name is refused (exit 2) naming Run:preset;
#  - paper is exactly the list docs/method.md gives as "the paper's settings";
#  - the planner's fast and converged (tools/studies/time_to_solution.py
#    PRESETS) are the C table's.
set -u
bin=${1:?usage: test_preset.sh SPHSEG}
root=$(cd "$(dirname "$0")/.." && pwd)
PY=${PYTHON:-/usr/bin/python3}
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail=0
pass() { echo "PASS $1"; }
bad() { echo "FAIL $1"; fail=1; }
used() { # outdir section key -> value in used_params.yml
    "$PY" -c "import sys, yaml; d = yaml.load(open(sys.argv[1] + '/used_params.yml'), Loader=yaml.BaseLoader); print(d[sys.argv[2]][sys.argv[3]])" "$@"
}
run() { # outdir args...
    local o=$1; shift
    OMP_NUM_THREADS=1 "$bin" "$root/inputs/drum_2d_EV.yml" -o "$o" --overwrite -P Run:max_steps=1 \
        -P Geometry:dr=0.002 -P Output:snapshots=off "$@" > "$o.log" 2>&1
}

# every key of each preset, as the C table gives it (scene_preset.c)
keys_of() {
    "$PY" - "$root/src/scene/scene_preset.c" "$1" <<'PYEOF'
import re, sys
src = open(sys.argv[1]).read()
flow = re.findall(r'"([A-Za-z]+:[A-Za-z_]+=[^"]*)"', src[src.index("#define SCENE_FLOW"):src.index("static const char *const paper")])
body = re.search(r"static const char \*const %s\[\] = \{(.*?)\};" % sys.argv[2], src, re.S).group(1)
keys = (flow if "SCENE_FLOW" in body else []) + re.findall(r'"([A-Za-z]+:[A-Za-z_]+=[^"]*)"', body)
print("\n".join(keys))
PYEOF
}
for p in paper converged fast; do
    run "$tmp/$p" -P Run:preset=$p || { bad "preset $p: exit $?: $(tail -1 "$tmp/$p.log")"; continue; }
    ok=1
    while IFS= read -r kv; do
        k=${kv%%=*} v=${kv#*=}
        got=$(used "$tmp/$p" "${k%%:*}" "${k#*:}")
        "$PY" -c "import sys; a, b = sys.argv[1:]; sys.exit(0 if a == b or (a.replace('.','',1).replace('e','',1).replace('+','').replace('-','').isdigit() and float(a) == float(b)) else 1)" "$got" "$v" \
            || { bad "preset $p: $k is $got in used_params.yml, the preset's $v"; ok=0; }
    done < <(keys_of $p)
    [ $ok = 1 ] && pass "preset $p: its $(keys_of $p | wc -l) keys in used_params.yml, over the scene file's"
done

run "$tmp/w1" -P Material:E=1e6 -P Run:preset=fast && [ "$(used "$tmp/w1" Material E)" = 1000000 ] \
    && pass "a -P before -P Run:preset wins over the preset" || bad "-P Material:E=1e6 before the preset: E $(used "$tmp/w1" Material E)"
run "$tmp/w2" -P Run:preset=fast -P Run:cfl_flow=0.15 && [ "$(used "$tmp/w2" Run cfl_flow)" = 0.15 ] \
    && pass "a -P after -P Run:preset wins over the preset" || bad "-P Run:cfl_flow=0.15 after the preset"

sed 's/^Run:$/Run:\n  preset: fast/' "$root/inputs/drum_2d_EV.yml" > "$tmp/file.yml"
grep -q "preset: fast" "$tmp/file.yml" || bad "could not put Run:preset into a copy of drum_2d_EV.yml"
OMP_NUM_THREADS=1 "$bin" "$tmp/file.yml" -o "$tmp/f" --overwrite -P Run:max_steps=1 -P Geometry:dr=0.002 \
    -P Output:snapshots=off > "$tmp/f.log" 2>&1 && [ "$(used "$tmp/f" Material E)" = 30000 ] \
    && pass "Run:preset fast in the scene file sets Material:E 3e4 over the file's 1e7" \
    || bad "Run:preset in the file: E $(used "$tmp/f" Material E 2>/dev/null)"

run "$tmp/u" -P Run:preset=quick; rc=$?
if [ $rc -eq 2 ] && grep -q "Run:preset" "$tmp/u.log"; then pass "an unknown preset: exit 2 naming Run:preset"
else bad "an unknown preset: exit $rc: $(tail -1 "$tmp/u.log")"; fi

# the paper's settings as docs/method.md lists them = preset paper
doc=$("$PY" - "$root/docs/method.md" <<'PYEOF'
import re, sys
t = open(sys.argv[1]).read()
sec = t[t.index("## The paper's settings"):]
block = sec[:sec.index("| key |")]
print("\n".join(sorted(re.findall(r"-P (\S+)", block))))
PYEOF
)
if [ "$doc" = "$(keys_of paper | sort)" ]; then pass "preset paper is the list of docs/method.md, \"The paper's settings\""
else bad "preset paper differs from docs/method.md's list: $(diff <(echo "$doc") <(keys_of paper | sort) | tr '\n' ' ')"; fi

for p in fast converged; do
    want=$(keys_of $p | grep -E "^(Material:E|Run:cfl_flow)=" | sort | tr '\n' ' ')
    got=$(cd "$root" && "$PY" -c "from tools.studies.time_to_solution import PRESETS; p = PRESETS['$p']; print(' '.join(sorted('%s=%s' % (k, ('%g' % v).replace('e+0', 'e')) for k, v in p.items())))")
    w=$(echo "$want" | "$PY" -c "import sys; print(' '.join(sorted('%s=%g' % (kv.split('=')[0], float(kv.split('=')[1])) for kv in sys.stdin.read().split())))")
    g=$(echo "$got" | "$PY" -c "import sys; print(' '.join(sorted('%s=%g' % (kv.split('=')[0], float(kv.split('=')[1])) for kv in sys.stdin.read().split())))")
    [ "$w" = "$g" ] && pass "the planner's $p is the C table's ($w)" || bad "the planner's $p ($g) is not the C table's ($w)"
done
exit $fail
