#!/usr/bin/python3
"""scripts/check_include_directions.py fails on each rule it encodes (ctest include_directions_rules).

Each case writes a small source tree (a clean base plus the one file or include that breaks a
rule) into a temporary folder, runs the checker on it and expects exit 1 with the rule named; the
clean base alone passes.
"""
import os
import subprocess
import sys
import tempfile
import unittest

CHECKER = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts",
                       "check_include_directions.py")

# The clean base: one file per room, each including what the rules allow.
BASE = {
    "core/mesh.h": "",
    "core/io/document.h": '#include "core/mesh.h"\n',
    "service/job_runner.h": '#include "core/io/document.h"\n',
    "server/http/problem.h": "",
    "server/http/transport/gate_types.h": "",
    "server/http/transport/connection_gate.h": '#include <httplib.h>\n#include "server/http/transport/gate_types.h"\n',
    "server/http/transport/connection_probe.h": "",
    "server/http/transport/http_message.h": "",
    "server/http/jobs/job.h": '#include "server/http/problem.h"\n#include "service/job_runner.h"\n',
    "server/http/jobs/job_store.h": '#include "server/http/jobs/job.h"\n',
    "server/http/jobs/worker_pool.h": '#include "server/http/jobs/job.h"\n',
    "server/http/jobs/memory_job_store.h": '#include "server/http/jobs/job_store.h"\n',
    "server/http/jobs/redis/store.h": '#include "server/http/jobs/job_store.h"\n',
    "server/http/routes/job_routes.h": ('#include "server/http/jobs/job_store.h"\n#include "server/http/jobs/worker_pool.h"\n'
                                        '#include "server/http/transport/http_message.h"\n'),
    "server/http/http_server.h": '#include "server/http/jobs/job_store.h"\n',
    "server/http/http_server.cpp": ('#include <httplib.h>\n#include "server/http/http_server.h"\n'
                                    '#include "server/http/routes/job_routes.h"\n'
                                    '#include "server/http/transport/connection_gate.h"\n'),
    "server/service_parts.h": '#include "server/http/http_server.h"\n',
    "server/service_parts.cpp": ('#include "server/service_parts.h"\n#include "server/http/jobs/redis/store.h"\n'
                                 '#include "server/http/jobs/memory_job_store.h"\n'),
    "server/main.cpp": '#include "server/service_parts.h"\n',
    # core/auto as it stands: the scorer reaches the descent, not the ground-truth search.
    "core/auto/choice.h": '#include "core/auto/selection.h"\n',
    "core/auto/choose.h": '#include "core/auto/choice.h"\n',
    "core/auto/choose.cpp": '#include "core/auto/choose.h"\n#include "core/auto/recorrupted.h"\n',
    "core/auto/denoise.h": '#include "core/auto/choice.h"\n',
    "core/auto/denoise.cpp": '#include "core/auto/denoise.h"\n#include "core/auto/choose.h"\n',
    "core/auto/selection.h": "",
    "core/auto/recorrupted.h": '#include "core/auto/selection.h"\n',
    "core/auto/recorrupted.cpp": '#include "core/auto/recorrupted.h"\n#include "core/auto/descent.h"\n',
    "core/auto/descent.h": "",
    "core/auto/descent.cpp": '#include "core/auto/descent.h"\n',
    "core/auto/tune.h": '#include "core/auto/descent.h"\n',
    "core/auto/tune.cpp": '#include "core/auto/tune.h"\n#include "core/auto/denoise.h"\n',
}


def run(extra):
    files = dict(BASE)
    for path, text in extra.items():
        files[path] = files.get(path, "") + text
    with tempfile.TemporaryDirectory() as root:
        for path, text in files.items():
            os.makedirs(os.path.join(root, os.path.dirname(path)), exist_ok=True)
            with open(os.path.join(root, path), "w") as f:
                f.write(text)
        p = subprocess.run([sys.executable, CHECKER, root], capture_output=True, text=True)
        return p.returncode, p.stdout + p.stderr


class Rules(unittest.TestCase):
    def refused(self, extra, words):
        rc, out = run(extra)
        self.assertEqual(rc, 1, out)
        self.assertIn(words, out)

    def test_the_clean_base_passes(self):
        rc, out = run({})
        self.assertEqual(rc, 0, out)

    def test_transport_knows_no_jobs(self):
        self.refused({"server/http/transport/connection_probe.h": '#include "server/http/jobs/job.h"\n'},
                     "transport knows no jobs")

    def test_transport_knows_no_routes(self):
        self.refused({"server/http/transport/connection_probe.h": '#include "server/http/routes/job_routes.h"\n'},
                     "transport knows no jobs and no routes")

    def test_routes_reach_jobs_through_the_store_interface_only(self):
        self.refused({"server/http/routes/job_routes.h": '#include "server/http/jobs/memory_job_store.h"\n'},
                     "routes reach jobs only through")

    def test_jobs_know_no_routes(self):
        self.refused({"server/http/jobs/worker_pool.h": '#include "server/http/routes/job_routes.h"\n'},
                     "jobs know no transport and no routes")

    def test_the_library_never_names_redis(self):
        self.refused({"server/http/http_server.cpp": '#include "server/http/jobs/redis/store.h"\n'},
                     "only server/service_parts.cpp names the Redis store")

    def test_the_library_never_includes_the_composition_root(self):
        self.refused({"server/http/http_server.h": '#include "server/service_parts.h"\n'},
                     "includes the composition root")

    def test_the_shared_base_names_no_room(self):
        self.refused({"server/http/problem.h": '#include "server/http/jobs/job.h"\n'},
                     "the shared base of server/http names no room")

    def test_only_the_transport_includes_httplib(self):
        self.refused({"server/http/routes/job_routes.h": "#include <httplib.h>\n"}, "includes cpp-httplib")
        self.refused({"server/http/routes/job_routes.h": '#include "server/http/transport/connection_gate.h"\n'},
                     "includes cpp-httplib")

    def test_two_modules_that_include_each_other(self):
        # A header and the other's .cpp: the shape core/io/detail and document had.
        self.refused({"core/io/detail.h": '#include "core/io/document.h"\n',
                      "core/io/document.cpp": '#include "core/io/document.h"\n#include "core/io/detail.h"\n'},
                     "core/io/detail and core/io/document include each other")

    def test_a_new_longer_cycle(self):
        self.refused({"service/a.h": '#include "service/b.h"\n', "service/b.h": '#include "service/c.h"\n',
                      "service/c.h": '#include "service/a.h"\n'},
                     "include cycle among service/a, service/b, service/c")

    def test_the_old_core_auto_cycle_fails(self):
        # The scorer including the ground-truth search again (which runs mdn::denoise) closes
        # the cycle that core/auto/descent.h broke.
        self.refused({"core/auto/recorrupted.cpp": '#include "core/auto/tune.h"\n'},
                     "include cycle among core/auto/choose, core/auto/denoise, core/auto/recorrupted, core/auto/tune")


if __name__ == "__main__":
    unittest.main()
