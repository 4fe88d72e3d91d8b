#!/usr/bin/env bash
# mesh2svo on a textured mesh under address-space limits (`ulimit -v`) from 150 MB to 800 MB in
# 50 MB steps: every run ends with exit 0, or 5 (out of memory) and one line on stderr; never a
# signal, never a hang (a generous 60 s cap per run turns a hang into a failure).
# Usage: address_space_sweep_test.sh BIN_DIR MESH_DIR png|tiff
#   The PNG is decoded by svokit's own decoder; the TIFF loads the OpenImageIO plugin, which
#   refuses (exit 5) when the address space left cannot hold it.
set -euo pipefail
bin="$1" data="$2" kind="$3"
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
cp "$data/uv-torus.obj" "$tmp/"
if [ "$kind" = png ]; then
  cp "$data/uv-torus.mtl" "$data/uv-torus.png" "$tmp/"
else
  sed 's/uv-torus\.png/uv-torus.tif/' "$data/uv-torus.mtl" >"$tmp/uv-torus.mtl"
  # A 2 × 2 RGB TIFF, uncompressed: header, one directory of 9 entries, 12 bytes of pixels.
  python3 - "$tmp/uv-torus.tif" <<'PY'
import struct, sys
entries = [(256, 3, 1, 2), (257, 3, 1, 2), (258, 3, 1, 8), (259, 3, 1, 1), (262, 3, 1, 2),
           (273, 4, 1, 8 + 2 + 9 * 12 + 4), (277, 3, 1, 3), (278, 3, 1, 2), (279, 4, 1, 12)]
ifd = struct.pack('<H', len(entries))
for tag, kind, count, value in entries:
    ifd += struct.pack('<HHI', tag, kind, count) + (struct.pack('<HH', value, 0) if kind == 3 else struct.pack('<I', value))
open(sys.argv[1], 'wb').write(b'II*\0' + struct.pack('<I', 8) + ifd + struct.pack('<I', 0) +
                               bytes([255, 0, 0, 0, 255, 0, 0, 0, 255, 128, 128, 128]))
PY
fi
failed=0 ok=0 refused=0
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
      fi ;;
    *) echo "$mb MB: FAILED, exit $status (137 is the 60 s cap)"; failed=1 ;;
  esac
  echo "$mb MB: exit $status $(head -c 200 "$tmp/stderr")"
done
echo "$kind: $ok runs succeeded, $refused refused with exit 5"
exit $failed
