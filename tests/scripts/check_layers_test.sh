#!/usr/bin/env bash
# scripts/check-layers on scratch copies of the tree: the tree as it is passes; an unknown folder,
# an include of one, and an include up the layers each fail and are named.
set -euo pipefail
root="$1"
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
fresh() {
  rm -rf "$scratch/tree" && mkdir -p "$scratch/tree/scripts"
  cp "$root/scripts/check-layers" "$scratch/tree/scripts/"
  cp -r "$root/lib" "$root/apps" "$scratch/tree/"
}
expect_fail() {  # description, pattern the output must hold
  if out=$(bash "$scratch/tree/scripts/check-layers" "$scratch/tree" 2>&1); then
    echo "FAIL: $1 passed the check"; exit 1
  fi
  grep -q -- "$2" <<<"$out" || { echo "FAIL: $1: the output does not name it:"; echo "$out"; exit 1; }
  echo "ok: $1"
}
fresh
bash "$scratch/tree/scripts/check-layers" "$scratch/tree" >/dev/null || { echo "FAIL: the tree"; exit 1; }
echo "ok: the tree passes, pipeline included"
grep -q 'pipeline=7' "$root/scripts/check-layers" || { echo "FAIL: pipeline has no rank"; exit 1; }

fresh
mkdir -p "$scratch/tree/lib/svokit/render"
echo '#pragma once' >"$scratch/tree/lib/svokit/render/render.hpp"
expect_fail "an unknown folder" "lib/svokit/render: a folder that is no layer"

fresh
echo '#include "svokit/render/render.hpp"' >"$scratch/tree/lib/svokit/core/uses_render.cpp"
expect_fail "an include of an unknown folder" "core/uses_render.cpp:1: includes a folder that is no layer"

fresh
echo '#include "svokit/pipeline/chain.hpp"' >"$scratch/tree/lib/svokit/validate/uses_pipeline.cpp"
expect_fail "validate including pipeline" "validate includes the higher layer pipeline"

fresh
echo '#include "svokit/bake/bake_svo.hpp"' >"$scratch/tree/lib/svokit/export/uses_bake.cpp"
expect_fail "export including bake" "export includes the higher layer bake"
