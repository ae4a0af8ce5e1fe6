#!/usr/bin/env bash
# test_keys.sh BINARY — the key documentation is current and complete:
# docs/keys.md equals `sphseg --keys` (written from the key table,
# src/scene/scene_keys.h), every key has a meaning, and every key that
# used_params.yml echoes for inputs/hopper_2d.yml is documented.
set -u
bin=${1:?usage: $0 BINARY}
root=$(cd "$(dirname "$0")/.." && pwd)
. "$(dirname "$0")/testlib.sh" # $tmp (removed at exit), $fail, check NAME CONDITION
"$bin" --keys > "$tmp/keys.md" || { echo "FAIL --keys exited with $?"; exit 1; }
if diff -q "$tmp/keys.md" "$root/docs/keys.md" > /dev/null; then
    echo "PASS docs/keys.md is what sphseg --keys writes"
else
    echo "FAIL docs/keys.md differs from sphseg --keys (regenerate: sphseg --keys > docs/keys.md)"
    diff "$tmp/keys.md" "$root/docs/keys.md" | head -5 | sed 's/^/    /'
    fail=1
fi
empty=$(grep -c '^| `[^`]*` | .* |  |$' "$tmp/keys.md")
if [ "$empty" -eq 0 ]; then echo "PASS every key has a meaning"; else echo "FAIL $empty keys without a meaning"; fail=1; fi
"$bin" "$root/inputs/hopper_2d.yml" -o "$tmp/run" --backend cpu -P Run:max_steps=1 -P Output:snapshots=off \
    -P Run:progress_s=1e9 > /dev/null 2>&1 || { echo "FAIL hopper_2d did not run"; exit 1; }
missing=0
while IFS= read -r line; do
    if [[ "$line" =~ ^([A-Z][A-Za-z]*):$ ]]; then sec=${BASH_REMATCH[1]}; continue; fi
    if [[ "$line" =~ ^\ \ ([A-Za-z_0-9]+): ]]; then
        key=${BASH_REMATCH[1]}
        if ! awk -v s="## $sec" -v k="| \`$key\` |" '$0 == s {on = 1; next} /^## / {on = 0} on && index($0, k) == 1 {f = 1} END {exit !f}' "$tmp/keys.md"; then
            echo "    $sec:$key is echoed but not documented"; missing=$((missing + 1))
        fi
    fi
done < "$tmp/run/used_params.yml"
if [ "$missing" -eq 0 ]; then echo "PASS every echoed key is documented"; else echo "FAIL $missing echoed keys undocumented"; fail=1; fi
exit $fail
