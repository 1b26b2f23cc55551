#!/usr/bin/env python3
"""The size check: no source file of src/, include/ or apps/ over 600 lines, no function over 100.

A file that needs more is several files, one job each; a function that needs a scroll bar is
several named steps (docs/architecture.md, "Sizes"). Lines are counted as `wc -l` counts them.
A function is a brace-matched body at namespace or class scope whose head ends in `)` (with
`const`, `noexcept`, `override` or a trailing return type after it): lambdas and local blocks
count with the function around them. Its length runs from the first line of its head (the
first line after the `;`, `{` or `}` before it, comments not counted) to its closing brace.
Comments, strings and character literals are blanked first. A heuristic, not a parser: a
macro with a body (PYBIND11_MODULE, TEST) counts as a function, which is what it reads like.

Exits 1 naming file:line for every file or function over its limit that is not a known
exception below, and for every known exception that no longer applies (then delete its line;
an IN_PROGRESS one gets a note instead).

    python3 scripts/check-sizes.py [--root DIR] [--list]
"""
import argparse
import os
import re
import sys

ROOTS = ("src", "include", "apps")
SOURCE = re.compile(r"\.(c|cc|cpp|h|hpp|inc)$")
MAX_FILE_LINES = 600
MAX_FUNCTION_LINES = 100

# Known over-long files and functions, each waiting for its split (issue 42 item 2 split the
# last of them). Shorten one, then delete its line: the check fails while a line names
# something no longer over its limit.
# A file: (path, what it holds). A function: (path, name, what it does in one).
KNOWN_FILES = [
]
KNOWN_FUNCTIONS = [
]
# Exceptions a change under way removes: allowed while over, and no error once they are not (a
# note instead), so that the change need not touch this file. Delete each line once it is in.
IN_PROGRESS = [
]

CONTROL = re.compile(r"^(if|for|while|switch|catch|do|else|return|case)\b")
SCOPE = re.compile(r"^(template\s*<.*>\s*)?(namespace|struct|class|union|enum|extern)\b", re.S)


def blank(text):
    """The text with comments, strings and character literals replaced by spaces (newlines kept)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == "R" and text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            if not m:
                out.append(c)
                i += 1
                continue
            end = text.find(")" + m.group(1) + '"', i)
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c in "\"'":
            if c == "'" and i > 0 and text[i - 1].isalnum():  # a digit separator: 1'000
                out.append(" ")
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


def function_name(head):
    """The name before the head's parameter list ('FitResult fit(const X& x) const' -> 'fit')."""
    head = re.sub(r"^\s*template\s*<", "", head)
    depth, cut = 0, None
    for k, c in enumerate(head):  # the first '(' outside template arguments
        if c == "<":
            depth += 1
        elif c == ">":
            depth = max(depth - 1, 0)
        elif c == "(" and depth == 0:
            cut = k
            break
    m = re.search(r"([\w:~]+(?:\s*operator\s*\S+?)?)\s*$", head[:cut] if cut is not None else head)
    return m.group(1).split("::")[-1] if m else "?"


def functions(text):
    """[(name, first line, last line)] of the bodies at namespace or class scope."""
    code = blank(text)
    found = []
    scopes = []  # per open brace: 'scope' (namespace, class, ...), 'function', or 'block'
    head_start = 0  # index after the last ';', '{' or '}' at the current level
    start = None
    for i, c in enumerate(code):
        if c == "{":
            in_function = "function" in scopes
            head = code[head_start:i].strip()
            kind = "block"
            if not in_function:
                if SCOPE.match(head) or head.endswith("=") or not head:
                    kind = "scope"
                elif re.search(r"\)\s*(const|noexcept|override|final|mutable|->[^;{}]*|\s)*$", head) and not CONTROL.match(head):
                    kind = "function"
                    offset = head_start + (len(code[head_start:i]) - len(code[head_start:i].lstrip()))
                    start = (function_name(head), code.count("\n", 0, offset) + 1)
                else:
                    kind = "scope"  # an initializer or anything else: look inside
            scopes.append(kind)
            head_start = i + 1
        elif c == "}":
            kind = scopes.pop() if scopes else "scope"
            if kind == "function" and "function" not in scopes and start:
                found.append((start[0], start[1], code.count("\n", 0, i) + 1))
                start = None
            head_start = i + 1
        elif c == ";":
            head_start = i + 1
        elif c == ":" and "function" not in scopes:
            # access specifiers (public:) end a head; '::' does not
            if code[i - 1:i + 1] != "::" and code[i:i + 2] != "::" and re.search(r"\b(public|private|protected)\s*$", code[head_start:i]):
                head_start = i + 1
        elif c == "#" and "function" not in scopes:
            # a preprocessor line is not part of the next head
            j = code.find("\n", i)
            line_start = code.rfind("\n", 0, i) + 1
            if code[line_start:i].strip() == "":
                head_start = j if j >= 0 else len(code)
    return found


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    parser.add_argument("--list", action="store_true", help="print every file and function over its limit")
    args = parser.parse_args()
    root = os.path.abspath(args.root)

    over_files, over_functions = {}, {}
    for top in ROOTS:
        for directory, _, names in os.walk(os.path.join(root, top)):
            for name in sorted(names):
                if not SOURCE.search(name):
                    continue
                path = os.path.join(directory, name)
                rel = os.path.relpath(path, root).replace(os.sep, "/")
                with open(path, encoding="utf-8", errors="replace") as f:
                    text = f.read()
                lines = text.count("\n")
                if lines > MAX_FILE_LINES:
                    over_files[rel] = lines
                for fn, first, last in functions(text):
                    length = last - first + 1
                    if length > MAX_FUNCTION_LINES:
                        key = (rel, fn)
                        if length > over_functions.get(key, (0, 0))[0]:
                            over_functions[key] = (length, first)

    if args.list:
        for rel, lines in sorted(over_files.items(), key=lambda x: -x[1]):
            print(f"file {rel}: {lines} lines")
        for (rel, fn), (length, first) in sorted(over_functions.items(), key=lambda x: -x[1][0]):
            print(f"function {rel}:{first} {fn}: {length} lines")

    errors = []
    known_files = {path for path, _ in KNOWN_FILES}
    known_functions = {(path, name) for path, name, _ in KNOWN_FUNCTIONS}
    moving_files = {path for path, name, _ in IN_PROGRESS if name is None}
    moving_functions = {(path, name) for path, name, _ in IN_PROGRESS if name is not None}
    notes = [f"note: {path}{'' if name is None else ': ' + name} is no longer over its limit: delete its line in IN_PROGRESS"
             for path, name, _ in IN_PROGRESS
             if (path not in over_files if name is None else (path, name) not in over_functions)]
    for rel, lines in sorted(over_files.items()):
        if rel not in known_files | moving_files:
            errors.append(f"{rel}: {lines} lines (at most {MAX_FILE_LINES}: split it by job)")
    for (rel, fn), (length, first) in sorted(over_functions.items()):
        if (rel, fn) not in known_functions | moving_functions:
            errors.append(f"{rel}:{first}: {fn} is {length} lines (at most {MAX_FUNCTION_LINES}: name its steps)")
    for path in sorted(known_files - set(over_files)):
        errors.append(f"{path}: a known exception no longer over {MAX_FILE_LINES} lines: delete its line in KNOWN_FILES")
    for path, fn in sorted(known_functions - set(over_functions)):
        errors.append(f"{path}: {fn}: a known exception no longer over {MAX_FUNCTION_LINES} lines: delete its line in KNOWN_FUNCTIONS")
    for note in notes:
        print(note)
    for e in errors:
        print(e, file=sys.stderr)
    if errors:
        return 1
    print(f"sizes: no file over {MAX_FILE_LINES} lines, no function over {MAX_FUNCTION_LINES} "
          f"({len(KNOWN_FILES)} files and {len(KNOWN_FUNCTIONS)} functions known to be)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
