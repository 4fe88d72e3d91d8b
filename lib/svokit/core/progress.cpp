#include "svokit/core/progress.hpp"

#include <unistd.h>

#include <algorithm>

#include <fmt/format.h>

#include "svokit/core/std_streams.hpp"

namespace svokit {

Progress::Progress(Style style, std::FILE* out) : style_(style), out_(out) {
  if (style_ == Style::kAuto) style_ = ::isatty(::fileno(out_)) ? Style::kBar : Style::kLines;
}

Progress& Progress::Silent() {
  static Progress silent(Style::kQuiet);
  static const bool unrecorded = (silent.record_ = false, true);  // shared by all: keep nothing
  (void)unrecorded;
  return silent;
}

Progress::Stage::Stage(Progress& progress, std::string name, std::uint64_t total)
    : progress_(progress),
      name_(std::move(name)),
      total_(total),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {
  if (progress_.style_ == Style::kBar) Draw(false);
}

Progress::Stage::~Stage() {
  if (cancelled_) {
    if (progress_.style_ == Style::kBar) WriteDiagnostic("\r\x1b[K", progress_.out_);
    return;
  }
  const std::uint64_t reported = done_.load();
  done_ = total_.load();
  Draw(true);
  if (progress_.record_) {
    std::lock_guard lock(progress_.timings_mutex_);
    progress_.timings_.push_back({name_, seconds(), reported, total_.load()});
  }
}

std::vector<Progress::Timing> Progress::timings() const {
  std::lock_guard lock(timings_mutex_);
  return timings_;
}

double Progress::Stage::seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void Progress::Stage::Advance(std::uint64_t units) {
  done_.fetch_add(units, std::memory_order_relaxed);
  if (progress_.style_ != Style::kBar && progress_.style_ != Style::kLines) return;
  // Redraw a bar at most every 100 ms; in a log (lines), a line every 10 s of a long stage. Never
  // block a worker on another one's drawing.
  const auto now = std::chrono::steady_clock::now();
  const auto every = progress_.style_ == Style::kBar ? std::chrono::milliseconds(100)
                                                     : std::chrono::milliseconds(10000);
  if (now - last_draw_ < every) return;
  std::unique_lock lock(draw_mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return;
  last_draw_ = now;
  Draw(false);
}

// "45% 12.3 s, 1234/5000, 12.5 MB written, ETA 15 s": what a long stage has done and has left.
std::string Progress::Stage::Status() const {
  const std::uint64_t total = total_.load(), done = std::min(done_.load(), total);
  const double t = seconds();
  const double frac = total == 0 ? 1.0 : static_cast<double>(done) / static_cast<double>(total);
  std::string s = fmt::format("{:3.0f}% {:.1f} s", frac * 100.0, t);
  if (total > 1) s += fmt::format(", {}/{}", done, total);
  if (const std::uint64_t b = bytes_.load(); b > 0) {
    s += fmt::format(", {:.1f} MB written", static_cast<double>(b) / 1e6);
  }
  if (done > 0 && done < total) s += fmt::format(", ETA {:.0f} s", t * (1.0 - frac) / frac);
  return s;
}

void Progress::Stage::Draw(bool final) {
  std::FILE* out = progress_.out_;
  const std::string tail = summary_.empty() ? "" : "  " + summary_;
  switch (progress_.style_) {
    case Style::kQuiet:
    case Style::kAuto:
      return;
    case Style::kLines:
      if (final) {
        WriteDiagnostic(fmt::format("{:<12} done in {:.3f} s{}\n", name_, seconds(), tail), out);
      } else {
        WriteDiagnostic(fmt::format("{:<12} {}\n", name_, Status()), out);
      }
      break;
    case Style::kBar: {
      constexpr int kWidth = 30;
      const std::uint64_t total = total_.load();
      const double frac =
          total == 0
              ? 1.0
              : std::min(1.0, static_cast<double>(done_.load()) / static_cast<double>(total));
      const int filled = static_cast<int>(frac * kWidth);
      WriteDiagnostic(
          fmt::format("\r{:<12} [{}{}] {}{}\x1b[K{}", name_, std::string(filled, '#'),
                      std::string(kWidth - filled, '.'),
                      final ? fmt::format("{:3.0f}% {:.1f} s", frac * 100.0, seconds()) : Status(),
                      final ? tail : "", final ? "\n" : ""),
          out);
      break;
    }
  }
}

}  // namespace svokit
