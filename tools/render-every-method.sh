#!/usr/bin/env bash
# Renders every method on every shipped scene with the relume binary RELUME into OUT (256 x 256;
# bakes of 64 rays per texel, light path maps of E = 1024, C = 16, D = 2; light path maps in each
# composition and with an ambient term). Given a third folder (the same run of another binary),
# compares every EXR with its twin byte for byte and exits 1 on any difference: the check that a
# restructuring changed no pixel (docs/BENCHMARKS.md, "Methods as units").
#   bash tools/render-every-method.sh ./relume-before out/before
#   bash tools/render-every-method.sh ./target/release/relume out/after out/before
set -euo pipefail
relume=$1; out=$2; twin=${3:-}
cd "$(dirname "$0")/.."
mkdir -p "$out"
render() { "$relume" render "$scene" --width 256 --height 256 --out "$out/$s-$1.exr" "${@:2}" >/dev/null; }
for scene in scenes/*.gltf; do
  s=$(basename "$scene" .gltf)
  render direct --direct-only
  render constant
  "$relume" bake "$scene" --method obscurance --rays 64 --out "$out/bake-$s-obscurance" >/dev/null
  render obscurance --bake "$out/bake-$s-obscurance"
  # Light path maps need a punctual light: a scene lit by its environment alone is refused
  # ("this scene has none"); any other failure stops the check.
  if "$relume" bake "$scene" --method light-path-maps --rays 64 --entry-points 1024 --clusters 16 --basis 2 --out "$out/bake-$s-light-path-maps" >/dev/null 2>"$out/$s-light-path-maps.log"; then
    for c in plain times-obscurance times-obscurance-with-direct; do
      render "light-path-maps-$c" --bake "$out/bake-$s-light-path-maps" --composition $c
    done
    render light-path-maps-ambient --bake "$out/bake-$s-light-path-maps" --ambient 0.5 --beta 0.2
  elif grep -q "this scene has none" "$out/$s-light-path-maps.log"; then
    echo "$s: light path maps not baked: $(tail -1 "$out/$s-light-path-maps.log")"
  else
    cat "$out/$s-light-path-maps.log" >&2
    exit 1
  fi
  echo "$s rendered"
done
[ -z "$twin" ] && exit 0
differ=0
for f in "$out"/*.exr; do
  if ! cmp -s "$f" "$twin/$(basename "$f")"; then echo "differs: $(basename "$f")"; differ=1; fi
done
echo "$(ls "$out"/*.exr | wc -l) images compared with $twin"
exit $differ
