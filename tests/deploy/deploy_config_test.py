#!/usr/bin/env python3
"""The deployment files agree with each other and with the server they deploy.

The server's own --help is the reference for settings: every MDN_* variable set in the
Dockerfile, docker-compose.yml or the Kubernetes manifests must exist and hold a value the server
accepts (it exits 2 on a bad one), and docker/README.md must list every setting with the default
--help prints. Then the numbers that must fit together: nginx's body limit equals the server's,
its read timeout exceeds the job time limit, its keep-alive stays below the server's, stop and
grace periods exceed the drain, workers equal CPU limits, ports, user and probes match. The
shared job store: compose and Kubernetes run a Redis with an append-only file, the replicas'
MDN_QUEUE points at it, and nginx passes /v1/jobs through.
"""

import argparse
import glob
import os
import re
import shutil
import subprocess
import sys
import tempfile

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from deploy_support import TestFailure, check, log, read_dockerfile, read_stages, run_main  # noqa: E402

try:
    import yaml  # python3-yaml (scripts/deps/apt-test.txt)
except ImportError:
    yaml = None


def parse_args():
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--server", required=True)
    p.add_argument("--docker-dir", required=True)
    p.add_argument("--source-dir", help="repository root: configure what the build stage copies")
    return p.parse_args()


def check_build_context(dockerfile, source_dir):
    """The build stage's COPY lines bring everything CMake needs: copy exactly those paths from
    the repository and configure them with the Dockerfile's own cmake --preset command."""
    build = [s for s in read_stages(dockerfile) if s.name == "build"]
    check(len(build) == 1, "the Dockerfile has no stage named build")
    build = build[0]
    configure = [r for r in build.other_runs + [build.package_run] if "cmake --preset" in r]
    check(len(configure) == 1, "the build stage has no RUN with cmake --preset")
    command = configure[0].split("&&")[0].strip()
    check(command.startswith("cmake --preset"), "the build RUN should start with cmake --preset: " + command)
    tmp = tempfile.mkdtemp(prefix="mdn-docker-context-")
    try:
        work = os.path.join(tmp, build.workdir.lstrip("/"))
        for copy in build.local_copies:
            sources, dest = copy[:-1], copy[-1]
            target = os.path.join(work, dest) if not dest.startswith("/") else os.path.join(tmp, dest.lstrip("/"))
            for src in sources:
                matches = glob.glob(os.path.join(source_dir, src))
                check(matches, "the build stage copies %s, which is not in the repository" % src)
                for m in matches:
                    to = target if (len(sources) == 1 and not dest.endswith("/") and dest != "./") \
                        else os.path.join(target, os.path.basename(m))
                    os.makedirs(os.path.dirname(to) or ".", exist_ok=True)
                    if os.path.isdir(m):
                        shutil.copytree(m, to, dirs_exist_ok=True,
                                        ignore=shutil.ignore_patterns("build", "node_modules"))
                    else:
                        shutil.copy2(m, to)
        # A RUN of install-deps.sh build also installs the web page's npm packages (npm ci from
        # server/web/package-lock.json, copied above): take this checkout's, installed by the same
        # script, rather than fetch them again.
        if any("install-deps.sh build" in r for r in build.other_runs):
            npm = os.path.join("server", "web", "node_modules")
            check(os.path.isdir(os.path.join(source_dir, npm)), "%s is missing: run scripts/install-deps.sh build" % npm)
            check(os.path.exists(os.path.join(work, "server", "web", "package-lock.json")),
                  "the build stage runs install-deps.sh build but copies no server/web/package-lock.json")
            shutil.copytree(os.path.join(source_dir, npm), os.path.join(work, npm), dirs_exist_ok=True)
        # Ninja here (the image uses CMake's default generator; the files needed are the same) so
        # that `ninja -t inputs` can list every source file of the two executables.
        env = dict(os.environ, CMAKE_GENERATOR="Ninja")
        r = subprocess.run(command, shell=True, cwd=work, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        check(r.returncode == 0, "'%s' fails on exactly what the build stage copies (a COPY is missing?):\n%s"
              % (command, r.stdout.decode(errors="replace")[-3000:]))
        r = subprocess.run(["ninja", "-C", os.path.join(work, "build", "release"), "-t", "inputs",
                            "meshdenoise-server", "meshdenoise"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        check(r.returncode == 0, "ninja -t inputs failed: " + r.stdout.decode(errors="replace"))
        inputs = [line for line in r.stdout.decode().splitlines() if line.startswith(work + "/")]
        generated = os.path.join(work, "build") + "/"
        missing = [i[len(work) + 1:] for i in inputs if not i.startswith(generated) and not os.path.exists(i)]
        check(not missing, "the executables need files the build stage does not COPY: %s" % missing)
        check(any(i.endswith("main.cpp") for i in inputs), "ninja listed no sources: %s" % inputs[:5])
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    log("Dockerfile build stage: its COPY lines configure with '%s'" % command)


def server_settings(server):
    """{env var: (flag, default text)} from meshdenoise-server --help (with no MDN_* set)."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("MDN_")}
    out = subprocess.run([server, "--help"], env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    check(out.returncode == 0, "meshdenoise-server --help failed: %s" % out.stdout.decode(errors="replace"))
    text = out.stdout.decode()
    settings = {}
    for flag, var, default in re.findall(r"^  --([a-z-]+) \((MDN_[A-Z_]+)\)\n      .*; default: (.*)$", text, re.M):
        settings[var] = (flag, default.strip())
    check(len(settings) >= 10, "could not read the settings from --help:\n" + text)
    return settings


def check_env_accepted(server, settings, env, where):
    """Every variable is a setting and the server starts its parsing without complaint."""
    for k in env:
        check(k in settings, "%s sets %s, which is not a meshdenoise-server setting" % (where, k))
    base = {k: v for k, v in os.environ.items() if not k.startswith("MDN_")}
    base.update({k: str(v) for k, v in env.items()})
    r = subprocess.run([server, "--help"], env=base, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    check(r.returncode == 0, "the server rejects the environment of %s: %s" % (where, r.stdout.decode(errors="replace")))


def seconds(text):
    m = re.fullmatch(r"\s*(\d+(?:\.\d+)?)\s*(ms|s|m|h)?\s*", str(text))
    check(m is not None, "not a duration: %r" % text)
    scale = {"ms": 0.001, "s": 1, None: 1, "m": 60, "h": 3600}[m.group(2)]
    return float(m.group(1)) * scale


def size_bytes(text):
    m = re.fullmatch(r"\s*(\d+)\s*([kKmMgG])?\s*", str(text))
    check(m is not None, "not a size: %r" % text)
    return int(m.group(1)) << {None: 0, "k": 10, "m": 20, "g": 30}[(m.group(2) or "").lower() or None]


def cpus(text):
    text = str(text)
    return float(text[:-1]) / 1000 if text.endswith("m") else float(text)


def nginx_directive(conf, name, context=None):
    """The single value of a directive in docker/nginx/meshdenoise.conf (comments stripped)."""
    body = re.sub(r"#[^\n]*", "", conf)
    if context:
        m = re.search(context + r"\s*\{(.*?)\}", body, re.S)
        check(m is not None, "no %s block in the nginx configuration" % context)
        body = m.group(1)
    values = re.findall(r"(?:^|[;{\s])" + re.escape(name) + r"\s+([^;]*);", body)
    check(len(values) == 1, "expected one '%s' in the nginx configuration, found %s" % (name, values))
    return values[0].strip()


def redis_url_host_port(url):
    m = re.fullmatch(r"redis://(?:[^@]*@)?([^:/]+)(?::(\d+))?(?:/(\d+))?", url)
    check(m is not None, "MDN_QUEUE %r is not a redis:// URL" % url)
    return m.group(1), int(m.group(2) or 6379)


def redis_args_durable(args, where):
    """Accepted jobs must survive a crash of Redis: appendonly yes, appendfsync always (everysec
    may answer before writing; docker/README.md, "Job store")."""
    text = " ".join(args)
    check(re.search(r"--appendonly\s+yes", text) is not None, "%s runs Redis without --appendonly yes" % where)
    check(re.search(r"--appendfsync\s+always\b", text) is not None, "%s runs Redis without --appendfsync always" % where)


def check_compose_redis(compose, env):
    """The replicas share their jobs through the compose file's redis service."""
    check("MDN_QUEUE" in env, "docker-compose.yml runs several replicas without a shared MDN_QUEUE")
    host, port = redis_url_host_port(env["MDN_QUEUE"])
    check(host in compose["services"], "MDN_QUEUE names %s, which is not a compose service" % host)
    redis = compose["services"][host]
    check(str(port) in [str(p) for p in redis.get("expose", [])] or port == 6379,
          "the redis service does not expose port %d" % port)
    check("ports" not in redis, "compose publishes Redis; only the replicas need it")
    redis_args_durable(redis.get("command", []), "docker-compose.yml")
    check(any(str(v).endswith(":/data") for v in redis.get("volumes", [])), "compose keeps Redis's data on no volume")
    depends = compose["services"]["meshdenoise"].get("depends_on", {})
    check(depends.get(host, {}).get("condition") == "service_healthy", "the replicas start before Redis is healthy")


def check_k8s_redis(docs, env):
    """The pods' MDN_QUEUE names a Service that selects a Redis with an append-only file."""
    check("MDN_QUEUE" in env, "the Deployment runs several pods without a shared MDN_QUEUE")
    host, port = redis_url_host_port(env["MDN_QUEUE"])
    services = [d for d in docs if d["kind"] == "Service" and d["metadata"]["name"] == host]
    check(services, "MDN_QUEUE names %s, which is no Service in docker/k8s" % host)
    svc = services[0]
    check(any(p["port"] == port for p in svc["spec"]["ports"]), "Service %s has no port %d" % (host, port))
    workloads = [d for d in docs if d["kind"] in ("StatefulSet", "Deployment")
                 and all(d["spec"]["template"]["metadata"]["labels"].get(k) == v
                         for k, v in svc["spec"]["selector"].items())]
    check(len(workloads) == 1, "Service %s selects %d workloads" % (host, len(workloads)))
    container = workloads[0]["spec"]["template"]["spec"]["containers"][0]
    check("redis" in container["image"], "Service %s selects %s, not Redis" % (host, container["image"]))
    redis_args_durable(container.get("command", []) + container.get("args", []), "docker/k8s")


def main():
    args = parse_args()
    check(yaml is not None, "python3-yaml is not installed (scripts/install-deps.sh test)")
    d = args.docker_dir
    settings = server_settings(args.server)
    defaults = {k: v[1] for k, v in settings.items()}

    # --- The Dockerfile's runtime stage.
    stage = read_dockerfile(os.path.join(d, "Dockerfile"))
    check_env_accepted(args.server, settings, stage.env, "Dockerfile ENV")
    image_env = dict(defaults, **stage.env)
    port = int(image_env["MDN_PORT"])
    uid = int(stage.user.split(":")[0])
    check(image_env["MDN_HOST"] == "0.0.0.0", "the image listens on %s, not 0.0.0.0" % image_env["MDN_HOST"])
    check(str(port) in stage.expose, "EXPOSE %s but MDN_PORT %d" % (stage.expose, port))
    check(any("/healthz" in a for a in stage.healthcheck), "the HEALTHCHECK does not ask /healthz: %s" % stage.healthcheck)

    # --- docker-compose.yml
    with open(os.path.join(d, "docker-compose.yml")) as f:
        compose = yaml.safe_load(f)
    svc = compose["services"]["meshdenoise"]
    compose_env = {k: ("" if v is None else str(v)) for k, v in svc.get("environment", {}).items()}
    # ${VAR:-} interpolation: compose fills it from the shell; check the empty default.
    compose_env = {k: re.sub(r"\$\{[A-Z_]+:-([^}]*)\}", r"\1", v) for k, v in compose_env.items()}
    check_env_accepted(args.server, settings, compose_env, "docker-compose.yml")
    env = dict(image_env, **compose_env)
    check(svc["deploy"]["replicas"] >= 2, "compose runs fewer than 2 replicas")
    check(int(env["MDN_WORKERS"]) == cpus(svc["deploy"]["resources"]["limits"]["cpus"]),
          "compose: MDN_WORKERS %s but a CPU limit of %s" % (env["MDN_WORKERS"], svc["deploy"]["resources"]["limits"]["cpus"]))
    check(seconds(svc["stop_grace_period"]) > float(env["MDN_DRAIN_GRACE"]),
          "compose: stop_grace_period %s does not exceed MDN_DRAIN_GRACE %s" % (svc["stop_grace_period"], env["MDN_DRAIN_GRACE"]))
    check("ports" not in svc, "compose publishes the replicas themselves; only nginx should be")
    lb = compose["services"]["nginx"]
    mounts = [v for v in lb["volumes"] if "nginx/meshdenoise.conf" in v]
    check(mounts and mounts[0].split(":")[1] == "/etc/nginx/conf.d/default.conf",
          "compose does not mount nginx/meshdenoise.conf as the nginx site: %s" % lb["volumes"])
    check(lb["depends_on"]["meshdenoise"]["condition"] == "service_healthy", "nginx starts before the replicas are healthy")
    check_compose_redis(compose, env)

    # --- nginx
    with open(os.path.join(d, "nginx", "meshdenoise.conf")) as f:
        conf = f.read()
    check(re.search(r"upstream\s+meshdenoise\s*\{[^}]*\bleast_conn;", conf) is not None, "the upstream is not least_conn")
    check(re.search(r"server\s+meshdenoise:%d\b" % port, conf) is not None,
          "the nginx upstream does not point at the compose service on port %d" % port)
    body = size_bytes(nginx_directive(conf, "client_max_body_size"))
    check(body == int(env["MDN_MAX_BODY"]) if env["MDN_MAX_BODY"].isdigit() else body == size_bytes(env["MDN_MAX_BODY"]),
          "nginx client_max_body_size %d differs from MDN_MAX_BODY %s" % (body, env["MDN_MAX_BODY"]))
    check(seconds(nginx_directive(conf, "proxy_read_timeout")) > float(env["MDN_JOB_TIME_LIMIT"]),
          "proxy_read_timeout must exceed MDN_JOB_TIME_LIMIT %s" % env["MDN_JOB_TIME_LIMIT"])
    check(seconds(nginx_directive(conf, "keepalive_timeout", r"upstream\s+meshdenoise")) < float(env["MDN_KEEP_ALIVE_TIMEOUT"]),
          "nginx's upstream keepalive_timeout must stay below MDN_KEEP_ALIVE_TIMEOUT")
    check(int(nginx_directive(conf, "keepalive_requests", r"upstream\s+meshdenoise")) <= int(env["MDN_KEEP_ALIVE_MAX"]),
          "nginx's upstream keepalive_requests must not exceed MDN_KEEP_ALIVE_MAX")
    check(nginx_directive(conf, "max_ranges") == "1", "max_ranges is not 1")
    check(nginx_directive(conf, "proxy_request_buffering") == "on", "proxy_request_buffering is not on")
    check(re.search(r"location\s+[=~^]*\s*/v1/jobs", re.sub(r"#[^\n]*", "", conf)) is None,
          "nginx handles /v1/jobs itself; with the shared job store it must pass them to the replicas")
    retry = nginx_directive(conf, "proxy_next_upstream").split()
    check("error" in retry and "non_idempotent" in retry, "nginx does not resend a POST whose replica failed: %s" % retry)
    check(not any(s in retry for s in ("http_500", "http_400", "http_404", "http_429")),
          "nginx retries answers that a replica gave on purpose: %s" % retry)

    # --- Kubernetes
    docs = []
    for name in sorted(os.listdir(os.path.join(d, "k8s"))):
        if name.endswith(".yaml") and name != "kustomization.yaml":
            with open(os.path.join(d, "k8s", name)) as f:
                docs += [doc for doc in yaml.safe_load_all(f) if doc]
    # The service's own objects are named meshdenoise; others (its Redis) have other names.
    kinds = {doc["kind"]: doc for doc in docs if doc["metadata"]["name"] == "meshdenoise"}
    for kind in ("Deployment", "Service", "HorizontalPodAutoscaler"):
        check(kind in kinds, "docker/k8s has no %s named meshdenoise" % kind)
    dep, svc_k8s, hpa = kinds["Deployment"], kinds["Service"], kinds["HorizontalPodAutoscaler"]
    pod = dep["spec"]["template"]["spec"]
    c = pod["containers"][0]
    k8s_env = {e["name"]: e.get("value", "") for e in c.get("env", []) if "value" in e}
    check_env_accepted(args.server, settings, k8s_env, "the Kubernetes Deployment")
    for e in c.get("env", []):
        check(e["name"] in settings, "the Deployment sets %s, which is not a setting" % e["name"])
    env = dict(image_env, **k8s_env)
    check(c["ports"][0]["containerPort"] == port, "containerPort %s, image port %d" % (c["ports"][0]["containerPort"], port))
    check(c["readinessProbe"]["httpGet"]["path"] == "/readyz", "the readiness probe is not /readyz")
    check(c["livenessProbe"]["httpGet"]["path"] == "/healthz", "the liveness probe is not /healthz")
    check(int(env["MDN_WORKERS"]) == cpus(c["resources"]["limits"]["cpu"]),
          "Kubernetes: MDN_WORKERS %s but a CPU limit of %s" % (env["MDN_WORKERS"], c["resources"]["limits"]["cpu"]))
    check("requests" in c["resources"] and "memory" in c["resources"]["limits"], "resource requests/limits incomplete")
    pre_stop = 0.0
    cmd = c.get("lifecycle", {}).get("preStop", {}).get("exec", {}).get("command", [])
    if cmd[:1] == ["sleep"]:
        pre_stop = float(cmd[1])
    check(pod["terminationGracePeriodSeconds"] > pre_stop + float(env["MDN_DRAIN_GRACE"]),
          "terminationGracePeriodSeconds %s does not cover preStop %g s + MDN_DRAIN_GRACE %s"
          % (pod["terminationGracePeriodSeconds"], pre_stop, env["MDN_DRAIN_GRACE"]))
    sc = pod.get("securityContext", {})
    check(sc.get("runAsNonRoot") is True and sc.get("runAsUser") == uid,
          "the pod must run as non-root uid %d (the image's USER): %s" % (uid, sc))
    labels = dep["spec"]["template"]["metadata"]["labels"]
    check(all(labels.get(k) == v for k, v in svc_k8s["spec"]["selector"].items()), "the Service selects no pod of the Deployment")
    target = svc_k8s["spec"]["ports"][0]["targetPort"]
    check(target in (port, c["ports"][0].get("name")), "the Service targets %s, not the container port" % target)
    ref = hpa["spec"]["scaleTargetRef"]
    check(ref["kind"] == "Deployment" and ref["name"] == dep["metadata"]["name"], "the HPA scales %s" % ref)
    check([m["resource"]["name"] for m in hpa["spec"]["metrics"]] == ["cpu"], "the HPA does not scale on CPU")
    check_k8s_redis(docs, env)
    with open(os.path.join(d, "k8s", "kustomization.yaml")) as f:
        kustomized = yaml.safe_load(f)["resources"]
    for name in sorted(os.listdir(os.path.join(d, "k8s"))):
        if name.endswith(".yaml") and name != "kustomization.yaml":
            check(name in kustomized, "kustomization.yaml leaves out %s" % name)

    # --- docker/README.md lists every setting with --help's default.
    with open(os.path.join(d, "README.md")) as f:
        readme = f.read()
    rows = {m[1]: (m[0], m[2]) for m in re.findall(r"^\| `--([a-z-]+)` \| `(MDN_[A-Z_]+)` \| ([^|]*) \|", readme, re.M)}
    for var, (flag, default) in settings.items():
        check(var in rows, "docker/README.md's configuration table lacks %s" % var)
        check(rows[var][0] == flag, "docker/README.md names the flag of %s --%s, the server --%s" % (var, rows[var][0], flag))
        doc_default = rows[var][1].strip().strip("`")
        # --help prints "0 (N here)" for workers: the documented default is the setting, 0.
        check(default == doc_default or default.startswith(doc_default + " ("),
              "docker/README.md gives %s the default '%s', --help says '%s'" % (var, doc_default, default))
    for var in rows:
        check(var in settings, "docker/README.md documents %s, which the server does not have" % var)
    if args.source_dir:
        check_build_context(os.path.join(d, "Dockerfile"), args.source_dir)
    log("deployment files: %d settings documented, Dockerfile/compose/Kubernetes/nginx consistent" % len(settings))


if __name__ == "__main__":
    run_main(main)
