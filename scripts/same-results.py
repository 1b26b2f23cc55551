#!/usr/bin/env python3
"""Whether the committed results that a fresh run rewrote still say the same, number for number.

    scripts/same-results.py FILE...

Each FILE (a path in the repository, changed in the work tree) is compared with its committed
version (git show HEAD:FILE). A processor other than the one the results were made on may round
the last digits differently (seen: 5e-13 relative in a correlation, 5e-7 in an interval that a
fit's own tolerance bounds, 1e-9 K in a sensor bias that is zero up to that tolerance), so
numbers are compared to a relative 1e-6 plus an absolute 1e-8 (a field ending in "_percent", a
difference of two fitted RMSEs over one, to 1e-5), as tests/calibration_test.cpp compares a
fresh calibration; every other character must be the same. JSON files are compared by field,
other text by its number tokens. Exit 0 when every file holds, 1 with the differences otherwise.
"""
import json
import math
import re
import subprocess
import sys

RELATIVE = 1e-6
ABSOLUTE = 1e-8
ABSOLUTE_PERCENT = 1e-5
NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def close(x, y, absolute):
    if x == y:
        return True
    if not (math.isfinite(x) and math.isfinite(y)):
        return False
    return abs(x - y) <= RELATIVE * max(abs(x), abs(y)) + absolute


def json_differences(a, b, where, out):
    if isinstance(a, bool) or isinstance(b, bool) or a is None or b is None or isinstance(a, str) or isinstance(b, str):
        if a != b:
            out.append(f"{where}: {a!r} vs {b!r}")
    elif isinstance(a, (int, float)) and isinstance(b, (int, float)):
        if not close(float(a), float(b), ABSOLUTE_PERCENT if where.endswith("_percent") else ABSOLUTE):
            out.append(f"{where}: {a!r} vs {b!r}")
    elif isinstance(a, dict) and isinstance(b, dict):
        if a.keys() != b.keys():
            out.append(f"{where}: fields {sorted(a.keys() ^ b.keys())} in one only")
        for key in a.keys() & b.keys():
            json_differences(a[key], b[key], f"{where}.{key}", out)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            out.append(f"{where}: {len(a)} entries vs {len(b)}")
        for i, (x, y) in enumerate(zip(a, b)):
            json_differences(x, y, f"{where}[{i}]", out)
    else:
        out.append(f"{where}: {type(a).__name__} vs {type(b).__name__}")


def text_differences(a, b, out):
    # Split into alternating text and number tokens: the texts must match, the numbers be close.
    ta, tb = NUMBER.split(a), NUMBER.split(b)
    na, nb = NUMBER.findall(a), NUMBER.findall(b)
    if ta != tb or len(na) != len(nb):
        line = next((i for i, (x, y) in enumerate(zip(a.splitlines(), b.splitlines())) if NUMBER.sub("#", x) != NUMBER.sub("#", y)), None)
        out.append("the text differs beyond its numbers" + (f" (line {line + 1})" if line is not None else ""))
        return
    for i, (x, y) in enumerate(zip(na, nb)):
        if x != y and not close(float(x), float(y), ABSOLUTE):
            out.append(f"number {i + 1}: {x} vs {y}")


def main(files):
    failed = False
    for path in files:
        committed = subprocess.run(["git", "show", f"HEAD:{path}"], capture_output=True, text=True)
        if committed.returncode != 0:
            print(f"{path}: not committed: a fresh run made a file the repository does not hold")
            failed = True
            continue
        try:
            with open(path, encoding="utf-8") as f:
                fresh = f.read()
        except OSError as e:
            print(f"{path}: committed, but a fresh run did not write it ({e.strerror})")
            failed = True
            continue
        out = []
        if path.endswith(".json"):
            json_differences(json.loads(committed.stdout), json.loads(fresh), "", out)
        else:
            text_differences(committed.stdout, fresh, out)
        if out:
            failed = True
            print(f"{path}: {len(out)} difference(s) beyond the last digits:")
            for line in out[:10]:
                print(f"  {line}")
        else:
            print(f"{path}: the same numbers (last digits differ)")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
