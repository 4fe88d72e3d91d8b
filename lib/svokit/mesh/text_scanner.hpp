#pragma once
// A line-oriented tokenizer for text mesh formats (OBJ, MTL, OFF, ASCII PLY/STL). Numbers are
// parsed with std::from_chars (locale-independent, exact round-trip); every error carries the file
// name and line number.

#include <charconv>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <system_error>

#include "svokit/core/status.hpp"

namespace svokit::detail {

class TextScanner {
 public:
  TextScanner(std::string_view text, std::string file) : text_(text), file_(std::move(file)) {}
  std::string_view text() const { return text_; }

  /// Advances to the next line (without its terminator, '\r' stripped); false at end of text.
  bool NextLine() {
    if (pos_ >= text_.size()) return false;
    const std::size_t end = text_.find('\n', pos_);
    const std::size_t stop = end == std::string_view::npos ? text_.size() : end;
    line_ = text_.substr(pos_, stop - pos_);
    if (!line_.empty() && line_.back() == '\r') line_.remove_suffix(1);
    pos_ = stop + 1;
    ++line_number_;
    return true;
  }
  /// Advances to the next line that is not blank and does not start with `comment`.
  bool NextContentLine(char comment = '#') {
    while (NextLine()) {
      SkipSpace();
      if (!line_.empty() && line_.front() != comment) return true;
    }
    return false;
  }

  std::string_view line() const { return line_; }
  std::size_t line_number() const { return line_number_; }
  bool AtLineEnd() {
    SkipSpace();
    return line_.empty();
  }

  /// The next whitespace-separated token of the current line (empty at the line's end).
  std::string_view Token() {
    const std::string_view tok = PeekToken();
    line_.remove_prefix(tok.size());
    return tok;
  }
  /// The next token without consuming it.
  std::string_view PeekToken() {
    SkipSpace();
    std::size_t n = 0;
    while (n < line_.size() && !IsSpace(line_[n])) ++n;
    return line_.substr(0, n);
  }
  /// The rest of the current line, trimmed.
  std::string_view Rest() {
    SkipSpace();
    std::string_view r = line_;
    while (!r.empty() && IsSpace(r.back())) r.remove_suffix(1);
    line_ = {};
    return r;
  }

  /// Parses the next token as a number of type T; "what" names it in the error message.
  template <class T>
  Status Number(T& value, std::string_view what) {
    const std::string_view tok = Token();
    if (tok.empty()) return Error("expected {}, found end of line", what);
    if (!ParseNumber(tok, value)) return Error("expected {}, found '{}'", what, Clip(tok));
    return Status::Ok();
  }

  /// "FILE:LINE: message" as a bad-input Status.
  template <class... Args>
  Status Error(fmt::format_string<Args...> f, Args&&... args) const {
    return Status::BadInput("{}:{}: {}", file_, line_number_,
                            fmt::format(f, std::forward<Args>(args)...));
  }

  template <class T>
  static bool ParseNumber(std::string_view tok, T& value) {
    const char* first = tok.data();
    const char* last = tok.data() + tok.size();
    if constexpr (std::is_floating_point_v<T>) {
      if (first != last && *first == '+') ++first;  // from_chars rejects a leading '+'
    }
    auto [ptr, ec] = std::from_chars(first, last, value);
    return ec == std::errc() && ptr == last;
  }
  static std::string Clip(std::string_view s) {
    return std::string(s.substr(0, 40)) + (s.size() > 40 ? "..." : "");
  }

 private:
  static bool IsSpace(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
  }
  void SkipSpace() {
    while (!line_.empty() && IsSpace(line_.front())) line_.remove_prefix(1);
  }

  std::string_view text_;
  std::string file_;
  std::size_t pos_ = 0;
  std::string_view line_;
  std::size_t line_number_ = 0;
};

/// Views a byte buffer as text.
inline std::string_view AsText(std::span<const std::uint8_t> bytes) {
  return {reinterpret_cast<const char*>(bytes.data()), bytes.size()};
}

/// Views a text file's bytes as UTF-8/ASCII text, skipping a UTF-8 byte order mark; UTF-16 files
/// (which some Windows exporters write) are rejected with a clear message rather than misparsed.
inline StatusOr<std::string_view> TextOf(std::span<const std::uint8_t> bytes,
                                         const std::string& file) {
  std::string_view text = AsText(bytes);
  if (text.starts_with("\xEF\xBB\xBF")) text.remove_prefix(3);
  if (text.starts_with("\xFE\xFF") || text.starts_with("\xFF\xFE")) {
    return Status::BadInput("{}: UTF-16 text is not supported (save the file as UTF-8)", file);
  }
  return text;
}

}  // namespace svokit::detail
