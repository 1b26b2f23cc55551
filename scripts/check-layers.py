#!/usr/bin/env python3
"""The layering check: no file of src/, include/ or apps/ includes a header of a higher layer.

The layer order is docs/architecture.md's line

    layers: core = data < io < models < … < apps = python

(`<`: the left layer is lower; `=`: beside each other, neither includes the other). A file's
layer is its first folder under src/ or include/lmcal/ (files directly in them are `core`);
apps/ is `apps`. A file may include its own layer's headers and those of any lower layer.
Only quoted includes count (`#include "…"`); they resolve as the build resolves them: beside
the file, then from src/, apps/ and include/. A folder the order does not name fails the check
(a new folder needs its place in docs/architecture.md first).

Exits 1 naming file:line and the include for every upward include that is not a known debt
below, and for every known debt that no longer occurs (then delete its line).

    python3 scripts/check-layers.py [--root DIR]
"""
import argparse
import os
import re
import sys

ROOTS = ("src", "include", "apps")
SOURCE = re.compile(r"\.(c|cc|cpp|h|hpp|inc|in)$")
INCLUDE = re.compile(r'^\s*#\s*include\s*"([^"]+)"')

# Upward includes that the code still has, each a known debt with the item that removes it:
# (the including file, the included header as written, why it is there).
KNOWN_DEBTS = [
]


def read_order(root):
    """{layer: rank} from docs/architecture.md's `layers:` line."""
    doc = os.path.join(root, "docs", "architecture.md")
    with open(doc, encoding="utf-8") as f:
        for line in f:
            m = re.match(r"^\s*layers:\s*(.+?)\s*$", line)
            if m:
                ranks = {}
                for rank, group in enumerate(m.group(1).split("<")):
                    for name in group.split("="):
                        ranks[name.strip()] = rank
                return ranks, m.group(1)
    sys.exit(f"{doc}: no line 'layers: a < b < …' (the layer order this check reads)")


def layer_of(path):
    """The layer of a path relative to the root ('src/fit/x.cc' -> 'fit')."""
    parts = path.split("/")
    if parts[0] == "apps":
        return "apps"
    if parts[0] == "include" and parts[1:2] == ["lmcal"]:
        parts = parts[1:]
    return parts[1] if len(parts) > 2 else "core"


def resolve(root, including, header):
    """The included file relative to the root, or None (a generated or system header)."""
    here = os.path.dirname(including)
    for base in (here, "src", "apps", "include"):
        candidate = os.path.normpath(os.path.join(base, header))
        if os.path.isfile(os.path.join(root, candidate)):
            return candidate.replace(os.sep, "/")
    return None


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    root = os.path.abspath(parser.parse_args().root)
    ranks, order = read_order(root)
    known = {(f, h): why for f, h, why in KNOWN_DEBTS}
    seen, problems = set(), []
    for top in ROOTS:
        for folder, dirs, files in os.walk(os.path.join(root, top)):
            dirs.sort()
            for name in sorted(f for f in files if SOURCE.search(f)):
                path = os.path.relpath(os.path.join(folder, name), root).replace(os.sep, "/")
                layer = layer_of(path)
                if layer not in ranks:
                    problems.append(f"{path}: layer '{layer}' is not in docs/architecture.md's layers line")
                    continue
                with open(os.path.join(root, path), encoding="utf-8", errors="replace") as f:
                    for number, line in enumerate(f, 1):
                        m = INCLUDE.match(line)
                        target = m and resolve(root, path, m.group(1))
                        if not target:
                            continue
                        other = layer_of(target)
                        if other == layer or ranks.get(other, -1) < ranks[layer]:
                            continue
                        if (path, m.group(1)) in known:
                            seen.add((path, m.group(1)))
                            continue
                        how = "beside it" if ranks.get(other) == ranks[layer] else "above it"
                        problems.append(f'{path}:{number}: #include "{m.group(1)}": {layer} includes {other}, '
                                        f"a layer {how} (docs/architecture.md)")
    for (path, header), why in known.items():
        if (path, header) not in seen:
            problems.append(f'{path}: the known debt #include "{header}" ({why}) is gone: delete its line in '
                            "scripts/check-layers.py")
    for p in problems:
        print(p)
    if problems:
        return 1
    print(f"layers: {order}: every include points down"
          + (f" ({len(seen)} known debts, listed in scripts/check-layers.py)" if seen else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
