#!/usr/bin/python3
"""The A/B scripts of scripts/bench/ that the speed rounds cite (ctest bench_scripts): ab.sh
alternates the binaries and tags their rows, ab_sum.py takes the medians per binary and row,
cli_time.py alternates commands and prints one median line per command. A fake scale_bench
(a shell script printing one row with the run's number) stands in for the real one.
"""
import os
import stat
import subprocess
import sys
import tempfile
import unittest

BENCH = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts", "bench")

FAKE_BENCH = """#!/bin/bash
# prints a scale_bench-like row whose total is the run's number (a counter file beside it)
n=$(( $(cat "$(dirname "$0")/count" 2>/dev/null || echo 0) + 1 )); echo $n > "$(dirname "$0")/count"
echo "machine: fake"
echo "fandisk        12946 paper natural  2 |   $n.000     201     - 197 160.0 20.4 7.5 |   0.02   0.01    20.0     7.0 |      10     800 |  0.359000 | 1/20/10"
"""


FAKE_CLI = """#!/bin/bash
# meshdenoise --params P --report IN OUT: prints a report with the stage times, writes OUT
echo x > "${@: -1}"
echo '{"files": [{"timings_ms": {"decode": 4.0, "denoise": 20.0}}]}'
"""


def write_fake(folder, relative=("build", "release", "tests", "bench", "scale_bench"), text=None):
    path = os.path.join(folder, *relative)
    os.makedirs(os.path.dirname(path))
    with open(path, "w") as f:
        f.write(FAKE_BENCH if text is None else text)
    os.chmod(path, os.stat(path).st_mode | stat.S_IEXEC)
    return path


class Bench(unittest.TestCase):
    def test_ab_alternates_tags_and_ab_sum_takes_medians(self):
        with tempfile.TemporaryDirectory() as tmp:
            before = write_fake(os.path.join(tmp, "before"))
            after = write_fake(os.path.join(tmp, "after"))
            out = os.path.join(tmp, "ab.txt")
            subprocess.run(["bash", os.path.join(BENCH, "ab.sh"), "3", "fandisk:0", "paper", out, before, after],
                           check=True, cwd=tmp)
            lines = open(out).read().splitlines()
            tags = [l.split()[0] for l in lines if l.split()[1] == "LOAD"]
            self.assertEqual(tags, ["before", "after"] * 3)  # alternated, one run each per round
            rows = [l for l in lines if l.startswith("before fandisk")]
            self.assertEqual([r.split()[7] for r in rows], ["1.000", "2.000", "3.000"])
            self.assertEqual(len([l for l in lines if l.startswith("after TIME")]), 3)
            summary = subprocess.run([sys.executable, os.path.join(BENCH, "ab_sum.py"), out], check=True,
                                     capture_output=True, text=True).stdout.splitlines()
            row = [l for l in summary if l.startswith("before fandisk 12946 paper natural 2")]
            self.assertEqual(len(row), 1, summary)
            cells = row[0].split("  ")[1].split()
            self.assertEqual(cells[:3], ["|", "2", "201"])  # the median of 1, 2, 3; a constant column
            self.assertEqual(cells[3], "-")  # not a number: kept as written
            self.assertIn("(n=3)", row[0])
            self.assertTrue(any(l.startswith("after TIME ") for l in summary))

    def test_ab_sum_takes_the_medians_of_cli_ab_lines(self):
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "cli.txt")
            with open(out, "w") as f:
                for wall, decode in (("5.5", "410"), ("5.7", "430"), ("5.6", "400")):
                    f.write("after LOAD 1.0 1.0 1.0\nafter TIME %s 9.0 0.5 580000\n" % wall)
                    f.write("after STAGES decode=%s encode=15.0\n" % decode)
            summary = subprocess.run([sys.executable, os.path.join(BENCH, "ab_sum.py"), out], check=True,
                                     capture_output=True, text=True).stdout.splitlines()
            self.assertIn("after TIME  5.6 9 0.5 580000  (n=3)", summary)
            self.assertIn("after STAGES decode  410  (n=3)", summary)
            self.assertIn("after STAGES encode  15  (n=3)", summary)

    def test_cli_ab_alternates_and_reads_the_reports_stage_times(self):
        with tempfile.TemporaryDirectory() as tmp:
            bins = [write_fake(os.path.join(tmp, side), ("build", "release", "cli", "meshdenoise"), FAKE_CLI)
                    for side in ("before", "after")]
            out = os.path.join(tmp, "cli.txt")
            subprocess.run(["bash", os.path.join(BENCH, "cli_ab.sh"), "2", "{}", "in.off", out] + bins, check=True,
                           cwd=tmp)
            lines = open(out).read().splitlines()
            self.assertEqual([l.split()[0] for l in lines if " LOAD " in l], ["before", "after"] * 2)
            self.assertEqual(len([l for l in lines if l.startswith("after TIME ")]), 2)
            self.assertIn("before STAGES decode=4.0 denoise=20.0", lines)

    def test_ab_refuses_missing_arguments(self):
        p = subprocess.run(["bash", os.path.join(BENCH, "ab.sh"), "3"], capture_output=True, text=True)
        self.assertEqual(p.returncode, 2)
        self.assertIn("Usage", p.stderr)

    def test_cli_time_prints_one_median_per_command(self):
        p = subprocess.run([sys.executable, os.path.join(BENCH, "cli_time.py"), "3", "true ;; sleep 0.05"],
                           check=True, capture_output=True, text=True)
        lines = p.stdout.splitlines()
        self.assertEqual(len(lines), 2)
        wall_sleep = float(lines[1].split("wall ")[1].split(" ms")[0])
        self.assertGreaterEqual(wall_sleep, 50.0)


if __name__ == "__main__":
    unittest.main()
