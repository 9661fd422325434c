#!/usr/bin/env bash
# Makes the README's pictures, docs/images/demo_{left,depth,depth_gt}.png, from a 320x320
# `curvestereo demo`, and docs/images/rig_panorama{,_depth}.png, the grey and range panoramas
# of a synthetic four-camera ring (`synth --rig ring4`) solved by `run` (CPU backend both: the
# same bytes on every machine):
#   tools/make-readme-images.sh [CLI]        (CLI defaults to build/tools/curvestereo)
set -euo pipefail
cd "$(dirname "$0")/.."
cli=${1:-build/tools/curvestereo}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$cli" demo --size 320 --backend cpu -o "$work/demo" >/dev/null
mkdir -p docs/images
cp "$work/demo/left.png" docs/images/demo_left.png
cp "$work/demo/depth.png" docs/images/demo_depth.png
cp "$work/demo/depth_gt.png" docs/images/demo_depth_gt.png
# A modest size: the ring renders and solves in seconds; the panorama is 1024 x 512.
"$cli" synth --rig ring4 --size 256 -o "$work/ring4" --quiet >/dev/null
"$cli" run --calib "$work/ring4/camchain.yaml" "$work"/ring4/cam{0,1,2,3}.png -o "$work/ring4/out" \
  --backend cpu --panorama-width 1024 >/dev/null
cp "$work/ring4/out/panorama.png" docs/images/rig_panorama.png
cp "$work/ring4/out/panorama_depth.png" docs/images/rig_panorama_depth.png
ls -l docs/images/demo_*.png docs/images/rig_panorama*.png
