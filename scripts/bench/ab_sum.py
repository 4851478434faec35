#!/usr/bin/python3
"""Medians of an A/B file written by scripts/bench/ab.sh (or cli_ab.sh): for each binary's tag
and each scale_bench row key (mesh, faces, params, order, threads), the median of every numeric
column over the rounds; each tag's median TIME (ab.sh: user, system, wall s; cli_ab.sh: wall,
user, system s, peak KiB) and LOAD (1, 5, 15 min); and cli_ab.sh's STAGES, the median of each
name=ms. Columns that are not numbers in every round (a dash, a text) are printed as in the
first.

Usage: scripts/bench/ab_sum.py OUT
"""
import statistics
import sys
from collections import OrderedDict


def number(text):
    try:
        return float(text)
    except ValueError:
        return None


def summarize(lines):
    rows = OrderedDict()  # (tag, kind, key...) -> list of token lists
    for line in lines:
        tokens = line.split()
        if len(tokens) < 2:
            continue
        tag, rest = tokens[0], tokens[1:]
        if rest[0] == "STAGES":
            for pair in rest[1:]:
                name, _, value = pair.partition("=")
                rows.setdefault((tag, "STAGES", name), []).append([value])
            continue
        if rest[0] in ("TIME", "LOAD"):
            key, values = (tag, rest[0]), rest[1:]
        else:
            cut = rest.index("|") if "|" in rest else len(rest)
            key, values = (tag,) + tuple(rest[:cut]), rest[cut:]
        rows.setdefault(key, []).append(values)
    out = []
    for key, runs in rows.items():
        width = min(len(r) for r in runs)
        cells = []
        for i in range(width):
            column = [number(r[i]) for r in runs]
            if all(v is not None for v in column):
                cells.append("%.6g" % statistics.median(column))  # six digits: MSAE's too
            else:
                cells.append(runs[0][i])
        out.append("%s  %s  (n=%d)" % (" ".join(key), " ".join(cells), len(runs)))
    return out


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    with open(sys.argv[1], encoding="utf-8") as f:
        for line in summarize(f.read().splitlines()):
            print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
