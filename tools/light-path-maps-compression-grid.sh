#!/usr/bin/env bash
# Image error of light path maps per clustered-PCA size (docs/BENCHMARKS.md): bakes `cornell`
# uncompressed and at every C in 8 16 32 64 and D in 1 2 4 8, renders each at 128x128 with the
# Vulkan renderer, and compares it with the reference path tracer (256 spp at pixel centres)
# and with the uncompressed render. Prints one line per bake.
#   bash tools/light-path-maps-compression-grid.sh [OUT] [ENTRY_POINTS] [PATCHES]
# The defaults (2048 entry points, a 2,700-patch atlas) keep the uncompressed transfer within
# the 128 MiB one storage buffer may span on lavapipe. Needs a built relume (cargo build
# --release -p relume-tools; RELUME=path picks another binary).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/light-path-maps-grid}
entry_points=${2:-2048}
patches=${3:-2700}
relume=${RELUME:-$PWD/target/release/relume}
scene=$PWD/scenes/cornell.gltf
mkdir -p "$out"
cd "$out"
common=(--method light-path-maps --entry-points "$entry_points" --atlas-max 128 --patches "$patches")
size=(--width 128 --height 128)
nrmse() { "$relume" compare "$@" | sed -n 's/^NRMSE //p'; }

[ -f reference.exr ] || "$relume" reference "$scene" "${size[@]}" --spp 256 --pixel-centres --out reference.exr > /dev/null
"$relume" bake "$scene" "${common[@]}" --uncompressed --out uncompressed > uncompressed.log 2>&1
# Past 128 MiB the renderer refuses the uncompressed transfer: the grid goes on without it.
rm -f uncompressed.exr
if "$relume" render "$scene" --bake uncompressed "${size[@]}" --out uncompressed.exr > uncompressed-render.log 2>&1; then
  echo "uncompressed: $(grep -o '[0-9.]* MiB -> [0-9.]* MiB' uncompressed.log); image vs reference $(nrmse uncompressed.exr reference.exr)"
else
  echo "uncompressed: $(grep -o '[0-9.]* MiB -> [0-9.]* MiB' uncompressed.log); not rendered: $(tail -1 uncompressed-render.log)"
fi
vs_uncompressed() { [ -f uncompressed.exr ] && echo ", vs uncompressed $(nrmse "$1" uncompressed.exr --reference-layer radiance)" || true; }
for c in 8 16 32 64; do
  for d in 1 2 4 8; do
    name=c${c}_d${d}
    "$relume" bake "$scene" "${common[@]}" --clusters $c --basis $d --out $name > $name.log 2>&1
    "$relume" render "$scene" --bake $name "${size[@]}" --out $name.exr > /dev/null
    echo "C $c D $d: $(grep -o 'relative error [0-9.]*, [0-9.]* MiB -> [0-9.]* MiB' $name.log); image vs reference $(nrmse $name.exr reference.exr)$(vs_uncompressed $name.exr)"
  done
done
