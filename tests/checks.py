"""The check lines of the Python tests that check a tool against known answers
(test_drum_mui_ref, test_drum_readers, test_inertial_range): one line per
check, PASS or FAIL with the value, its tolerance and where the reference comes
from, and the names of the failed ones in FAILS (one test per process)."""
import argparse

FAILS = []


def check(name, value, tol, ok, ref):
    print("%s %s: %.3e (tolerance %s; reference: %s)" % ("PASS" if ok else "FAIL", name, value, tol, ref))
    if not ok:
        FAILS.append(name)


def parse_args(doc, work_help="ignored"):
    """The runner's arguments (tests/run.sh passes --sphseg and --work to every test); --work is the
    only one such a test may use."""
    ap = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    ap.add_argument("--sphseg", default=None, help="ignored (the runner passes it)")
    ap.add_argument("--work", default=None, help=work_help)
    return ap.parse_known_args()[0]


def summary(test):
    """The last line, and the exit status: 1 if a check failed."""
    print("%s: %s" % (test, "FAIL: " + ", ".join(FAILS) if FAILS else "all checks passed"))
    return 1 if FAILS else 0
