#pragma once
// Shared test helpers: scratch directories, file writers, and the locations of test data.

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

namespace svokit::test {

inline std::filesystem::path DataDir() {
  return SVOKIT_DATA_DIR;
}
inline std::filesystem::path CgalMeshes() {
  return SVOKIT_CGAL_MESHES;
}
inline std::filesystem::path AssimpModels() {
  return SVOKIT_ASSIMP_MODELS;
}

/// Whether this build runs under AddressSanitizer, which reserves terabytes of address space:
/// address-space limits cannot be tested there.
constexpr bool kAddressSanitizer =
#if defined(__SANITIZE_ADDRESS__)
    true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
    true;
#else
    false;
#endif
#else
    false;
#endif

/// A fresh directory under the system temp dir, removed with its contents on destruction.
class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    std::random_device rd;
    path_ = std::filesystem::temp_directory_path() /
            ("svokit-test-" + std::to_string(rd()) + "-" + std::to_string(counter++));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

  /// Writes `content` to `name` inside the directory and returns the full path.
  std::filesystem::path Write(const std::string& name, const std::string& content) const {
    const auto p = path_ / name;
    std::ofstream(p, std::ios::binary) << content;
    return p;
  }
  std::filesystem::path Write(const std::string& name,
                              const std::vector<std::uint8_t>& content) const {
    const auto p = path_ / name;
    std::ofstream(p, std::ios::binary)
        .write(reinterpret_cast<const char*>(content.data()),
               static_cast<std::streamsize>(content.size()));
    return p;
  }
  /// Names of the files in the directory (to check that no partial output was left behind).
  std::vector<std::string> Files() const {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(path_)) {
      names.push_back(e.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    return names;
  }

 private:
  std::filesystem::path path_;
};

inline std::string ReadText(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline std::vector<std::uint8_t> ReadBytes(const std::filesystem::path& p) {
  const std::string text = ReadText(p);
  return {text.begin(), text.end()};
}

/// True when missing test data must fail rather than skip (scripts/test sets it, so CI never
/// passes by skipping).
inline bool TestDataRequired() {
  const char* v = std::getenv("SVOKIT_REQUIRE_TEST_DATA");
  return v && std::string(v) == "1";
}

/// Skips the test (or fails it, see TestDataRequired) when a Debian test-data file is absent.
#define SVOKIT_REQUIRE_FILE(path)                                                          \
  do {                                                                                     \
    if (!std::filesystem::exists(path)) {                                                  \
      if (::svokit::test::TestDataRequired()) FAIL() << "missing test data " << (path);    \
      GTEST_SKIP() << "missing test data " << (path) << " (run scripts/deps --test-data)"; \
    }                                                                                      \
  } while (false)

}  // namespace svokit::test
