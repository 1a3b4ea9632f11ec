#!/usr/bin/env bash
# Builds the anchors' mesh generator, makes the million-triangle mesh, and runs
# `glint bench` on the course's meshes plus that one. Usage: scripts/bench.sh [WORKDIR]
set -euo pipefail
cd "$(dirname "$0")/.."
work=${1:-target/anchors}
mkdir -p "$work"
[ -x "$work/meshgen" ] || gcc -O3 -o "$work/meshgen" ../shared/anchors/meshgen.c -lm
[ -f "$work/sphere1m.obj" ] || "$work/meshgen" 296 "$work/sphere1m.obj"
cargo build --release --bin glint
./target/release/glint bench --mesh "$work/sphere1m.obj" "${@:2}"
