#!/usr/bin/python3
"""Lists product source files over MAX_FILE lines and functions over MAX_FUNCTION lines.

A function is a brace block opened after a ')' (optionally followed by const, noexcept,
override, final, mutable, a trailing return type or a constructor's initialiser list) outside
any other function; lambdas and blocks inside a function count toward it. Comments, strings
and preprocessor lines are skipped. Heuristic, but it needs no compiler.

Usage: check_sizes.py [--max-file N] [--max-function N] [PATH...]   (default: the product
folders core, service, cli, server, relative to this script's repository). Exit 1 when
something is over, 2 when a PATH does not exist.
"""
import argparse
import os
import re
import sys

SUFFIXES = (".h", ".hpp", ".cpp", ".cc")
DEFAULT_DIRS = ("core", "service", "cli", "server")
TAIL = re.compile(r"\)\s*(const|noexcept|override|final|mutable|&|&&|\s|->\s*[\w:<>,\s*&]+)*$")
INIT_LIST = re.compile(r"\)\s*:\s*[\w:]+\s*[({].*[)}]\s*$", re.S)


def strip(text):
    """Comments, string and character literals blanked (newlines kept)."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("\n" * text.count("\n", i, j))
            i = j
        elif text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            end = text.find(")" + (m.group(1) if m else "") + '"', i)
            end = n if end < 0 else end + len(m.group(1) if m else "") + 2
            out.append('""' + "\n" * text.count("\n", i, end))
            i = end
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            out.append(c + c)
            i = j + 1
        else:
            out.append(c)
            i += 1
    lines = "".join(out).split("\n")
    return "\n".join("" if line.lstrip().startswith("#") else line for line in lines)


def functions(text):
    """(first line, line count, head) of each outermost function body."""
    code = strip(text)
    found, depth, fn_depth, start, head_start = [], 0, None, 0, 0
    for i, c in enumerate(code):
        if c == "{":
            if fn_depth is None:
                head = code[head_start:i].strip()
                if TAIL.search(head) or INIT_LIST.search(head):
                    fn_depth, start = depth, i
            depth += 1
        elif c == "}":
            depth -= 1
            if fn_depth is not None and depth == fn_depth:
                first = code.count("\n", 0, start) + 1
                last = code.count("\n", 0, i) + 1
                head = code[head_start:start].strip().split("\n")[-1][:80]
                found.append((first, last - first + 1, head))
                fn_depth = None
            if fn_depth is None:
                head_start = i + 1
        elif c == ";" and fn_depth is None:
            head_start = i + 1
    return found


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--max-file", type=int, default=600)
    ap.add_argument("--max-function", type=int, default=80)
    ap.add_argument("paths", nargs="*")
    args = ap.parse_args()
    root = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    paths = args.paths or [os.path.join(root, d) for d in DEFAULT_DIRS]
    files = []
    for p in paths:
        if not os.path.exists(p):  # a renamed folder must not make the check pass on nothing
            print("%s: no such file or folder" % p, file=sys.stderr)
            return 2
        if os.path.isfile(p):
            files.append(p)
        for dirpath, dirnames, filenames in os.walk(p):
            dirnames[:] = sorted(d for d in dirnames if d != "node_modules")
            files += [os.path.join(dirpath, f) for f in sorted(filenames) if f.endswith(SUFFIXES)]
    over = 0
    for path in files:
        with open(path, encoding="utf-8", errors="replace") as f:
            text = f.read()
        rel = os.path.relpath(path, root)
        lines = text.count("\n")
        if lines > args.max_file:
            print("%s: %d lines (file)" % (rel, lines))
            over += 1
        for first, count, head in functions(text):
            if count > args.max_function:
                print("%s:%d: %d lines: %s" % (rel, first, count, head))
                over += 1
    return 1 if over else 0


if __name__ == "__main__":
    sys.exit(main())
