#pragma once
// The container writer for sections produced in parallel and too large to copy: they are written
// in place into a mapped temporary, then laid out as Writer lays them out (README.md here).

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <vector>

#include "svokit/core/file_io.hpp"
#include "svokit/core/status.hpp"
#include "svokit/formats/container/container.hpp"

namespace svokit::container {

/// A container file whose large sections are written in place: producers fill *regions* of a
/// temporary file mapped in memory (from any threads), and Commit() lays the sections out,
/// checksums them and renames the file into place. Nothing is copied into the file afterwards,
/// and no second set of fresh pages is touched: the bytes are written once, where the file keeps
/// them.
/// Region sizes need not be known up front: rooms are planned, and Commit() moves each region's
/// used part to its final place.
class MappedWriter {
 public:
  /// A section: `bytes`, or (region ≥ 0) the first `size` bytes of that region.
  struct Section {
    Tag tag;
    std::span<const std::uint8_t> bytes = {};
    int region = -1;
    std::uint64_t size = 0;
  };

  MappedWriter(const FormatId& format, std::uint32_t flags) : format_(format), flags_(flags) {}
  ~MappedWriter();
  MappedWriter(const MappedWriter&) = delete;
  MappedWriter& operator=(const MappedWriter&) = delete;

  /// Creates the temporary beside `path` laid out for `plan` (a region section's `size` is its
  /// room; regions numbered 0, 1, ... in file order) and maps it. Disk space for the whole plan
  /// is reserved, so a full disk is this error, not a fault while the regions are written.
  Status Open(const std::filesystem::path& path, std::vector<Section> plan);
  /// Region i's room, to fill; its address changes with Resize().
  std::span<std::uint8_t> region(std::size_t i) const;
  /// New rooms for the regions: each keeps its first min(old, new room) bytes (the rest is
  /// unspecified). Not while regions are being written.
  Status Resize(std::span<const std::uint64_t> rooms);
  /// Lays out `sections` (the plan's tags in the plan's order; a region's `size` at most its
  /// room), zeroes the padding, checksums every section, writes header and table, and renames
  /// the file into place. The writer is closed after, whatever the result.
  Status Commit(std::vector<Section> sections);

 private:
  // Offsets of `sections` laid out in order; returns the file's size.
  std::uint64_t Layout(const std::vector<Section>& sections, std::vector<std::uint64_t>& offsets);
  // Moves every region from its current offset to offsets[its section], keeping keep[region]
  // bytes, in an order that never overwrites bytes still to be moved.
  Status Relayout(const std::vector<Section>& sections, const std::vector<std::uint64_t>& offsets,
                  std::uint64_t file_size, const std::vector<std::uint64_t>& keep);
  // Commit() but for closing the file.
  Status Finish(const std::vector<Section>& sections);
  // Sets the file's size (reserving the space when it grows) and maps all of it.
  Status MapFile(std::uint64_t size);
  void Unmap();

  FormatId format_;
  std::uint32_t flags_;
  std::unique_ptr<AtomicFileWriter> file_;
  std::vector<Section> plan_;
  std::vector<std::uint64_t> region_offsets_;  // per region, where it is now
  std::uint8_t* data_ = nullptr;
  std::uint64_t mapped_ = 0;
};

}  // namespace svokit::container
