#!/usr/bin/env bash
# Writes the sample torus into OUT_DIR with its texture as a 2 × 2 RGB TIFF (uncompressed: a
# header, one directory of 9 entries, 12 bytes of pixels): a mesh whose texture only the
# OpenImageIO plugin decodes.
# Usage: tiff_textured_torus.sh DATA_DIR OUT_DIR
set -euo pipefail
data="$1" out="$2"
cp "$data/uv-torus.obj" "$out/"
sed 's/uv-torus\.png/uv-torus.tif/' "$data/uv-torus.mtl" >"$out/uv-torus.mtl"
python3 - "$out/uv-torus.tif" <<'PY'
import struct, sys
entries = [(256, 3, 1, 2), (257, 3, 1, 2), (258, 3, 1, 8), (259, 3, 1, 1), (262, 3, 1, 2),
           (273, 4, 1, 8 + 2 + 9 * 12 + 4), (277, 3, 1, 3), (278, 3, 1, 2), (279, 4, 1, 12)]
ifd = struct.pack('<H', len(entries))
for tag, kind, count, value in entries:
    ifd += struct.pack('<HHI', tag, kind, count) + (struct.pack('<HH', value, 0) if kind == 3 else struct.pack('<I', value))
open(sys.argv[1], 'wb').write(b'II*\0' + struct.pack('<I', 8) + ifd + struct.pack('<I', 0) +
                               bytes([255, 0, 0, 0, 255, 0, 0, 0, 255, 128, 128, 128]))
PY
