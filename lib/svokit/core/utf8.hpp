#pragma once
// Byte strings from outside (file paths, names inside mesh files) shown as text: JSON and terminals
// need UTF-8, while a POSIX path is any bytes but '\0'.

#include <cstddef>
#include <string>
#include <string_view>

namespace svokit {

/// `bytes` unchanged if it is valid UTF-8; otherwise each byte that does not belong to a valid
/// sequence becomes the four characters "\xNN" (upper-case hex), so the text still names the file
/// and can be fed to JSON.
inline std::string EscapeInvalidUtf8(std::string_view bytes) {
  const auto at = [&](std::size_t i) { return static_cast<unsigned char>(bytes[i]); };
  // Length of the valid sequence starting at `i`, 0 if none (RFC 3629: no overlong forms, no
  // surrogates, nothing above U+10FFFF).
  const auto sequence = [&](std::size_t i) -> std::size_t {
    const unsigned char b = at(i);
    if (b < 0x80) return 1;
    std::size_t n = 0;
    unsigned char lo = 0x80, hi = 0xBF;
    if (b >= 0xC2 && b <= 0xDF) {
      n = 2;
    } else if (b >= 0xE0 && b <= 0xEF) {
      n = 3;
      if (b == 0xE0) lo = 0xA0;
      if (b == 0xED) hi = 0x9F;
    } else if (b >= 0xF0 && b <= 0xF4) {
      n = 4;
      if (b == 0xF0) lo = 0x90;
      if (b == 0xF4) hi = 0x8F;
    } else {
      return 0;
    }
    if (i + n > bytes.size() || at(i + 1) < lo || at(i + 1) > hi) return 0;
    for (std::size_t k = 2; k < n; ++k) {
      if (at(i + k) < 0x80 || at(i + k) > 0xBF) return 0;
    }
    return n;
  };
  std::size_t i = 0;
  while (i < bytes.size() && sequence(i) > 0) i += sequence(i);
  if (i == bytes.size()) return std::string(bytes);
  static constexpr char kHex[] = "0123456789ABCDEF";
  std::string out(bytes.substr(0, i));
  while (i < bytes.size()) {
    if (const std::size_t n = sequence(i); n > 0) {
      out.append(bytes.substr(i, n));
      i += n;
    } else {
      out += "\\x";
      out += kHex[at(i) >> 4];
      out += kHex[at(i) & 15];
      ++i;
    }
  }
  return out;
}

}  // namespace svokit
