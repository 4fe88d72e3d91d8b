#pragma once
// Progress reporting on stderr: a redrawn bar on a terminal, one line per finished stage
// otherwise (logs and CI stay readable), nothing at all when quiet.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <mutex>
#include <string>
#include <vector>

namespace svokit {

class Progress {
 public:
  enum class Style { kAuto, kBar, kLines, kQuiet };

  /// kAuto picks kBar when `out` is a terminal, kLines otherwise.
  explicit Progress(Style style = Style::kAuto, std::FILE* out = stderr);
  /// A reporter that prints nothing.
  static Progress& Silent();

  Style style() const { return style_; }

  /// Name and wall time of every stage that finished (not cancelled), in finishing order, and
  /// the work units it had reported done of its total when it finished.
  struct Timing {
    std::string stage;
    double seconds;
    std::uint64_t units_done = 0, units = 0;
  };
  std::vector<Timing> timings() const;

  /// One named stage with `total` work units; finishes (and prints its line) on destruction.
  class Stage {
   public:
    Stage(Progress& progress, std::string name, std::uint64_t total);
    ~Stage();
    Stage(const Stage&) = delete;
    Stage& operator=(const Stage&) = delete;

    /// Thread-safe; cheap enough to call from parallel loops once per chunk.
    void Advance(std::uint64_t units = 1);
    /// The stage's work units, once known (a reader learns its page count from the file).
    void SetTotal(std::uint64_t total) { total_.store(total, std::memory_order_relaxed); }
    /// The stage failed: no "done" line (a bar is erased instead).
    void Cancel() { cancelled_ = true; }
    /// Text appended to the stage's final line (e.g. "1.2 M triangles").
    void SetSummary(std::string summary) { summary_ = std::move(summary); }
    /// Bytes the stage has written so far, shown while it runs (thread-safe).
    void AddBytes(std::uint64_t bytes) { bytes_.fetch_add(bytes, std::memory_order_relaxed); }
    double seconds() const;

   private:
    void Draw(bool final);
    std::string Status() const;

    Progress& progress_;
    std::string name_;
    std::string summary_;
    std::atomic<std::uint64_t> total_;
    bool cancelled_ = false;
    std::atomic<std::uint64_t> done_{0};
    std::atomic<std::uint64_t> bytes_{0};
    std::chrono::steady_clock::time_point start_;
    std::chrono::steady_clock::time_point last_draw_;
    std::mutex draw_mutex_;
  };

 private:
  Style style_;
  std::FILE* out_;
  bool record_ = true;  // false for the shared Silent() reporter
  mutable std::mutex timings_mutex_;
  std::vector<Timing> timings_;
};

/// Runs `work` as the stage `name` of `progress` (one unit) and returns what it returns. A result
/// that is not ok (a Status or StatusOr) cancels the stage: no "done" line.
template <class Work>
auto RunStage(Progress& progress, std::string name, const Work& work) -> decltype(work()) {
  Progress::Stage stage(progress, std::move(name), 1);
  auto result = work();
  if constexpr (requires { result.ok(); }) {
    if (!result.ok()) stage.Cancel();
  }
  return result;
}

/// The same, with `summarize(result)` appended to the "done" line of a stage that succeeds.
template <class Work, class Summarize>
auto RunStage(Progress& progress, std::string name, const Work& work, const Summarize& summarize)
    -> decltype(work()) {
  Progress::Stage stage(progress, std::move(name), 1);
  auto result = work();
  if (result.ok()) {
    stage.SetSummary(summarize(result));
  } else {
    stage.Cancel();
  }
  return result;
}

}  // namespace svokit
