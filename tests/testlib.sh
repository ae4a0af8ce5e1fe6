# testlib.sh — what the shell tests share; source it after reading the
# arguments: `. "$(dirname "$0")/testlib.sh"`. Gives
#   $tmp                  a temporary folder, removed when the test exits;
#   $fail                 0 until a check fails, then 1 (the test exits with it);
#   check NAME CONDITION  evaluates CONDITION and prints PASS NAME or FAIL NAME
#                         (returns 1 on FAIL, so `check ... || show details`).
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
check() { if eval "$2"; then echo "PASS $1"; else echo "FAIL $1"; fail=1; return 1; fi; }
