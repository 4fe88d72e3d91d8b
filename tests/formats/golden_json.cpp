#include "tests/formats/golden_json.hpp"

#include <algorithm>

namespace svokit::test {

namespace {

void Format(const Json& json, int indent, std::string& out) {
  const std::string pad(static_cast<std::size_t>(indent + 2), ' ');
  if (json.is_object() && !json.empty()) {
    out += "{\n";
    std::size_t i = 0;
    for (const auto& [key, value] : json.items()) {
      out += pad + Json(key).dump() + ": ";
      Format(value, indent + 2, out);
      out += ++i < json.size() ? ",\n" : "\n";
    }
    out += std::string(static_cast<std::size_t>(indent), ' ') + "}";
    return;
  }
  const bool flat = std::none_of(json.begin(), json.end(),
                                 [](const Json& v) { return v.is_structured() && !v.empty(); });
  if (json.is_array() && !flat) {
    out += "[\n";
    for (std::size_t i = 0; i < json.size(); ++i) {
      out += pad;
      Format(json[i], indent + 2, out);
      out += i + 1 < json.size() ? ",\n" : "\n";
    }
    out += std::string(static_cast<std::size_t>(indent), ' ') + "]";
    return;
  }
  if (json.is_array()) {
    out += "[";
    for (std::size_t i = 0; i < json.size(); ++i) {
      if (i > 0) out += ", ";
      out += json[i].dump();
    }
    out += "]";
    return;
  }
  out += json.dump();
}

// A JSON pointer token: '~' and '/' escaped.
std::string Token(const std::string& key) {
  std::string out;
  for (const char c : key) {
    if (c == '~') {
      out += "~0";
    } else if (c == '/') {
      out += "~1";
    } else {
      out += c;
    }
  }
  return out;
}

std::string Short(const Json& json) {
  std::string text = json.dump();
  return text.size() > 80 ? text.substr(0, 77) + "..." : text;
}

std::optional<std::string> Difference(const Json& expected, const Json& actual,
                                      const std::string& path) {
  const auto differ = [&] {
    return path + ": expected " + Short(expected) + ", got " + Short(actual);
  };
  if (expected.is_number() && actual.is_number()) {
    if (expected == actual) return std::nullopt;
    return differ();
  }
  if (expected.type() != actual.type()) return differ();
  if (expected.is_object()) {
    for (const auto& [key, value] : expected.items()) {
      if (!actual.contains(key)) return path + "/" + Token(key) + ": missing";
      if (auto d = Difference(value, actual.at(key), path + "/" + Token(key))) return d;
    }
    for (const auto& [key, value] : actual.items()) {
      if (!expected.contains(key)) return path + "/" + Token(key) + ": not expected";
    }
    return std::nullopt;
  }
  if (expected.is_array()) {
    const std::size_t common = std::min(expected.size(), actual.size());
    for (std::size_t i = 0; i < common; ++i) {
      if (auto d = Difference(expected[i], actual[i], path + "/" + std::to_string(i))) return d;
    }
    if (expected.size() != actual.size()) {
      return path + ": expected " + std::to_string(expected.size()) + " elements, got " +
             std::to_string(actual.size());
    }
    return std::nullopt;
  }
  if (expected == actual) return std::nullopt;
  return differ();
}

}  // namespace

std::string FormatJson(const Json& json) {
  std::string out;
  Format(json, 0, out);
  return out + "\n";
}

std::optional<std::string> FirstDifference(const Json& expected, const Json& actual) {
  return Difference(expected, actual, "");
}

}  // namespace svokit::test
