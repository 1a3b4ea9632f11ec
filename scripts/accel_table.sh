#!/usr/bin/env bash
# The measured tables of docs/acceleration.md ("Every choice side by side"), in
# one command: every accelerator on glint's own mesh scenes plus two generated
# scenes with deep transform hierarchies (flattened and not), then on the
# course's meshes (the stadiums are left out: the grids take minutes there,
# and the table above this one in the doc already shows them).
# Usage: scripts/accel_table.sh [extra `glint bench` args]
# (the course folder is $GLINT_SHARED/scenes/6837, GLINT_SHARED defaulting to
# ../shared).
set -euo pipefail
cd "$(dirname "$0")/.."
course="${GLINT_SHARED:-../shared}/scenes/6837"
cargo build --release --bin glint
args=(--size 128 --runs 3 --none-limit 5 "$@")
"${CARGO_TARGET_DIR:-target}"/release/glint bench --only mesh_knot,tree,_x64 "${args[@]}"
echo
"${CARGO_TARGET_DIR:-target}"/release/glint bench --course "$course" --only bunny_mesh,logo "${args[@]}"
