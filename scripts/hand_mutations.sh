#!/usr/bin/env bash
# The mutations issue 18 lists, applied one at a time: each must make at
# least one fast test (unit or property test, no reference image) fail.
#
#   scripts/hand_mutations.sh                 # all of scripts/mutations/*.patch
#   scripts/hand_mutations.sh swap_refraction_indices
#
# For each patch: apply it, build and run the fast tests (the `mutants`
# profile, as scripts/mutants.sh does), list the tests that failed, revert.
# The tree must be clean of changes to the patched files. Logs go to
# mutants/hand/<name>.log.
set -euo pipefail
cd "$(dirname "$0")/.."

# Unit tests, then these modules of the integration-test binary (tests/main.rs).
FAST_MODULES=(physics:: accel_edges:: whitted_tree:: accel_agree:: watertight::)

if [ $# -eq 0 ]; then
  set -- $(ls scripts/mutations/*.patch | xargs -n1 basename | sed 's/\.patch$//')
fi
mkdir -p mutants/hand
for name in "$@"; do
  patch=scripts/mutations/$name.patch
  git apply "$patch"
  trap 'git apply -R "$patch"' EXIT
  log=mutants/hand/$name.log
  status=0
  cargo test --profile mutants --no-fail-fast --lib > "$log" 2>&1 || status=1
  cargo test --profile mutants --no-fail-fast --test suite -- "${FAST_MODULES[@]}" >> "$log" 2>&1 || status=1
  if [ $status -eq 0 ]; then
    echo "$name: NOT CAUGHT (every fast test passed)"
  elif grep -q 'could not compile' "$log"; then
    echo "$name: DOES NOT BUILD (see $log)"
  else
    failed=$(grep -E '^test .* FAILED$' "$log" | sed 's/^test //; s/ \.\.\. FAILED$//' | sort -u | tr '\n' ' ')
    echo "$name: caught by $failed"
  fi
  git apply -R "$patch"
  trap - EXIT
done
