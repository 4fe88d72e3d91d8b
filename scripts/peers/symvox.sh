#!/usr/bin/env bash
# =====================================================================================
# symvox.sh - builds SymVox's command-line SVDAG builder `svbuilder` (Villanueva, Marton,
# Gobbetti, "SSVDAGs: Symmetry-aware Sparse Voxel DAGs", CRS4 2016; SymVox v0.1) as a
# benchmarking peer for svokit. Only the builder is built, not the OpenGL viewer.
#
# Licence of what this script builds: SymVox is GPL-3 plus a CRS4 clause (no commercial or
# closed-source derivatives without CRS4's authorization; see readme.txt in the source). Nothing
# of SymVox is kept in svokit's tree: the source comes from a bare git directory at build time.
#
# Source: a bare git directory of github.com/RvanderLaan/SVDAG-Compression, whose first commit
# ("Init commit", a74a219d) is SymVox v0.1 as released by CRS4. Get it once beforehand (e.g. a
# bare clone) and pass it as SYMVOX_GIT. This script downloads NOTHING.
#
# SymVox needs CRS4's SpaceLand ("SL") geometry library, which is not in Debian and not public
# any more. The script writes its own minimal stand-in for the few SL pieces svbuilder uses
# (3D points/vectors, axis-aligned boxes, conversions, a wall clock, human-readable printing),
# written from scratch for this purpose, into $PREFIX/src/sl-standin, and builds it as the
# libsl.a that SymVox's CMake (cmake_modules/FindSL.cmake) looks for.
#
# Prerequisites (Debian 12), checked, never installed: build-essential (g++ 12 with libgomp for
# OpenMP), cmake, git. GLFW/GLEW/OpenGL are NOT needed (viewer off).
#
# Usage:   bash symvox.sh          (PREFIX=./peers-symvox by default; wipes and rebuilds
#                                   $PREFIX/src, $PREFIX/build and $PREFIX/bin only)
# Env:     SYMVOX_GIT, SYMVOX_REV, PREFIX, JOBS (<= 2), SELFTEST=0 to skip the self-test
# Result:  $PREFIX/bin/svbuilder, $PREFIX/bin/BUILD_INFO.txt
#
# Running it (see also the notes printed by the self-test):
#   svbuilder MESH.obj LEVELS STEPS out.svdag out.ssvdag [out.ussvdag] [out.svo]
#   - MESH must be an ASCII OBJ (triangles; 'v' and 'f' lines). svbuilder WRITES A CACHE
#     "MESH.obj.bincache" NEXT TO THE MESH and loads it instead of the OBJ on the next run:
#     run it on a symlink in a scratch folder, and delete the cache for cold timings.
#   - grid = 2^LEVELS a side; the root cube is centred on the mesh's bounding box, its side the
#     box's largest extent.
#   - STEPS = 0: one thread, whole SVO then DAG; STEPS > 0: a top SVO of STEPS+1 levels, then
#     one subtree per top voxel, built and reduced to a DAG in parallel (OpenMP; threads from
#     OMP_NUM_THREADS). Every subtree tests every triangle of the mesh against its cube first.
#   - Known upstream bugs (unpatched): with STEPS = 0 a mesh of fewer than 5 triangles divides by
#     zero in the progress printout (SIGFPE); a quad is split only if its 'f' line has a trailing
#     blank; faces are read with "%d//%d", so "v/vt/vn" indices work but only the vertex is used.
#   - It prints "Voxels: ... (N)", "DAG Nodes", "SDAG Nodes" and the encoded sizes at the end.
# =====================================================================================
set -euo pipefail

SYMVOX_GIT=${SYMVOX_GIT:-/work/.mirror/RvanderLaan+SVDAG-Compression/repo}
SYMVOX_REV=${SYMVOX_REV:-a74a219d554b06770d81539a1a9e9b7aeff92868}   # "Init commit" = SymVox v0.1 (2016-08-31)
PREFIX=${PREFIX:-$PWD/peers-symvox}
JOBS=${JOBS:-2}
SELFTEST=${SELFTEST:-1}
BUILD_TYPE=Release                 # CMake Release with GCC => -O3 -DNDEBUG

SRC=$PREFIX/src; BLD=$PREFIX/build; BIN=$PREFIX/bin
SV=$SRC/symvox; SLD=$SRC/sl-standin
log() { printf '\n==== %s\n' "$*"; }
die() { printf 'ERROR: %s\n' "$*" >&2; exit 1; }

# ---- prerequisites (checked, never installed) -----------------------------------------
log "checking prerequisites"
for t in git tar g++ ar make cmake sed grep od stat; do command -v "$t" >/dev/null || die "missing tool: $t (apt-get install --no-install-recommends build-essential cmake git)"; done
[ "$JOBS" -le 2 ] || die "JOBS must be <= 2 on this shared machine"
[ -d "$SYMVOX_GIT" ] || die "SYMVOX_GIT=$SYMVOX_GIT is not a directory (get a bare clone of github.com/RvanderLaan/SVDAG-Compression first)"
git --git-dir="$SYMVOX_GIT" cat-file -e "$SYMVOX_REV^{commit}" 2>/dev/null || die "commit $SYMVOX_REV not in $SYMVOX_GIT"
printf '#include <omp.h>\nint main(){return omp_get_max_threads()>0?0:1;}\n' | g++ -x c++ -fopenmp - -o /dev/null 2>/dev/null \
  || die "g++ cannot build OpenMP programs (libgomp missing? apt-get install --no-install-recommends build-essential)"

log "cleaning $SRC $BLD $BIN"
rm -rf "$SRC" "$BLD" "$BIN"
mkdir -p "$SV" "$SLD/sl" "$BLD" "$BIN"

log "exporting SymVox @ $SYMVOX_REV"
git --git-dir="$SYMVOX_GIT" archive --format=tar "$SYMVOX_REV" | tar -x -C "$SV"
for f in CMakeLists.txt cmake_modules/FindSL.cmake src/svbuilder/main.cpp src/symvox/geom_octree.cpp src/symvox/encoded_ssvdag.cpp; do
  [ -f "$SV/$f" ] || die "unexpected source tree: $f missing"
done
echo "  $(git --git-dir="$SYMVOX_GIT" log -1 --format='%H %ad %s' --date=short "$SYMVOX_REV") -> $SV"

# =====================================================================================
# SL stand-in: our own minimal implementation of the SpaceLand API that svbuilder uses.
# Design: sl::fixed_size_point<N,T> and sl::fixed_size_vector<N,T> are distinct affine types
# (point - point = vector, point +/- vector = point) holding exactly N packed T's (SymVox
# memcpy's and fwrite's them as raw floats); sl::axis_aligned_box<N,T> is two points [min, max]
# (to_empty, merge, center, half_side_lengths); sl::conv_to<To>::from converts between the float
# and double flavours; a steady-clock real_time_clock with time_point / time_duration; and the
# human_readable_* printers, sl::min/max/tie and pathname_directory. Only 3D is implemented.
# =====================================================================================
log "writing the SL stand-in into $SLD"
cat >"$SLD/README.txt" <<'EOF'
Minimal stand-in for the parts of CRS4's SpaceLand (SL) library that SymVox v0.1's svbuilder
uses. Written from scratch for svokit's peer build (scripts/peers/symvox.sh); it contains no
SpaceLand code. 3D only. Not a general replacement for SL.
EOF

cat >"$SLD/sl/config.hpp" <<'EOF'
// SL stand-in (svokit peers): shared basics. Also pulls in the standard headers that the 2016
// SymVox sources expect to get transitively from their SL includes.
#pragma once
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <limits>
#include <map>
#include <string>
#include <tuple>
#include <type_traits>
#include <vector>

namespace sl {
  typedef std::int8_t   int8_t;   typedef std::uint8_t  uint8_t;
  typedef std::int16_t  int16_t;  typedef std::uint16_t uint16_t;
  typedef std::int32_t  int32_t;  typedef std::uint32_t uint32_t;
  typedef std::int64_t  int64_t;  typedef std::uint64_t uint64_t;

  using std::tie;

  template <class A, class B>
  inline typename std::common_type<A, B>::type min(A a, B b) {
    typedef typename std::common_type<A, B>::type R; return R(b) < R(a) ? R(b) : R(a);
  }
  template <class A, class B>
  inline typename std::common_type<A, B>::type max(A a, B b) {
    typedef typename std::common_type<A, B>::type R; return R(a) < R(b) ? R(b) : R(a);
  }

  // conv_to<To>::from(x): value conversion between the float/double flavours of the geometric
  // types; each type provides an overload of sl_convert_into(To&, const From&) found by ADL.
  template <class To>
  struct conv_to {
    template <class From> static To from(const From& x) { To r; sl_convert_into(r, x); return r; }
  };

  // printing helpers (defined in sl_standin.cpp -> libsl.a)
  std::string human_readable_quantity(std::uint64_t n);   // 1234567 -> "1.23M"
  std::string human_readable_size(std::uint64_t bytes);   // 1536 -> "1.50KB" (1024-based)
  std::string pathname_directory(const std::string& path); // "a/b/c.obj" -> "a/b", "c.obj" -> "."
}
EOF

cat >"$SLD/sl/cstdint.hpp" <<'EOF'
#pragma once
#include <sl/config.hpp>
EOF

cat >"$SLD/sl/external_array.hpp" <<'EOF'
// SL stand-in: SymVox v0.1 includes this header but uses nothing from it.
#pragma once
#include <sl/config.hpp>
EOF

cat >"$SLD/sl/any.hpp" <<'EOF'
// SL stand-in: only here because SymVox's FindSL.cmake looks for sl/any.hpp.
#pragma once
#include <sl/config.hpp>
EOF

cat >"$SLD/sl/fixed_size_vector.hpp" <<'EOF'
// SL stand-in: a free vector of N components (displacement). 3D only.
#pragma once
#include <sl/config.hpp>

namespace sl {
  template <std::size_t N, class T>
  class fixed_size_vector {
    static_assert(N == 3, "SL stand-in: only 3D vectors are implemented");
  public:
    typedef T value_t;
  private:
    T c_[N];
  public:
    fixed_size_vector() : c_{T(0), T(0), T(0)} {}
    fixed_size_vector(T x, T y, T z) : c_{x, y, z} {}

    T& operator[](std::size_t i) { return c_[i]; }
    const T& operator[](std::size_t i) const { return c_[i]; }
    T* to_pointer() { return c_; }
    const T* to_pointer() const { return c_; }

    fixed_size_vector& operator+=(const fixed_size_vector& o) { for (std::size_t i = 0; i < N; ++i) c_[i] += o.c_[i]; return *this; }
    fixed_size_vector& operator-=(const fixed_size_vector& o) { for (std::size_t i = 0; i < N; ++i) c_[i] -= o.c_[i]; return *this; }
    fixed_size_vector& operator*=(T s) { for (std::size_t i = 0; i < N; ++i) c_[i] *= s; return *this; }
    fixed_size_vector& operator/=(T s) { for (std::size_t i = 0; i < N; ++i) c_[i] /= s; return *this; }
    fixed_size_vector operator+(const fixed_size_vector& o) const { fixed_size_vector r(*this); r += o; return r; }
    fixed_size_vector operator-(const fixed_size_vector& o) const { fixed_size_vector r(*this); r -= o; return r; }
    fixed_size_vector operator-() const { return fixed_size_vector(-c_[0], -c_[1], -c_[2]); }
    fixed_size_vector operator*(T s) const { fixed_size_vector r(*this); r *= s; return r; }
    fixed_size_vector operator/(T s) const { fixed_size_vector r(*this); r /= s; return r; }
    friend fixed_size_vector operator*(T s, const fixed_size_vector& v) { return v * s; }

    T dot(const fixed_size_vector& o) const { return c_[0] * o.c_[0] + c_[1] * o.c_[1] + c_[2] * o.c_[2]; }
    fixed_size_vector cross(const fixed_size_vector& o) const {
      return fixed_size_vector(c_[1] * o.c_[2] - c_[2] * o.c_[1],
                               c_[2] * o.c_[0] - c_[0] * o.c_[2],
                               c_[0] * o.c_[1] - c_[1] * o.c_[0]);
    }
    T two_norm_squared() const { return dot(*this); }
    T two_norm() const { return T(std::sqrt(two_norm_squared())); }

    bool operator==(const fixed_size_vector& o) const { return c_[0] == o.c_[0] && c_[1] == o.c_[1] && c_[2] == o.c_[2]; }
    bool operator!=(const fixed_size_vector& o) const { return !(*this == o); }
  };

  template <std::size_t N, class T, class U>
  inline void sl_convert_into(fixed_size_vector<N, T>& to, const fixed_size_vector<N, U>& from) {
    for (std::size_t i = 0; i < N; ++i) to[i] = T(from[i]);
  }

  typedef fixed_size_vector<3, float>  vector3f;
  typedef fixed_size_vector<3, double> vector3d;
}
EOF

cat >"$SLD/sl/fixed_size_point.hpp" <<'EOF'
// SL stand-in: a point (position) of N components; point - point is a vector. 3D only.
#pragma once
#include <sl/config.hpp>
#include <sl/fixed_size_vector.hpp>

namespace sl {
  template <std::size_t N, class T>
  class fixed_size_point {
    static_assert(N == 3, "SL stand-in: only 3D points are implemented");
  public:
    typedef T value_t;
    typedef fixed_size_vector<N, T> vector_t;
  private:
    T c_[N];
  public:
    fixed_size_point() : c_{T(0), T(0), T(0)} {}
    fixed_size_point(T x, T y, T z) : c_{x, y, z} {}

    T& operator[](std::size_t i) { return c_[i]; }
    const T& operator[](std::size_t i) const { return c_[i]; }
    T* to_pointer() { return c_; }
    const T* to_pointer() const { return c_; }

    vector_t as_vector() const { return vector_t(c_[0], c_[1], c_[2]); }

    fixed_size_point& operator+=(const vector_t& v) { for (std::size_t i = 0; i < N; ++i) c_[i] += v[i]; return *this; }
    fixed_size_point& operator-=(const vector_t& v) { for (std::size_t i = 0; i < N; ++i) c_[i] -= v[i]; return *this; }
    fixed_size_point operator+(const vector_t& v) const { fixed_size_point r(*this); r += v; return r; }
    fixed_size_point operator-(const vector_t& v) const { fixed_size_point r(*this); r -= v; return r; }
    vector_t operator-(const fixed_size_point& o) const { return vector_t(c_[0] - o.c_[0], c_[1] - o.c_[1], c_[2] - o.c_[2]); }

    bool operator==(const fixed_size_point& o) const { return c_[0] == o.c_[0] && c_[1] == o.c_[1] && c_[2] == o.c_[2]; }
    bool operator!=(const fixed_size_point& o) const { return !(*this == o); }
  };

  template <std::size_t N, class T, class U>
  inline void sl_convert_into(fixed_size_point<N, T>& to, const fixed_size_point<N, U>& from) {
    for (std::size_t i = 0; i < N; ++i) to[i] = T(from[i]);
  }

  typedef fixed_size_point<3, float>  point3f;
  typedef fixed_size_point<3, double> point3d;
  typedef fixed_size_point<3, float>  color3f;   // SymVox only stores and copies colours
}
EOF

cat >"$SLD/sl/axis_aligned_box.hpp" <<'EOF'
// SL stand-in: axis-aligned box = [min point, max point], box[0] = min, box[1] = max. 3D only.
#pragma once
#include <sl/config.hpp>
#include <sl/fixed_size_point.hpp>

namespace sl {
  template <std::size_t N, class T>
  class axis_aligned_box {
  public:
    typedef fixed_size_point<N, T> point_t;
    typedef fixed_size_vector<N, T> vector_t;
  private:
    point_t corner_[2];
  public:
    axis_aligned_box() { to_empty(); }
    axis_aligned_box(const point_t& lo, const point_t& hi) { corner_[0] = lo; corner_[1] = hi; }

    point_t& operator[](std::size_t i) { return corner_[i]; }
    const point_t& operator[](std::size_t i) const { return corner_[i]; }

    void to_empty() {
      for (std::size_t i = 0; i < N; ++i) { corner_[0][i] = std::numeric_limits<T>::max(); corner_[1][i] = -std::numeric_limits<T>::max(); }
    }
    bool is_empty() const {
      for (std::size_t i = 0; i < N; ++i) if (corner_[0][i] > corner_[1][i]) return true;
      return false;
    }
    void merge(const point_t& p) {
      for (std::size_t i = 0; i < N; ++i) {
        if (p[i] < corner_[0][i]) corner_[0][i] = p[i];
        if (p[i] > corner_[1][i]) corner_[1][i] = p[i];
      }
    }
    void merge(const axis_aligned_box& b) { if (!b.is_empty()) { merge(b[0]); merge(b[1]); } }
    point_t center() const {
      point_t c;
      for (std::size_t i = 0; i < N; ++i) c[i] = (corner_[0][i] + corner_[1][i]) / T(2);
      return c;
    }
    vector_t diagonal() const { return corner_[1] - corner_[0]; }
    vector_t half_side_lengths() const { return diagonal() / T(2); }
    bool contains(const point_t& p) const {
      for (std::size_t i = 0; i < N; ++i) if (p[i] < corner_[0][i] || p[i] > corner_[1][i]) return false;
      return true;
    }
  };

  template <std::size_t N, class T, class U>
  inline void sl_convert_into(axis_aligned_box<N, T>& to, const axis_aligned_box<N, U>& from) {
    for (int k = 0; k < 2; ++k) sl_convert_into(to[k], from[k]);
  }

  typedef axis_aligned_box<3, float>  aabox3f;
  typedef axis_aligned_box<3, double> aabox3d;
}
EOF

cat >"$SLD/sl/clock.hpp" <<'EOF'
// SL stand-in: wall clock (std::chrono::steady_clock), durations in nanoseconds.
#pragma once
#include <sl/config.hpp>

namespace sl {
  class time_duration {
    std::int64_t ns_;
  public:
    explicit time_duration(std::int64_t ns = 0) : ns_(ns) {}
    std::int64_t as_nanoseconds() const { return ns_; }
    double as_microseconds() const { return double(ns_) * 1e-3; }
    double as_milliseconds() const { return double(ns_) * 1e-6; }
    double as_seconds() const { return double(ns_) * 1e-9; }
    time_duration operator+(const time_duration& o) const { return time_duration(ns_ + o.ns_); }
    time_duration operator-(const time_duration& o) const { return time_duration(ns_ - o.ns_); }
    time_duration& operator+=(const time_duration& o) { ns_ += o.ns_; return *this; }
    time_duration& operator-=(const time_duration& o) { ns_ -= o.ns_; return *this; }
    time_duration operator*(double f) const { return time_duration(std::int64_t(double(ns_) * f)); }
    bool operator<(const time_duration& o) const { return ns_ < o.ns_; }
  };

  class time_point {
    std::int64_t ns_;   // since the steady clock's epoch
  public:
    explicit time_point(std::int64_t ns = 0) : ns_(ns) {}
    time_duration operator-(const time_point& o) const { return time_duration(ns_ - o.ns_); }
    time_point operator+(const time_duration& d) const { return time_point(ns_ + d.as_nanoseconds()); }
  };

  class real_time_clock {
    time_point start_;
  public:
    real_time_clock() { restart(); }
    static time_point now() {
      return time_point(std::chrono::duration_cast<std::chrono::nanoseconds>(
        std::chrono::steady_clock::now().time_since_epoch()).count());
    }
    void restart() { start_ = now(); }
    time_duration elapsed() const { return now() - start_; }
  };

  std::string human_readable_duration(const time_duration& d);   // "12.3 ms", "4.56 s", "2 m 3.4 s"
}
EOF

cat >"$SLD/sl_standin.cpp" <<'EOF'
// SL stand-in (svokit peers): out-of-line helpers, built into libsl.a.
#include <sl/config.hpp>
#include <sl/clock.hpp>

namespace sl {
  static std::string fmt(const char* f, double v, const char* unit) {
    char b[64]; std::snprintf(b, sizeof b, f, v, unit); return std::string(b);
  }
  std::string human_readable_quantity(std::uint64_t n) {
    static const char* u[] = {"", "K", "M", "G", "T", "P"};
    double v = double(n); int k = 0;
    while (v >= 1000.0 && k < 5) { v /= 1000.0; ++k; }
    return k == 0 ? std::to_string(n) : fmt("%.2f%s", v, u[k]);
  }
  std::string human_readable_size(std::uint64_t bytes) {
    static const char* u[] = {"B", "KB", "MB", "GB", "TB", "PB"};
    double v = double(bytes); int k = 0;
    while (v >= 1024.0 && k < 5) { v /= 1024.0; ++k; }
    return k == 0 ? std::to_string(bytes) + "B" : fmt("%.2f%s", v, u[k]);
  }
  std::string human_readable_duration(const time_duration& d) {
    double s = d.as_seconds();
    if (s < 1e-3) return fmt("%.1f %s", s * 1e6, "us");
    if (s < 1.0)  return fmt("%.2f %s", s * 1e3, "ms");
    if (s < 60.0) return fmt("%.3f %s", s, "s");
    char b[64]; std::snprintf(b, sizeof b, "%d m %.1f s", int(s / 60.0), s - 60.0 * int(s / 60.0));
    return std::string(b);
  }
  std::string pathname_directory(const std::string& path) {
    std::string::size_type p = path.find_last_of('/');
    if (p == std::string::npos) return ".";
    return p == 0 ? "/" : path.substr(0, p);
  }
}
EOF

log "building the SL stand-in (libsl.a)"
mkdir -p "$BLD/sl-standin"
g++ -std=c++11 -O3 -DNDEBUG -fPIC -I"$SLD" -c "$SLD/sl_standin.cpp" -o "$BLD/sl-standin/sl_standin.o" \
  || die "SL stand-in does not compile"
ar rcs "$BLD/sl-standin/libsl.a" "$BLD/sl-standin/sl_standin.o"

# =====================================================================================
# PATCHES: none. SymVox v0.1 builds unmodified with GCC 12 against the stand-in (which supplies
# the standard headers the sources expect to get through SL). Only its CMake configuration is
# steered from the command line below (SL paths, viewer off).
# =====================================================================================

# =====================================================================================
# configure + build svbuilder with SymVox's own CMakeLists (Release = -O3 -DNDEBUG, OpenMP)
# =====================================================================================
log "cmake (svbuilder only)"
# The viewer's find_package(OpenGL/GLFW/GLEW) calls are switched off: SymVox's FindGLFW.cmake
# aborts the configuration when Xrandr is missing, and the viewer is not wanted anyway.
cmake -S "$SV" -B "$BLD/symvox" -DCMAKE_BUILD_TYPE=$BUILD_TYPE \
      -DSL_INCLUDE_DIR="$SLD" -DSL_LIBRARY="$BLD/sl-standin/libsl.a" -DBUILD_SVVIEWER=OFF \
      -DCMAKE_DISABLE_FIND_PACKAGE_OpenGL=ON -DCMAKE_DISABLE_FIND_PACKAGE_GLFW=ON -DCMAKE_DISABLE_FIND_PACKAGE_GLEW=ON \
      >"$BLD/symvox.cmake.log" 2>&1 || { tail -30 "$BLD/symvox.cmake.log"; die "cmake failed"; }
grep -q 'SL Library: Found' "$BLD/symvox.cmake.log" || die "FindSL did not accept the stand-in"
grep -q '^OpenMP_CXX_FLAGS:STRING=-fopenmp' "$BLD/symvox/CMakeCache.txt" || die "CMake found no OpenMP"
cmake --build "$BLD/symvox" -j"$JOBS" --target svbuilder -- VERBOSE=1 >"$BLD/symvox.log" 2>&1 \
  || { grep -E 'error|Error' "$BLD/symvox.log" | head -30; die "svbuilder build failed (log: $BLD/symvox.log)"; }
grep -q -- '-O3 -DNDEBUG' "$BLD/symvox.log" || die "not built with -O3 -DNDEBUG"
grep -q -- '-fopenmp' "$BLD/symvox.log" || die "not built with -fopenmp"
[ -x "$SV/bin/svbuilder" ] || die "svbuilder not produced"
install -m 755 "$SV/bin/svbuilder" "$BIN/svbuilder"

# =====================================================================================
# build manifest
# =====================================================================================
log "manifest"
{
  echo "built: $(date -u +%FT%TZ) on $(uname -srm)"
  echo "g++: $(g++ --version | head -1)"
  echo "cmake: $(cmake --version | head -1)"
  echo "libgomp: $(dpkg-query -W -f='${Version}' libgomp1 2>/dev/null || echo '?')"
  echo "flags: SymVox CMakeLists, CMAKE_BUILD_TYPE=$BUILD_TYPE (-O3 -DNDEBUG), -std=c++0x, OpenMP (-fopenmp), FindSL's -fPIC -D_ISOC99_SOURCE...; BUILD_SVVIEWER=OFF"
  echo "source: $(basename "$(dirname "$SYMVOX_GIT")") $(git --git-dir="$SYMVOX_GIT" rev-parse "$SYMVOX_REV") (SymVox v0.1, GPL-3 + CRS4 clause)"
  echo "SL: svokit's own stand-in headers ($SLD, written by scripts/peers/symvox.sh), libsl.a"
  echo "patches: none"
  echo "binaries (sha256):"
  (cd "$BIN" && sha256sum svbuilder | sed 's/^/  /')
} | tee "$BIN/BUILD_INFO.txt"

# =====================================================================================
# self-test (tiny mesh, NOT a benchmark): an octahedron at 2^5 = 32 a side, serial (steps 0)
# and parallel (steps 1) builds; both must write non-empty, well-formed .svdag and .ssvdag
# files and report the same voxel count.
# =====================================================================================
u32() { od -An -t u4 -j "$2" -N 4 "$1" | tr -d ' '; }
if [ "$SELFTEST" = 1 ]; then
  log "self-test: octahedron, 5 levels (32^3), steps 0 and 1"
  T=$(mktemp -d "$BLD/selftest.XXXXXX")
  cat >"$T/octa.obj" <<'EOF'
v 1 0 0
v -1 0 0
v 0 1 0
v 0 -1 0
v 0 0 1
v 0 0 -1
f 1 3 5
f 3 2 5
f 2 4 5
f 4 1 5
f 3 1 6
f 2 3 6
f 4 2 6
f 1 4 6
EOF
  L=5
  declare -A vox
  for steps in 0 1; do
    (cd "$T" && rm -f octa.obj.bincache && "$BIN/svbuilder" octa.obj $L $steps s$steps.svdag s$steps.ssvdag >s$steps.log 2>&1) \
      || { tail -20 "$T/s$steps.log"; die "svbuilder failed (steps $steps)"; }
    for f in s$steps.svdag s$steps.ssvdag; do [ -s "$T/$f" ] || die "$f missing or empty"; done
    sz=$(stat -c %s "$T/s$steps.svdag");  cnt=$(u32 "$T/s$steps.svdag" 40)
    [ "$(u32 "$T/s$steps.svdag" 28)" = $L ] && [ "$sz" = $((44 + 4 * cnt)) ] || die "s$steps.svdag malformed (size $sz, count $cnt)"
    ssz=$(stat -c %s "$T/s$steps.ssvdag"); n16=$(u32 "$T/s$steps.ssvdag" 36)
    nb=$(u32 "$T/s$steps.ssvdag" $((40 + 2 * n16)))
    [ "$(u32 "$T/s$steps.ssvdag" 28)" = $L ] && [ "$ssz" = $((48 + 2 * n16 + nb + 4 * (L - 2))) ] || die "s$steps.ssvdag malformed (size $ssz)"
    vox[$steps]=$(sed -n 's/^Voxels:.*(\([0-9]*\))$/\1/p' "$T/s$steps.log")
    echo "  steps $steps: ${vox[$steps]} voxels; .svdag $sz B, .ssvdag $ssz B"
    [ "${vox[$steps]:-0}" -gt 0 ] || die "no voxels reported (steps $steps)"
  done
  [ "${vox[0]}" = "${vox[1]}" ] || die "serial and parallel builds disagree: ${vox[0]} vs ${vox[1]} voxels"
  cmp -s "$T/s0.svdag" "$T/s1.svdag" && echo "  .svdag files of steps 0 and 1 are identical" \
                                     || echo "  (.svdag files of steps 0 and 1 differ in node order; same voxel count)"
  rm -rf "$T"
  echo "  self-test OK"
fi

log "done: $BIN/svbuilder"
ls -l "$BIN"
