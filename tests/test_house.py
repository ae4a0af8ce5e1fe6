#!/usr/bin/env python3
"""The house stays walkable: the limits issue 54 set on docs/ and the key table.

- docs/ at most 4 MB and 300 files (measured data only as the tables and
  charts the pages show; raw logs and per-run outputs stay out of the tree);
- no page (docs/*.md, README.md) over 40 kB, docs/architecture.md at most
  25 kB (a map, not a notebook);
- no line of the key table src/scene/scene_keys.h over 200 characters (a
  key's doc says meaning, unit and range; measurements go to docs/).

It reads the tree only.
"""
import glob
import os
import sys

from tools import ROOT

DOCS_BYTES, DOCS_FILES = 4 * 1024 * 1024, 300
PAGE_BYTES, MAP_BYTES = 40 * 1024, 25 * 1024
KEY_LINE = 200


def check(root=ROOT):
    problems = []
    files = [f for f in glob.glob(os.path.join(root, "docs", "**"), recursive=True) if os.path.isfile(f)]
    size = sum(os.path.getsize(f) for f in files)
    if size > DOCS_BYTES:
        problems.append(f"docs/ holds {size / 2**20:.2f} MB (at most {DOCS_BYTES / 2**20:.0f} MB)")
    if len(files) > DOCS_FILES:
        problems.append(f"docs/ holds {len(files)} files (at most {DOCS_FILES})")
    pages = glob.glob(os.path.join(root, "docs", "*.md")) + [os.path.join(root, "README.md")]
    for page in pages:
        limit = MAP_BYTES if os.path.basename(page) == "architecture.md" else PAGE_BYTES
        n = os.path.getsize(page)
        if n > limit:
            problems.append(f"{os.path.relpath(page, root)}: {n / 1024:.1f} kB (at most {limit / 1024:.0f} kB)")
    keys = os.path.join(root, "src", "scene", "scene_keys.h")
    for k, line in enumerate(open(keys, encoding="utf-8"), 1):
        if len(line.rstrip("\n")) > KEY_LINE:
            problems.append(f"src/scene/scene_keys.h:{k}: {len(line.rstrip())} characters (at most {KEY_LINE})")
    return problems, size, len(files)


def main():
    problems, size, n = check()
    for p in problems:
        print("FAIL", p)
    if problems:
        return 1
    print(f"ok: docs/ {size / 2**20:.2f} MB in {n} files; pages and key table within their limits")
    return 0


if __name__ == "__main__":
    sys.exit(main())
