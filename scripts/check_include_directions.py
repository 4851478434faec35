#!/usr/bin/python3
"""Checks that #include lines point the way the layers do (the READMEs state it; ctest runs this
as include_directions):

    core (the method)  <-  core/io  <-  service  <-  cli, server/http  <-  server/http/redis

- core/ (outside core/io) never includes core/io, service, cli or server, and outside core/auto
  never includes core/auto (the parameter choice calls the pipeline, not the reverse);
- core/io includes from core/ only the data types it adapts (mesh.h, errors.h, progress.h),
  never a method header (prefilter.h, pipeline.h, core/auto/...), and nothing above it;
- service never includes cli or server;
- cli never includes server; server never includes cli;
- server/http includes its Redis store (server/http/redis) in service_parts.cpp only;
- only the transport includes cpp-httplib (<httplib.h>, or connection_gate.h, which does):
  http_server.cpp and the connection gate under it (connection_gate.*, connection_probe.cpp);
  the route handlers work on the service's own types (server/http/http_message.h).

Usage: check_include_directions.py [SOURCE_DIR]   (default: this script's repository)
Prints every violation as FILE:LINE: INCLUDE (rule) and exits 1 if there is one.
"""
import os
import re
import sys

INCLUDE = re.compile(r'^\s*#\s*include\s+(?:"([^"]+)"|<(httplib\.h)>)')
CORE_TYPES_FOR_IO = {"core/mesh.h", "core/errors.h", "core/progress.h"}
SOURCE_SUFFIXES = (".h", ".hpp", ".cpp", ".cc", ".inc")
LAYERS = ("core", "service", "cli", "server")
# The transport: the only files that may include cpp-httplib, directly or through the gate.
HTTPLIB = {"httplib.h", "server/http/connection_gate.h"}
TRANSPORT = {"server/http/http_server.cpp", "server/http/connection_gate.h", "server/http/connection_gate.cpp",
             "server/http/connection_probe.cpp"}


def under(path, folder):
    return path == folder or path.startswith(folder + "/")


def violation(src, inc):
    """The rule that `src` including `inc` breaks, or None. Both are repository-relative."""
    if inc in HTTPLIB and src not in TRANSPORT:
        return "only the transport (http_server.cpp, connection_gate) includes cpp-httplib"
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
        if under(inc, "cli"):
            return "server includes cli"
        if (under(inc, "server/http/redis") and not under(src, "server/http/redis")
                and src != "server/http/service_parts.cpp"):
            return "server/http includes its Redis store outside service_parts.cpp"
        return None
    return None


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else
                           os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    found, checked = [], 0
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
                        if m:
                            inc = m.group(1) or m.group(2)
                            rule = violation(src, inc)
                            if rule:
                                found.append("%s:%d: %s (%s)" % (src, number, inc, rule))
    if checked == 0:
        print("check_include_directions: no source file under %s" % root, file=sys.stderr)
        return 1
    for line in found:
        print(line)
    print("%d files checked, %d violations" % (checked, len(found)))
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main())
