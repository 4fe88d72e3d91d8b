#!/usr/bin/env bash
# scripts/pipeline/Makefile: every mesh gets its chain, and an edited mesh rebuilds only its own.
set -euo pipefail
root="$1" bin="$2"
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/meshes"
cp "$root/data/tetra.off" "$root/data/box-room.obj" "$root/data/box-room.mtl" "$tmp/meshes/"
run() { make -s -f "$root/scripts/pipeline/Makefile" MESHES="$tmp/meshes" OUT="$tmp/out" BIN="$bin" RESOLUTION=32 -j2 "$@"; }
run
for name in tetra box-room; do
  for ext in svm vfrag svo; do [ -s "$tmp/out/$name.$ext" ] || { echo "missing $name.$ext"; exit 1; }; done
done
before=$(stat -c %Y.%N "$tmp/out/box-room.svo")
sleep 1.1
touch "$tmp/meshes/tetra.off"
plan=$(make -n -f "$root/scripts/pipeline/Makefile" MESHES="$tmp/meshes" OUT="$tmp/out" BIN="$bin" RESOLUTION=32)
echo "$plan" | grep -q "tetra.svo" || { echo "edited tetra does not rebuild"; exit 1; }
if echo "$plan" | grep -q "box-room"; then echo "box-room rebuilds though unchanged"; exit 1; fi
run
[ "$(stat -c %Y.%N "$tmp/out/box-room.svo")" = "$before" ] || { echo "box-room.svo was rewritten"; exit 1; }
[ "$tmp/out/tetra.svo" -nt "$tmp/meshes/tetra.off" ] || { echo "tetra.svo not rebuilt"; exit 1; }
echo "pipeline ok"
