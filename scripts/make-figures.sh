#!/usr/bin/env bash
# Rebuilds every picture in docs/figures/ from real runs of the built binaries (about three
# minutes on 2 cores):
#   msae-vs-noise.png  MSAE against the noise level: auto (the default), the paper's Table 1 row
#                      and the Laplacian filter, on fandisk (CAD) and bunny00 (a scan)
#   time-vs-faces.png  seconds against face count (fandisk subdivided up to 828k faces)
#                      (both: tests/bench/figures_bench's rows, kept beside them as *.tsv, plotted
#                      by scripts/plot_figures.py with Debian's python3-matplotlib)
#   denoised.png       before/after renders of a CAD part (fandisk) and a scan (bunny00), each
#                      with noise added (0.3 mean edge lengths along the normal) and denoised by
#                      the built meshdenoise with its default parameters, and the displacement
#                      heat map (scripts/render_figures.mjs: three.js in headless Chromium)
#   architecture.png   docs/architecture.dot (regenerated from the folders by
#                      scripts/architecture_dot.py), drawn by graphviz's dot
# Each plot is stamped with the commit and this command.
# Usage: bash scripts/make-figures.sh [BUILD_DIR]     (default build/release)
# Needs: bash scripts/install-deps.sh build test figures, and a build with the benchmarks
# (cmake --preset release -DMDN_BUILD_BENCH=ON; cmake --build build/release --target figures_bench).
# MDN_FIGURE_THREADS sets the threads per run (default 2).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build/release}"
out="$root/docs/figures"
threads="${MDN_FIGURE_THREADS:-2}"
fail() { echo "make-figures.sh: $*" >&2; exit 2; }

bench="$build/tests/bench/figures_bench"
cli="$build/cli/meshdenoise"
[ -x "$cli" ] || fail "$cli is not built: cmake --build $build --target meshdenoise"
[ -d "$root/tests/tools/node_modules/three" ] || fail "three.js and puppeteer-core are missing: bash scripts/install-deps.sh test"
[ -x "$bench" ] || fail "$bench is not built: cmake --build $build --target figures_bench (a build with -DMDN_BUILD_BENCH=ON)"
command -v dot >/dev/null || fail "graphviz's dot is missing: bash scripts/install-deps.sh figures"
/usr/bin/python3 -c 'import matplotlib' 2>/dev/null || fail "python3-matplotlib is missing: bash scripts/install-deps.sh figures"
mkdir -p "$out"

commit="$(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)"
git -C "$root" diff --quiet HEAD -- core server 2>/dev/null || commit="$commit + uncommitted changes"
stamp="commit $commit, $(date -u +%Y-%m-%d), bash scripts/make-figures.sh, $threads threads on $(nproc) cores"

echo "make-figures.sh: MSAE against noise (figures_bench msae)" >&2
"$bench" msae --threads "$threads" > "$out/msae.tsv.partial"
mv "$out/msae.tsv.partial" "$out/msae.tsv"
echo "make-figures.sh: time against faces (figures_bench time)" >&2
"$bench" time --threads "$threads" --levels 0,1,2,3 --runs 3 > "$out/time.tsv.partial"
mv "$out/time.tsv.partial" "$out/time.tsv"
/usr/bin/python3 "$root/scripts/plot_figures.py" "$out/msae.tsv" "$out/time.tsv" "$out" "$stamp"
echo "make-figures.sh: before/after renders (meshdenoise, then three.js in Chromium)" >&2
meshes="$(bash "$root/scripts/fetch-cgal-data.sh" "$root/third_party_data/cgal")"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
for mesh in fandisk bunny00; do
  "$cli" --add-noise '{"kind": "along_normal", "sigma": 0.3, "seed": 1}' "$meshes/$mesh.off" "$work/${mesh}_noisy.off"
  "$cli" --no-progress --threads "$threads" "$work/${mesh}_noisy.off" "$work/${mesh}_denoised.off"
done
node "$root/scripts/render_figures.mjs" "$out/denoised.png" "$stamp" \
  "A CAD part: fandisk, noise 0.3 edge lengths" "$work/fandisk_noisy.off" "$work/fandisk_denoised.off" \
  "A scan: bunny00, noise 0.3 edge lengths" "$work/bunny00_noisy.off" "$work/bunny00_denoised.off"
python3 "$root/scripts/architecture_dot.py" > "$root/docs/architecture.dot"  # from the folders as they are
dot -Tpng -Gdpi=110 "$root/docs/architecture.dot" -o "$out/architecture.png"
echo "make-figures.sh: wrote $(cd "$out" && ls *.png | tr '\n' ' ')" >&2
