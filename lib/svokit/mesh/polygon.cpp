#include "svokit/mesh/polygon.hpp"

#include <cmath>

namespace svokit::detail {

namespace {

struct P2 {
  double x, y;
};

double Cross2(const P2& o, const P2& a, const P2& b) {
  return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

void Fan(std::span<const std::uint32_t> local, std::vector<std::uint32_t>& out) {
  for (std::size_t i = 1; i + 1 < local.size(); ++i) {
    out.insert(out.end(), {local[0], local[i], local[i + 1]});
  }
}

}  // namespace

void TriangulatePolygon(std::span<const Vec3d> positions, std::span<const std::uint32_t> corners,
                        std::vector<std::uint32_t>& out) {
  const std::size_t n = corners.size();
  if (n < 3) return;
  if (n == 3) {
    out.insert(out.end(), {0u, 1u, 2u});
    return;
  }
  std::vector<std::uint32_t> remaining(n);
  for (std::uint32_t i = 0; i < n; ++i) remaining[i] = i;

  // Newell's normal is robust for non-planar and concave polygons.
  Vec3d normal{};
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3d& a = positions[corners[i]];
    const Vec3d& b = positions[corners[(i + 1) % n]];
    normal = normal +
             Vec3d{(a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y)};
  }
  int drop = 0;
  for (int a = 1; a < 3; ++a) {
    if (std::abs(normal[a]) > std::abs(normal[drop])) drop = a;
  }
  if (!(std::abs(normal[drop]) > 0.0)) return Fan(remaining, out);
  // Project onto the plane of the two other axes, oriented so the polygon runs counter-clockwise.
  const int u = (drop + 1) % 3, v = (drop + 2) % 3;
  const double flip = normal[drop] > 0 ? 1.0 : -1.0;
  std::vector<P2> p(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3d& q = positions[corners[i]];
    p[i] = {q[u], q[v] * flip};
  }

  while (remaining.size() > 3) {
    const std::size_t m = remaining.size();
    bool clipped = false;
    for (std::size_t i = 0; i < m && !clipped; ++i) {
      const std::uint32_t ia = remaining[(i + m - 1) % m], ib = remaining[i],
                          ic = remaining[(i + 1) % m];
      if (Cross2(p[ia], p[ib], p[ic]) <= 0) continue;  // reflex or degenerate corner
      bool empty = true;
      for (std::uint32_t j : remaining) {
        if (j == ia || j == ib || j == ic) continue;
        if (Cross2(p[ia], p[ib], p[j]) >= 0 && Cross2(p[ib], p[ic], p[j]) >= 0 &&
            Cross2(p[ic], p[ia], p[j]) >= 0) {
          empty = false;
          break;
        }
      }
      if (!empty) continue;
      out.insert(out.end(), {ia, ib, ic});
      remaining.erase(remaining.begin() + static_cast<std::ptrdiff_t>(i));
      clipped = true;
    }
    if (!clipped) return Fan(remaining, out);
  }
  out.insert(out.end(), {remaining[0], remaining[1], remaining[2]});
}

}  // namespace svokit::detail
