#!/usr/bin/env bash
# Rebuilds the trained parameter choice from nothing: corpus labels, descriptors, model.
#
#   bash tools/train/run.sh [--tiny] [--jobs N] WORK_DIR
#
# WORK_DIR keeps labels.tsv and descriptors.tsv (resumable: a rerun computes only the cases
# they lack; delete descriptors.tsv after changing core/auto/descriptors.cpp, labels.tsv after
# changing the method or the label grid) and the model. Without --tiny the model is written to
# core/auto/model_data.inc (rebuild afterwards); with --tiny (CI: a dozen small cases, seconds)
# to WORK_DIR/model_data.inc only. Needs a Release build with the benchmarks
# (build/release/tools/train/train_corpus; $MDN_BUILD_DIR overrides), CGAL's demo data for the
# full corpus (fetched on first use) and Debian's python3-sklearn.
#
# Reproducible to the bit (decision 85): the tables are sorted by case once filled (the same
# bytes for any --jobs), and the training runs on one thread with Debian's reference BLAS
# (libblas3) whatever BLAS the alternatives select, so the same tables give the same model.
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
tiny=0
jobs="$(nproc)"
while [ $# -gt 1 ]; do
  case "$1" in
    --tiny) tiny=1; shift ;;
    --jobs) jobs="$2"; shift 2 ;;
    *) echo "usage: $0 [--tiny] [--jobs N] WORK_DIR" >&2; exit 2 ;;
  esac
done
[ $# -eq 1 ] || { echo "usage: $0 [--tiny] [--jobs N] WORK_DIR" >&2; exit 2; }
work="$1"
mkdir -p "$work"
bin="${MDN_BUILD_DIR:-$root/build/release}/tools/train/train_corpus"
[ -x "$bin" ] || { echo "$bin not found: build the Release preset with -DMDN_BUILD_BENCH=ON" >&2; exit 2; }
python=/usr/bin/python3  # Debian's, with python3-sklearn (not a virtual environment's)

select=()
train_args=()
if [ "$tiny" = 1 ]; then
  # Small procedural shapes only (no CGAL data), two of them holdout shapes.
  select=(--shapes box_coarse,sphere_coarse,torus_coarse,gear_coarse,washer_coarse,rounded_box_coarse --limit 12)
  train_args=(--members 1 --sets 8 --hidden 8)
  out="$work/model_data.inc"
else
  out="$root/core/auto/model_data.inc"
fi
# Rows are appended as cases finish (in any order with several jobs): the header, then by case.
sort_table() { { head -n 1 "$1"; tail -n +2 "$1" | LC_ALL=C sort; } > "$1.sorted" && mv "$1.sorted" "$1"; }
"$bin" label --jobs "$jobs" "${select[@]}" "$work/labels.tsv"
sort_table "$work/labels.tsv"
"$bin" describe --jobs "$jobs" "${select[@]}" "$work/descriptors.tsv"
sort_table "$work/descriptors.tsv"
# One thread, one BLAS: numpy and scipy link libblas.so.3 and liblapack.so.3, which the loader
# finds in libblas3's and liblapack3's own directories before the alternatives' choice (an
# OpenBLAS picks its kernels by CPU and may use threads; OPENBLAS_CORETYPE pins the x86-64
# baseline's should one be loaded all the same). train.py records the library it got.
lib=/usr/lib/x86_64-linux-gnu
for f in blas/libblas.so.3 lapack/liblapack.so.3; do
  [ -e "$lib/$f" ] || { echo "$lib/$f not found: install libblas3 and liblapack3" >&2; exit 2; }
done
pinned_python=(env LD_LIBRARY_PATH="$lib/blas:$lib/lapack" OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1
               OPENBLAS_CORETYPE=Prescott PYTHONHASHSEED=0 "$python")
"${pinned_python[@]}" "$root/tools/train/train.py" "$work/labels.tsv" "$work/descriptors.tsv" "$out" \
  --report "$work/report.json" "${train_args[@]}"
echo "model written to $out"

# The per-face prior (issue 48; decisions 87-89): its rows and its network, into
# core/auto/face_model_data.inc, on the same pinned BLAS as the parameter model (decision 85).
# Not with --tiny: ctest's face_tiny_test.sh checks that part.
if [ "$tiny" = 0 ]; then
  "$bin" faces --jobs "$jobs" --cases 1000 --rows 600 "$work/face_rows"
  "${pinned_python[@]}" "$root/tools/train/face_train.py" "$work/face_rows" "$root/core/auto/face_model_data.inc" \
    --hidden 32 --report "$work/face_report.json"
  echo "face prior written to $root/core/auto/face_model_data.inc"
fi
