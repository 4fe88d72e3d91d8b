#pragma once
// The JSON reports' one spelling of what the text reports may say in British English.

#include <string>

namespace svokit {

/// A section's name (SvoSectionBytes::name) as the JSON reports spell their keys: "color" (the
/// text says colour), words joined by underscores ("voxel colours" → "voxel_colors").
inline std::string SectionKey(std::string name) {
  for (std::size_t at; (at = name.find("colour")) != std::string::npos;) name.erase(at + 4, 1);
  for (char& c : name) c = c == ' ' ? '_' : c;
  return name;
}

}  // namespace svokit
