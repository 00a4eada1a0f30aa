#!/usr/bin/env bash
# relume's test command: installs what is missing, then runs every test of the workspace.
# GPU tests run on lavapipe (or a real GPU when there is one) with validation layers on.
set -euo pipefail
cd "$(dirname "$0")/.."
bash tools/setup.sh
cargo test --workspace --locked
