#!/usr/bin/python3
"""Checks that #include lines point the way the layers and the server's rooms do (the READMEs
state it; ctest runs this as include_directions):

    core (the method)  <-  core/io  <-  service  <-  cli
                                               <-  server/http  <-  server (main.cpp, service_parts)

    inside server/http:  the shared base (config, log, metrics, problem, secure_random, embedded)
                         <-  transport/  <-  routes/  <-  http_server (the route table, the wiring)
                         <-  jobs/ (job.h, job_store.h, worker_pool, memory_job_store; jobs/redis/)

- core/ (outside core/io) never includes core/io, service, cli or server, and outside core/auto
  never includes core/auto (the parameter choice calls the pipeline, not the reverse);
- core/io includes from core/ only the data types it adapts (mesh.h, errors.h, progress.h),
  never a method header (prefilter.h, pipeline.h, core/auto/...), and nothing above it;
- service never includes cli or server;
- cli never includes server; server never includes cli;
- the library server/http never includes the composition root (the files directly in server/);
- only the composition root's service_parts.cpp names the Redis store (server/http/jobs/redis/),
  besides the store's own files;
- transport/ knows no jobs and no routes;
- routes/ reach jobs/ only through job.h (a job's state and snapshot), job_store.h (the store
  interface) and worker_pool.h (the synchronous route runs there; readiness reads its queue),
  never a store's implementation;
- jobs/ know no transport and no routes;
- the shared base (the files directly in server/http but http_server.*) names no room;
- only the transport includes cpp-httplib (<httplib.h>, or connection_gate.h / gate_stream.h,
  which do): http_server.cpp and the connection gate under it; the route handlers work on the
  service's own types (server/http/transport/http_message.h);
- no two files include each other: the files of one module (a header and its .cpp) count as one,
  and no module reaches itself again through its includes (core/auto's one longer cycle, once
  listed here as known, was broken by core/auto/descent.h; none is allowed now).

Usage: check_include_directions.py [SOURCE_DIR]   (default: this script's repository)
Prints every violation as FILE:LINE: INCLUDE (rule), every cycle as the modules in it, and exits
1 if there is one.
"""
import os
import re
import sys

INCLUDE = re.compile(r'^\s*#\s*include\s+(?:"([^"]+)"|<(httplib\.h)>)')
CORE_TYPES_FOR_IO = {"core/mesh.h", "core/errors.h", "core/progress.h"}
SOURCE_SUFFIXES = (".h", ".hpp", ".cpp", ".cc", ".inc")
LAYERS = ("core", "service", "cli", "server")
HTTP = "server/http"
TRANSPORT_DIR, ROUTES_DIR, JOBS_DIR, REDIS_DIR = (HTTP + "/transport", HTTP + "/routes", HTTP + "/jobs",
                                                  HTTP + "/jobs/redis")
ROOMS = (TRANSPORT_DIR, ROUTES_DIR, JOBS_DIR)
# What routes/ may include from jobs/.
JOBS_FOR_ROUTES = {JOBS_DIR + "/job.h", JOBS_DIR + "/job_store.h", JOBS_DIR + "/worker_pool.h"}
# The one file outside jobs/redis/ that names the Redis store: the composition root's choice.
REDIS_CHOOSER = "server/service_parts.cpp"
# The transport: the only files that may include cpp-httplib, directly or through the gate.
HTTPLIB = {"httplib.h", TRANSPORT_DIR + "/connection_gate.h", TRANSPORT_DIR + "/gate_stream.h"}
TRANSPORT = {HTTP + "/http_server.cpp", TRANSPORT_DIR + "/connection_gate.h", TRANSPORT_DIR + "/connection_gate.cpp",
             TRANSPORT_DIR + "/gate_stream.h", TRANSPORT_DIR + "/gate_stream.cpp"}


def under(path, folder):
    return path == folder or path.startswith(folder + "/")


def folder_of(path):
    return path.rsplit("/", 1)[0] if "/" in path else ""


def server_violation(src, inc):
    """The server's rules (src is under server/)."""
    if under(inc, "cli"):
        return "server includes cli"
    if under(src, HTTP) and folder_of(inc) == "server":
        return "the library server/http includes the composition root (server/)"
    if under(inc, REDIS_DIR) and not under(src, REDIS_DIR) and src != REDIS_CHOOSER:
        return "only server/service_parts.cpp names the Redis store (server/http/jobs/redis)"
    if under(src, TRANSPORT_DIR) and (under(inc, JOBS_DIR) or under(inc, ROUTES_DIR)):
        return "transport knows no jobs and no routes"
    if under(src, ROUTES_DIR) and under(inc, JOBS_DIR) and inc not in JOBS_FOR_ROUTES:
        return "routes reach jobs only through job.h, job_store.h and worker_pool.h"
    if under(src, JOBS_DIR) and (under(inc, TRANSPORT_DIR) or under(inc, ROUTES_DIR)):
        return "jobs know no transport and no routes"
    if (folder_of(src) == HTTP and not os.path.basename(src).startswith("http_server.")
            and any(under(inc, room) for room in ROOMS)):
        return "the shared base of server/http names no room (transport, routes, jobs)"
    return None


def violation(src, inc):
    """The rule that `src` including `inc` breaks, or None. Both are repository-relative."""
    if inc in HTTPLIB and src not in TRANSPORT:
        return "only the transport (http_server.cpp, connection_gate, gate_stream) includes cpp-httplib"
    if under(src, "core/io"):
        if under(inc, "core") and not under(inc, "core/io") and inc not in CORE_TYPES_FOR_IO:
            return "core/io includes a method header; only mesh.h, errors.h, progress.h"
        if any(under(inc, top) for top in ("service", "cli", "server")):
            return "core/io includes a layer above it"
        return None
    if under(src, "core"):
        if under(inc, "core/io"):
            return "the method includes core/io"
        if under(inc, "core/auto") and not under(src, "core/auto"):
            return "the pipeline includes core/auto, which calls it"
        if any(under(inc, top) for top in ("service", "cli", "server")):
            return "core includes a layer above it"
        return None
    if under(src, "service"):
        if under(inc, "cli") or under(inc, "server"):
            return "service includes cli or server"
        return None
    if under(src, "cli"):
        if under(inc, "server"):
            return "cli includes server"
        return None
    if under(src, "server"):
        return server_violation(src, inc)
    return None


def module_of(path):
    """A header and its .cpp are one module: the path without its suffix."""
    return os.path.splitext(path)[0]


def cycles(edges):
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index, low, on_stack, stack, found = {}, {}, set(), [], []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in sorted(edges.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    sys.setrecursionlimit(10000)
    for v in sorted(edges):
        if v not in index:
            visit(v)
    return sorted(found)


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else
                           os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    found, checked, edges = [], 0, {}
    for top in LAYERS:
        for dirpath, dirnames, filenames in os.walk(os.path.join(root, top)):
            dirnames[:] = sorted(d for d in dirnames if d not in ("node_modules", "web"))
            for name in sorted(filenames):
                if not name.endswith(SOURCE_SUFFIXES):
                    continue
                path = os.path.join(dirpath, name)
                src = os.path.relpath(path, root).replace(os.sep, "/")
                checked += 1
                with open(path, encoding="utf-8", errors="replace") as f:
                    for number, line in enumerate(f, 1):
                        m = INCLUDE.match(line)
                        if not m:
                            continue
                        inc = m.group(1) or m.group(2)
                        rule = violation(src, inc)
                        if rule:
                            found.append("%s:%d: %s (%s)" % (src, number, inc, rule))
                        if m.group(1) and os.path.isfile(os.path.join(root, inc)) and module_of(inc) != module_of(src):
                            edges.setdefault(module_of(src), set()).add(module_of(inc))
    if checked == 0:
        print("check_include_directions: no source file under %s" % root, file=sys.stderr)
        return 1
    loops = cycles(edges)
    pairs = sorted((a, b) for a in edges for b in edges[a] if a < b and a in edges.get(b, ()))
    for line in found:
        print(line)
    for a, b in pairs:
        print("%s and %s include each other (a header and its .cpp count as one module)" % (a, b))
    for modules in loops:
        print("include cycle among %s (no module may reach itself through its includes)" % ", ".join(modules))
    print("%d files checked, %d violations, %d pairs that include each other, %d include cycles"
          % (checked, len(found), len(pairs), len(loops)))
    return 1 if found or pairs or loops else 0


if __name__ == "__main__":
    sys.exit(main())
