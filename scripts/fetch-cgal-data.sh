#!/usr/bin/env bash
# Fetches the mesh data of Debian's libcgal-demo package (fandisk.off and friends) for the
# benchmarks, without installing the package: downloads the .deb, extracts the data.tar.gz
# it ships under /usr/share/doc, and keeps its data/meshes folder.
#
#   scripts/fetch-cgal-data.sh DEST     -> meshes under DEST/data/meshes; prints that folder
#
# Idempotent: does nothing if DEST/data/meshes/fandisk.off already exists. The data is
# third-party (CGAL, LGPL/GPL): never commit it (/third_party_data/ is git-ignored).
set -euo pipefail

if [ $# -ne 1 ]; then
  echo "usage: $0 DEST" >&2
  exit 2
fi
dest="$1"
meshes="$dest/data/meshes"
if [ -f "$meshes/fandisk.off" ]; then
  (cd "$meshes" && pwd)
  exit 0
fi

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
chmod 755 "$work"  # apt's download user (_apt) must be able to write here

download() { (cd "$work" && apt-get download -qq libcgal-demo >/dev/null 2>&1); }
if ! download; then
  echo "apt-get download failed; running apt-get update and retrying" >&2
  apt-get update -qq >/dev/null
  download || { echo "error: could not download libcgal-demo" >&2; exit 1; }
fi
deb="$(ls "$work"/libcgal-demo_*.deb)"

# Locate data.tar.gz inside the package (its path has moved between releases).
inner="$(dpkg-deb -c "$deb" | awk '{print $NF}' | grep '/data\.tar\.gz$' | head -n1)"
if [ -z "$inner" ]; then
  echo "error: no data.tar.gz in $(basename "$deb")" >&2
  exit 1
fi

mkdir -p "$dest"
dpkg-deb --fsys-tarfile "$deb" | tar -xO "$inner" > "$work/data.tar.gz"
tar -xzf "$work/data.tar.gz" -C "$work" data/meshes
mkdir -p "$dest/data"
rm -rf "$meshes.partial"
mv "$work/data/meshes" "$meshes.partial"
rm -rf "$meshes"
mv "$meshes.partial" "$meshes"  # atomic from the reader's side: fandisk.off appears last

if [ ! -f "$meshes/fandisk.off" ]; then
  echo "error: fandisk.off is missing from the extracted data" >&2
  exit 1
fi
(cd "$meshes" && pwd)
