#!/usr/bin/env bash
# mesh2svo on a textured mesh under address-space limits (`ulimit -v`) from 150 MB to 800 MB in
# 50 MB steps: every run ends with exit 0, or 5 (out of memory) and one line on stderr; never a
# signal, never a hang (a generous 60 s cap per run turns a hang into a failure).
# Usage: address_space_sweep_test.sh BIN_DIR MESH_DIR png|tiff
#   The PNG is decoded by svokit's own decoder; the TIFF loads the OpenImageIO plugin, which
#   refuses (exit 5, naming the texture, what it needs and what is left) when the address space
#   left cannot hold it.
set -euo pipefail
bin="$1" data="$2" kind="$3"
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
if [ "$kind" = png ]; then
  cp "$data/uv-torus.obj" "$data/uv-torus.mtl" "$data/uv-torus.png" "$tmp/"
else
  bash "$(dirname "$0")/tiff_textured_torus.sh" "$data" "$tmp"
fi
failed=0 ok=0 refused=0 need=""
for ((mb = 150; mb <= 800; mb += 50)); do
  rm -f "$tmp/out.svo"
  set +e
  (ulimit -v $((mb * 1024)); exec timeout -s KILL 60 "$bin/mesh2svo" "$tmp/uv-torus.obj" -r 32 \
    --attributes color -o "$tmp/out.svo" -q) >"$tmp/stdout" 2>"$tmp/stderr"
  status=$?
  set -e
  lines=$(wc -l <"$tmp/stderr")
  case "$status" in
    0) ok=$((ok + 1)) ;;
    5)
      refused=$((refused + 1))
      if [ "$lines" != 1 ] || [ -e "$tmp/out.svo" ]; then
        echo "$mb MB: exit 5 with $lines lines on stderr or an output left:"; cat "$tmp/stderr"
        failed=1
      fi
      # The plugin's refusal says what it needs and what is left, not just "out of memory"; above
      # what it needs the plugin loads and the build itself may run out.
      if grep -q "MiB of address space, [0-9]* MiB are left" "$tmp/stderr"; then
        need=$(grep -o "it needs [0-9]* MiB" "$tmp/stderr" | grep -o "[0-9]*")
      elif [ "$kind" = tiff ] && { [ -z "$need" ] || [ "$mb" -lt "$need" ]; }; then
        echo "$mb MB: exit 5 without the plugin's needs:"; cat "$tmp/stderr"
        failed=1
      fi ;;
    *) echo "$mb MB: FAILED, exit $status (137 is the 60 s cap)"; failed=1 ;;
  esac
  echo "$mb MB: exit $status $(head -c 200 "$tmp/stderr")"
done
echo "$kind: $ok runs succeeded, $refused refused with exit 5"
exit $failed
