#!/usr/bin/env bash
# Digests of `curvestereo run`'s outputs for every backend x preset x pair given, one line
# each ("backend preset pair file md5"), so that two revisions' lines can be compared with
# diff: a refactoring that must keep results bit-identical (issue 16) shows no difference.
#
#   tools/output_digest.sh CLI "cuda vulkan" "realtime quality" PAIRDIR... > digest.txt
#
# A PAIRDIR holds camchain.yaml, left.png, right.png (and mask.png, used when present).
set -euo pipefail
cli=$1 backends=$2 presets=$3
shift 3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for pair in "$@"; do
  name=$(basename "$pair")
  mask=()
  [ -f "$pair/mask.png" ] && mask=(--mask "$pair/mask.png")
  for backend in $backends; do
    for preset in $presets; do
      out="$work/$backend-$preset-$name"
      "$cli" run --calib "$pair/camchain.yaml" "$pair/left.png" "$pair/right.png" -o "$out" \
        --backend "$backend" --preset "$preset" "${mask[@]}" >/dev/null
      for f in "$out"/*; do
        echo "$backend $preset $name $(basename "$f") $(md5sum <"$f" | cut -d' ' -f1)"
      done
    done
  done
done
