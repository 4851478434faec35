#!/usr/bin/env bash
# The offline pipeline end to end on a dozen cases (ctest): the model file it writes must have
# the shipped model's shape (the descriptors core computes, the identity set, every array), and
# its two tables and the model must be the bits recorded in tiny_digests.txt (decision 85).
#
#   bash tools/train/tiny_test.sh BUILD_DIR WORK_DIR [--jobs N] [--refresh]
#
# --refresh rewrites tiny_digests.txt from this run: after an intended change of the method, the
# corpus, the descriptors or the trainer (say which in the commit).
set -euo pipefail
build="$1"
work="$2"
shift 2
jobs=2
refresh=0
while [ $# -gt 0 ]; do
  case "$1" in
    --jobs) jobs="$2"; shift 2 ;;
    --refresh) refresh=1; shift ;;
    *) echo "usage: $0 BUILD_DIR WORK_DIR [--jobs N] [--refresh]" >&2; exit 2 ;;
  esac
done
rm -rf "$work"
root="$(cd "$(dirname "$0")/../.." && pwd)"
MDN_BUILD_DIR="$build" bash "$root/tools/train/run.sh" --tiny --jobs "$jobs" "$work"
model="$work/model_data.inc"
fail() { echo "FAIL: $*" >&2; exit 1; }
# Bit for bit: the tables, and the model file but for its "built" line (the date and the commit).
digests="$root/tools/train/tiny_digests.txt"
{
  echo "# tools/train/tiny_test.sh's run: the C++ build, the model card's toolchain line, and the SHA-256 of"
  echo "# the tables and of the model without its \"built\" line. Refresh after an intended change:"
  echo "#   bash tools/train/tiny_test.sh build/release /tmp/tiny --refresh"
  # The tables are the C++ build's: its compiler and build type (CMake's record of them; the
  # last one listed, should the build directory hold several CMake versions' records).
  cxx="$(ls "$build"/CMakeFiles/*/CMakeCXXCompiler.cmake | tail -n 1)"
  echo "compiler $(sed -n 's/^set(CMAKE_CXX_COMPILER_\(ID\|VERSION\) "\(.*\)")$/\2/p' "$cxx" | tr '\n' ' ')$(
    sed -n 's/^CMAKE_BUILD_TYPE:STRING=//p' "$build/CMakeCache.txt")"
  echo "toolchain $(grep -m1 '^//   python ' "$model" | cut -c6-)"
  echo "labels.tsv $(sha256sum < "$work/labels.tsv" | cut -d' ' -f1)"
  echo "descriptors.tsv $(sha256sum < "$work/descriptors.tsv" | cut -d' ' -f1)"
  echo "model_data.inc $(grep -v '^//   built ' "$model" | sha256sum | cut -d' ' -f1)"
} > "$work/digests.txt"
if [ "$refresh" = 1 ]; then
  cp "$work/digests.txt" "$digests"
  echo "tiny_digests.txt refreshed"
fi
if ! cmp -s <(grep -E '^(compiler|toolchain) ' "$work/digests.txt") <(grep -E '^(compiler|toolchain) ' "$digests"); then
  diff <(grep -E '^(compiler|toolchain) ' "$digests") <(grep -E '^(compiler|toolchain) ' "$work/digests.txt") >&2 || true
  fail "the compiler or the toolchain differs from those tiny_digests.txt was made with (<, above): the bits may differ for that alone"
fi
for name in labels.tsv descriptors.tsv model_data.inc; do
  [ "$(grep "^$name " "$work/digests.txt")" = "$(grep "^$name " "$digests")" ] \
    || fail "$name is not the recorded bits (tiny_digests.txt; $work/digests.txt has this run's)"
done
grep -q '^//   labels.tsv sha256 '"$(grep '^labels.tsv ' "$digests" | cut -d' ' -f2)" "$model" \
  || fail "the model card does not name the labels table's SHA-256"
[ "$(wc -l < "$work/labels.tsv")" -eq 13 ] || fail "labels.tsv should hold 12 cases and a header"
[ "$(wc -l < "$work/descriptors.tsv")" -eq 13 ] || fail "descriptors.tsv should hold 12 cases and a header"
# The descriptor names are the shipped model's (both lists generated from the same tables).
grep -o 'kDescriptorNames\[kInputs\] = {[^}]*}' "$model" > "$work/names.tiny"
grep -o 'kDescriptorNames\[kInputs\] = {[^}]*}' "$root/core/auto/model_data.inc" > "$work/names.shipped"
cmp -s "$work/names.tiny" "$work/names.shipped" || fail "descriptor names differ from core/auto/model_data.inc"
grep -q 'kSetNames\[kSetCount\] = {"identity", "a0.1_t30_k2_g30_n20_v10"' "$model" || fail "identity and the paper's row come first"
for array in kMean kScale kSetValues kW0 kB0 kW1 kB1 kW2 kB2 kProbeInputs kProbeOutputs; do
  grep -q "constexpr double $array\[" "$model" || fail "$array missing"
done
grep -q '"holdout"' "$work/report.json" || fail "no holdout figures"
# The generated shapes (generated_shapes.cpp) are the same on every run, 200 to 12,000 faces
# each (so every one gets all the noise kinds), and some of them are holdout.
"$build/tools/train/train_corpus" shapes > "$work/shapes.1"
"$build/tools/train/train_corpus" shapes > "$work/shapes.2"
cmp -s "$work/shapes.1" "$work/shapes.2" || fail "train_corpus shapes differs between two runs"
grep -v '~tess' "$work/shapes.1" > "$work/generated.1"
[ "$(grep -c '^gen_' "$work/generated.1")" -eq 80 ] || fail "expected 80 generated shapes (64, and 16 rough ones: decision 96)"
awk '/^gen_/ && ($4 > 12000 || $4 < 200) { bad = 1 } END { exit bad }' "$work/generated.1" \
  || fail "a generated shape is outside 200-12,000 faces"
[ "$(grep '^gen_' "$work/generated.1" | grep -c holdout)" -ge 8 ] || fail "too few generated holdout shapes"
# train_corpus export writes a case's two meshes: the same faces, the noise on the positions.
"$build/tools/train/train_corpus" export box_coarse/along:0.3 "$work/export" > /dev/null
faces=$(sed -n 2p "$work/export.clean.off" | cut -d' ' -f2)
[ "$faces" -gt 0 ] && [ "$(sed -n 2p "$work/export.noisy.off")" = "$(sed -n 2p "$work/export.clean.off")" ] \
  || fail "export: the two meshes' counts differ"
cmp -s <(tail -n "$faces" "$work/export.clean.off") <(tail -n "$faces" "$work/export.noisy.off") \
  || fail "export: the two meshes' faces differ"
! cmp -s "$work/export.clean.off" "$work/export.noisy.off" || fail "export: no noise on the noisy mesh"
"$build/tools/train/train_corpus" export no_such_shape/clean "$work/bad" 2> /dev/null && fail "export: an unknown shape was accepted"
"$build/tools/train/train_corpus" export box_coarse/clean "$work/no/such/dir/x" 2> /dev/null && fail "export: an unwritable path was accepted"
# A retessellated shape (decision 44) is in its parent's split: the same surface never in both.
awk '{ split_of[$1] = $3 } END { for (s in split_of) if (s ~ /~tess$/) { p = s; sub(/~tess$/, "", p);
       if (!(p in split_of) || split_of[p] != split_of[s]) { print s; bad = 1 } } exit bad }' "$work/shapes.1" \
  || fail "a retessellated shape is not in its parent's split"
[ "$(grep -c '~tess' "$work/shapes.1")" -ge 20 ] || fail "too few retessellated shapes"
# `fields` (issue 48's per-face bound): its "best1" is the best of candidates that hold the pick's
# own normals, so it never exceeds the pick's error; every case gets its row and the table its
# "all" line.
"$build/tools/train/train_corpus" fields --shapes washer_coarse,rounded_box_coarse --cases 3 > "$work/fields.txt"
awk '$1 ~ /\// && NF == 7 { rows++; if ($4 > 1.0000005) bad = 1 } $1 == "all" { all = 1 }
     END { exit !(rows >= 1 && all && !bad) }' "$work/fields.txt" \
  || fail "fields: a case whose best1 exceeds its pick's error, or no rows ($work/fields.txt)"
echo "tiny training pipeline: ok"
