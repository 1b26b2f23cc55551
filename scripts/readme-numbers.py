#!/usr/bin/env python3
"""The numbers README.md and docs/*.md quote from the committed results in fits/, checked
against fits/ (and, with --write, rewritten from it).

    python3 scripts/readme-numbers.py            # exit 1 when a quoted number differs from fits/
    python3 scripts/readme-numbers.py --write    # rewrite every quoted number from fits/

The scheme. A number quoted from fits/ carries an HTML comment right before it (GitHub and
other Markdown viewers do not show it):

    k1 <!-- fits: cheng2017/calibration.json calibrated_model.friction.parameters[name=k1] %.3f [%.3f, %.3f] -->0.312 [0.307, 0.317]

- FILE is a JSON (or TOML) file, relative to fits/.
- PATH walks into it: keys separated by dots; `[3]` takes a list's element; `[name=k1]` the
  element of a list of records whose `name` is `k1` (any key: `[effect=seal_drag]`).
- An optional `*100` (any factor) after the path scales the numbers (a share as a percent).
- FORMAT is a printf format (Python's %-formatting), filled from what PATH points at: a number
  fills one conversion; a list fills one per element; a parameter record (a dict with `value`
  and `ci95`) fills the value and the interval's two ends. `%s` quotes a text value.
- The quoted text is what follows the comment and matches FORMAT read as a pattern (each
  conversion a number, `%s` any text up to the format's next literal). It must equal FORMAT
  filled from fits/: the number as the sentence rounds it. The comment holds no `--`.

Every marked number of README.md and docs/*.md is checked. A file of fits/ that is missing, a
PATH that leads nowhere, or a marker whose text does not follow it, is an error too. The
CTest test `readme_numbers` runs this script: regenerate the numbers with --write after
fits/ changes (scripts/run.sh), and mark a new quoted number the same way.
Python 3 standard library only.
"""
import argparse
import json
import pathlib
import re
import sys

MARKER = re.compile(r"<!-- fits: (?P<spec>[^>]*?) -->")
NUMBER = r"[-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?"
CONVERSION = re.compile(r"%(?:[-+ #0]*)(?:\d+)?(?:\.\d+)?([diouxXeEfFgGs%])")


class MarkerError(Exception):
    pass


def parse_spec(spec):
    """FILE PATH [*FACTOR] FORMAT -> (file, path, factor, format)."""
    parts = spec.split(" ", 2)
    if len(parts) < 3:
        raise MarkerError(f"expected 'FILE PATH [*FACTOR] FORMAT', found '{spec}'")
    file, path, rest = parts
    factor = 1.0
    m = re.match(r"\*(" + NUMBER + r") (.*)$", rest)
    if m:
        factor, rest = float(m.group(1)), m.group(2)
    return file, path, factor, rest


def walk(document, path):
    """The value at PATH (dots, [index], [key=value]) in a parsed JSON or TOML document."""
    value = document
    for token in re.findall(r"[^.\[\]]+|\[[^\]]*\]", path):
        if token.startswith("["):
            inner = token[1:-1]
            if not isinstance(value, list):
                raise MarkerError(f"'{token}' of '{path}': not a list")
            if "=" in inner:
                key, wanted = inner.split("=", 1)
                found = [v for v in value if isinstance(v, dict) and str(v.get(key)) == wanted]
                if len(found) != 1:
                    raise MarkerError(f"'{token}' of '{path}': {len(found)} elements match")
                value = found[0]
            else:
                index = int(inner)
                if not -len(value) <= index < len(value):
                    raise MarkerError(f"'{token}' of '{path}': the list has {len(value)} elements")
                value = value[index]
        else:
            if not isinstance(value, dict) or token not in value:
                raise MarkerError(f"'{token}' of '{path}': no such key")
            value = value[token]
    return value


def fill(value, factor, fmt):
    """FORMAT filled from VALUE (a number, a list, a parameter record or a text)."""
    if isinstance(value, dict) and "value" in value and "ci95" in value:
        values = [value["value"], *value["ci95"]]
    elif isinstance(value, list):
        values = value
    else:
        values = [value]
    scaled = []
    for v in values:
        if isinstance(v, bool) or v is None:
            raise MarkerError(f"not a number or text: {v!r}")
        scaled.append(v * factor if isinstance(v, (int, float)) else v)
    try:
        return fmt % tuple(scaled)
    except (TypeError, ValueError) as error:
        raise MarkerError(f"format '{fmt}' with {scaled!r}: {error}")


def pattern(fmt):
    """A regex that matches what FORMAT prints: each conversion a number (%s: any text up to
    the format's next literal, which it must have: "`%s`")."""
    out, last = [], 0
    for m in CONVERSION.finditer(fmt):
        out.append(re.escape(fmt[last:m.start()]))
        kind = m.group(1)
        if kind == "s" and m.end() == len(fmt):
            raise MarkerError(f"format '{fmt}': a %s needs text after it (\"`%s`\")")
        out.append("%" if kind == "%" else r"[^\n<]*?" if kind == "s" else NUMBER)
        last = m.end()
    out.append(re.escape(fmt[last:]))
    return re.compile("".join(out))


def check_file(md, fits, write, cache):
    """(marker count, stale numbers, marker errors) for one Markdown file; with write=True the
    stale numbers are rewritten in place."""
    text = md.read_text(encoding="utf-8")
    stale, errors, pieces, last, count = [], [], [], 0, 0
    if text.count("<!-- fits:") != len(MARKER.findall(text)):
        errors.append(f"{md}: a '<!-- fits:' comment that does not read as "
                      "'<!-- fits: FILE PATH [*FACTOR] FORMAT -->'")
    for m in MARKER.finditer(text):
        count += 1
        where = f"{md}:{text.count(chr(10), 0, m.start()) + 1}"
        try:
            file, path, factor, fmt = parse_spec(m.group("spec"))
            source = fits / file
            if source not in cache:
                if not source.is_file():
                    raise MarkerError(f"no file fits/{file}")
                with open(source, "rb") as handle:
                    if source.suffix == ".toml":
                        import tomllib  # Python 3.11
                        cache[source] = tomllib.load(handle)
                    else:
                        cache[source] = json.load(handle)
            expected = fill(walk(cache[source], path), factor, fmt)
            stated = pattern(fmt).match(text, m.end())
            if not stated:
                raise MarkerError(f"the text after the marker does not read as '{fmt}': "
                                  f"'{text[m.end():m.end() + 40]}…'")
        except MarkerError as error:
            errors.append(f"{where}: {error}")
            continue
        if stated.group(0) != expected:
            stale.append(f"{where}: states '{stated.group(0)}', fits/{file} {path} gives "
                         f"'{expected}'")
            pieces += [text[last:m.end()], expected]
            last = stated.end()
    if write and pieces:
        md.write_text("".join(pieces) + text[last:], encoding="utf-8")
    return count, stale, errors


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--write", action="store_true",
                        help="rewrite the quoted numbers from fits/ instead of failing")
    parser.add_argument("--root", type=pathlib.Path,
                        default=pathlib.Path(__file__).resolve().parent.parent,
                        help="the repository (default: this script's)")
    args = parser.parse_args()
    fits = args.root / "fits"
    readme = args.root / "README.md"
    files = [readme, *sorted((args.root / "docs").glob("*.md"))]
    cache, total, stale, errors = {}, 0, [], []
    for md in files:
        count, file_stale, file_errors = check_file(md, fits, args.write, cache)
        if md == readme and count == 0:
            file_errors.append(f"{md}: no quoted number is marked")
        total += count
        stale += file_stale
        errors += file_errors
    for problem in stale:
        print(("rewritten: " if args.write else "") + problem, file=sys.stderr)
    for problem in errors:
        print(problem, file=sys.stderr)
    print(f"readme-numbers: {total} quoted numbers in {len(files)} files; "
          f"{len(stale)} differ from fits/{' (rewritten)' if args.write and stale else ''}; "
          f"{len(errors)} markers in error")
    return 1 if errors or (stale and not args.write) else 0


if __name__ == "__main__":
    sys.exit(main())
