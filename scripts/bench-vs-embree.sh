#!/usr/bin/env bash
# glint's fast BVH against Embree on the anchors' meshes and rays, as ratios taken in one run.
# usage: scripts/bench-vs-embree.sh [WORKDIR] [REPS] [MESHES...]
#   WORKDIR  anchors' work folder (default $TMPDIR/glint-anchors); ../shared/anchors/run.sh fills it
#            (apt-installs libembree-dev, builds the harness, makes meshes and rays; ~5 minutes once)
#   REPS     repetitions (default 3); each ratio in the table is the median over them
#   MESHES   default: bunny40k sphere1m sphere4m
# Each repetition runs Embree's harness and `glint bench rays` back to back, per mesh and thread
# count (1 and 2), so both see the same machine load; both report the best of 3 passes after a
# warm-up and the best of 5 builds. Ratios: throughput glint/Embree (>1: glint faster), build time glint/Embree MEDIUM (<1:
# glint faster), both against Embree's default MEDIUM build and single-ray queries (rtcIntersect1 /
# rtcOccluded1). glint traces the camera rays with its coherent hint (MeshScene::intersect_coherent,
# the walk per octant); the column "primary without the hint" is the same rays through
# MeshScene::intersect. A second table compares glint's packets (`Bvh8` packets of 8: the camera rays in 4x2
# tiles, the shadow rays eight consecutive ones) with Embree's single rays and its packets
# (rtcIntersect8/rtcOccluded8 fed the same way); their checksums count in the checksums column.
# Raw outputs are kept in WORKDIR/compare/.
# THREADS="1 2" (default) picks the thread counts. BASELINE=path/to/an/older/glint also runs that
# binary in each repetition, right after the current one, and prints a second table for it: a
# before/after comparison against the same Embree runs.
set -euo pipefail
cd "$(dirname "$0")/.."
work=${1:-${TMPDIR:-/tmp}/glint-anchors}
reps=${2:-3}
shift $(( $# > 2 ? 2 : $# ))
meshes=${*:-bunny40k sphere1m sphere4m}
anchors=../shared/anchors
[ -d "$anchors" ] || anchors=/work/shared/anchors
if ! [ -x "$work/embree_bench" ] || ! [ -f "$work/rays/sphere4m.shadow.rays" ]; then
  bash "$anchors/run.sh" "$work" >/dev/null
fi
cargo build --release --quiet --bin glint
out="$work/compare"
mkdir -p "$out"
# SUMMARY_ONLY=1: only print the table from the outputs already in WORKDIR/compare (e.g. after
# stopping a long run); incomplete repetitions are left out and the table says how many were used.
[ "${SUMMARY_ONLY:-0}" = 1 ] || rm -f "$out"/*.txt "$out"/*.json
for rep in $(seq 1 "$reps"); do
  [ "${SUMMARY_ONLY:-0}" = 1 ] && break
  for m in $meshes; do
    for t in ${THREADS:-1 2}; do
      echo "rep $rep: $m, $t thread(s)" >&2
      "$work/embree_bench" "$work/$m.obj" "$work/rays/$m" "$t" > "$out/embree.$m.$t.$rep.txt"
      "${CARGO_TARGET_DIR:-target}"/release/glint bench rays "$work/$m.obj" "$work/rays/$m" --threads "$t" --json \
        > "$out/glint.$m.$t.$rep.json"
      if [ -n "${BASELINE:-}" ]; then
        "$BASELINE" bench rays "$work/$m.obj" "$work/rays/$m" --threads "$t" --json \
          > "$out/baseline.$m.$t.$rep.json"
      fi
    done
  done
done
for who in glint ${BASELINE:+baseline}; do
[ "$who" = glint ] || echo -e "\nBASELINE ($BASELINE), same Embree runs:"
WHO=$who THREADS="${THREADS:-1 2}" python3 - "$out" "$reps" $meshes <<'PY'
import json, os, re, statistics, sys
out, reps, meshes = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
who, threads = os.environ["WHO"], [int(t) for t in os.environ["THREADS"].split()]
def embree(path):
    e = {}
    for line in open(path):
        if m := re.match(r"build MEDIUM threads=\d+: best ([\d.]+) ms", line):
            e["build_ms"] = float(m[1])
        elif m := re.match(r"\s+MEDIUM T=\d+ (primary|incoherent)\s+rtcIntersect1\s+([\d.]+) Mrays/s\s+hits=(\d+) tsum=([\d.e+]+)", line):
            e[m[1]] = {"mrays": float(m[2]), "hits": int(m[3]), "tsum": float(m[4])}
        elif m := re.match(r"\s+MEDIUM T=\d+ shadow\s+rtcOccluded1\s+([\d.]+) Mrays/s\s+occluded=(\d+)", line):
            e["shadow"] = {"mrays": float(m[1]), "occluded": int(m[2])}
        elif m := re.match(r"\s+MEDIUM T=\d+ primary\s+rtcIntersect8\s+([\d.]+) Mrays/s", line):
            e["primary8"] = float(m[1])
        elif m := re.match(r"\s+MEDIUM T=\d+ shadow\s+rtcOccluded8\s+([\d.]+) Mrays/s", line):
            e["shadow8"] = float(m[1])
    return e
def close(a, b):  # the issue's criterion: within 0.1%
    return abs(a - b) <= 1e-3 * max(abs(a), abs(b), 1e-30)
packets = {}
print("| mesh | threads | primary | primary without the hint | incoherent | shadow | build (glint/Embree MEDIUM) | glint build ms | Embree build ms | bytes/triangle | checksums |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
for m in meshes:
    for t in threads:
        rows = []
        ok = True
        for rep in range(1, reps + 1):
            try:  # a repetition cut short (see SUMMARY_ONLY) is left out
                e = embree(f"{out}/embree.{m}.{t}.{rep}.txt")
                g = json.load(open(f"{out}/{who}.{m}.{t}.{rep}.json"))
                e["shadow"]
            except (OSError, ValueError, KeyError):
                continue
            for k in ("primary", "incoherent"):
                ok &= close(g[k]["hits"], e[k]["hits"]) and close(g[k]["tsum"], e[k]["tsum"])
            ok &= close(g["shadow"]["occluded"], e["shadow"]["occluded"])
            gp, gs = g.get("primary_packets"), g.get("shadow_packets")
            if gp and gs and "primary8" in e and "shadow8" in e:
                ok &= close(gp["hits"], e["primary"]["hits"]) and close(gp["tsum"], e["primary"]["tsum"])
                ok &= close(gs["occluded"], e["shadow"]["occluded"])
                packets.setdefault((m, t), []).append({
                    "p1": gp["mrays"] / e["primary"]["mrays"], "p8": gp["mrays"] / e["primary8"],
                    "s1": gs["mrays"] / e["shadow"]["mrays"], "s8": gs["mrays"] / e["shadow8"],
                    "gp": gp["mrays"] / g["primary"]["mrays"], "gs": gs["mrays"] / g["shadow"]["mrays"],
                    "ep": e["primary8"] / e["primary"]["mrays"], "es": e["shadow8"] / e["shadow"]["mrays"],
                })
            gu = g.get("primary_unhinted")
            if gu:
                ok &= close(gu["hits"], e["primary"]["hits"]) and close(gu["tsum"], e["primary"]["tsum"])
            rows.append({
                "primary": g["primary"]["mrays"] / e["primary"]["mrays"],
                "unhinted": (gu or {"mrays": float("nan")})["mrays"] / e["primary"]["mrays"],
                "incoherent": g["incoherent"]["mrays"] / e["incoherent"]["mrays"],
                "shadow": g["shadow"]["mrays"] / e["shadow"]["mrays"],
                "build": g["build_ms"] / e["build_ms"],
                "gb": g["build_ms"], "eb": e["build_ms"], "bytes": g["bytes_per_triangle"],
            })
        if not rows:
            print(f"| {m} | {t} | not measured | | | | | | | | |")
            continue
        med = {k: statistics.median(r[k] for r in rows) for k in rows[0]}
        print(f"| {m} | {t} ({len(rows)} rep.) | {med['primary']:.2f} | {med['unhinted']:.2f} | {med['incoherent']:.2f} | {med['shadow']:.2f} | "
              f"{med['build']:.2f} | {med['gb']:.0f} | {med['eb']:.0f} | {med['bytes']:.1f} | "
              f"{'within 0.1%' if ok else 'DIFFER'} |")
print(f"\nratios: medians over the repetitions shown (of {reps} planned); throughput ratios > 1 and build ratios < 1 favour glint")
if packets:
    print("\nPackets (glint: Bvh8 packets of 8, 4x2 camera tiles / 8 consecutive shadow rays, as Embree's rtcIntersect8/rtcOccluded8 are fed):")
    print("| mesh | threads | camera packets / Embree rtcIntersect1 | / Embree rtcIntersect8 | shadow packets / Embree rtcOccluded1 | / Embree rtcOccluded8 | glint packets / glint single (camera, shadow) | Embree 8 / Embree 1 (camera, shadow) |")
    print("|---|---|---|---|---|---|---|---|")
    for (m, t), rs in packets.items():
        med = {k: statistics.median(r[k] for r in rs) for k in rs[0]}
        print(f"| {m} | {t} ({len(rs)} rep.) | {med['p1']:.2f} | {med['p8']:.2f} | {med['s1']:.2f} | {med['s8']:.2f} | "
              f"{med['gp']:.2f}, {med['gs']:.2f} | {med['ep']:.2f}, {med['es']:.2f} |")
PY
done
