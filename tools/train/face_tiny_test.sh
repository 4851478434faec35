#!/usr/bin/env bash
# The per-face prior's offline pipeline on a few cases (ctest; decision 89): `train_corpus faces`
# writes the same bytes for one and two jobs, face_train.py --tiny writes the same model file
# twice, and that file has the shipped file's shape (core/auto/face_model_data.inc).
set -euo pipefail
build="$1"
work="$2"
rm -rf "$work"
mkdir -p "$work"
root="$(cd "$(dirname "$0")/../.." && pwd)"
fail() { echo "FAIL: $*" >&2; exit 1; }
"$build/tools/train/train_corpus" faces --jobs 1 --cases 8 --rows 200 "$work/one" > /dev/null
"$build/tools/train/train_corpus" faces --jobs 2 --cases 8 --rows 200 "$work/two" > /dev/null
for part in train.f32 holdout.f32 cases.tsv; do
  cmp -s "$work/one.$part" "$work/two.$part" || fail "train_corpus faces: $part differs between --jobs 1 and 2"
done
[ "$(wc -l < "$work/one.cases.tsv")" -eq 9 ] || fail "one.cases.tsv should hold 8 cases and a header"
[ "$(awk -F'\t' 'NR > 1 && $3 == "holdout"' "$work/one.cases.tsv" | wc -l)" -eq 2 ] || fail "a quarter of the cases are holdout"
# 46 float32 per row, at most 200 rows per case.
size=$(stat -c %s "$work/one.train.f32")
[ $((size % (46 * 4))) -eq 0 ] && [ "$size" -gt 0 ] && [ "$size" -le $((6 * 200 * 46 * 4)) ] || fail "train.f32 has $size bytes"
/usr/bin/python3 "$root/tools/train/face_train.py" "$work/one" "$work/a.inc" --tiny > /dev/null
/usr/bin/python3 "$root/tools/train/face_train.py" "$work/one" "$work/b.inc" --tiny > /dev/null
cmp -s "$work/a.inc" "$work/b.inc" || fail "face_train.py --tiny wrote different bytes twice"
for name in kVersion kCommit kTorch kBlas kTrainSha256 kHoldoutSha256 kTrainRows kHoldoutRows kInputs kHidden; do
  grep -q "constexpr .* $name = " "$work/a.inc" || fail "$name missing"
  grep -q "constexpr .* $name = " "$root/core/auto/face_model_data.inc" || fail "$name missing from the shipped file"
done
for array in kMean kScale kW0 kB0 kW1 kB1 kW2 kB2 kProbeInputs kProbeOutputs; do
  grep -q "constexpr double $array\[" "$work/a.inc" || fail "$array missing"
done
grep -q 'kInputs = 41;' "$work/a.inc" || fail "not 41 inputs"
sha=$(sha256sum "$work/one.train.f32" | cut -d' ' -f1)
grep -q "kTrainSha256 = \"$sha\"" "$work/a.inc" || fail "the training table's digest is not recorded"
echo "face prior pipeline: OK"
