#pragma once
// svo-validate's findings: one CheckResult per check (structure, bricks, contours, occupancy,
// contour_surface), each with counts per finding kind, the first few findings, and statistics;
// rendered as text or as JSON with stable keys (docs/tools/svo-validate.md).

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace svokit::validate {

struct Finding {
  std::string kind;     ///< stable key, e.g. "section_checksum", "missing_voxel"
  std::string message;  ///< one line
  std::optional<std::array<std::int64_t, 3>> voxel;  ///< node or voxel coordinates, if any
  std::optional<std::uint32_t> level;                ///< octree level of `voxel`
  std::optional<double> distance;  ///< occupancy: centre–surface distance in voxels
};

struct CheckResult {
  enum class State { kPassed, kFailed, kSkipped };

  explicit CheckResult(std::string check_name, std::size_t keep = 10)
      : name(std::move(check_name)), max_examples(keep) {}

  std::string name;
  State state = State::kPassed;
  std::string note;  ///< why skipped, or what was checked (one line)
  std::size_t max_examples;
  std::map<std::string, std::uint64_t> counts;  ///< findings per kind
  std::vector<Finding> examples;                ///< the first max_examples findings of each kind
  std::vector<std::pair<std::string, std::uint64_t>> stats;  ///< e.g. {"checked", n}, in order

  /// Records a finding (the check fails); keeps it as an example while its kind has room.
  void Add(Finding f);
  /// Records `n` findings of one kind whose first examples were added with Add (or none).
  void AddCount(const std::string& kind, std::uint64_t n);
  void Skip(std::string why) {
    state = State::kSkipped;
    note = std::move(why);
  }
  void Stat(std::string key, std::uint64_t value) { stats.emplace_back(std::move(key), value); }
  std::uint64_t findings() const;
};

struct Report {
  std::string file;
  std::string summary;  ///< depth, voxels, mode, bricks, contours (text)
  std::vector<CheckResult> checks;

  bool ok() const;
  std::uint64_t findings() const;
  std::string Text() const;
  std::string Json() const;
};

}  // namespace svokit::validate
