#pragma once
// The options every tool that imports a mesh shares: --asset-path (where the mesh's side files
// may also be read from) and --strict (any warning is an error); and the sink that prints each
// warning as one line on stderr and counts it for the summary.

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "apps/run.hpp"
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
  }

  /// Prints each warning as "TOOL: warning: FILE: ..." and counts it.
  std::function<void(const std::string&)> Sink(const std::string& tool) {
    return [this, tool](const std::string& warning) {
      ++warnings;
      Warn(tool, {warning});
    };
  }
};

}  // namespace svokit::app
