#!/usr/bin/env bash
# Simulates a render farm on this machine: N processes each render one piece
# of the frame (as a Slurm array task or Kubernetes index would), then
# `glint merge` assembles them, and the result is compared with a single
# render of the same frame.
#
#   scripts/render-pieces.sh N [SCENE] [glint render flags...]
#   scripts/render-pieces.sh 7 scenes/whitted.txt --size 320 240 --spp 16 --shadows
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:?usage: scripts/render-pieces.sh N [SCENE] [flags...]}
scene=${2:-scenes/whitted.txt}
shift $(( $# >= 2 ? 2 : 1 ))
flags=("$@")
[ ${#flags[@]} -gt 0 ] || flags=(--size 320 240 --spp 16 --sampler sobol --filter gaussian:0.6 --shadows --shade-back --bounces 5)
cargo build --release --quiet --bin glint
glint=${CARGO_TARGET_DIR:-target}/release/glint
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
threads=$(( $(nproc) / n )); [ "$threads" -ge 1 ] || threads=1
for ((i = 0; i < n; i++)); do
  TASK_INDEX=$i "$glint" render "$scene" -o "$work/piece-$i.exr" "${flags[@]}" --threads "$threads" --quiet --tile-from-env TASK_INDEX/"$n" &
done
wait
"$glint" merge "$work"/piece-*.exr -o "$work/merged.exr"
"$glint" render "$scene" -o "$work/single.exr" "${flags[@]}" --quiet
if cmp -s "$work/merged.exr" "$work/single.exr"; then
  echo "$n pieces merged into an image identical to a single render"
else
  echo "the merged image differs from a single render" >&2
  exit 1
fi
