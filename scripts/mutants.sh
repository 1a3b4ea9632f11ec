#!/usr/bin/env bash
# Mutation testing of glint's core with cargo-mutants (issue 18).
#
#   scripts/mutants.sh                      # every core module
#   scripts/mutants.sh integrator light     # just these (folders under src/)
#   scripts/mutants.sh src/light/mod.rs     # or single files
#   MUTANTS_ARGS="--shard 0/4" scripts/mutants.sh accel   # a quarter of one
#   MUTANTS_STAGE=unit scripts/mutants.sh render   # unit tests only, then
#   MUTANTS_ARGS=--iterate scripts/mutants.sh render   # the rest on the misses
#   MUTANTS_EXCLUDE_RE='mod\.rs:169:34:' ...            # minus explained ones
#
# Needs `cargo install cargo-mutants` and cargo-nextest (and uses the mold
# linker when it is installed). Not part of CI: every mutant rebuilds the
# crate (the `mutants` profile, opt-level 1, keeps that to a few seconds)
# and runs the fast tests below under nextest, which stops at the first
# failure (`.config/nextest.toml`, profile `mutants`). Results go to
# `mutants/<name>/mutants.out/` (caught.txt, missed.txt, timeout.txt,
# unviable.txt), which git ignores; docs/testing.md records the counts.
set -euo pipefail
cd "$(dirname "$0")/.."

if [ $# -eq 0 ]; then
  set -- integrator material light shape render accel
fi

# The fast selection: the unit tests and the integration-test modules that
# check the renderer's results
# (unit tests, closed forms, reference images, analytic and convergence
# tests, views, pieces), without the ones about input handling and process
# behaviour (cli, hostile, malformed, formats, fuzz corpus, grammar) and
# without the two slowest tests, which repeat what others check:
# assignment 6 with every accelerator (brute force on the 40k bunny is
# 120 s at opt-level 1; accel_agree checks every accelerator against brute
# force) and, outside render/, every assignment 7 line (25 s; it checks the
# samplers, filters and views, all in render/). Accelerators and shapes add
# the brute-force agreement and watertightness tests.
common='physics|whitted_tree|raytree_cli|reference_images|textures|distribution|sampling|sampling_reference|numerics|reintersect|moved_scenes|viz_cost|viz_grid|viz_traversal|pieces|animation'
# One nextest filterset: the unit tests plus the selected modules of the
# integration-test binary `suite` (tests/main.rs).
filter_for() {
  # Stage "unit": the crate's unit tests alone (a few seconds at the
  # mutants profile). Most mutants fail one of them; a second run with
  # `--iterate` then gives only the survivors the whole selection below,
  # instead of every mutant up to a minute of integration tests.
  #
  # Dependencies point one way (math <- shape <- accel <- world <-
  # integrator <- render), so the unit tests of the layers below a target
  # never run its code and cannot catch its mutants: stage 1 leaves them
  # out (the accelerators' brute-force agreement tests alone take most of
  # a render mutant's test time). Stage 2 gives the survivors everything.
  if [ "${MUTANTS_STAGE:-}" = unit ]; then
    local below=''
    case "$1" in
      render*|*/render/*) below='math|shape|accel|world|scene|format|query|sampler|light|material|integrator' ;;
      accel*|*/accel/*) below='math|shape|sampler' ;;
    esac
    if [ -n "$below" ]; then
      echo "kind(lib) & not test(/^($below)::/)"
    else
      echo "kind(lib)"
    fi
    return
  fi
  local mods=$common slow='test(=reference_images::assignment6_with_every_accelerator)'
  case "$1" in
    accel*|*/accel/*|shape*|*/shape/*) mods="$mods|accel_agree|accel_edges|watertight" ;;
  esac
  # The render loop, film, filters and the course's sample/filter views are
  # what assignment 7's lines check: render mutants keep that test.
  case "$1" in
    render*|*/render/*) ;;
    *) slow="$slow | test(=sampling_reference::assignment7_every_line_runs_and_matches)" ;;
  esac
  echo "(kind(lib) | test(/^($mods)::/)) & not ($slow)"
}

# In the background (`setsid nice -n 19 scripts/mutants.sh ...`), per-process
# nice is not enough where the kernel schedules by session group
# (sched_autogroup): the new session's group keeps nice 0 and takes a full
# core's share against everything else. A run that leads its own session
# lowers its group too.
if [ "$(ps -o sid= -p $$ | tr -d ' ')" = "$$" ] && [ -w /proc/self/autogroup ]; then
  echo 19 > /proc/self/autogroup 2>/dev/null || true
fi

export NEXTEST_PROFILE=mutants
# Stage 1's tests are short: its profile kills a hung one sooner.
[ "${MUTANTS_STAGE:-}" = unit ] && NEXTEST_PROFILE=mutants-unit
if command -v mold >/dev/null; then
  export RUSTFLAGS="${RUSTFLAGS:-} -C link-arg=-fuse-ld=mold"
fi

# Mutants are built in this tree's own target/ (--in-place): a copy would
# build every dependency again. cargo-mutants edits the sources while it
# runs and restores them; start from a tree with nothing uncommitted in src/
# and edit nothing in it until the run ends.
if ! git diff --quiet -- src; then
  echo "src/ has uncommitted changes: commit or stash them first" >&2
  exit 1
fi

# The unit stage builds the library's tests only, not the suite binary.
# They go to every cargo call (--cargo-arg), the build's too: cargo-mutants's build
# step (`nextest run --no-run`) otherwise builds every target, the two
# binaries and their tests included, which tripled a unit-stage mutant's
# build time (13.4 s against 4.4 s for the library's tests alone).
binaries=(--cargo-arg=--lib --cargo-arg=--test --cargo-arg=suite)
[ "${MUTANTS_STAGE:-}" = unit ] && binaries=(--cargo-arg=--lib)

# MUTANTS_EXCLUDE_RE leaves out mutants already explained (e.g. equivalent
# ones, which would only run the second stage's whole selection to survive).
exclude=()
[ -n "${MUTANTS_EXCLUDE_RE:-}" ] && exclude=(--exclude-re "$MUTANTS_EXCLUDE_RE")

for target in "$@"; do
  if [ -f "$target" ]; then
    files=(-f "$target")
    name=$(basename "${target%.rs}")
  else
    files=(-f "src/$target/*.rs" -f "src/$target/**/*.rs")
    name=$target
  fi
  mkdir -p "mutants/$name"
  echo "== $target"
  # cargo-mutants exits non-zero when a mutant is missed: keep going.
  # MUTANTS_ARGS passes more options, e.g. "--baseline=skip" or "--shard 0/8".
  # shellcheck disable=SC2086,SC2046
  cargo mutants --in-place --profile mutants --test-tool nextest \
    --timeout "${MUTANTS_TIMEOUT:-240}" ${MUTANTS_ARGS:-} \
    "${binaries[@]}" "${exclude[@]}" "${files[@]}" --output "mutants/$name" -- -E "$(filter_for "$target")" || true
  for kind in caught missed timeout unviable; do
    f="mutants/$name/mutants.out/$kind.txt"
    printf '%-9s %s\n' "$kind" "$( [ -f "$f" ] && wc -l < "$f" || echo 0)"
  done
done
