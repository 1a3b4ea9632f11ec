#!/usr/bin/env bash
# Times the README's two set-up commands on a fresh clone, as a new user runs
# them: a clone of HEAD in a temporary folder, no ../shared beside it, no
# GLINT_SHARED, an empty target folder (the registry's downloaded crates are
# reused; downloading them is not timed). Prints each command's wall time,
# the machine's cores and its load average before and after.
#
#   scripts/time-fresh-clone.sh            # prints the table
#   KEEP=1 scripts/time-fresh-clone.sh     # keeps the clone
#
# The README's figures come from this script on a quiet machine; on a loaded
# one the times grow with the load.
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
[ -n "${KEEP:-}" ] || trap 'rm -rf "$work"' EXIT
git clone --quiet "$repo" "$work/glint"
cd "$work/glint"
unset GLINT_SHARED GLINT_REQUIRE_SHARED CARGO_TARGET_DIR
# The README's set-up commands: the first two fenced sh blocks of "## Set up".
mapfile -t cmds < <(awk '/^## Set up/{s=1;next} /^## /{s=0} s&&/^```sh/{b=1;next} s&&/^```/{b=0;next} s&&b' README.md | head -2)
[ "${#cmds[@]}" -eq 2 ] || { echo "time-fresh-clone: expected two commands in README's Set up" >&2; exit 1; }
cargo fetch --quiet
echo "cores: $(nproc); load average before: $(cut -d' ' -f1-3 /proc/loadavg)"
for c in "${cmds[@]}"; do
  t0=$(date +%s.%N)
  bash -c "$c" >"$work/log" 2>&1 || { tail -20 "$work/log"; echo "failed: $c" >&2; exit 1; }
  t1=$(date +%s.%N)
  awk -v a="$t0" -v b="$t1" -v c="$c" 'BEGIN { printf "%8.1f s  %s\n", b - a, c }'
done
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
