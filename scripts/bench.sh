#!/usr/bin/env bash
# Builds the anchors' mesh generator, makes the million-triangle mesh, and runs
# `glint bench` on glint's meshes plus that one. Usage: scripts/bench.sh [WORKDIR]
# Needs the course data (the anchors' meshgen.c): GLINT_SHARED, or ../shared.
set -euo pipefail
cd "$(dirname "$0")/.."
shared=${GLINT_SHARED:-../shared}
if [ ! -f "$shared/anchors/meshgen.c" ]; then
  echo "scripts/bench.sh: needs the course data: no anchors/meshgen.c in $shared (set GLINT_SHARED)" >&2
  exit 2
fi
work=${1:-target/anchors}
mkdir -p "$work"
[ -x "$work/meshgen" ] || gcc -O3 -o "$work/meshgen" "$shared/anchors/meshgen.c" -lm
[ -f "$work/sphere1m.obj" ] || "$work/meshgen" 296 "$work/sphere1m.obj"
cargo build --release --bin glint
"${CARGO_TARGET_DIR:-target}"/release/glint bench --mesh "$work/sphere1m.obj" "${@:2}"
