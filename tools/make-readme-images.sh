#!/usr/bin/env bash
# Makes the README's pictures, docs/images/demo_{left,depth,depth_gt}.png, from a 320x320
# `curvestereo demo` (CPU backend: the same bytes on every machine):
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
ls -l docs/images/demo_*.png
