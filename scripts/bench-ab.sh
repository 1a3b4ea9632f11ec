#!/usr/bin/env bash
# Whole-render speed of two commits, in one run, as ratios.
#
#   scripts/bench-ab.sh OLD NEW [REPS]
#
# OLD and NEW are anything `git rev-parse` takes (`.` is the working tree); their release binaries are
# built as scripts/image-hashes.sh builds them (a temporary worktree, kept per commit). Each
# repetition renders every case with both binaries back to back, old first on odd repetitions and new
# first on even ones, so a change in the machine's load falls on both. The time is glint's own
# `render_ms` from --stats-json: the render alone (scene loading and the BVH build excluded). Medians
# of REPS (default 7) are printed with the ratio new/old.
#
# Cases, each at 1 and 16 spp (the default sampler and filter: the band loop), THREADS threads
# (default 1):
# - scenes/whitted.txt at 400x300 with its header's flags (shadows, refraction, 5 bounces);
# - the course's scene6_07 (40k-triangle bunny, two lights, shadows) at 400x400 and scene4_14
#   (the faceted gem, 5 bounces), as scripts/bench-vs-mitsuba.sh renders them; skipped, with a line,
#   without the course data ($GLINT_SHARED or ../shared).
# With AREA=1, also area lights (the Whitted tree's shadow rays from one point towards one light,
# traced in packets of 8 where a point takes at least 8 for a narrow sphere light), at 256x192:
# - scenes/sphere_lights_knot.txt with its own 4 shadow rays per light, and with 8
#   (--shadow-samples 8; its lights are near: few packets);
# - the same knot under two small far lights (its lights' spheres replaced by sed; packets walked
#   together), 8 shadow rays per light;
# - scenes/area_soft_shadows.txt (16 shadow rays per light: spheres and planes, a tree of one node).
# The machine may be shared: report `uptime` with the table.
set -euo pipefail
export LC_ALL=C
cd "$(dirname "$0")/.."
old_rev=${1:?usage: scripts/bench-ab.sh OLD NEW [REPS]}
new_rev=${2:?usage: scripts/bench-ab.sh OLD NEW [REPS]}
reps=${3:-7}
threads=${THREADS:-1}
old=$(scripts/image-hashes.sh --build "$old_rev")
new=$(scripts/image-hashes.sh --build "$new_rev")
shared=${GLINT_SHARED:-}
[ -n "$shared" ] || { [ -d ../shared/scenes ] && shared=../shared; } || true

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

names=()
args=()
add() { names+=("$1"); shift; args+=("$*"); }
add whitted "scenes/whitted.txt --size 400 300 --shadows --shade-back --bounces 5"
if [ -n "$shared" ] && [ -d "$shared/scenes/6837" ]; then
  add scene6_07 "$shared/scenes/6837/scene6_07_bunny_mesh_40k.txt --size 400 400 --shadows"
  add scene4_14 "$shared/scenes/6837/scene4_14_faceted_gem.txt --size 400 400 --shadows --shade-back --bounces 5 --weight 0.01"
else
  echo "bench-ab: no course data (set GLINT_SHARED): only scenes/whitted.txt" >&2
fi
if [ -n "${AREA:-}" ]; then
  knot="scenes/sphere_lights_knot.txt --size 256 192 --shadows"
  add knot_lights "$knot"
  add knot_lights_s8 "$knot --shadow-samples 8"
  sed -e 's/center -4.5 7 2 radius 1.2/center -30 40 25 radius 0.3/' \
    -e 's/center 5.5 3.5 -1 radius 0.35/center 35 25 -10 radius 0.1/' \
    -e "s#meshes/knot_16k.obj#$PWD/scenes/meshes/knot_16k.obj#" \
    scenes/sphere_lights_knot.txt >"$tmp/knot_small_lights.txt"
  add knot_small_lights_s8 "$tmp/knot_small_lights.txt --size 256 192 --shadows --shadow-samples 8"
  add area_soft_shadows "scenes/area_soft_shadows.txt --size 256 192 --shadows"
fi

# Prints the render time in ms of binary folder $1 on case $2 at $3 spp.
time_of() {
  local -a a
  read -ra a <<<"${args[$2]}"
  "$1/glint" render "${a[@]}" --spp "$3" --threads "$threads" --quiet -o "$tmp/out.png" \
    --stats-json "$tmp/stats.json" >/dev/null
  python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['render_ms'])" "$tmp/stats.json"
}

declare -A t_old t_new
for ((r = 1; r <= reps; r++)); do
  for c in "${!names[@]}"; do
    for spp in 1 16; do
      k=$c-$spp
      if ((r % 2)); then
        t_old[$k]+="$(time_of "$old" "$c" "$spp") "
        t_new[$k]+="$(time_of "$new" "$c" "$spp") "
      else
        t_new[$k]+="$(time_of "$new" "$c" "$spp") "
        t_old[$k]+="$(time_of "$old" "$c" "$spp") "
      fi
    done
  done
done

echo "| scene | spp | $old_rev ms | $new_rev ms | new/old |"
echo "|---|---|---|---|---|"
for c in "${!names[@]}"; do
  for spp in 1 16; do
    k=$c-$spp
    python3 - "${names[$c]}" "$spp" "${t_old[$k]}" "${t_new[$k]}" <<'PY'
import statistics, sys
name, spp = sys.argv[1], sys.argv[2]
o, n = (statistics.median(map(float, a.split())) for a in sys.argv[3:5])
print(f"| {name} | {spp} | {o:.1f} | {n:.1f} | {n / o:.3f} |")
PY
  done
done
echo "($reps alternating runs each, medians, $threads thread(s); $(uptime | sed 's/.*load/load/'))"
