#!/usr/bin/env bash
# Renders the Mitsuba 3 references of the path tracer's comparison tests (tests/mitsuba/), so
# that the tests need no Mitsuba. For each scene of scenes/ that has a twin:
#   NAME_ref.exr          the converged image (seed 0, REF_SPP samples per pixel)
#   NAME_seed1/2.exr      two renders at the tests' sample count (64) with seeds 1 and 2: their
#                         difference measures Mitsuba's own noise per 8x8 block
#   NAME_albedo95.exr     a deliberately wrong twin: every diffuse albedo times 0.95 (256 spp)
#   NAME_moved.exr        a deliberately wrong twin: every emitter moved by (0.1, 0, 0.1) (256 spp)
# 128x128 pixels, one thread each (the machine is shared). An image that exists is kept
# (FORCE=1 renders it again).
# usage: scripts/mitsuba_references.sh [VENV]   (default target/mitsuba-venv; made on first use)
set -euo pipefail
cd "$(dirname "$0")/.."
venv=${1:-target/mitsuba-venv}
if ! [ -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet mitsuba
fi
out=tests/mitsuba
twin() {
  if [ -e "$2" ] && [ -z "${FORCE:-}" ]; then return; fi
  echo "python3 scripts/mitsuba_twin.py $* --size 128 --threads 1"
  "$venv/bin/python" scripts/mitsuba_twin.py "$@" --size 128 --threads 1
}
for scene in cornell_box:1024 cornell_caustics:1024 mesh_sphere_light:1024; do
  name=${scene%%:*}
  ref_spp=${scene##*:}
  twin "scenes/$name.txt" "$out/${name}_ref.exr" --spp "$ref_spp" --seed 0
  twin "scenes/$name.txt" "$out/${name}_seed1.exr" --spp 64 --seed 1
  twin "scenes/$name.txt" "$out/${name}_seed2.exr" --spp 64 --seed 2
  twin "scenes/$name.txt" "$out/${name}_albedo95.exr" --spp 256 --seed 3 --albedo-scale 0.95
  twin "scenes/$name.txt" "$out/${name}_moved.exr" --spp 256 --seed 4 --move-emitters 0.1 0 0.1
done
