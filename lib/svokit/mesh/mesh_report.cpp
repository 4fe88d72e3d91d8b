#include "svokit/mesh/mesh_report.hpp"

#include <algorithm>
#include <numeric>

#include <tbb/parallel_sort.h>
#include <nlohmann/json.hpp>

#include "svokit/core/parallel.hpp"
#include "svokit/core/utf8.hpp"

namespace svokit {

namespace {

// Maps every vertex to the smallest index of a vertex at exactly the same position.
std::vector<std::uint32_t> WeldExactPositions(const std::vector<Vec3d>& positions,
                                              std::uint64_t& distinct) {
  std::vector<std::uint32_t> order(positions.size());
  std::iota(order.begin(), order.end(), 0u);
  auto less = [&](std::uint32_t a, std::uint32_t b) {
    const Vec3d &p = positions[a], &q = positions[b];
    if (p.x != q.x) return p.x < q.x;
    if (p.y != q.y) return p.y < q.y;
    if (p.z != q.z) return p.z < q.z;
    return a < b;
  };
  tbb::parallel_sort(order.begin(), order.end(), less);
  std::vector<std::uint32_t> weld(positions.size());
  distinct = 0;
  for (std::size_t i = 0; i < order.size(); ++i) {
    if (i == 0 || !(positions[order[i]] == positions[order[i - 1]])) {
      ++distinct;
      weld[order[i]] = order[i];
    } else {
      weld[order[i]] = weld[order[i - 1]];
    }
  }
  return weld;
}

struct DirectedEdge {
  std::uint64_t key;  // (min << 32) | max of the welded endpoints
  bool forward;       // traversed from min to max
  bool operator<(const DirectedEdge& o) const {
    return key != o.key ? key < o.key : forward < o.forward;
  }
};

void AnalyzeTopology(const Mesh& mesh, const std::vector<std::uint32_t>& weld, MeshReport& r) {
  std::vector<DirectedEdge> edges;
  edges.reserve(3 * mesh.triangles.size());
  for (const Triangle& t : mesh.triangles) {
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t a = weld[t[i]], b = weld[t[(i + 1) % 3]];
      if (a == b) continue;  // collapsed edge of a degenerate triangle
      edges.push_back({std::uint64_t{std::min(a, b)} << 32 | std::max(a, b), a < b});
    }
  }
  tbb::parallel_sort(edges.begin(), edges.end());
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i, forward = 0;
    while (j < edges.size() && edges[j].key == edges[i].key) forward += edges[j++].forward;
    const std::size_t uses = j - i;
    ++r.edges;
    if (uses == 1) ++r.boundary_edges;
    if (uses > 2) ++r.non_manifold_edges;
    if (uses == 2 && forward != 1) ++r.inconsistent_edges;
    i = j;
  }

  // Union-find over welded vertices, joined through each triangle.
  std::vector<std::uint32_t> parent(mesh.positions.size());
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const Triangle& t : mesh.triangles) {
    const std::uint32_t a = find(weld[t[0]]);
    parent[find(weld[t[1]])] = a;
    parent[find(weld[t[2]])] = a;
  }
  std::vector<std::uint8_t> is_root(mesh.positions.size(), 0);
  for (const Triangle& t : mesh.triangles) is_root[find(weld[t[0]])] = 1;
  r.components = std::count(is_root.begin(), is_root.end(), 1);
}

std::string FormatColor(const Rgba& c) {
  return fmt::format("({:.4g}, {:.4g}, {:.4g}, {:.4g})", c.r, c.g, c.b, c.a);
}

}  // namespace

MeshReport AnalyzeMesh(const Mesh& mesh, const std::string& source, const ReportOptions& options,
                       Progress& progress) {
  MeshReport r;
  r.source = source;
  r.triangles = mesh.triangles.size();
  r.vertices = mesh.positions.size();
  r.bounds = mesh.Bounds();
  r.has_normals = mesh.has_normals();
  r.has_uvs = mesh.has_uvs();
  r.has_colors = mesh.has_colors();
  r.warnings = mesh.warnings;
  {
    Progress::Stage stage(progress, "analyze", r.triangles);
    r.surface_area = OrderedReduce(
        mesh.triangles.size(), 1 << 16, 0.0,
        [&](std::size_t begin, std::size_t end) {
          double area = 0;
          for (std::size_t t = begin; t < end; ++t) {
            const Triangle& tri = mesh.triangles[t];
            const Vec3d& a = mesh.positions[tri[0]];
            area += 0.5 * Length(Cross(mesh.positions[tri[1]] - a, mesh.positions[tri[2]] - a));
          }
          stage.Advance(end - begin);
          return area;
        },
        [](double& acc, double part) { acc += part; });
    const std::vector<std::uint8_t> degenerate = detail::FindDegenerateTriangles(mesh);
    r.degenerate_triangles = std::count(degenerate.begin(), degenerate.end(), 1);
    const std::vector<std::uint32_t> weld =
        WeldExactPositions(mesh.positions, r.distinct_positions);
    AnalyzeTopology(mesh, weld, r);
  }

  for (const Material& m : mesh.materials) {
    r.materials.push_back({m.name, m.base_color, m.texture, m.missing_texture, 0, m.alpha_mode,
                           m.alpha_cutoff, m.alpha_texture});
  }
  for (std::uint32_t id : mesh.material_ids) {
    if (id < r.materials.size()) ++r.materials[id].triangles;
  }
  for (const Texture& t : mesh.textures) {
    TextureReport tr{t.name(), t.encoded().size()};
    if (StatusOr<Texture::Info> info = t.ReadInfo(); info.ok()) {
      tr.width = info->width, tr.height = info->height, tr.channels = info->channels;
      tr.format = info->format;
    } else {
      tr.error = info.status().message();
      r.warnings.push_back(tr.error);
    }
    r.textures.push_back(std::move(tr));
  }
  if (options.self_intersections) {
    Progress::Stage stage(progress, "self-isect", 1);
    r.self_intersections = detail::CountSelfIntersections(mesh);
  }
  return r;
}

std::string FormatReportText(const MeshReport& r) {
  std::string s;
  auto line = [&](std::string_view key, const std::string& value) {
    s += fmt::format("{:<19}{}\n", key, value);
  };
  const Vec3d size = r.bounds.extent();
  line("mesh", EscapeInvalidUtf8(r.source));
  line("triangles", fmt::format("{}", r.triangles));
  line("vertices", fmt::format("{} ({} distinct positions)", r.vertices, r.distinct_positions));
  line("bounds",
       fmt::format("[{:.9g}, {:.9g}, {:.9g}] .. [{:.9g}, {:.9g}, {:.9g}]", r.bounds.lo.x,
                   r.bounds.lo.y, r.bounds.lo.z, r.bounds.hi.x, r.bounds.hi.y, r.bounds.hi.z));
  line("size", fmt::format("{:.9g} x {:.9g} x {:.9g}", size.x, size.y, size.z));
  line("surface area", fmt::format("{:.9g}", r.surface_area));
  std::string attrs;
  for (auto [on, name] : {std::pair{r.has_normals, "normals"}, std::pair{r.has_uvs, "uvs"},
                          std::pair{r.has_colors, "vertex colours"}}) {
    if (on) attrs += (attrs.empty() ? "" : ", ") + std::string(name);
  }
  line("attributes", attrs.empty() ? "none" : attrs);
  line("materials", fmt::format("{}", r.materials.size()));
  for (std::size_t i = 0; i < r.materials.size(); ++i) {
    const MaterialReport& m = r.materials[i];
    std::string tex = "no texture";
    if (m.texture >= 0) {
      const TextureReport& t = r.textures[m.texture];
      tex = t.error.empty()
                ? fmt::format("texture {} ({}x{}, {} ch)", t.name, t.width, t.height, t.channels)
                : fmt::format("texture {} (undecodable)", t.name);
    } else if (!m.missing_texture.empty()) {
      tex = fmt::format("texture {} MISSING, base colour used", m.missing_texture);
    }
    std::string alpha;
    if (m.alpha_mode == AlphaMode::kMask) alpha = fmt::format(", alpha mask {}", m.alpha_cutoff);
    if (m.alpha_mode == AlphaMode::kBlend) alpha = ", alpha blend";
    if (m.alpha_texture >= 0) alpha += fmt::format(" by {}", r.textures[m.alpha_texture].name);
    s += fmt::format("  [{}] {:<16} {} triangles, colour {}, {}{}\n", i, m.name, m.triangles,
                     FormatColor(m.base_color), tex, alpha);
  }
  line("degenerate tris", fmt::format("{}", r.degenerate_triangles));
  line("edges", fmt::format("{} ({} boundary, {} non-manifold, {} inconsistently oriented)",
                            r.edges, r.boundary_edges, r.non_manifold_edges, r.inconsistent_edges));
  line("surface", r.closed() ? "closed" : "open");
  line("components", fmt::format("{}", r.components));
  line("self-intersections", r.self_intersections
                                 ? fmt::format("{} triangle pairs", *r.self_intersections)
                                 : std::string("not checked (--self-intersections)"));
  if (r.warnings.empty()) {
    line("warnings", "none");
  } else {
    for (const std::string& w : r.warnings) line("warning", w);
  }
  return s;
}

std::string FormatReportJson(const MeshReport& r) {
  using nlohmann::json;
  json j;
  // Paths and names from files are bytes; JSON needs UTF-8.
  const auto text = [](const std::string& s) { return EscapeInvalidUtf8(s); };
  j["source"] = text(r.source);
  j["triangles"] = r.triangles;
  j["vertices"] = r.vertices;
  j["distinct_positions"] = r.distinct_positions;
  j["bounds"] = {{"min", {r.bounds.lo.x, r.bounds.lo.y, r.bounds.lo.z}},
                 {"max", {r.bounds.hi.x, r.bounds.hi.y, r.bounds.hi.z}}};
  j["surface_area"] = r.surface_area;
  j["attributes"] = {{"normals", r.has_normals}, {"uvs", r.has_uvs}, {"colors", r.has_colors}};
  j["materials"] = json::array();
  for (const MaterialReport& m : r.materials) {
    json jm = {{"name", text(m.name)},
               {"triangles", m.triangles},
               {"base_color", {m.base_color.r, m.base_color.g, m.base_color.b, m.base_color.a}},
               {"texture", m.texture >= 0 ? json(m.texture) : json(nullptr)}};
    jm["missing_texture"] =
        m.missing_texture.empty() ? json(nullptr) : json(text(m.missing_texture));
    static constexpr const char* kModes[] = {"opaque", "mask", "blend"};
    jm["alpha"] = {{"mode", kModes[static_cast<std::uint32_t>(m.alpha_mode)]},
                   {"cutoff", m.alpha_cutoff},
                   {"texture", m.alpha_texture >= 0 ? json(m.alpha_texture) : json(nullptr)}};
    j["materials"].push_back(jm);
  }
  j["textures"] = json::array();
  for (const TextureReport& t : r.textures) {
    j["textures"].push_back({{"name", text(t.name)},
                             {"bytes", t.bytes},
                             {"width", t.width},
                             {"height", t.height},
                             {"channels", t.channels},
                             {"format", t.format},
                             {"error", t.error.empty() ? json(nullptr) : json(text(t.error))}});
  }
  j["topology"] = {{"degenerate_triangles", r.degenerate_triangles},
                   {"edges", r.edges},
                   {"boundary_edges", r.boundary_edges},
                   {"non_manifold_edges", r.non_manifold_edges},
                   {"inconsistent_edges", r.inconsistent_edges},
                   {"closed", r.closed()},
                   {"components", r.components}};
  j["self_intersections"] = r.self_intersections ? json(*r.self_intersections) : json(nullptr);
  j["warnings"] = json::array();
  for (const std::string& w : r.warnings) j["warnings"].push_back(text(w));
  return j.dump(2) + "\n";
}

}  // namespace svokit
