#!/usr/bin/env bash
# Installs a build into a temporary prefix and builds examples/read_svo against that prefix alone:
# against svokit::reader (find_package(svokit COMPONENTS reader)) in Debug and in Release, through
# pkg-config (svokit-reader.pc), and against the whole library (svokit::svokit, with every other
# component found). The reader's consumers must name none of the build stages' dependencies, and
# their configure must print no warning; so must examples/voxel_colors and pages_near_camera (the
# streaming reader's consumers). Then checks the installed tools and the examples against
# each other: the per-level node counts against svo-inspect --json (parsed by python3), every
# consumer's output alike, and the installed mesh2svo's TIFF texture decoding through the plugin.
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
  bin/svo-inspect bin/svo-validate lib/libsvokit.a lib/libsvokit_reader.a lib/libsvokit_oiio.so \
  lib/cmake/svokit/svokitConfig.cmake lib/cmake/svokit/svokitConfigVersion.cmake \
  lib/cmake/svokit/svokitTargets.cmake lib/cmake/svokit/svokitReaderTargets.cmake \
  lib/pkgconfig/svokit-reader.pc; do
  [ -e "$prefix/$f" ] || fail "not installed: $f"
done
while IFS= read -r header; do
  [ -f "$prefix/include/$header" ] || fail "header not installed: include/$header"
done < <(cd "$src/lib" && find svokit -name '*.hpp')
# The packages refer to the prefix only, never to the tree it was built from.
if grep -rlF -e "$src" -e "$build" "$prefix/lib/cmake" "$prefix/lib/pkgconfig"; then
  fail "the installed CMake or pkg-config package names the source or build tree"
fi

# What a reader's consumer must not see: the build stages' dependencies.
foreign='cgal|draco|openmesh|openimageio|oiio|openvdb|tbb|embree'
# The example against svokit::reader, from the prefix only (no package registry, no build tree),
# in each configuration; its compile and link commands as the build ran them (-v).
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
for build in read_svo:Debug read_svo:Release voxel_colors:Release pages_near_camera:Release; do
  example="${build%:*}" config="${build#*:}"
  dir="$work/example-$config"
  [ "$example" = read_svo ] || dir="$work/$example"
  cmake -S "$src/examples/$example" -B "$dir" "${generator[@]}" -DCMAKE_BUILD_TYPE=$config \
    -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF \
    -DCMAKE_EXPORT_COMPILE_COMMANDS=ON -DCMAKE_CXX_FLAGS="-Wall -Wextra -Werror" \
    >"$dir.configure.log" 2>&1 ||
    { cat "$dir.configure.log" >&2; fail "configuring examples/$example ($config) against $prefix"; }
  found="$(sed -n 's/^svokit_DIR:PATH=//p' "$dir/CMakeCache.txt")"
  [ "$found" = "$prefix/lib/cmake/svokit" ] || fail "find_package(svokit) found '$found'"
  if grep -n "CMake Warning" "$dir.configure.log"; then
    fail "find_package(svokit COMPONENTS reader) warned ($config)"
  fi
  if grep -inE "^[A-Za-z_]*($foreign)[A-Za-z_]*_DIR:" "$dir/CMakeCache.txt"; then
    fail "find_package(svokit COMPONENTS reader) looked for a build stage's dependency ($config)"
  fi
  cmake --build "$dir" --verbose >"$dir.build.log" 2>&1 ||
    { cat "$dir.build.log" >&2; fail "building examples/$example ($config) against $prefix"; }
  # The commands, with this test's own folder names taken out (they are random).
  commands="$(sed "s|$work|WORK|g" "$dir.build.log" "$dir/compile_commands.json")"
  if grep -inE "$foreign" <<<"$commands"; then
    fail "the reader's consumer $example ($config) compiles or links with a build stage's dependency"
  fi
done

# The same program through pkg-config alone.
pc_flags="$(PKG_CONFIG_PATH="$prefix/lib/pkgconfig" pkg-config --cflags --libs svokit-reader)" ||
  fail "pkg-config --cflags --libs svokit-reader"
if grep -inE "$foreign" <<<"${pc_flags//$work/WORK}"; then
  fail "svokit-reader.pc names a build stage's dependency: $pc_flags"
fi
# shellcheck disable=SC2086  # the flags are words
c++ -std=c++20 -O2 -Wall -Wextra -Werror "$src/examples/read_svo/main.cpp" -o "$work/read_svo_pc" \
  $pc_flags >"$work/pkg-config.log" 2>&1 ||
  { cat "$work/pkg-config.log" >&2; fail "building examples/read_svo with pkg-config's flags"; }

# And against the whole library: no components is svokit::svokit, and the other components load.
mkdir "$work/whole"
cat >"$work/whole/CMakeLists.txt" <<CMAKE
cmake_minimum_required(VERSION 3.20)
project(whole LANGUAGES CXX)
find_package(svokit 0.1 REQUIRED)
find_package(svokit 0.1 REQUIRED COMPONENTS export validate bake)
foreach(target svokit::reader svokit::svokit svokit::svokit_export svokit::svokit_validate
               svokit::svokit_bake)
  if(NOT TARGET \${target})
    message(FATAL_ERROR "no \${target}")
  endif()
endforeach()
add_executable(read_svo "$src/examples/read_svo/main.cpp")
target_link_libraries(read_svo PRIVATE svokit::svokit)
CMAKE
cmake -S "$work/whole" -B "$work/whole/build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF >"$work/whole.log" 2>&1 &&
  cmake --build "$work/whole/build" >>"$work/whole.log" 2>&1 ||
  { cat "$work/whole.log" >&2; fail "building examples/read_svo against svokit::svokit"; }

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
  fail "installed svo-voxelize"  # runs from the prefix
"$bin/svo-inspect" --json --levels "$work/torus.svo" >"$work/inspect.json" 2>/dev/null ||
  fail "installed svo-inspect"
# Every consumer reads the file whole, then streams the top chunk and every page meeting a box
# around the whole grid; all of them print the same.
for reader in example-Release/read_svo example-Debug/read_svo read_svo_pc whole/build/read_svo; do
  out="$work/$(tr / _ <<<"$reader").txt"
  "$work/$reader" "$work/torus.svo" >"$out" || fail "$reader torus.svo"
  "$work/$reader" "$work/torus.svo" --box -1e9 -1e9 -1e9 1e9 1e9 1e9 >>"$out" ||
    fail "$reader torus.svo --box"
done
release="$work/example-Release_read_svo.txt"
for out in "$work"/example-Debug_read_svo.txt "$work"/read_svo_pc.txt "$work"/whole_build_read_svo.txt; do
  cmp -s "$release" "$out" || fail "$(basename "$out") differs from the Release build's output:
$(diff "$release" "$out" | head -20)"
done

# The streaming examples: every voxel once, with its colour and normal; a camera's pages through a
# cache of 1 MiB.
"$work/voxel_colors/voxel_colors" "$work/torus.svo" --memory-limit 64 >"$work/voxels.txt" ||
  fail "voxel_colors torus.svo"
"$work/pages_near_camera/pages_near_camera" "$work/torus.svo" 4 1e9 1 >"$work/camera.txt" ||
  fail "pages_near_camera torus.svo"
grep -q "^stop 3 pages 1 " "$work/camera.txt" ||
  fail "pages_near_camera: $(cat "$work/camera.txt")"
voxels_listed="$(awk 'NF == 9 { n++ } END { print n + 0 }' "$work/voxels.txt")"
[ "$voxels_listed" = "$(sed -n 's/^voxels \([0-9]*\)$/\1/p' "$release")" ] ||
  fail "voxel_colors listed $voxels_listed voxels with colour and normal, read_svo $(grep '^voxels' "$release")"

python3 - "$work/inspect.json" "$release" <<'PY'
import json, sys
inspect = json.load(open(sys.argv[1]))
def fields(path):
    out = {}
    for line in open(path):
        key, *values = line.split()
        out.setdefault(key, []).append(values)
    return out
out = fields(sys.argv[2])
errors = []
want = [(level["level"], level["nodes"]) for level in inspect["levels"]]
got = [(int(l), int(n)) for l, _, n in out["level"]]
if got != want:
    errors.append(f"per-level nodes: read_svo {got}, svo-inspect {want}")
streamed = [(int(l), int(n)) for l, _, n, _, _ in out["streamed"]]
if streamed != want:
    errors.append(f"per-level nodes streamed page by page: read_svo {streamed}, svo-inspect {want}")
if any(int(s) != 27 * int(n) for _, _, n, _, s in out["streamed"]):
    errors.append(f"streamed brick pools are not 27 samples per node: {out['streamed']}")
if int(out["depth"][0][0]) != inspect["octree"]["depth"] or len(want) != inspect["octree"]["depth"] + 1:
    errors.append(f"depth: read_svo {out['depth'][0][0]}, svo-inspect {inspect['octree']['depth']}")
if int(out["voxels"][0][0]) != inspect["voxels"]:
    errors.append(f"voxels: read_svo {out['voxels'][0][0]}, svo-inspect {inspect['voxels']}")
# The texture decoded: without it every voxel has the material's white base colour (Kd 1 1 1).
lo, hi = inspect["bricks"]["color_range"]["min"], inspect["bricks"]["color_range"]["max"]
if max(h - l for l, h in zip(lo[:3], hi[:3])) < 0.25:
    errors.append(f"colours {lo}..{hi}: the torus's texture was not decoded")
for e in errors:
    print("FAIL:", e, file=sys.stderr)
sys.exit(1 if errors else 0)
PY
echo "install test: $(grep -c '^level' "$release") levels agree in 4 consumers, texture decoded by \
$prefix/lib/libsvokit_oiio.so"
