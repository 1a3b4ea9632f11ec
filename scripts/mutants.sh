#!/usr/bin/env bash
# Mutation testing of glint's core with cargo-mutants (issue 18).
#
#   scripts/mutants.sh                      # every core module, most important first
#   scripts/mutants.sh integrator light     # just these (folders under src/)
#   scripts/mutants.sh src/light/mod.rs     # or single files
#
# Needs `cargo install cargo-mutants`. Not part of CI: every mutant rebuilds
# the crate (the `mutants` profile, opt-level 1, keeps that short) and runs
# only the fast tests: the unit tests and the property/agreement tests that
# need no course data and render no reference images. Results go to
# `mutants/<module>/mutants.out/` (caught.txt, missed.txt, timeout.txt,
# unviable.txt); docs/testing.md records the counts and each missed mutant.
#
set -euo pipefail
cd "$(dirname "$0")/.."

if [ $# -eq 0 ]; then
  set -- integrator shape accel light material render
fi

# The fast test selection per module: the unit tests plus the integration
# tests that check closed forms or brute-force agreement without course data
# (every extra test binary is linked again for every mutant).
tests_for() {
  case "$1" in
    accel*|*/accel/*) echo --lib --test accel_edges --test accel_agree ;;
    shape*|*/shape/*) echo --lib --test accel_edges --test watertight --test physics ;;
    *) echo --lib --test physics --test ray_tree ;;
  esac
}

# Mutants are built in this tree's own target/ (--in-place): a copy would
# build every dependency again. cargo-mutants edits the sources while it
# runs and restores them; start from a tree with nothing uncommitted in src/.
if ! git diff --quiet -- src; then
  echo "src/ has uncommitted changes: commit or stash them first" >&2
  exit 1
fi

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
  # shellcheck disable=SC2046
  # MUTANTS_ARGS passes more options, e.g. "--baseline=skip" or "--shard 0/8".
  # shellcheck disable=SC2086
  cargo mutants --in-place --profile mutants --timeout "${MUTANTS_TIMEOUT:-300}" ${MUTANTS_ARGS:-} \
    "${files[@]}" --output "mutants/$name" -- $(tests_for "$target") || true
  for kind in caught missed timeout unviable; do
    f="mutants/$name/mutants.out/$kind.txt"
    printf '%-9s %s\n' "$kind" "$( [ -f "$f" ] && wc -l < "$f" || echo 0)"
  done
done
