#pragma once
// The option svo-export and mesh2svo share for the DAG files they write.

#include <CLI/CLI.hpp>

#include "apps/cli.hpp"
#include "svokit/export/dag_files.hpp"

namespace svokit::app {

/// --colors hashdag|packed|none: the colour file beside a DAG.
inline CLI::Option* AddDagColorsOption(CLI::App& cli, DagColorFile& colors) {
  return AddChoice(cli, "--colors", colors,
                   {{"default", DagColorFile::kDefault},
                    {"hashdag", DagColorFile::kHashDag},
                    {"packed", DagColorFile::kPacked},
                    {"none", DagColorFile::kNone}},
                   "hashdag|packed|none",
                   "DAG outputs: the colour file beside it, in its depth-first order: hashdag "
                   "(HashDAG's uncompressed_colors.bin, RGBA8; the default beside a .dag.bin), "
                   "packed (svokit's .dagcolors, zstd; the default beside a .svdag or .ssvdag) "
                   "or none");
}

}  // namespace svokit::app
