#!/usr/bin/env bash
# Hashes every image glint makes of its own scenes and of the course's command lines, to show that
# a change leaves them bit for bit as they were.
#
#   scripts/image-hashes.sh [COMMIT]     print "name sha256" for every output file of COMMIT (default HEAD)
#   scripts/image-hashes.sh OLD NEW      both lists side by side: same / DIFFERENT; exit 1 on any difference
#   scripts/image-hashes.sh --build C    only build C's binaries; print their folder (scripts/bench-ab.sh)
#   IMAGE_HASHES_ONLY=REGEX              only the runs whose folder matches (e.g. 'tent|pieces|A7-5')
#
# COMMIT is anything `git rev-parse` takes; `.` is the working tree as it is (uncommitted edits too).
# Each commit's release binaries are built in a temporary git worktree, with one cargo target
# directory shared by every call ($IMAGE_HASHES_TARGET, default target/image-hashes; only the
# crate itself is recompiled) and kept per commit in its bins/ folder, so a commit is built once.
#
# What is rendered (the scenes and command files are this checkout's, the same input for both commits):
# - every `glint render scenes/...` command in the headers of scenes/*.txt, at 136x100 (5x4 tiles of
#   32, 25 bands of 4 rows, partial ones at the edges), at --spp 1 and --spp 16, each with the
#   colour (.pfm, the float values), depth, normals, samples and cost images; plus, per scene,
#   --adaptive 0.05 (depth, normals, samples), a tent filter reaching over tile edges (--spp 4
#   --filter tent:1.5, the tiled path with margins) and three pieces (--tile I/3, --spp 2, the same
#   tent) merged by `glint merge`.
# - every line of $GLINT_SHARED/scenes/6837/commands/A*_cmd.txt as written, run with `raytracer` in
#   a scratch folder with the scene read from the course's scenes folder (as tests/common does),
#   and, for lines without sampling or filter flags, again with -jittered_samples 16.
#   Without GLINT_SHARED (or ../shared) these are skipped, with a line saying so.
# Every run also writes --stats-json; its hash leaves out the timings (*_ms, rays_per_second), so it
# pins the rays by kind, intersection tests and nodes visited. A run that fails is listed with its
# exit code instead of a hash.
set -euo pipefail
export LC_ALL=C
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
target=${IMAGE_HASHES_TARGET:-$root/target/image-hashes}
shared=${GLINT_SHARED:-}
[ -n "$shared" ] || { [ -d ../shared/scenes ] && shared=$(cd ../shared && pwd); } || true
course=""
[ -n "$shared" ] && [ -d "$shared/scenes/6837/commands" ] && course="$shared/scenes/6837"

# Builds COMMIT's glint and raytracer (once per commit); prints the folder holding them.
build() {
  local rev=$1 sha dir src
  if [ "$rev" = . ]; then
    cargo build --release --quiet --bins >&2
    echo "$root/target/release"
    return
  fi
  sha=$(git rev-parse --verify "$rev^{commit}")
  dir=$target/bins/$sha
  if [ -x "$dir/glint" ] && [ -x "$dir/raytracer" ]; then
    echo "$dir"
    return
  fi
  src=$(mktemp -d)
  git worktree add --quiet --detach "$src/tree" "$sha" >&2
  if ! (cd "$src/tree" && cargo build --release --quiet --bins --target-dir "$target" >&2); then
    git worktree remove --force "$src/tree"
    rm -rf "$src"
    echo "image-hashes: building $rev failed" >&2
    return 1
  fi
  mkdir -p "$dir"
  cp "$target/release/glint" "$target/release/raytracer" "$dir/"
  git worktree remove --force "$src/tree"
  rm -rf "$src"
  echo "$dir"
}

# Runs one command into folder $1 (created), the rest of the arguments the command; on failure
# leaves a FAILED file with the exit code (hashed like any output).
run_into() {
  local out=$1
  shift
  [[ $out =~ ${IMAGE_HASHES_ONLY:-.} ]] || return 0
  mkdir -p "$out"
  local rc=0
  (cd "$out" && "$@" >/dev/null 2>stderr.txt) || rc=$?
  if [ "$rc" != 0 ]; then echo "exit $rc: $*" >>"$out/FAILED"; fi
  rm -f "$out/stderr.txt"
}

# The flags of a header's `glint render scenes/X.txt ...` line, without -o, --size and --spp.
header_flags() {
  local -a t
  read -ra t <<<"$1"
  local i=0 n=${#t[@]}
  while [ "$i" -lt "$n" ]; do
    case ${t[$i]} in
      -o | --output | --spp) i=$((i + 2)) ;;
      --size) i=$((i + 3)) ;;
      *) printf '%s\n' "${t[$i]}"; i=$((i + 1)) ;;
    esac
  done
}

# Renders everything with the binaries in $1 into folder $2.
render_all() {
  local bin=$1 out=$2 f name v line
  local -a flags
  for f in scenes/*.txt; do
    name=$(basename "$f" .txt)
    v=0
    while IFS= read -r line; do
      mapfile -t flags < <(header_flags "${line#*glint render "$f"}")
      local chans=(--depth 0 30 depth.pfm --normals normals.pfm --samples-image samples.png
        --cost-image cost.png --stats-json stats.json --quiet)
      for spp in 1 16; do
        run_into "$out/scenes/$name/v$v-spp$spp" "$bin/glint" render "$root/$f" -o color.pfm \
          --size 136 100 "${flags[@]}" --spp "$spp" "${chans[@]}"
      done
      if [ "$v" = 0 ]; then
        run_into "$out/scenes/$name/adaptive" "$bin/glint" render "$root/$f" -o color.pfm \
          --size 136 100 "${flags[@]}" --adaptive 0.05 --depth 0 30 depth.pfm --normals normals.pfm \
          --samples-image samples.png --stats-json stats.json --quiet
        run_into "$out/scenes/$name/tent" "$bin/glint" render "$root/$f" -o color.pfm \
          --size 136 100 "${flags[@]}" --spp 4 --filter tent:1.5 --stats-json stats.json --quiet
        for t in 0 1 2; do
          run_into "$out/scenes/$name/pieces" "$bin/glint" render "$root/$f" -o "piece$t.exr" \
            --size 136 100 "${flags[@]}" --spp 2 --filter tent:1.5 --tile "$t/3" --quiet
        done
        # The pieces' headers hold their timings: the merged image and statistics are hashed.
        run_into "$out/scenes/$name/pieces" "$bin/glint" merge "$out/scenes/$name/pieces"/piece?.exr \
          -o merged.pfm --stats-json stats.json
        rm -f "$out/scenes/$name/pieces"/piece?.exr
      fi
      v=$((v + 1))
    done < <(grep -E "^#.*glint render $f( |$)" "$f" | grep -v '\$')
  done
  if [ -z "$course" ]; then
    echo "image-hashes: no course data (set GLINT_SHARED): the course's command lines are skipped" >&2
    return
  fi
  local cmd k
  local -a a
  for cmd in "$course"/commands/A*_cmd.txt; do
    k=0
    while IFS= read -r line; do
      k=$((k + 1))
      read -ra a <<<"$line"
      [ "${#a[@]}" -gt 1 ] || continue
      a=("${a[@]:1}")
      # -gui starts the browser view (and, without -output, waits in it):
      # the lines are rendered without it.
      for i in "${!a[@]}"; do
        [ "${a[$i]}" = -gui ] && unset 'a[i]'
      done
      a=("${a[@]}")
      for i in "${!a[@]}"; do
        [ "${a[$i]}" = -input ] && a[$((i + 1))]=$course/${a[$((i + 1))]}
      done
      local id
      id=$(basename "$cmd" _cmd.txt)-$(printf %02d "$k")
      run_into "$out/course/$id" "$bin/raytracer" "${a[@]}" -stats_json stats.json -quiet </dev/null
      if ! grep -qE -- '-[a-z_]+_(samples|filter)|-adaptive' <<<"$line"; then
        run_into "$out/course/$id-spp16" "$bin/raytracer" "${a[@]}" -jittered_samples 16 \
          -stats_json stats.json -quiet </dev/null
      fi
    done <"$cmd"
  done
}

# "name sha256" for every file under $1, statistics without their timings.
hash_all() {
  local dir=$1 f
  (cd "$dir" && find . -type f | sort | while IFS= read -r f; do
    if [ "$(basename "$f")" = stats.json ]; then
      h=$(grep -vE '"[a-z_]+_ms":|"rays_per_second":' "$f" | sha256sum)
    else
      h=$(sha256sum <"$f")
    fi
    echo "${f#./} ${h%% *}"
  done)
}

hashes_of() {
  local bin work
  bin=$(build "$1")
  work=$(mktemp -d)
  render_all "$bin" "$work"
  hash_all "$work"
  rm -rf "$work"
}

if [ "${1:-}" = --build ]; then
  # For other scripts (bench-ab.sh): only build; print the binaries' folder.
  build "${2:?usage: scripts/image-hashes.sh --build COMMIT}"
  exit
fi
case $# in
  0 | 1) hashes_of "${1:-HEAD}" ;;
  2)
    old=$(mktemp)
    new=$(mktemp)
    trap 'rm -f "$old" "$new"' EXIT
    hashes_of "$1" >"$old"
    hashes_of "$2" >"$new"
    join -a1 -a2 -e MISSING -o 0,1.2,2.2 "$old" "$new" | awk -v o="$1" -v n="$2" '
      { s = ($2 == $3 && $2 != "MISSING") ? "same" : "DIFFERENT"; print $1, s; c[s]++ }
      END { printf "%d files: %d same, %d DIFFERENT (%s vs %s)\n", NR, c["same"], c["DIFFERENT"], o, n
            exit c["DIFFERENT"] > 0 }'
    ;;
  *)
    echo "usage: scripts/image-hashes.sh [COMMIT] | OLD NEW" >&2
    exit 2
    ;;
esac
