#!/usr/bin/env bash
# Runs `glint render` over every .ply, .gltf and .glb file under a folder
# (a local copy of the Khronos glTF sample models, PLY files from the
# Stanford scanning repository, or what scripts/make_asset_files.py writes)
# and prints a Markdown table: each file loads (exit 0) or is refused with a
# message (exit 2). Anything else (a panic, a crash, a timeout, another
# status) is a failure, and the script exits 1.
#
#   scripts/conformance.sh DIR [GLINT]     # GLINT: default target/release/glint
#
# Each render is 64x64, limited to 120 s and 4 GiB of address space.
set -u
dir=${1:?usage: scripts/conformance.sh DIR [GLINT]}
glint=${2:-${CARGO_TARGET_DIR:-target}/release/glint}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
fail=0
echo "| file | result | message |"
echo "|---|---|---|"
while IFS= read -r -d '' f; do
    rel=${f#"$dir"/}
    err=$( (ulimit -v 4194304; timeout 120 "$glint" render "$f" -o "$out/x.png" --size 64 64) 2>&1 >/dev/null)
    code=$?
    msg=$(printf '%s' "$err" | head -n 1 | cut -c 1-160 | sed 's/|/\\|/g')
    case $code in
        0) result="loads" ;;
        2) result="refused" ;;
        *) result="**FAIL (exit $code)**"; fail=1 ;;
    esac
    if printf '%s' "$err" | grep -q "panicked"; then result="**PANIC**"; fail=1; fi
    echo "| $rel | $result | $msg |"
done < <(find "$dir" -type f \( -iname '*.ply' -o -iname '*.gltf' -o -iname '*.glb' \) -print0 | sort -z)
exit $fail
