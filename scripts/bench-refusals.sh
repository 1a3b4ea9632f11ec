#!/usr/bin/env bash
# How long glint takes to refuse requests it must refuse before any work
# (the timing the tests do not assert: a loaded machine would fail them).
# Prints, per request, the median wall time of N runs (default 9) in ms.
# Usage: scripts/bench-refusals.sh [N]. Runs on a fresh clone (own scenes only).
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-9}
cargo build --release --bins --quiet
rt=$PWD/target/release/raytracer
glint=$PWD/target/release/glint
scene=$PWD/scenes/whitted.txt
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
printf '%s\n' 'OrthographicCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 size 4 }' \
  'Lights { numLights 0 }' 'Background { color 0 0 0 }' \
  'Materials { numMaterials 1 Noise { materialIndex 0 materialIndex 0 octaves 2000000000 } }' \
  'Group { numObjects 0 }' > octaves.txt

median_ms() { # command...: median wall time in ms of $n runs (exit status ignored)
  local t=()
  for _ in $(seq "$n"); do
    local s e
    s=$(date +%s%N)
    "$@" >/dev/null 2>&1 || true
    e=$(date +%s%N)
    t+=($(((e - s) / 1000000)))
  done
  printf '%s\n' "${t[@]}" | sort -n | sed -n "$(((n + 1) / 2))p"
}

printf '%-58s %s\n' "request (each must be refused with exit 2)" "median ms"
row() { printf '%-58s %s\n' "$1" "$(median_ms "${@:2}")"; }
row "raytracer -size 100000 100000 (596 GiB)" "$rt" -input "$scene" -size 100000 100000 -output h.png
row "raytracer -size 4000 4000 -bounces 9 -normals bad.jpeg" "$rt" -input "$scene" -size 4000 4000 -bounces 9 -shadows -output f.png -normals bad.jpeg
row "raytracer -threads 100000" "$rt" -input "$scene" -output o.png -threads 100000
row "glint render --threads 100000" "$glint" render "$scene" -o o.png --threads 100000
row "raytracer, Noise octaves 2000000000" "$rt" -input octaves.txt -output o.png -size 8 8
row "raytracer -input /dev/zero" "$rt" -input /dev/zero -output o.png
