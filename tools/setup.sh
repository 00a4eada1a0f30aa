#!/usr/bin/env bash
# Installs what relume needs from Debian when it is missing: Mesa's lavapipe (software
# Vulkan), the Vulkan loader and validation layers, and shaderc with the glslang and
# SPIRV-Tools static libraries it links against (and g++ for libstdc++, which they need), and
# the DejaVu font the bench's charts set their text in, the X virtual framebuffer the viewer's
# tests open their window on, Embree 3 (the ray caster the tests and `relume rays` hold relume's
# BVH against; relume itself never needs it), Slurm and munge (the one-node cluster on loopback,
# tools/slurm-local.sh, that the sharded bakes' tests run on) (and, when asked, Blender's
# probes).
# Safe to run again: it installs nothing
# that is already there.
set -euo pipefail

packages=(mesa-vulkan-drivers libvulkan1 libvulkan-dev vulkan-validationlayers g++
          libshaderc-dev glslang-dev spirv-tools fonts-dejavu-core xvfb libembree-dev
          slurmctld slurmd slurm-client munge)
# `setup.sh probes` adds Blender's CC0 studio-light probes (real captured environments, 1024 x
# 512 lat-long EXRs in /usr/share/blender/datafiles/studiolights/world/), which the main job
# and the fiv-probes sweep light fiv-blobs by; the tests need none of them.
if [ "${1:-}" = probes ]; then
  packages+=(blender-data)
fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if ! command -v cargo >/dev/null; then
  echo "setup: cargo is missing; install a Rust toolchain (rustup) first" >&2
  exit 1
fi
