#!/usr/bin/env bash
# relume's test command: installs what is missing, checks the formatting, builds the renderer
# crate alone (so that a feature only the workspace turns on cannot hide a wrong dependency),
# then runs every test of the workspace, and the ray-casting tests once more with Embree (the
# yardstick `relume rays --features embree` measures relume's BVH against, and the backend
# `--ray-backend embree` puts behind its ray calls). GPU tests run on
# lavapipe (or a real GPU when there is one) with validation layers on.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
cargo fmt --all --check
cargo build --locked -p relume-renderer
cargo test --workspace --locked
cargo test --locked -p relume-bake --features embree --test ray_casting
