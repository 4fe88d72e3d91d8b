#include "svokit/inspect/render_options.hpp"

#include <charconv>

namespace svokit {

namespace {

// In the enums' order: a name's index is its value.
constexpr std::array<std::string_view, 7> kViewNames = {"front", "back",   "left", "right",
                                                        "top",   "bottom", "iso"};
constexpr std::array<std::string_view, 4> kShadeNames = {"color", "normal", "depth", "ao"};

}  // namespace

StatusOr<View> ParseView(std::string_view name) {
  for (std::size_t i = 0; i < kViewNames.size(); ++i) {
    if (kViewNames[i] == name) return static_cast<View>(i);
  }
  return Status::BadInput("view '{}' is not front, back, left, right, top, bottom or iso", name);
}

StatusOr<Shade> ParseShade(std::string_view name) {
  for (std::size_t i = 0; i < kShadeNames.size(); ++i) {
    if (kShadeNames[i] == name) return static_cast<Shade>(i);
  }
  return Status::BadInput("shade '{}' is not color, normal, depth or ao", name);
}

StatusOr<std::optional<Background>> ParseBackground(std::string_view text) {
  if (text == "none") return std::optional<Background>();
  Background rgb{};
  bool ok = text.size() == 6;
  for (std::size_t i = 0; ok && i < 3; ++i) {
    const char* begin = text.data() + 2 * i;
    const auto [ptr, ec] = std::from_chars(begin, begin + 2, rgb[i], 16);
    ok = ec == std::errc() && ptr == begin + 2;
  }
  if (!ok) {
    return Status::BadInput("background '{}': expected none or RRGGBB in hexadecimal, e.g. 334d66",
                            text);
  }
  return std::optional<Background>(rgb);
}

StatusOr<std::array<int, 2>> ParseImageSize(std::string_view text) {
  const auto bad = [&] {
    return Status::BadInput("size '{}': expected WxH with each side 1 to {}", text, kMaxImageSide);
  };
  const std::size_t x = text.find('x');
  if (x == std::string_view::npos) return bad();
  std::array<int, 2> size{};
  const std::array<std::string_view, 2> parts = {text.substr(0, x), text.substr(x + 1)};
  for (int i = 0; i < 2; ++i) {
    const char* end = parts[i].data() + parts[i].size();
    const auto [ptr, ec] = std::from_chars(parts[i].data(), end, size[i]);
    if (ec != std::errc() || ptr != end || size[i] < 1 || size[i] > kMaxImageSide) return bad();
  }
  return size;
}

std::string_view ViewName(View view) {
  return kViewNames[static_cast<std::size_t>(view)];
}
std::string_view ShadeName(Shade shade) {
  return kShadeNames[static_cast<std::size_t>(shade)];
}

}  // namespace svokit
