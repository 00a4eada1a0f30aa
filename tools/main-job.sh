#!/usr/bin/env bash
# relume's main job: installs what is missing, builds, then
# 1. bakes and renders the default scene `cornell` headless with the Vulkan renderer (every
#    method that suits it: direct, constant, obscurance, light path maps, light clouds, MRT)
#    and with the reference path tracer, compares them and writes the images and
#    out/cornell/report.md (extra arguments go to `relume run`);
# 2. does the same for `fiv-blobs` under a real captured probe (Blender's CC0 forest, from
#    Debian's blender-data): fullsphere irradiance vectors and their competitors, constant and
#    obscurance ambient light by the probe's irradiance, into out/fiv-blobs/report.md;
# 3. runs the cross-method sweep (every method on five scenes where it applies, at two
#    configurations of each method with parameters: costs, errors, a chart per scene with every method and its Pareto
#    front, and per scene the cheapest method within NRMSE 0.2 in out/bench/recommended.toml)
#    into out/bench/report.md, and out/report.md, the page to open first: the budget's
#    answer, the charts across methods and the table across methods, linking the reports.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh probes
echo "main job: building relume (release; minutes on a fresh machine)"
cargo build --release --locked -p relume-tools
echo "main job: 1/3 cornell, every method that suits it, against the reference"
./target/release/relume run scenes/cornell.gltf --out out/cornell --frames 20 "$@"
echo "main job: 2/3 fiv-blobs under Blender's forest probe"
./target/release/relume run scenes/fiv-blobs.gltf --out out/fiv-blobs --frames 10 \
  --environment /usr/share/blender/datafiles/studiolights/world/forest.exr "$@"
echo "main job: 3/3 the cross-method sweep (tools/sweeps/default.toml)"
./target/release/relume bench tools/sweeps/default.toml --out out/bench --budget 0.2 \
  --overview out/report.md --link out/cornell/report.md --link out/fiv-blobs/report.md
echo "main job: done; open out/report.md"
