#include "svokit/validate/report.hpp"

#include <iterator>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "svokit/core/utf8.hpp"

namespace svokit::validate {

void CheckResult::Add(Finding f) {
  state = State::kFailed;
  const std::uint64_t seen = counts[f.kind]++;
  if (seen < max_examples) examples.push_back(std::move(f));
}

void CheckResult::AddCount(const std::string& kind, std::uint64_t n) {
  if (n == 0) return;
  state = State::kFailed;
  counts[kind] += n;
}

std::uint64_t CheckResult::findings() const {
  std::uint64_t n = 0;
  for (const auto& [kind, count] : counts) n += count;
  return n;
}

bool Report::ok() const {
  for (const CheckResult& c : checks) {
    if (c.state == CheckResult::State::kFailed) return false;
  }
  return true;
}

std::uint64_t Report::findings() const {
  std::uint64_t n = 0;
  for (const CheckResult& c : checks) n += c.findings();
  return n;
}

namespace {

const char* StateName(CheckResult::State s) {
  switch (s) {
    case CheckResult::State::kPassed:
      return "passed";
    case CheckResult::State::kFailed:
      return "failed";
    case CheckResult::State::kSkipped:
      return "skipped";
  }
  return "?";
}

}  // namespace

std::string Report::Text() const {
  std::string out = fmt::format("{:<16}{}\n", "file", file);
  if (!summary.empty()) fmt::format_to(std::back_inserter(out), "{:<16}{}\n", "octree", summary);
  for (const CheckResult& c : checks) {
    std::string stats;
    for (const auto& [key, value] : c.stats) {
      stats += fmt::format("{}{} {}", stats.empty() ? "" : ", ", key, value);
    }
    std::string line = StateName(c.state);
    if (!c.note.empty()) line += "  " + c.note;
    if (!stats.empty()) line += "  (" + stats + ")";
    fmt::format_to(std::back_inserter(out), "{:<16}{}\n", c.name, line);
    for (const auto& [kind, count] : c.counts) {
      fmt::format_to(std::back_inserter(out), "  {:<26}{}\n", kind, count);
    }
    for (const Finding& f : c.examples) {
      fmt::format_to(std::back_inserter(out), "    {}: {}\n", f.kind, f.message);
    }
  }
  fmt::format_to(std::back_inserter(out), "{:<16}{}\n", "result",
                 ok() ? std::string("valid") : fmt::format("INVALID ({} findings)", findings()));
  return out;
}

std::string Report::Json() const {
  nlohmann::ordered_json checks_json = nlohmann::ordered_json::object();
  for (const CheckResult& c : checks) {
    nlohmann::ordered_json stats = nlohmann::ordered_json::object();
    for (const auto& [key, value] : c.stats) stats[key] = value;
    nlohmann::ordered_json examples = nlohmann::ordered_json::array();
    for (const Finding& f : c.examples) {
      nlohmann::ordered_json e = {{"kind", f.kind}, {"message", EscapeInvalidUtf8(f.message)}};
      e["voxel"] = f.voxel ? nlohmann::ordered_json(*f.voxel) : nlohmann::ordered_json();
      e["level"] = f.level ? nlohmann::ordered_json(*f.level) : nlohmann::ordered_json();
      e["distance"] = f.distance ? nlohmann::ordered_json(*f.distance) : nlohmann::ordered_json();
      examples.push_back(std::move(e));
    }
    checks_json[c.name] = {{"status", StateName(c.state)},
                           {"note", EscapeInvalidUtf8(c.note)},
                           {"findings", c.findings()},
                           {"counts", c.counts},
                           {"stats", stats},
                           {"examples", examples}};
  }
  const nlohmann::ordered_json j = {{"file", EscapeInvalidUtf8(file)},
                                    {"valid", ok()},
                                    {"findings", findings()},
                                    {"octree", summary},
                                    {"checks", checks_json}};
  return j.dump(2) + "\n";
}

}  // namespace svokit::validate
