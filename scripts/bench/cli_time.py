#!/usr/bin/python3
"""Whole-process time of short commands, alternated: runs each of the commands (separated by
";;") once per round, N rounds, and prints for each its median wall time (time.perf_counter) and
median CPU time (user + system of the child, from getrusage(RUSAGE_CHILDREN)), in ms. For runs
too short for /usr/bin/time's 10 ms resolution (Fandisk's whole process, tens of ms).

Usage: scripts/bench/cli_time.py N "COMMAND A ;; COMMAND B ..."
  e.g. scripts/bench/cli_time.py 41 "before/meshdenoise --mode manual noisy.off o1.off ;;
       build/release/cli/meshdenoise --mode manual noisy.off o2.off"
"""
import resource
import shlex
import statistics
import subprocess
import sys
import time


def cpu_s():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def measure(rounds, commands):
    wall = [[] for _ in commands]
    cpu = [[] for _ in commands]
    for _ in range(rounds):
        for i, command in enumerate(commands):
            c0, t0 = cpu_s(), time.perf_counter()
            subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            wall[i].append((time.perf_counter() - t0) * 1e3)
            cpu[i].append((cpu_s() - c0) * 1e3)
    return [(statistics.median(w), statistics.median(c)) for w, c in zip(wall, cpu)]


def main():
    if len(sys.argv) != 3 or not sys.argv[1].isdigit() or int(sys.argv[1]) < 1:
        print(__doc__, file=sys.stderr)
        return 2
    commands = [shlex.split(c) for c in sys.argv[2].split(";;") if c.strip()]
    for command, (wall, cpu) in zip(commands, measure(int(sys.argv[1]), commands)):
        print("%-60s wall %.1f ms  cpu %.1f ms" % (" ".join(command)[:60], wall, cpu))
    return 0


if __name__ == "__main__":
    sys.exit(main())
