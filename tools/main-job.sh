#!/usr/bin/env bash
# relume's main job on the default scene: installs what is missing, builds, bakes and renders
# `cornell` headless with the Vulkan renderer and with the reference path tracer, compares
# them and writes the images and out/cornell/report.md (extra arguments go to `relume run`);
# then runs the default bench sweep (every method, cornell with a moving light and classroom:
# costs, errors, charts with the Pareto front, and the cheapest configuration of each method
# within NRMSE 0.2 in out/bench/recommended.toml) into out/bench/report.md.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
cargo build --release --locked -p relume-tools
./target/release/relume run scenes/cornell.gltf --out out/cornell "$@"
./target/release/relume bench tools/sweeps/default.toml --out out/bench --budget 0.2
