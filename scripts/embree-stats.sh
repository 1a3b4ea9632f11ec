#!/usr/bin/env bash
# Nodes, leaves and blocks a ray for Embree (its statistics counters) and nodes and triangles a
# ray for glint (`glint bench rays --stats`), on the anchors' meshes and rays: whether the two
# trees make a ray do the same work, apart from how fast each does it.
# usage: scripts/embree-stats.sh EMBREE_SRC [WORKDIR] [MESHES...]
#   EMBREE_SRC  an Embree 3.13.5 source tree (the version of Debian's libembree-dev, which the
#               anchors' harness links), e.g. from
#               git clone --depth 1 --branch v3.13.5 https://github.com/embree/embree
#               built here once with EMBREE_STAT_COUNTERS=ON (AVX2 at most; about 15 minutes
#               on 2 cores) into WORKDIR/embree-stats-build
#   WORKDIR     anchors' work folder (default $TMPDIR/glint-anchors), as for bench-vs-embree.sh
#   MESHES      default: bunny40k sphere1m sphere4m
# Embree counts Triangle4 blocks (up to four triangles each) where glint counts triangles.
set -euo pipefail
cd "$(dirname "$0")/.."
src=${1:?usage: scripts/embree-stats.sh EMBREE_SRC [WORKDIR] [MESHES...]}
work=${2:-${TMPDIR:-/tmp}/glint-anchors}
shift $(( $# > 2 ? 2 : $# ))
meshes=${*:-bunny40k sphere1m sphere4m}
anchors=${GLINT_SHARED:-../shared}/anchors
if ! [ -f "$work/rays/sphere4m.shadow.rays" ]; then
  scripts/bench-vs-embree.sh "$work" 1 >/dev/null
fi
build="$work/embree-stats-build"
if ! [ -f "$build/libembree3.so" ]; then
  command -v cmake >/dev/null || (apt-get update -qq && apt-get install -y -qq cmake) >/dev/null
  mkdir -p "$build"
  (cd "$build" && cmake "$src" -DCMAKE_BUILD_TYPE=Release -DEMBREE_ISPC_SUPPORT=OFF \
    -DEMBREE_TUTORIALS=OFF -DEMBREE_TASKING_SYSTEM=INTERNAL -DEMBREE_STAT_COUNTERS=ON \
    -DEMBREE_MAX_ISA=AVX2 >/dev/null && make -j"$(nproc)" embree >/dev/null)
fi
gcc -O2 -o "$build/embree_stats" scripts/embree_stats.c -I"$src/include" -I"$anchors" \
  -L"$build" -lembree3 -lm
cargo build --release --quiet --bin glint
echo "| mesh | rays | Embree nodes | Embree leaves | Embree blocks | glint nodes | glint triangles |"
echo "|---|---|---|---|---|---|---|"
for m in $meshes; do
  glint=$(target/release/glint bench rays "$work/$m.obj" "$work/rays/$m" --threads 1 --stats 2>&1)
  for kind in primary incoherent shadow; do
    mode=closest; [ "$kind" = shadow ] && mode=any
    LD_LIBRARY_PATH="$build" "$build/embree_stats" "$work/$m.obj" "$work/rays/$m.$kind.rays" "$mode" |
      python3 -c '
import re, sys
kind, mode, glint, mesh = sys.argv[1:5]
text = sys.stdin.read()
rays = int(re.search(r"^rays (\d+)", text, re.M).group(1))
# The first block of absolute counts (millions) of the ray kind traced.
head = "#normal_travs" if mode == "closest" else "#shadow_travs"
block = text[text.index(head):]
get = lambda name: float(re.search(name + r"\s*=\s*([0-9.e+-]+)M", block).group(1)) * 1e6 / rays
g = re.search(r"^\s*" + kind + r"\s+([0-9.]+) nodes/ray, ([0-9.]+) triangles", glint, re.M)
nodes, leaves, blocks = get("#nodes"), get("#leaves"), get("#prims")
print(f"| {mesh} | {kind} | {nodes:.2f} | {leaves:.2f} | {blocks:.2f} | {g.group(1)} | {g.group(2)} |")
' "$kind" "$mode" "$glint" "$m"
  done
done
