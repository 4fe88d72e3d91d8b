#!/usr/bin/env bash
# Installs a build into a temporary prefix, builds examples/read_svo against that prefix alone
# (find_package(svokit)), and checks the installed tools and the example against each other:
# the example's per-level node counts against svo-inspect --json (parsed by python3), and the
# installed mesh2svo's TIFF texture decoding through the installed plugin.
# Usage: install_test.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
src="$(cd "$1" && pwd)"
build="$(cd "$2" && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
work="$(cd "$work" && pwd -P)"  # /proc/self/exe, which the plugin search starts from, is resolved
prefix="$work/prefix"
fail() {
  echo "FAIL: $*" >&2
  exit 1
}

cmake --install "$build" --prefix "$prefix" >"$work/install.log" ||
  { cat "$work/install.log" >&2; fail "cmake --install $build"; }

# The layout: tools, libraries, plugin, package files, and every header of lib/svokit.
for f in bin/svo-import bin/svo-voxelize bin/svo-build bin/mesh2svo bin/svo-export \
  bin/svo-inspect bin/svo-validate lib/libsvokit.a lib/libsvokit_oiio.so \
  lib/cmake/svokit/svokitConfig.cmake lib/cmake/svokit/svokitConfigVersion.cmake \
  lib/cmake/svokit/svokitTargets.cmake; do
  [ -e "$prefix/$f" ] || fail "not installed: $f"
done
while IFS= read -r header; do
  [ -f "$prefix/include/$header" ] || fail "header not installed: include/$header"
done < <(cd "$src/lib" && find svokit -name '*.hpp')
# The package refers to the prefix only, never to the tree it was built from.
if grep -rlF -e "$src" -e "$build" "$prefix/lib/cmake"; then
  fail "the installed CMake package names the source or build tree"
fi

# The example, against the prefix only (no package registry, no build tree).
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
cmake -S "$src/examples/read_svo" -B "$work/example" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF \
  -DCMAKE_CXX_FLAGS="-Wall -Wextra -Werror" >"$work/configure.log" 2>&1 ||
  { cat "$work/configure.log" >&2; fail "configuring examples/read_svo against $prefix"; }
found="$(sed -n 's/^svokit_DIR:PATH=//p' "$work/example/CMakeCache.txt")"
[ "$found" = "$prefix/lib/cmake/svokit" ] || fail "find_package(svokit) found '$found'"
cmake --build "$work/example" >"$work/build.log" 2>&1 ||
  { cat "$work/build.log" >&2; fail "building examples/read_svo against $prefix"; }

# The installed tools on the torus textured with a TIFF, which only the plugin decodes.
# LD_DEBUG=files logs every dlopen attempt ("dynamically loaded by") and, for the file that opens,
# "generating link map".
bin="$prefix/bin"
mkdir "$work/tiff"
bash "$src/tests/cli/tiff_textured_torus.sh" "$src/data" "$work/tiff"
LD_DEBUG=files "$bin/mesh2svo" "$work/tiff/uv-torus.obj" -r 32 -o "$work/torus.svo" -q \
  >/dev/null 2>"$work/mesh2svo.err" || { cat "$work/mesh2svo.err" >&2; fail "installed mesh2svo"; }
grep -F "file=$prefix/lib/libsvokit_oiio.so " "$work/mesh2svo.err" | grep -q "generating link map" ||
  fail "installed mesh2svo did not load $prefix/lib/libsvokit_oiio.so:
$(grep -F "libsvokit_oiio.so [0];  generating link map" "$work/mesh2svo.err")"
"$bin/svo-voxelize" "$src/data/uv-torus.obj" -r 32 -o "$work/torus.vfrag" -q >/dev/null ||
  fail "installed svo-voxelize"
"$bin/svo-inspect" --json --levels "$work/torus.svo" >"$work/inspect.json" 2>/dev/null ||
  fail "installed svo-inspect"
"$work/example/read_svo" "$work/torus.svo" >"$work/svo.txt" || fail "read_svo torus.svo"
"$work/example/read_svo" "$work/torus.vfrag" >"$work/vfrag.txt" || fail "read_svo torus.vfrag"
# Streamed: the top chunk and every page meeting a box around the whole grid.
"$work/example/read_svo" "$work/torus.svo" --box -1e9 -1e9 -1e9 1e9 1e9 1e9 >"$work/stream.txt" ||
  fail "read_svo torus.svo --box"

python3 - "$work/inspect.json" "$work/svo.txt" "$work/vfrag.txt" "$work/stream.txt" <<'PY'
import json, sys
inspect = json.load(open(sys.argv[1]))
def fields(path):
    out = {}
    for line in open(path):
        key, *values = line.split()
        out.setdefault(key, []).append(values)
    return out
svo, vfrag, stream = fields(sys.argv[2]), fields(sys.argv[3]), fields(sys.argv[4])
errors = []
want = [(level["level"], level["nodes"]) for level in inspect["levels"]]
got = [(int(l), int(n)) for l, _, n in svo["level"]]
if got != want:
    errors.append(f"per-level nodes: read_svo {got}, svo-inspect {want}")
streamed = [(int(l), int(n)) for l, _, n, _, _ in stream["streamed"]]
if streamed != want:
    errors.append(f"per-level nodes streamed page by page: read_svo {streamed}, svo-inspect {want}")
if any(int(s) != 27 * int(n) for _, _, n, _, s in stream["streamed"]):
    errors.append(f"streamed brick pools are not 27 samples per node: {stream['streamed']}")
if int(svo["depth"][0][0]) != inspect["octree"]["depth"] or len(want) != inspect["octree"]["depth"] + 1:
    errors.append(f"depth: read_svo {svo['depth'][0][0]}, svo-inspect {inspect['octree']['depth']}")
if int(svo["voxels"][0][0]) != inspect["voxels"]:
    errors.append(f"voxels: read_svo {svo['voxels'][0][0]}, svo-inspect {inspect['voxels']}")
# The .vfrag of the same mesh, resolution and mode holds the .svo's voxels on the same grid.
if int(vfrag["voxels"][0][0]) != inspect["voxels"]:
    errors.append(f".vfrag voxels: read_svo {vfrag['voxels'][0][0]}, .svo {inspect['voxels']}")
if [int(d) for d in vfrag["grid"][0]] != inspect["grid"]["dims"]:
    errors.append(f".vfrag grid: read_svo {vfrag['grid'][0]}, .svo {inspect['grid']['dims']}")
if float(vfrag["voxel_size"][0][0]) != inspect["grid"]["voxel_size"]:
    errors.append(f".vfrag voxel size: read_svo {vfrag['voxel_size'][0][0]}, .svo {inspect['grid']['voxel_size']}")
# The texture decoded: without it every voxel has the material's white base colour (Kd 1 1 1).
lo, hi = inspect["bricks"]["color_range"]["min"], inspect["bricks"]["color_range"]["max"]
if max(h - l for l, h in zip(lo[:3], hi[:3])) < 0.25:
    errors.append(f"colours {lo}..{hi}: the torus's texture was not decoded")
for e in errors:
    print("FAIL:", e, file=sys.stderr)
sys.exit(1 if errors else 0)
PY
echo "install test: $(grep -c '^level' "$work/svo.txt") levels agree, texture decoded by $prefix/lib/libsvokit_oiio.so"
