#pragma once
// What svokit's benchmark binaries share: the command line scripts/bench gives them (input files,
// --resolution N where the binary voxelizes, every other --flag for Google Benchmark), benchmarks
// timed as wall time in milliseconds, and meshes with the grid fitted to them.

#include <benchmark/benchmark.h>

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "svokit/core/grid_transform.hpp"
#include "svokit/core/status.hpp"
#include "svokit/mesh/mesh.hpp"

namespace svokit::bench {

/// The inputs named on the command line.
struct Inputs {
  std::vector<std::string> files;
  std::uint32_t resolution = 1024;  ///< --resolution N, where the binary takes it
};

/// A mesh and the grid fitted to it: what the voxelizing benchmarks run on.
struct Scene {
  std::string name;  ///< the file's stem
  Mesh mesh;
  GridTransform grid;
};

/// Imports `path` and fits a grid of `resolution` voxels along its longest axis.
StatusOr<Scene> LoadScene(const std::string& path, std::uint32_t resolution);

/// Registers `fn(state, args...)` as the benchmark `name`, timed as wall time in milliseconds.
template <class Fn, class... Args>
void Register(const std::string& name, Fn&& fn, Args&&... args) {
  benchmark::RegisterBenchmark(name.c_str(), std::forward<Fn>(fn), std::forward<Args>(args)...)
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime();
}

/// A benchmark binary's main: reads the command line (--resolution only `with_resolution`), has
/// `setup` register the benchmarks of the inputs and runs them. A `setup` that fails is bad
/// input: one line "BINARY: message" on stderr, exit 2.
int Main(int argc, char** argv, bool with_resolution,
         const std::function<Status(const Inputs&)>& setup);

}  // namespace svokit::bench
