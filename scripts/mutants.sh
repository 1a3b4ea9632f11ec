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
# One job at a time (`-j 1`): the machine this was written on has two cores.
set -euo pipefail
cd "$(dirname "$0")/.."

if [ $# -eq 0 ]; then
  set -- integrator shape accel light material render
fi

# The fast test selection: unit tests plus the integration tests that check
# closed forms and brute-force agreement without course data.
FAST_TESTS=(--lib --test physics --test accel_edges --test ray_tree --test accel_agree --test watertight)

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
  cargo mutants --profile mutants -j 1 --timeout "${MUTANTS_TIMEOUT:-240}" \
    "${files[@]}" --output "mutants/$name" -- "${FAST_TESTS[@]}" || true
  for kind in caught missed timeout unviable; do
    f="mutants/$name/mutants.out/$kind.txt"
    printf '%-9s %s\n' "$kind" "$( [ -f "$f" ] && wc -l < "$f" || echo 0)"
  done
done
