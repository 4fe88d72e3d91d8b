#pragma once
// The command line every svokit tool shares: version text, the common options (--quiet,
// --threads), the help's layout, and option helpers (files, choices, numbers, sizes).

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "svokit/core/byte_size.hpp"
#include "svokit/core/progress.hpp"
#include "svokit/core/status.hpp"

namespace svokit::app {

struct CommonOptions {
  bool quiet = false;
  bool json = false;        ///< the report as one JSON object (Report)
  std::size_t threads = 0;  // 0 = all cores

  Progress MakeProgress() const {
    return Progress(quiet ? Progress::Style::kQuiet : Progress::Style::kAuto);
  }
};

/// --help that reads well: each option's value as a word or a list of choices ("N", "FILE",
/// "conservative|thin": the option text every tool sets), and its default after the description.
class HelpFormatter : public CLI::Formatter {
 public:
  // The names alone: CLI11 marks a negated flag's names with "{false}".
  std::string make_option_name(const CLI::Option* opt, bool positional) const override {
    if (positional) return opt->get_name(true, false);
    std::string names;
    for (const std::string& s : opt->get_snames()) names += (names.empty() ? "-" : ",-") + s;
    for (const std::string& l : opt->get_lnames()) names += (names.empty() ? "--" : ",--") + l;
    return names;
  }
  std::string make_option_opts(const CLI::Option* opt) const override {
    std::string out;
    if (opt->get_type_size() != 0) {
      out += " " + (opt->get_option_text().empty() ? opt->get_type_name() : opt->get_option_text());
      if (opt->get_required()) out += " REQUIRED";
    }
    for (const CLI::Option* other : opt->get_excludes())
      out += " (not with " + other->get_name() + ")";
    return out;
  }
  std::string make_option_desc(const CLI::Option* opt) const override {
    const std::string default_value = opt->get_default_str();
    return default_value.empty() ? opt->get_description()
                                 : opt->get_description() + " (default: " + default_value + ")";
  }
};

/// What every tool's command line has: --version, --quiet, --json, --threads, the help's layout
/// and, at its end, `example`: one command line that shows the tool at work.
inline void AddCommonOptions(CLI::App& cli, CommonOptions& options, std::string_view example) {
  cli.formatter(std::make_shared<HelpFormatter>());
  cli.footer(fmt::format("Example:\n  {}", example));
  cli.set_version_flag("--version", std::string("svokit ") + SVOKIT_VERSION);
  cli.add_flag("-q,--quiet", options.quiet,
               "No progress on stderr and no report on stdout (errors and warnings still go to "
               "stderr; --json still prints)");
  cli.add_flag("--json", options.json,
               "Print the report as one JSON object on stdout, with the text's keys");
  cli.add_option("-j,--threads", options.threads, "Worker threads; 0 = all cores")
      ->option_text("N")
      ->capture_default_str()
      ->check(CLI::Range(0, 4096));
}

/// A number > 0 and finite; "nan", "inf" and out-of-range values are refused with the value as
/// given (CLI11's own range checks print DBL_MAX in full).
inline CLI::Validator PositiveFinite() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(text, v) || !(v > 0) || !std::isfinite(v)) {
          return "must be a positive finite number (got " + text + ")";
        }
        return {};
      },
      "");
}

/// A number ≥ 0, where "inf" means no limit; "nan" is refused.
inline CLI::Validator NonNegativeOrInfinite() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(text, v) || !(v >= 0)) {
          return "must be a number >= 0, or inf (got " + text + ")";
        }
        return {};
      },
      "");
}

/// A count of at most `max`, the documented bound of an option that sets the amount of work;
/// more is refused with the value and the maximum.
inline CLI::Validator AtMost(std::uint64_t max) {
  return CLI::Validator(
      [max](std::string& text) -> std::string {
        std::uint64_t v = 0;
        if (CLI::detail::lexical_cast(text, v) && v > max) {
          return fmt::format("{}: the maximum is {}", text, max);
        }
        return {};
      },
      "");
}

/// An option naming a file (`flags` "input" for the positional one), shown as FILE in --help.
inline CLI::Option* AddFile(CLI::App& cli, const std::string& flags, std::filesystem::path& path,
                            const std::string& description) {
  return cli.add_option(flags, path, description)->option_text("FILE");
}

/// The name of `value` in `names` ("" for none).
template <class Enum>
std::string NameOf(const std::map<std::string, Enum>& names, Enum value) {
  for (const auto& [name, v] : names) {
    if (v == value) return name;
  }
  return "";
}

/// An option taking one of `names` (any case), shown as "a|b|c" in --help with its default.
template <class Enum>
CLI::Option* AddChoice(CLI::App& cli, const std::string& flags, Enum& value,
                       const std::map<std::string, Enum>& names, const std::string& order,
                       const std::string& description) {
  return cli.add_option(flags, value, description)
      ->transform(CLI::CheckedTransformer(names, CLI::ignore_case).description(""))
      ->option_text(order)
      ->default_str(NameOf(names, value));
}

/// --memory-limit SIZE: the bytes it names, or none when not given (given empty, it is refused).
struct MemoryLimitOption {
  std::string text;
  CLI::Option* option = nullptr;

  void Add(CLI::App& cli, const std::string& description) {
    option = cli.add_option("--memory-limit", text, description)->option_text("SIZE");
  }
  bool given() const { return option != nullptr && option->count() > 0; }
  StatusOr<std::optional<std::uint64_t>> Bytes() const {
    if (!given()) return std::optional<std::uint64_t>();
    StatusOr<std::uint64_t> bytes = ParseByteSize("--memory-limit", text);
    if (!bytes.ok()) return bytes.status();
    return std::optional<std::uint64_t>(*bytes);
  }
};

}  // namespace svokit::app
