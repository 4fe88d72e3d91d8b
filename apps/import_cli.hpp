#pragma once
// The options every tool that imports a mesh shares: --asset-path (where the mesh's side files
// may also be read from), --strict (any warning is an error), --up and --rotate (how the file's
// axes turn into svokit's, y up); and the sink that prints each warning as one line on stderr and
// counts it for the summary.

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "apps/run.hpp"
#include "svokit/mesh/orientation.hpp"
#include "svokit/mesh/side_files.hpp"

namespace svokit::app {

struct ImportCli {
  ImportOptions options;
  bool strict = false;
  std::size_t warnings = 0;  ///< printed so far

  void Add(CLI::App& cli) {
    cli.add_option("--asset-path", options.asset_paths,
                   "A folder the mesh's textures, material libraries and buffers may also be "
                   "read from, with its subfolders (repeatable); by default only the mesh's own "
                   "folder is")
        ->option_text("DIR")
        ->allow_extra_args(false)
        ->check(CLI::ExistingDirectory.description(""));
    cli.add_flag("--strict", strict,
                 "Treat any warning (a texture or material library missing, refused or "
                 "unreadable, ...) as an error: exit 2, nothing written");
    // Each callback recomputes the whole orientation: their order does not matter.
    cli.add_option_function<std::string>(
           "--up",
           [this](const std::string& text) {
             up_ = *ParseUp(text);
             Combine();
           },
           "The file's up axis, turned to svokit's +y: x, y, z, -x, -y or -z (default y, glTF's; "
           "z for most CAD, 3ds Max and unconverted Blender exports). Later stages reading the "
           "mesh again (--mesh) turn it as the file they read records, unless given this")
        ->option_text("AXIS")
        ->check(Valid(ParseUp));
    cli.add_option_function<std::vector<std::string>>(
           "--rotate",
           [this](const std::vector<std::string>& texts) {
             rotations_.clear();
             for (const std::string& t : texts) rotations_.push_back(*ParseRotation(t));
             Combine();
           },
           "Then turn the mesh by DEGREES about svokit's AXIS (x, y or z), right-handed: x:90 "
           "takes +y to +z (repeatable, applied in order after --up)")
        ->option_text("AXIS:DEGREES")
        ->allow_extra_args(false)
        ->check(Valid(ParseRotation));
  }

  /// Prints each warning as "TOOL: warning: FILE: ..." and counts it.
  std::function<void(const std::string&)> Sink(const std::string& tool) {
    return [this, tool](const std::string& warning) {
      ++warnings;
      Warn(tool, {warning});
    };
  }

 private:
  /// An option's check: the parser's message for text it refuses.
  static CLI::Validator Valid(StatusOr<Orientation> (*parse)(std::string_view)) {
    return CLI::Validator(
        [parse](std::string& text) -> std::string {
          const StatusOr<Orientation> parsed = parse(text);
          return parsed.ok() ? std::string() : std::string(parsed.status().message());
        },
        "");
  }

  void Combine() {
    Orientation o = up_;
    for (const Orientation& r : rotations_) o = o.Then(r);
    options.orientation = o;
  }

  Orientation up_;
  std::vector<Orientation> rotations_;
};

}  // namespace svokit::app
