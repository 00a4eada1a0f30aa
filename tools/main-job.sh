#!/usr/bin/env bash
# relume's main job on the default scene: installs what is missing, builds, renders `cornell`
# headless with the Vulkan renderer and with the reference path tracer, compares them and
# writes the images and out/cornell/report.md. Extra arguments go to `relume run`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
cargo build --release --locked -p relume-tools
./target/release/relume run scenes/cornell.gltf --out out/cornell "$@"
