#!/usr/bin/env bash
# kill -9 at random moments of a mesh2svo run over an existing output: every time the output must
# be the old file or the new one, byte for byte, and nothing else may be left in the directory.
# Usage: kill_during_write_test.sh BIN_DIR MESH RESOLUTION KILLS [SEED]
#   e.g. in the suite: the torus at 256³, 6 kills; by hand: armadillo at 2048³, 20 kills.
set -euo pipefail
bin="$1" mesh="$2" resolution="$3" kills="$4" seed="${5:-1}"
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
mkdir "$tmp/out" "$tmp/ref"
chain=(--bricks 3 --attributes color,normal --contours -q)
"$bin/mesh2svo" "$mesh" -r 16 --no-contours -o "$tmp/ref/old.svo" -q >/dev/null
start=$(date +%s%N)
"$bin/mesh2svo" "$mesh" -r "$resolution" "${chain[@]}" -o "$tmp/ref/new.svo" >/dev/null
run_ns=$(($(date +%s%N) - start))
echo "one run: $((run_ns / 1000000)) ms, $(stat -c %s "$tmp/ref/new.svo") bytes"
old=0 new=0
for ((i = 1; i <= kills; i++)); do
  cp "$tmp/ref/old.svo" "$tmp/out/out.svo"
  # A moment drawn uniformly over the run's length (seeded, so a failure can be replayed).
  delay_ns=$(awk -v s="$seed" -v i="$i" -v n="$run_ns" 'BEGIN { srand(s * 1000 + i); printf "%.0f", rand() * n }')
  "$bin/mesh2svo" "$mesh" -r "$resolution" "${chain[@]}" -o "$tmp/out/out.svo" >/dev/null &
  pid=$!
  sleep "$(awk -v n="$delay_ns" 'BEGIN { printf "%.6f", n / 1e9 }')"
  kill -9 "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null && status=0 || status=$?
  left=$(ls -A "$tmp/out" | tr '\n' ' ')
  if [ "$left" != "out.svo " ]; then
    echo "kill $i at $((delay_ns / 1000000)) ms (exit $status): directory holds: $left"
    exit 1
  fi
  if cmp -s "$tmp/out/out.svo" "$tmp/ref/old.svo"; then
    old=$((old + 1)) state=old
  elif cmp -s "$tmp/out/out.svo" "$tmp/ref/new.svo"; then
    new=$((new + 1)) state=new
  else
    echo "kill $i at $((delay_ns / 1000000)) ms (exit $status): out.svo is neither the old file nor the new one"
    exit 1
  fi
  echo "kill $i at $((delay_ns / 1000000)) ms: exit $status, $state file intact, nothing else left"
done
echo "$kills kills: $old left the old file, $new the new one; never anything else"
