#include "svokit/formats/provenance.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <map>
#include <sstream>
#include <string_view>
#include <type_traits>

#include <nlohmann/json.hpp>

#include "svokit/core/utf8.hpp"

namespace svokit {

namespace {

using Json = nlohmann::json;

Json GridJson(const GridFit& g) {
  Json j = {{"pad", g.pad}};
  if (g.resolution > 0) {
    j["resolution"] = g.resolution;
  } else {
    j["voxel_size"] = g.voxel_size;
  }
  if (g.bounds) {
    const Box3d& b = *g.bounds;
    j["bounds"] = {b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z};
  }
  return j;
}

Json VoxelJson(const VoxelSettings& v) {
  return {{"mode", v.mode == VoxelMode::kThin ? "thin" : "conservative"},
          {"color", v.colors},
          {"normal", v.normals},
          {"fill", v.solid ? "solid" : "surface"}};
}

Json BuildJson(const BuildSettings& b) {
  Json j = {{"bricks", b.brick_side},
            {"contours", b.contours},
            {"compression", b.compression.zstd ? "zstd" : "none"}};
  if (b.compression.zstd) j["zstd_level"] = b.compression.level;
  if (b.prune) {
    j["prune"] = {
        {"color", b.prune->color}, {"normal", b.prune->normal}, {"geometry", b.prune->geometry}};
  }
  return j;
}

Json BakeJson(const BakeSettings& b) {
  Json j = {{"term", "ao"},           {"cones", b.cones},     {"aperture", b.aperture},
            {"distance", b.distance}, {"falloff", b.falloff}, {"offset", b.offset}};
  if (b.jitter_seed) j["jitter_seed"] = *b.jitter_seed;
  return j;
}

// Three rows of three finite numbers forming a rotation (orthonormal, determinant +1, to
// rounding); anything else reads as absent.
std::optional<Orientation> ParseOrientation(const Json& j) {
  if (!j.is_array() || j.size() != 3) return std::nullopt;
  Orientation o;
  for (std::size_t r = 0; r < 3; ++r) {
    if (!j[r].is_array() || j[r].size() != 3) return std::nullopt;
    for (std::size_t c = 0; c < 3; ++c) {
      if (!j[r][c].is_number()) return std::nullopt;
      o.rows[r][static_cast<int>(c)] = j[r][c].get<double>();
      if (!std::isfinite(o.rows[r][static_cast<int>(c)])) return std::nullopt;
    }
  }
  const Orientation product = o.Then(o.Inverse());
  for (int r = 0; r < 3; ++r) {
    if (Length(product.rows[r] - Orientation{}.rows[r]) > 1e-9) return std::nullopt;
  }
  if (!(o.Determinant() > 0)) return std::nullopt;
  return o;
}

// Typed members, read leniently: a member of another type is as good as absent.
template <class T>
std::optional<T> Member(const Json& j, const char* key) {
  const auto it = j.find(key);
  if (it == j.end()) return std::nullopt;
  if constexpr (std::is_same_v<T, bool>) {
    if (!it->is_boolean()) return std::nullopt;
  } else if constexpr (std::is_same_v<T, std::string>) {
    if (!it->is_string()) return std::nullopt;
  } else if constexpr (std::is_floating_point_v<T>) {
    if (!it->is_number()) return std::nullopt;
  } else {
    if (!it->is_number_unsigned()) return std::nullopt;
  }
  return it->get<T>();
}

std::optional<VoxelSettings> ParseVoxelMember(const Json& j) {
  if (!j.is_object()) return std::nullopt;
  VoxelSettings v;
  v.mode = Member<std::string>(j, "mode") == "thin" ? VoxelMode::kThin : VoxelMode::kConservative;
  v.colors = Member<bool>(j, "color").value_or(false);
  v.normals = Member<bool>(j, "normal").value_or(false);
  v.solid = Member<std::string>(j, "fill") == "solid";
  return v;
}

std::optional<BuildSettings> ParseBuild(const Json& j) {
  if (!j.is_object()) return std::nullopt;
  BuildSettings b;
  b.brick_side = Member<std::uint32_t>(j, "bricks").value_or(0);
  b.contours = Member<bool>(j, "contours").value_or(false);
  b.compression.zstd = Member<std::string>(j, "compression") == "zstd";
  b.compression.level = static_cast<int>(Member<std::uint32_t>(j, "zstd_level").value_or(3));
  if (const auto it = j.find("prune"); it != j.end() && it->is_object()) {
    const std::optional<double> color = Member<double>(*it, "color"),
                                normal = Member<double>(*it, "normal"),
                                geometry = Member<double>(*it, "geometry");
    if (color && normal && geometry) b.prune = PruneTolerances{*color, *normal, *geometry};
  }
  return b;
}

// Files written before the typed members recorded each stage as the option text its tool was
// given (formats/svo.md, "Metadata"): words led by two dashes, each with the value after it,
// if any. That text is frozen; it is read here as data, by its words.
std::map<std::string, std::string> OptionWords(const std::string& text) {
  std::map<std::string, std::string> words;
  std::istringstream in(text);
  std::string token, name;
  while (in >> token) {
    if (token.size() > 2 && token[0] == '-' && token[1] == '-') {
      name = token.substr(2);
      words[name] = "";
    } else if (!name.empty()) {
      words[name] = token;
      name.clear();
    }
  }
  return words;
}

template <class T>
std::optional<T> ParseNumber(std::string_view text) {
  T value{};
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end) return std::nullopt;
  return value;
}

template <class T>
std::optional<T> Number(const std::map<std::string, std::string>& words, const char* word) {
  const auto it = words.find(word);
  return it == words.end() ? std::nullopt : ParseNumber<T>(it->second);
}

// A stage's settings by name, from its typed JSON object or its option words: the grid fit and the
// bake read alike from both (`legacy` names the word where it differs).
struct JsonFields {
  const Json& j;
  template <class T>
  std::optional<T> Get(const char* key, const char* = nullptr) const {
    return Member<T>(j, key);
  }
};
struct WordFields {
  std::map<std::string, std::string> words;
  template <class T>
  std::optional<T> Get(const char* key, const char* legacy = nullptr) const {
    return Number<T>(words, legacy != nullptr ? legacy : key);
  }
};

template <class Fields>
std::optional<GridFit> GridFrom(const Fields& f) {
  GridFit g;
  g.pad = f.template Get<std::uint32_t>("pad").value_or(0);
  if (const auto r = f.template Get<std::uint32_t>("resolution")) {
    g.resolution = *r;
  } else if (const auto s = f.template Get<double>("voxel_size", "voxel-size")) {
    g.voxel_size = *s;
  } else {
    return std::nullopt;
  }
  return g;
}

template <class Fields>
BakeSettings BakeFrom(const Fields& f) {
  BakeSettings b;
  b.cones = f.template Get<std::uint32_t>("cones").value_or(b.cones);
  b.aperture = f.template Get<double>("aperture").value_or(b.aperture);
  b.distance = f.template Get<double>("distance").value_or(b.distance);
  b.falloff = f.template Get<double>("falloff").value_or(b.falloff);
  b.offset = f.template Get<double>("offset").value_or(b.offset);
  b.jitter_seed = f.template Get<std::uint64_t>("jitter_seed", "jitter");
  return b;
}

void ParseVoxelText(const std::string& text, Provenance& p) {
  const auto words = OptionWords(text);
  if (const auto grid = GridFrom(WordFields{words})) p.grid = grid;
  VoxelSettings v;
  const auto mode = words.find("mode");
  v.mode =
      mode != words.end() && mode->second == "thin" ? VoxelMode::kThin : VoxelMode::kConservative;
  const auto attributes = words.find("attributes");
  const std::string a = attributes == words.end() ? "" : attributes->second;
  v.colors = a.find("color") != std::string::npos;
  v.normals = a.find("normal") != std::string::npos;
  const auto fill = words.find("fill");
  v.solid = fill != words.end() && fill->second == "solid";
  p.voxelize = v;
}

void ParseBuildText(const std::string& text, Provenance& p) {
  const auto words = OptionWords(text);
  BuildSettings b;
  b.brick_side = Number<std::uint32_t>(words, "bricks").value_or(0);
  b.contours = words.count("contours") > 0;
  const auto compression = words.find("compression");
  const std::string c = compression == words.end() ? "" : compression->second;
  b.compression.zstd = c.starts_with("zstd");
  // Option text is older than zstd level 1 by default: plain "zstd" then meant level 3.
  b.compression.level = 3;
  if (c.starts_with("zstd:")) b.compression.level = ParseNumber<int>(c.substr(5)).value_or(3);
  p.build = b;
}

}  // namespace

std::string ProvenanceJson(const Provenance& p) {
  // nlohmann::json orders the keys alphabetically: the bytes follow from the values alone.
  Json j = {{"source", EscapeInvalidUtf8(p.source)}, {"generator", "svokit " SVOKIT_VERSION}};
  if (p.triangles > 0) j["triangles"] = p.triangles;
  if (p.grid) j["grid"] = GridJson(*p.grid);
  if (p.voxelize) j["voxelize"] = VoxelJson(*p.voxelize);
  if (p.build) j["build"] = BuildJson(*p.build);
  if (p.bake) j["bake"] = BakeJson(*p.bake);
  if (!p.orientation.IsIdentity()) j["orientation"] = Matrix(p.orientation);
  return j.dump();
}

Provenance ParseProvenance(std::string_view text) {
  Provenance p;
  const Json j = Json::parse(text.begin(), text.end(), nullptr, false);
  if (!j.is_object()) return p;
  p.source = Member<std::string>(j, "source").value_or("");
  p.generator = Member<std::string>(j, "generator").value_or("");
  p.triangles = Member<std::uint64_t>(j, "triangles").value_or(0);
  if (const auto it = j.find("orientation"); it != j.end()) {
    p.orientation = ParseOrientation(*it).value_or(Orientation{});
  }
  if (const auto grid = j.find("grid"); grid != j.end() && grid->is_object()) {
    p.grid = GridFrom(JsonFields{*grid});
    // Six finite numbers, min before max; anything else reads as absent.
    const auto b = grid->find("bounds");
    if (p.grid && b != grid->end() && b->is_array() && b->size() == 6) {
      std::array<double, 6> v{};
      bool ok = true;
      for (std::size_t k = 0; k < 6; ++k) {
        ok = ok && (*b)[k].is_number() && std::isfinite(v[k] = (*b)[k].get<double>());
      }
      if (ok && v[0] < v[3] && v[1] < v[4] && v[2] < v[5]) {
        p.grid->bounds = Box3d{{v[0], v[1], v[2]}, {v[3], v[4], v[5]}};
      }
    }
  }
  // Each stage: a typed object, or (files written before) its option text.
  for (const char* key : {"voxelize", "options"}) {
    const auto it = j.find(key);
    if (it == j.end()) continue;
    if (it->is_object()) p.voxelize = ParseVoxelMember(*it);
    if (it->is_string()) ParseVoxelText(it->get<std::string>(), p);
  }
  if (const auto it = j.find("build"); it != j.end()) {
    if (it->is_object()) p.build = ParseBuild(*it);
    if (it->is_string()) ParseBuildText(it->get<std::string>(), p);
  }
  if (const auto it = j.find("bake"); it != j.end()) {
    if (it->is_object()) p.bake = BakeFrom(JsonFields{*it});
    if (it->is_string()) p.bake = BakeFrom(WordFields{OptionWords(it->get<std::string>())});
  }
  return p;
}

}  // namespace svokit
