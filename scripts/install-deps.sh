#!/usr/bin/env bash
# Installs the Debian packages listed in scripts/deps/apt-<list>.txt, then the npm packages: for
# a build, the web page's three.js (server/web, `npm ci` from its lock file); for tests, the npm
# tools of tests/tools. Idempotent; needs root on a Debian bookworm machine.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/.." && pwd)"

packages=()
for list in "$@"; do
  while read -r line; do
    line="${line%%#*}"; line="$(echo "$line" | xargs)"
    [ -n "$line" ] && packages+=("$line")
  done < "$here/deps/apt-$list.txt"
done

missing=()
for p in "${packages[@]}"; do
  # node and npm may come from elsewhere on a developer machine; only install if absent.
  if [ "$p" = nodejs ] && command -v node >/dev/null 2>&1; then continue; fi
  if [ "$p" = npm ] && command -v npm >/dev/null 2>&1; then continue; fi
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ "${#missing[@]}" -gt 0 ]; then
  echo "installing: ${missing[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# The web page's three.js, exactly as locked (the build embeds it): for every build.
if [[ " $* " == *" build "* ]] && [ -f "$root/server/web/package-lock.json" ]; then
  if [ ! -d "$root/server/web/node_modules" ] || [ "$root/server/web/package-lock.json" -nt "$root/server/web/node_modules" ]; then
    (cd "$root/server/web" && npm ci --no-audit --no-fund --loglevel=error && touch node_modules)
  fi
fi

if [[ " $* " == *" test "* ]] && [ -f "$root/tests/tools/package.json" ]; then
  if [ ! -d "$root/tests/tools/node_modules" ] || [ "$root/tests/tools/package.json" -nt "$root/tests/tools/node_modules" ]; then
    (cd "$root/tests/tools" && npm install --no-audit --no-fund --loglevel=error && touch node_modules)
  fi
fi

# The Node glTF-Transform client example's own packages (its lock file): the tests run it as documented.
if [[ " $* " == *" test "* ]] && [ -f "$root/client-examples/node/package-lock.json" ]; then
  if [ ! -d "$root/client-examples/node/node_modules" ] || [ "$root/client-examples/node/package-lock.json" -nt "$root/client-examples/node/node_modules" ]; then
    (cd "$root/client-examples/node" && npm ci --no-audit --no-fund --loglevel=error && touch node_modules)
  fi
fi
