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
  for ext in svm vfrag svo validate.json stats.json; do
    [ -s "$tmp/out/$name.$ext" ] || { echo "missing $name.$ext"; exit 1; }
  done
  # Every octree the pipeline bakes passed svo-validate with its mesh.
  grep -q '"valid": *true' "$tmp/out/$name.validate.json" || { echo "$name.svo is not valid"; exit 1; }
done
run pictures
for name in tetra box-room; do [ -s "$tmp/out/$name.png" ] || { echo "missing $name.png"; exit 1; }; done
before=$(stat -c %Y.%N "$tmp/out/box-room.svo")
sleep 1.1
touch "$tmp/meshes/tetra.off"
plan=$(make -n -f "$root/scripts/pipeline/Makefile" MESHES="$tmp/meshes" OUT="$tmp/out" BIN="$bin" RESOLUTION=32)
echo "$plan" | grep -q "tetra.svo" || { echo "edited tetra does not rebuild"; exit 1; }
if echo "$plan" | grep -q "box-room"; then echo "box-room rebuilds though unchanged"; exit 1; fi
run
[ "$(stat -c %Y.%N "$tmp/out/box-room.svo")" = "$before" ] || { echo "box-room.svo was rewritten"; exit 1; }
[ "$tmp/out/tetra.svo" -nt "$tmp/meshes/tetra.off" ] || { echo "tetra.svo not rebuilt"; exit 1; }
# A damaged octree fails its check: make stops, and no report claims it valid.
printf '\xff' | dd of="$tmp/out/box-room.svo" bs=1 seek=200 conv=notrunc status=none
if run 2>/dev/null; then echo "a damaged box-room.svo passed the pipeline"; exit 1; fi
[ ! -e "$tmp/out/box-room.validate.json" ] || { echo "a stale report survived the failed check"; exit 1; }
echo "pipeline ok"
