#pragma once
// The sectioned container every svokit file format shares (.svm, and the later .vfrag and .svo):
// a fixed header, a table of tagged sections with offsets, sizes and CRC-32C checksums, and the
// 64-byte-aligned section payloads. Layout: formats/container.md. Writer streams such a file,
// Frame and Reader verify one; mapped_writer.hpp writes one in place.

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "svokit/core/file_io.hpp"
#include "svokit/core/status.hpp"

namespace svokit::container {

using Tag = std::array<char, 4>;
/// "ABCD" → Tag; the literal must have exactly four characters.
constexpr Tag MakeTag(const char (&s)[5]) {
  return {s[0], s[1], s[2], s[3]};
}

inline constexpr std::size_t kHeaderSize = 32;
inline constexpr std::size_t kSectionEntrySize = 32;
inline constexpr std::size_t kAlignment = 64;

/// What identifies one format: its 8-byte magic and the newest version this build reads.
struct FormatId {
  std::array<char, 8> magic;
  std::uint32_t version;
  std::string_view name;  ///< for messages, e.g. "svokit mesh (.svm)"
};

class Writer {
 public:
  Writer(const FormatId& format, std::uint32_t flags) : format_(format), flags_(flags) {}
  void AddSection(Tag tag, std::vector<std::uint8_t> bytes);
  /// A section whose bytes stay owned by the caller (no copy of large arrays); they must outlive
  /// the Writer.
  void AddSectionView(Tag tag, std::span<const std::uint8_t> bytes);
  /// Receives a produced section's bytes, piece by piece.
  using Emit = std::function<Status(std::span<const std::uint8_t>)>;
  /// Calls `emit` once per piece of the payload, in order; may fail.
  using Producer = std::function<Status(const Emit& emit)>;
  /// A section encoded while the file is written (e.g. compressed keys): its whole payload is
  /// never held in memory. Producers run once per Serialize() or WriteFile().
  void AddSectionProduced(Tag tag, Producer produce);
  /// The whole file as bytes.
  std::vector<std::uint8_t> Serialize() const;
  /// Streams the file to a temporary beside `path` and renames it into place.
  Status WriteFile(const std::filesystem::path& path) const;

  /// Where a section lies in a file, and its checksum.
  struct Placed {
    std::uint64_t offset = 0, size = 0;
    std::uint32_t crc = 0;
  };

 private:
  struct Section {
    Tag tag;
    std::vector<std::uint8_t> owned;
    std::span<const std::uint8_t> bytes;  // into `owned` or the caller's memory
    Producer produce;                     // set: the bytes come from here instead
  };
  /// Header and section table for sections placed as given.
  std::vector<std::uint8_t> HeaderAndTable(const std::vector<Placed>& placed) const;
  /// Emits the file as a sequence of byte runs (a zero placeholder for header and table, padding,
  /// payloads) to `sink`, then the real header and table to `patch` (at offset 0): sizes and
  /// checksums are known once the payloads have passed.
  template <class Sink, class Patch>
  Status EmitFile(const Sink& sink, const Patch& patch) const;
  FormatId format_;
  std::uint32_t flags_;
  std::vector<Section> sections_;
};

/// Sections for which the filter returns false are neither verified nor available.
using SectionFilter = bool (*)(Tag tag, const void* context);

/// A container's frame (header and section table) parsed without refusing anything but a foreign
/// file: every problem Reader would refuse is listed, in the order Reader checks them, so a
/// validator can report them all. Reader is this parse plus "fail on the first issue".
class Frame {
 public:
  enum class IssueKind {
    kFileSize,
    kSectionTable,
    kHeaderChecksum,
    kSectionBounds,
    kSectionChecksum,
    kLayout  ///< sections out of the writer's order, or padding that is not zero
  };
  struct Issue {
    IssueKind kind;
    std::string message;  ///< one line, starting with the file name
  };
  struct Section {
    Tag tag{};
    std::uint64_t offset = 0, size = 0;
    bool in_file = false;   ///< inside the file and aligned; `bytes` is empty otherwise
    bool loaded = false;    ///< the section filter asked for it (its checksum was verified)
    bool crc_ok = false;    ///< loaded and its checksum matches
    std::uint32_t crc = 0;  ///< the checksum the table states (for a reader that streams it)
    std::span<const std::uint8_t> bytes;
  };
  /// Fails (BadInput) only when the file cannot be read, lacks the format's magic or has a newer
  /// version: then it is not a file of this format at all.
  static StatusOr<Frame> Open(const std::filesystem::path& path, const FormatId& format,
                              SectionFilter load = nullptr, const void* context = nullptr);
  static StatusOr<Frame> FromBytes(std::span<const std::uint8_t> bytes, const std::string& name,
                                   const FormatId& format, SectionFilter load = nullptr,
                                   const void* context = nullptr);

  const std::string& name() const { return name_; }
  std::uint32_t version() const { return version_; }
  std::uint32_t flags() const { return flags_; }
  /// The file's size in bytes.
  std::uint64_t file_size() const { return file_size_; }
  const std::vector<Issue>& issues() const { return issues_; }
  const std::vector<Section>& sections() const { return sections_; }
  /// The first section with this tag that lies inside the file, whatever its checksum says.
  const Section* Find(Tag tag) const;

 private:
  friend class Reader;
  // FromBytes; with `release`, mapped bytes go back to the kernel once checksummed.
  static StatusOr<Frame> Parse(std::span<const std::uint8_t> bytes, const std::string& name,
                               const FormatId& format, SectionFilter load, const void* context,
                               bool release);
  std::shared_ptr<const void> mapping_;  // keeps mapped bytes alive
  std::string name_;
  std::uint32_t version_ = 0;
  std::uint32_t flags_ = 0;
  std::uint64_t file_size_ = 0;
  std::vector<Issue> issues_;
  std::vector<Section> sections_;
};

/// A verified, memory-mapped container file. Open() checks the magic, version, file size,
/// header checksum, section bounds and every section checksum before returning.
class Reader {
 public:
  /// Sections for which `load` returns false are neither verified nor available (a streaming
  /// reader touches only the pages it needs); by default every section is.
  using SectionFilter = container::SectionFilter;
  static StatusOr<Reader> Open(const std::filesystem::path& path, const FormatId& format,
                               SectionFilter load = nullptr, const void* context = nullptr);
  /// Verifies in-memory bytes (they must outlive the Reader); `name` is used in messages.
  static StatusOr<Reader> FromBytes(std::span<const std::uint8_t> bytes, const std::string& name,
                                    const FormatId& format, SectionFilter load = nullptr,
                                    const void* context = nullptr);
  /// The loaded sections of a frame without issues; otherwise its first issue, as BadInput.
  static StatusOr<Reader> FromFrame(Frame frame);

  std::uint32_t version() const { return version_; }
  std::uint32_t flags() const { return flags_; }
  const std::string& name() const { return name_; }
  /// The section with this tag, if present.
  std::optional<std::span<const std::uint8_t>> Find(Tag tag) const;
  /// Like Find, but a missing section is an error naming the file.
  StatusOr<std::span<const std::uint8_t>> Require(Tag tag) const;

 private:
  struct Entry {
    Tag tag;
    std::span<const std::uint8_t> bytes;
  };
  std::shared_ptr<const void> mapping_;
  std::string name_;
  std::uint32_t version_ = 0;
  std::uint32_t flags_ = 0;
  std::vector<Entry> entries_;
};

}  // namespace svokit::container
