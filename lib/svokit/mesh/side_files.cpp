#include "svokit/mesh/side_files.hpp"

#include <algorithm>
#include <cctype>

namespace svokit {

namespace {

namespace fs = std::filesystem;

int HexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// An absolute, canonical form of `path` (symlinks and ".." of its existing part resolved, the
// rest normalized); the path made absolute and normalized where even that fails.
fs::path Canonical(const fs::path& path) {
  std::error_code ec;
  fs::path absolute = fs::absolute(path, ec);
  if (ec) absolute = path;
  fs::path canonical = fs::weakly_canonical(absolute, ec);
  return ec ? absolute.lexically_normal() : canonical;
}

// Whether `path` is `root` or lies below it (both canonical), compared element by element.
bool IsWithin(const fs::path& path, const fs::path& root) {
  auto p = path.begin();
  for (auto r = root.begin(); r != root.end(); ++r, ++p) {
    if (r->empty()) continue;  // a trailing separator
    if (p == path.end() || *p != *r) return false;
  }
  return true;
}

// The scheme of a URI ("file" of "file:///x"), lower case; empty for a relative reference.
std::string SchemeOf(std::string_view uri) {
  const std::size_t colon = uri.find(':');
  if (colon == std::string_view::npos || colon == 0) return {};
  if (!std::isalpha(static_cast<unsigned char>(uri[0]))) return {};
  std::string scheme;
  for (const char c : uri.substr(0, colon)) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '+' && c != '-' && c != '.') return {};
    scheme.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
  }
  return scheme;
}

// The file path a reference names, as the format defines it; kBadInput for a reference that
// names no local file.
StatusOr<std::string> DecodeReference(std::string_view reference, SideFileSyntax syntax) {
  std::string path;
  if (syntax == SideFileSyntax::kPath) {
    // Windows exporters write "textures\\wood.jpg"; on POSIX that is one odd file name.
    path = std::string(reference);
    std::replace(path.begin(), path.end(), '\\', '/');
  } else {
    std::string_view rest = reference;
    const std::string scheme = SchemeOf(reference);
    if (scheme == "data") return Status::BadInput("is embedded data, not a file");
    if (!scheme.empty() && scheme != "file") {
      return Status::BadInput("is a {}: URI; only files are read", scheme);
    }
    if (scheme == "file") {
      // RFC 8089: file:///path, file://localhost/path and file:/path name local files.
      rest.remove_prefix(5);
      if (rest.starts_with("//")) {
        rest.remove_prefix(2);
        const std::size_t slash = std::min(rest.find('/'), rest.size());
        const std::string_view host = rest.substr(0, slash);
        if (!host.empty() && host != "localhost") {
          return Status::BadInput("names the host '{}'; only local files are read", host);
        }
        rest.remove_prefix(slash);
      }
    }
    path = PercentDecode(rest);
  }
  if (path.empty()) return Status::BadInput("is empty");
  if (path.find('\0') != std::string::npos) return Status::BadInput("contains a NUL character");
  return path;
}

}  // namespace

std::string PercentDecode(std::string_view uri) {
  std::string out;
  out.reserve(uri.size());
  for (std::size_t i = 0; i < uri.size(); ++i) {
    const int high = uri[i] == '%' && i + 2 < uri.size() ? HexValue(uri[i + 1]) : -1;
    const int low = high >= 0 ? HexValue(uri[i + 2]) : -1;
    if (low >= 0) {
      out += static_cast<char>(high * 16 + low);
      i += 2;
    } else {
      out += uri[i];
    }
  }
  return out;
}

Status CheckNotAnInput(const fs::path& output, const std::vector<fs::path>& inputs) {
  for (const fs::path& input : inputs) {
    std::error_code ec;
    if (!input.empty() && fs::equivalent(output, input, ec)) {
      return Status::BadInput("{}: is the input file {}; write the output elsewhere",
                              output.string(), input.string());
    }
  }
  return Status::Ok();
}

SideFileRule::SideFileRule(const fs::path& model, const ImportOptions& options)
    : model_folder_(model.parent_path().empty() ? fs::path(".") : model.parent_path()) {
  roots_.push_back(Canonical(model_folder_));
  for (const fs::path& dir : options.asset_paths) roots_.push_back(Canonical(dir));
}

StatusOr<fs::path> SideFileRule::Resolve(std::string_view reference, SideFileSyntax syntax,
                                         const fs::path& folder) const {
  StatusOr<std::string> decoded = DecodeReference(reference, syntax);
  if (!decoded.ok()) return decoded.status();
  const fs::path named = *decoded;
  const fs::path file = Canonical(named.is_absolute() ? named : folder / named);
  for (const fs::path& root : roots_) {
    if (IsWithin(file, root)) return file;
  }
  return Status::BadInput(
      "resolves to {}, outside the model's folder{} (--asset-path DIR allows a folder)",
      file.string(), roots_.size() > 1 ? " and every --asset-path" : "");
}

}  // namespace svokit
