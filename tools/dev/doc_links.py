#!/usr/bin/env python3
"""Check that the repository's references to files resolve.

Every markdown link and image `[text](target)` in a tracked *.md file must name a file
or folder that exists (relative to the markdown file; web links and pure anchors are
not checked), every path `docs/...`, `tools/...`, `tests/...` named in a tracked text
file (prose, tools, tests, jobs, scenes, sources) must exist, after brace expansion
({a,b}) and globbing (*), and every module of `python3 -m tools.X.Y` or `-m tests.Z`
must be a file; a path that names a prefix (`--png docs/data/drum/drum_EV`) passes
when files start with it. Paths in the measured data's own logs (docs/data/) are not checked: they
record what a command printed. Exit 1 with one line per dangling reference.

  /usr/bin/python3 -m tools.dev.doc_links
"""
import glob
import os
import re
import subprocess
import sys

from tools import ROOT  # noqa: E402
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
DOCS_PATH = re.compile(r"(?<![\w/.-])(?:docs|tools|tests)/[\w./{}*,-]*[\w/*}]")
MODULE = re.compile(r"-m ((?:tools|tests)(?:\.\w+)+)")
TEXT = (".md", ".py", ".sh", ".yml", ".sbatch", ".c", ".h", ".cu", ".cuh", "Makefile", ".txt", ".csv")


def tracked():
    out = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True)
    return [f for f in out.stdout.split("\n") if f]


def expand(tok):
    m = re.search(r"\{([^{}]*)\}", tok)
    if not m:
        return [tok]
    return [x for alt in m.group(1).split(",") for x in expand(tok[:m.start()] + alt + tok[m.end():])]


def exists(path):
    full = os.path.join(ROOT, path)
    if "*" in path:
        return bool(glob.glob(full))
    return os.path.exists(full) or bool(glob.glob(glob.escape(full) + "*"))


def check_links(f, text):
    bad = []
    for m in LINK.finditer(text):
        t = m.group(1)
        if re.match(r"[a-z]+:", t) or t.startswith("#"):
            continue
        t = t.split("#")[0]
        if not os.path.exists(os.path.join(ROOT, os.path.dirname(f), t)):
            bad.append(t)
    return bad


def check_docs_paths(text):
    bad = [m.group(1) for m in MODULE.finditer(text)
           if not re.search(r"\.[A-Z]\b", m.group(1))  # a placeholder: tools.X.Y
           and not os.path.exists(os.path.join(ROOT, *m.group(1).split(".")) + ".py")]
    for m in DOCS_PATH.finditer(text):
        tok = m.group(0).rstrip(".,")
        if re.search(r"/[A-Z]{3,}\b", tok):  # a placeholder: docs/data/STUDY
            continue
        if not all(exists(p) for p in expand(tok)):
            bad.append(tok)
    return bad


def main():
    problems = []
    for f in tracked():
        if not f.endswith(TEXT) or f.startswith("docs/data/") and not f.endswith(".md"):
            continue
        try:
            text = open(os.path.join(ROOT, f), encoding="utf-8").read()
        except (UnicodeDecodeError, FileNotFoundError):
            continue
        found = (check_links(f, text) if f.endswith(".md") else []) + check_docs_paths(text)
        problems += [f"{f}: {t}" for t in dict.fromkeys(found)]
    for p in problems:
        print(p)
    print(f"{len(problems)} dangling references")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
