#!/usr/bin/env bash
# relume's main job: installs what is missing, builds, bakes and renders the default scene
# `cornell` headless with the Vulkan renderer (every method that suits it: direct, constant,
# obscurance, light path maps, light clouds, MRT) and with the reference path tracer, compares
# them and writes the images and out/cornell/report.md (extra arguments go to `relume run`);
# then `fiv-blobs` under a real captured probe (Blender's CC0 forest, from Debian's
# blender-data): fullsphere irradiance vectors, and the ambient methods lit by the probe's
# irradiance, baked, rendered and compared the same way into out/fiv-blobs/report.md; then
# the default bench sweep (cornell with a moving light and classroom: costs, errors, charts
# with the Pareto front, and the cheapest configuration of each method within NRMSE 0.2 and
# per scene the cheapest method of all in out/bench/recommended.toml) into out/bench/report.md.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh probes
cargo build --release --locked -p relume-tools
./target/release/relume run scenes/cornell.gltf --out out/cornell "$@"
./target/release/relume run scenes/fiv-blobs.gltf --out out/fiv-blobs --frames 10 \
  --environment /usr/share/blender/datafiles/studiolights/world/forest.exr "$@"
./target/release/relume bench tools/sweeps/default.toml --out out/bench --budget 0.2
