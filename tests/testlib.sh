# testlib.sh — what the shell tests share; source it after reading the
# arguments: `. "$(dirname "$0")/testlib.sh"`. Gives
#   $tmp                  a temporary folder, removed when the test exits;
#   $fail                 0 until a check fails, then 1 (the test exits with it);
#   check NAME CONDITION  evaluates CONDITION and prints PASS NAME or FAIL NAME
#                         (returns 1 on FAIL, so `check ... || show details`);
#   start_run LOG CMD...  starts CMD in the background (its pid in $pid) and waits
#                         until it is stepping (a progress line in LOG), for at most
#                         ${START_TRIES:-400} x 0.05 s; returns 1 if it ended or never stepped.
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
check() { if eval "$2"; then echo "PASS $1"; else echo "FAIL $1"; fail=1; return 1; fi; }
start_run() { # log, command...
    local log=$1; shift
    "$@" >"$log" 2>&1 &
    pid=$!
    for _ in $(seq "${START_TRIES:-400}"); do
        grep -q "^step " "$log" 2>/dev/null && return 0
        kill -0 $pid 2>/dev/null || return 1
        sleep 0.05
    done
    return 1
}
