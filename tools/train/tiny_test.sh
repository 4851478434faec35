#!/usr/bin/env bash
# The offline pipeline end to end on a dozen cases (ctest): the model file it writes must have
# the shipped model's shape (the descriptors core computes, the identity set, every array).
set -euo pipefail
build="$1"
work="$2"
rm -rf "$work"
root="$(cd "$(dirname "$0")/../.." && pwd)"
MDN_BUILD_DIR="$build" bash "$root/tools/train/run.sh" --tiny --jobs 2 "$work"
model="$work/model_data.inc"
fail() { echo "FAIL: $*" >&2; exit 1; }
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
[ "$(grep -c '^gen_' "$work/generated.1")" -eq 64 ] || fail "expected 64 generated shapes"
awk '/^gen_/ && ($4 > 12000 || $4 < 200) { bad = 1 } END { exit bad }' "$work/generated.1" \
  || fail "a generated shape is outside 200-12,000 faces"
[ "$(grep '^gen_' "$work/generated.1" | grep -c holdout)" -ge 8 ] || fail "too few generated holdout shapes"
# A retessellated shape (decision 44) is in its parent's split: the same surface never in both.
awk '{ split_of[$1] = $3 } END { for (s in split_of) if (s ~ /~tess$/) { p = s; sub(/~tess$/, "", p);
       if (!(p in split_of) || split_of[p] != split_of[s]) { print s; bad = 1 } } exit bad }' "$work/shapes.1" \
  || fail "a retessellated shape is not in its parent's split"
[ "$(grep -c '~tess' "$work/shapes.1")" -ge 20 ] || fail "too few retessellated shapes"
echo "tiny training pipeline: ok"
