#include "svokit/inspect/ray_cast.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "svokit/core/held_bytes.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/formats/svo/svo_stream.hpp"
#include "svokit/inspect/paged_svo.hpp"
#include "svokit/mesh/image_codec.hpp"

namespace svokit {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kMargin = 0.02;  // of the image per side, around the fitted bounds
// Without a limit, the pages a paged render caches per thread: a band of tiles' worth.
constexpr std::uint64_t kDefaultPagesPerThread = 4;

Vec3d Normalized(const Vec3d& v) {
  return v / Length(v);
}

struct Basis {
  Vec3d forward, up;
};

Basis ViewBasis(View view) {
  switch (view) {
    case View::kFront:
      return {{0, 0, -1}, {0, 1, 0}};
    case View::kBack:
      return {{0, 0, 1}, {0, 1, 0}};
    case View::kLeft:
      return {{1, 0, 0}, {0, 1, 0}};
    case View::kRight:
      return {{-1, 0, 0}, {0, 1, 0}};
    case View::kTop:
      return {{0, -1, 0}, {0, 0, -1}};
    case View::kBottom:
      return {{0, 1, 0}, {0, 0, 1}};
    case View::kIso:
      break;
  }
  const Vec3d f = Normalized(Vec3d{-1, -1, -1});
  const Vec3d y{0, 1, 0};
  return {f, Normalized(y - f * Dot(y, f))};
}

std::array<Vec3d, 8> Corners(const Box3d& b) {
  std::array<Vec3d, 8> c;
  for (unsigned i = 0; i < 8; ++i) {
    c[i] = {i & 1 ? b.hi.x : b.lo.x, i & 2 ? b.hi.y : b.lo.y, i & 4 ? b.hi.z : b.lo.z};
  }
  return c;
}

// A node's span along the ray and the world normal of the surface the span was entered through
// (a cube face or a slab plane), facing the ray.
struct Span {
  double t0 = 0, t1 = 0;
  Vec3d entry_normal;
};

// The brick interpolated trilinearly at local position f ∈ [0, 1]³ of the node, opacity-weighted
// (samples store straight colour and unit normals, so they are premultiplied before mixing).
struct BrickValue {
  bool any = false;
  Rgba color{1, 1, 1, 1};
  Vec3d normal;  // zero when the bricks hold none
};

BrickValue SampleBrick(const Svo& svo, std::uint32_t level, std::uint64_t index, const Vec3d& f) {
  BrickValue v;
  const std::uint32_t side = svo.brick_side;
  if (side < 2) return v;
  std::array<std::uint32_t, 3> i0{};
  std::array<double, 3> w{};
  for (int a = 0; a < 3; ++a) {
    const double g = std::clamp(f[a], 0.0, 1.0) * (side - 1);
    i0[a] = std::min(static_cast<std::uint32_t>(g), side - 2);
    w[a] = g - i0[a];
  }
  double sum = 0, r = 0, g = 0, b = 0, alpha = 0;
  Vec3d n;
  for (unsigned c = 0; c < 8; ++c) {
    const std::uint32_t x = i0[0] + (c & 1), y = i0[1] + (c >> 1 & 1), z = i0[2] + (c >> 2 & 1);
    const double weight =
        (c & 1 ? w[0] : 1 - w[0]) * (c & 2 ? w[1] : 1 - w[1]) * (c & 4 ? w[2] : 1 - w[2]);
    const BrickSample s = svo.Sample(level, index, x + side * (y + side * z));
    const double wa = weight * s.opacity;
    sum += wa;
    r += wa * s.color.r;
    g += wa * s.color.g;
    b += wa * s.color.b;
    alpha += wa * s.color.a;
    n = n + Vec3d{s.normal.x, s.normal.y, s.normal.z} * wa;
  }
  if (!(sum > 0)) return v;
  v.any = true;
  if (svo.has_color) {
    v.color = {static_cast<float>(r / sum), static_cast<float>(g / sum),
               static_cast<float>(b / sum), static_cast<float>(alpha / sum)};
  }
  const double len = Length(n);
  if (svo.has_normal && len > 1e-12) v.normal = n / len;
  return v;
}

// The traversal runs in the octree's unit cube, mirrored so every direction component is positive
// (child c of the mirrored cube is child c ^ mirror of the real one); t stays the world distance.
// Where a ray enters a page (a node of the page level) of a paged render: the page's cube in the
// mirrored unit cube, the ray's span there, and the nodes the ray had visited before it.
struct PageEntry {
  std::size_t page = 0;
  Vec3d lo;
  double size = 0;
  Span span;
  std::uint32_t visits_before = 0;
  std::uint32_t ray = 0;  ///< the ray's index in its tile
};

constexpr std::uint32_t kNoPages = ~std::uint32_t{0};

// The pages of a paged render: page i (a node of `page_level`) as an Svo of its own (PageSvo).
struct SvoPageSource {
  std::uint32_t page_level = 0;
  std::function<StatusOr<std::shared_ptr<const Svo>>(std::size_t)> page;
};

// A paged render casts in two steps: Cast() runs over the levels above the pages (`svo`),
// recording each page the ray reaches as if it missed there; then ResolvePage() follows the ray
// into those pages in its order (the page at hand) until one is hit. What each visit computes is
// what the one-step traversal of the whole octree computes, so the pictures are the same.
class Caster {
 public:
  Caster(const Svo& svo, std::uint32_t page_level, std::vector<PageEntry>* record,
         std::uint32_t ray, const Vec3d& origin, const Vec3d& direction, std::uint32_t leaf_level,
         bool use_contours)
      : svo_(svo),
        page_level_(page_level),
        record_(record),
        ray_(ray),
        leaf_level_(leaf_level),
        contours_(use_contours),
        world_origin_(origin),
        world_dir_(direction) {
    const double root = svo.grid.voxel_size() * std::ldexp(1.0, static_cast<int>(svo.depth));
    const Vec3d o = (origin - svo.grid.origin()) / root, d = direction / root;
    const double largest = std::max({std::abs(d.x), std::abs(d.y), std::abs(d.z)});
    for (int a = 0; a < 3; ++a) {
      o_[a] = o[a];
      d_[a] = d[a];
      if (d_[a] < 0) {
        o_[a] = 1 - o_[a];
        d_[a] = -d_[a];
        mirror_ |= 1u << a;
      }
      // Axis-parallel rays: a tiny positive component keeps every slab test finite and ordered.
      d_[a] = std::max(d_[a], largest * 1e-14);
      inv_[a] = 1 / d_[a];
    }
  }

  RayHit Cast() {
    Span span;
    span.t0 = -kInf;
    span.t1 = kInf;
    int entry_axis = 0;
    for (int a = 0; a < 3; ++a) {
      const double t0 = -o_[a] * inv_[a], t1 = (1 - o_[a]) * inv_[a];
      if (t0 > span.t0) {
        span.t0 = t0;
        entry_axis = a;
      }
      span.t1 = std::min(span.t1, t1);
    }
    span.entry_normal = FaceNormal(entry_axis);
    span.t0 = std::max(span.t0, 0.0);
    if (span.t0 <= span.t1) {
      if (page_level_ == 0) {
        RecordPage(0, {0, 0, 0}, 1.0, span);
      } else {
        const SvoLevel& root = svo_.levels[0];
        Visit(svo_, 0, 0, root.contours.empty() ? 0 : root.contours[0], {0, 0, 0}, 1.0, span);
      }
    }
    hit_.visits = top_visits_ = visits_;
    return hit_;
  }

  // Follows the ray into the page it recorded at `entry`, `page` its nodes: true when it is hit
  // there (the ray is then done). hit() counts the visits the one-step traversal would.
  bool ResolvePage(const Svo& page, const PageEntry& entry) {
    const std::uint32_t before = visits_;
    const SvoLevel& root = page.levels[page_level_];
    const bool hit = Visit(page, page_level_, 0, root.contours.empty() ? 0 : root.contours[0],
                           entry.lo, entry.size, entry.span);
    page_visits_ += visits_ - before;
    hit_.visits = (hit ? entry.visits_before : top_visits_) + page_visits_;
    return hit;
  }
  const RayHit& hit() const { return hit_; }

 private:
  // The world normal of the mirrored cube face the ray enters through along `axis`.
  Vec3d FaceNormal(int axis) const {
    Vec3d n;
    n[axis] = (mirror_ >> axis & 1) ? 1.0 : -1.0;
    return n;
  }

  // Narrows `span` to the node's slab; false when nothing of the span is left.
  bool ClipToContour(std::uint32_t word, const Vec3d& lo, double size, Span& span) const {
    const Contour c = DecodeContour(word);
    const Vec3d n{static_cast<double>(c.nx), static_cast<double>(c.ny), static_cast<double>(c.nz)};
    Vec3d nm = n;  // the normal in mirrored space
    for (int a = 0; a < 3; ++a) {
      if (mirror_ >> a & 1) nm[a] = -nm[a];
    }
    const Vec3d center = lo + Vec3d{size, size, size} * 0.5;
    const double at = Dot(nm, o_ - center) / size, slope = Dot(nm, d_) / size;
    if (slope == 0) return at >= c.Low() && at <= c.High() && span.t0 <= span.t1;
    double ta = (c.Low() - at) / slope, tb = (c.High() - at) / slope;
    if (ta > tb) std::swap(ta, tb);
    if (ta > span.t0) {
      span.t0 = ta;
      const Vec3d unit = Normalized(n);
      span.entry_normal = Dot(unit, world_dir_) > 0 ? unit * -1.0 : unit;
    }
    span.t1 = std::min(span.t1, tb);
    return span.t0 <= span.t1;
  }

  // A page the ray reaches, followed later (ResolvePage): the traversal goes on as if it missed.
  bool RecordPage(std::size_t page, const Vec3d& lo, double size, const Span& span) {
    record_->push_back({page, lo, size, span, visits_, ray_});
    return false;
  }

  // Node `index` of `level` of `svo`; `contour`: its contour word, 0 for none (0 never encodes
  // one: its normal is zero).
  bool Visit(const Svo& svo, std::uint32_t level, std::uint64_t index, std::uint32_t contour,
             const Vec3d& lo, double size, Span span) {
    ++visits_;
    if (contours_ && contour != 0 && !ClipToContour(contour, lo, size, span)) return false;
    if (level == leaf_level_) {
      Hit(svo, level, index, contour, lo, size, span);
      return true;
    }
    const bool pages_below = level + 1 == page_level_;
    const SvoNode& node = svo.levels[level].nodes[index];
    // A pruned leaf: its contour bounds the subtree pruning dropped, its brick (normals
    // included: they are what the tolerances bound) shades it.
    if (node.child_mask == 0 && node.full_mask == 0) {
      Hit(svo, level, index, contour, lo, size, span, true);
      return true;
    }
    const double half = size * 0.5;
    Vec3d tm, t1;
    std::array<double, 3> t0{};
    for (int a = 0; a < 3; ++a) {
      t0[a] = (lo[a] - o_[a]) * inv_[a];
      tm[a] = (lo[a] + half - o_[a]) * inv_[a];
      t1[a] = (lo[a] + size - o_[a]) * inv_[a];
    }
    // The child holding the span's entry point, then siblings in the order the ray crosses the
    // three mid-planes: each step sets one more bit, so at most four children are visited.
    unsigned c = 0;
    for (int a = 0; a < 3; ++a) {
      if (tm[a] <= span.t0) c |= 1u << a;
    }
    while (true) {
      double cmin = -kInf, cmax = kInf;
      int entry_axis = 0;
      for (int a = 0; a < 3; ++a) {
        const bool upper = c >> a & 1;
        const double enter = upper ? tm[a] : t0[a], leave = upper ? t1[a] : tm[a];
        if (enter > cmin) {
          cmin = enter;
          entry_axis = a;
        }
        cmax = std::min(cmax, leave);
      }
      const unsigned real = c ^ mirror_;
      if (node.child_mask >> real & 1) {
        Span child = span;
        if (cmin > child.t0) {
          child.t0 = cmin;
          child.entry_normal = FaceNormal(entry_axis);
        }
        child.t1 = std::min(child.t1, cmax);
        if (child.t0 <= child.t1) {
          const Vec3d child_lo{lo.x + ((c & 1) ? half : 0), lo.y + ((c & 2) ? half : 0),
                               lo.z + ((c & 4) ? half : 0)};
          if (pages_below) {
            if (RecordPage(node.Child(real), child_lo, half, child)) return true;
          } else {
            std::uint32_t word = 0;
            if (node.contour_mask >> real & 1) {
              word = svo.levels[level + 1].contours[node.ChildContour(real)];
            }
            if (Visit(svo, level + 1, node.Child(real), word, child_lo, half, child)) return true;
          }
        }
      }
      // Leave through the nearest mid-plane not yet crossed, unless the ray leaves the node (or
      // its narrowed span) first.
      int next = -1;
      double best = kInf;
      for (int a = 0; a < 3; ++a) {
        if (!(c >> a & 1) && tm[a] < best) {
          best = tm[a];
          next = a;
        }
      }
      if (next < 0 || best > span.t1) break;
      bool left_parent = false;
      for (int a = 0; a < 3; ++a) {
        if ((c >> a & 1) && t1[a] < best) left_parent = true;
      }
      if (left_parent) break;
      c |= 1u << next;
    }
    return false;
  }

  void Hit(const Svo& svo, std::uint32_t level, std::uint64_t index, std::uint32_t contour,
           const Vec3d& lo, double size, const Span& span, bool pruned_leaf = false) {
    hit_.hit = true;
    hit_.t = span.t0;
    hit_.level = level;
    hit_.node = index;
    hit_.position = world_origin_ + world_dir_ * span.t0;
    // Local position in the (real, unmirrored) node from the mirrored one.
    Vec3d f;
    for (int a = 0; a < 3; ++a) {
      const double local = (o_[a] + d_[a] * span.t0 - lo[a]) / size;
      f[a] = (mirror_ >> a & 1) ? 1 - local : local;
    }
    const BrickValue brick = SampleBrick(svo, level, index, f);
    hit_.color = brick.color;
    // The leaf's own contour normal, else the filtered brick normal, else the face or slab the
    // span was entered through.
    Vec3d n = span.entry_normal;
    if (pruned_leaf && Length(brick.normal) > 0) {
      n = brick.normal;
    } else if (contours_ && contour != 0) {
      const Contour c = DecodeContour(contour);
      n = Normalized(
          Vec3d{static_cast<double>(c.nx), static_cast<double>(c.ny), static_cast<double>(c.nz)});
    } else if (Length(brick.normal) > 0) {
      n = brick.normal;
    }
    hit_.normal = Dot(n, world_dir_) > 0 ? n * -1.0 : n;
  }

  const Svo& svo_;
  std::uint32_t page_level_;
  std::vector<PageEntry>* record_;
  std::uint32_t ray_;
  std::uint32_t leaf_level_;
  bool contours_;
  Vec3d world_origin_, world_dir_;
  Vec3d o_, d_, inv_;
  unsigned mirror_ = 0;
  std::uint32_t visits_ = 0;
  std::uint32_t top_visits_ = 0, page_visits_ = 0;  // a paged cast's, apart
  RayHit hit_;
};

std::uint8_t Byte(double v) {
  return static_cast<std::uint8_t>(std::clamp(v, 0.0, 1.0) * 255.0 + 0.5);
}

}  // namespace

std::array<double, 2> OrthoCamera::Project(const Vec3d& p) const {
  const Vec3d rel = p - top_left;
  return {Dot(rel, right) / pixel_size, -Dot(rel, up) / pixel_size};
}

OrthoCamera FitCamera(const Svo& svo, View view, int width, int height) {
  const Basis basis = ViewBasis(view);
  OrthoCamera cam;
  cam.forward = basis.forward;
  cam.up = basis.up;
  cam.right = Cross(basis.forward, basis.up);
  cam.width = width;
  cam.height = height;
  double rmin = kInf, rmax = -kInf, umin = kInf, umax = -kInf, fmin = kInf;
  const Box3d bounds = svo.grid.GridBounds();
  for (const Vec3d& c : Corners(bounds)) {
    rmin = std::min(rmin, Dot(c, cam.right));
    rmax = std::max(rmax, Dot(c, cam.right));
    umin = std::min(umin, Dot(c, cam.up));
    umax = std::max(umax, Dot(c, cam.up));
    fmin = std::min(fmin, Dot(c, cam.forward));
  }
  cam.pixel_size = std::max((rmax - rmin) / (width * (1 - 2 * kMargin)),
                            (umax - umin) / (height * (1 - 2 * kMargin)));
  const double rc = (rmin + rmax) / 2, uc = (umin + umax) / 2;
  // The image plane sits a little in front of the grid, so every ray starts outside it.
  const double f0 = fmin - 0.01 * Length(bounds.extent()) - cam.pixel_size;
  cam.top_left = cam.right * (rc - width / 2.0 * cam.pixel_size) +
                 cam.up * (uc + height / 2.0 * cam.pixel_size) + cam.forward * f0;
  return cam;
}

RayHit CastRay(const Svo& svo, const Vec3d& origin, const Vec3d& direction,
               std::uint32_t leaf_level, bool use_contours) {
  return Caster(svo, kNoPages, nullptr, 0, origin, direction, leaf_level, use_contours).Cast();
}

namespace {

Status CheckImageSize(const RenderOptions& options) {
  if (options.width < 1 || options.height < 1 || options.width > kMaxImageSide ||
      options.height > kMaxImageSide) {
    return Status::BadInput("an image of {}x{}: each side must be 1 to {}", options.width,
                            options.height, kMaxImageSide);
  }
  return Status::Ok();
}

// Pixels go by tiles of this side, the tiles in Morton order: a paged render reads each page a
// tile's rays meet once for the tile, and neighbouring tiles find it still in the cache.
constexpr int kTile = 32;

// The tiles of a tiles_x × tiles_y grid, as (x, y), in Morton order.
std::vector<std::array<int, 2>> TileOrder(int tiles_x, int tiles_y) {
  std::vector<std::pair<std::uint64_t, std::array<int, 2>>> keyed;
  for (int y = 0; y < tiles_y; ++y) {
    for (int x = 0; x < tiles_x; ++x) {
      std::uint64_t key = 0;
      for (int b = 0; b < 16; ++b) {
        key |= std::uint64_t{static_cast<std::uint32_t>(x) >> b & 1u} << (2 * b);
        key |= std::uint64_t{static_cast<std::uint32_t>(y) >> b & 1u} << (2 * b + 1);
      }
      keyed.push_back({key, {x, y}});
    }
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::array<int, 2>> order;
  for (const auto& k : keyed) order.push_back(k.second);
  return order;
}

// The picture of `svo` (with `pages`, the levels above the pages) at leaf level `level`, tiles
// in parallel on the current arena; each pixel is its own ray's, so the image does not depend on
// the order. A page that cannot be read fails the render (the first tile's error).
StatusOr<RenderResult> Draw(const Svo& svo, const SvoPageSource* pages,
                            const RenderOptions& options, std::uint32_t level) {
  RenderResult result;
  result.level = level;
  result.camera = FitCamera(svo, options.view, options.width, options.height);
  result.image = RgbaImage(options.width, options.height);
  const OrthoCamera& cam = result.camera;
  double near = kInf, far = -kInf;
  for (const Vec3d& c : Corners(svo.grid.GridBounds())) {
    const double t = Dot(c - cam.top_left, cam.forward);
    near = std::min(near, t);
    far = std::max(far, t);
  }
  // A key light from the viewer's upper left: faces turned away darken, and the three faces of a
  // cube seen from iso differ (a pure headlight would shade them alike).
  const Vec3d light_dir = Normalized(cam.forward * -1.0 + cam.up * 0.6 - cam.right * 0.4);
  const std::vector<std::array<int, 2>> order =
      TileOrder((options.width + kTile - 1) / kTile, (options.height + kTile - 1) / kTile);
  std::vector<std::uint64_t> tile_hits(order.size()), tile_visits(order.size());
  std::vector<Status> tile_status(order.size(), Status::Ok());
  const std::uint32_t page_level = pages != nullptr ? pages->page_level : kNoPages;
  tbb::parallel_for(std::size_t{0}, order.size(), [&](std::size_t t) {
    const int x0 = order[t][0] * kTile, y0 = order[t][1] * kTile;
    const int x1 = std::min(x0 + kTile, options.width), y1 = std::min(y0 + kTile, options.height);
    std::vector<Caster> rays;
    std::vector<PageEntry> entries;
    for (int y = y0; y < y1; ++y) {
      for (int x = x0; x < x1; ++x) {
        const Vec3d origin = cam.top_left + cam.right * ((x + 0.5) * cam.pixel_size) -
                             cam.up * ((y + 0.5) * cam.pixel_size);
        rays.emplace_back(svo, page_level, &entries, static_cast<std::uint32_t>(rays.size()),
                          origin, cam.forward, level, options.contours);
        rays.back().Cast();
      }
    }
    if (pages != nullptr) {
      // The tile's pages one at a time, each read once, in an order every ray meets them in: a
      // ray's coordinates (mirrored) only grow, so the pages it crosses by their sum.
      std::sort(entries.begin(), entries.end(), [](const PageEntry& a, const PageEntry& b) {
        const double sa = (a.lo.x + a.lo.y + a.lo.z) / a.size;
        const double sb = (b.lo.x + b.lo.y + b.lo.z) / b.size;
        return sa != sb ? sa < sb : a.page != b.page ? a.page < b.page : a.ray < b.ray;
      });
      std::vector<std::uint8_t> done(rays.size(), 0);
      std::shared_ptr<const Svo> page;
      std::size_t held = 0;
      for (const PageEntry& entry : entries) {
        if (done[entry.ray]) continue;
        if (page == nullptr || entry.page != held) {
          StatusOr<std::shared_ptr<const Svo>> read = pages->page(entry.page);
          if (!read.ok()) {
            tile_status[t] = read.status();
            return;
          }
          page = std::move(*read);
          held = entry.page;
        }
        done[entry.ray] = rays[entry.ray].ResolvePage(*page, entry);
      }
    }
    for (int y = y0; y < y1; ++y) {
      for (int x = x0; x < x1; ++x) {
        const RayHit& hit = rays[static_cast<std::size_t>((y - y0) * (x1 - x0) + (x - x0))].hit();
        tile_visits[t] += hit.visits;
        std::uint8_t* px = result.image.at(x, y);
        if (!hit.hit) {
          if (options.background) {
            std::copy(options.background->begin(), options.background->end(), px);
            px[3] = 255;
          }
          continue;
        }
        ++tile_hits[t];
        px[3] = 255;
        switch (options.shade) {
          case Shade::kColor: {
            const double light = 0.2 + 0.8 * std::max(0.0, Dot(hit.normal, light_dir));
            px[0] = Byte(LinearToSrgb(static_cast<float>(hit.color.r * light)));
            px[1] = Byte(LinearToSrgb(static_cast<float>(hit.color.g * light)));
            px[2] = Byte(LinearToSrgb(static_cast<float>(hit.color.b * light)));
            break;
          }
          case Shade::kNormal:
            px[0] = Byte(hit.normal.x * 0.5 + 0.5);
            px[1] = Byte(hit.normal.y * 0.5 + 0.5);
            px[2] = Byte(hit.normal.z * 0.5 + 0.5);
            break;
          case Shade::kDepth: {
            const double v = 1 - 0.85 * (hit.t - near) / std::max(far - near, 1e-300);
            px[0] = px[1] = px[2] = Byte(v);
            break;
          }
          case Shade::kAo: {
            // The hit node's baked AO as grey, white where open (not lit: the term alone).
            const std::uint8_t ao = svo.levels[hit.level].ao[hit.node];
            px[0] = px[1] = px[2] = static_cast<std::uint8_t>(255 - ao);
            break;
          }
        }
      }
    }
  });
  for (std::size_t t = 0; t < tile_hits.size(); ++t) {
    SVOKIT_RETURN_IF_ERROR(tile_status[t]);
    result.hits += tile_hits[t];
    result.node_visits += tile_visits[t];
  }
  return result;
}

}  // namespace

StatusOr<RenderResult> RenderSvo(const Svo& svo, const RenderOptions& options) {
  SVOKIT_RETURN_IF_ERROR(CheckImageSize(options));
  if (svo.levels.empty() || svo.levels[0].node_count != 1) {
    return Status::Internal("render of an octree without a root");
  }
  const auto loaded = static_cast<std::uint32_t>(svo.levels.size() - 1);
  const std::uint32_t level = options.level.value_or(loaded);
  if (level > loaded) {
    return Status::BadInput("level {} is beyond the octree's levels 0..{}", level, loaded);
  }
  if (options.shade == Shade::kAo && !svo.has_ao) {
    return Status::BadInput(
        "shading by ambient occlusion: the octree has no baked ambient occlusion (svo-bake)");
  }
  return Draw(svo, nullptr, options, level);
}

StatusOr<RenderResult> RenderSvo(const SvoReader& reader, const RenderOptions& options,
                                 std::uint64_t memory_limit, PagedRenderStats* stats) {
  SVOKIT_RETURN_IF_ERROR(CheckImageSize(options).WithContext(reader.name()));
  const std::uint32_t level = options.level.value_or(reader.depth());
  SVOKIT_RETURN_IF_ERROR(CheckSvoLevel(reader, level));
  if (options.shade == Shade::kAo) {
    // AOCC is indexed by the whole octree's nodes, which a page does not know.
    return Status::BadInput("{}: shading by ambient occlusion reads the octree whole",
                            reader.name());
  }
  const std::uint32_t page_level = reader.page_level();
  StatusOr<Svo> top = ReadTopSvo(reader, level);
  if (!top.ok()) return top.status();
  if (level < page_level) return Draw(*top, nullptr, options, level);
  // Each thread holds at most one page outside the cache (one it assembles, or one the cache has
  // given up while its tile's rays are in it): the cache gets what the threads leave.
  std::uint64_t largest = 1;
  for (std::size_t i = 0; i < reader.page_count(); ++i) {
    StatusOr<std::uint64_t> bytes = PageSvoPeakBytes(reader, i, level);
    if (!bytes.ok()) return bytes.status();
    largest = std::max(largest, *bytes);
  }
  StatusOr<std::size_t> in_flight = InFlightWithin(memory_limit, largest, largest, largest,
                                                   "this file", "a page cached and one assembled");
  if (!in_flight.ok()) return in_flight.status().WithContext(reader.name());
  const std::size_t threads = std::min(*in_flight, Concurrency());
  const std::uint64_t capacity =
      memory_limit == 0 ? kDefaultPagesPerThread * threads * largest
                        : std::max(largest, CacheShare(memory_limit - threads * largest));
  PageCache<Svo> cache(
      capacity,
      [&](std::size_t i) -> StatusOr<Svo> {
        StatusOr<SvoChunk> chunk = reader.Page(i);
        if (!chunk.ok()) return chunk.status();
        return PageSvo(reader, *chunk, level);
      },
      &SvoHeldBytes);
  const SvoPageSource pages{page_level, [&](std::size_t i) { return cache.Page(i); }};
  tbb::task_arena arena(static_cast<int>(threads));
  StatusOr<RenderResult> drawn = arena.execute([&] { return Draw(*top, &pages, options, level); });
  if (stats != nullptr) {
    stats->threads = threads;
    stats->cache_capacity = capacity;
    stats->largest_page = largest;
    stats->page_reads = cache.misses();
    stats->page_hits = cache.hits();
  }
  return drawn;
}

}  // namespace svokit
