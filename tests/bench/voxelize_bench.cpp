// Voxelization work split: the triangle-parallel, fragment-parallel and hybrid methods on the same
// meshes and grid, in one process (the voxel sets are identical; only the time differs), and the
// hybrid cutoff swept to choose its default.
//
//   voxelize_bench --resolution N MESH... [benchmark flags]

#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "svokit/formats/mesh_import.hpp"
#include "svokit/voxelize/voxelize.hpp"

namespace {

struct Scene {
  std::string name;
  svokit::Mesh mesh;
  svokit::GridTransform grid;
};
std::vector<Scene> g_scenes;

void Run(benchmark::State& state, const Scene* scene, svokit::VoxelMethod method, double cutoff) {
  svokit::VoxelizeOptions options;
  options.method = method;
  options.hybrid_cutoff = cutoff;
  std::size_t voxels = 0;
  for (auto _ : state) {
    auto set = svokit::Voxelize(scene->mesh, scene->grid, options);
    voxels = set->size();
    benchmark::DoNotOptimize(set->keys.data());
  }
  state.counters["voxels"] = static_cast<double>(voxels);
  state.counters["triangles"] = static_cast<double>(scene->mesh.triangle_count());
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(voxels));
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<char*> rest = {argv[0]};
  std::uint32_t resolution = 1024;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--resolution" && i + 1 < argc)
      resolution = static_cast<std::uint32_t>(std::stoul(argv[++i]));
    else if (a.rfind("--", 0) == 0)
      rest.push_back(argv[i]);
    else
      files.push_back(a);
  }
  for (const std::string& f : files) {
    auto mesh = svokit::ImportMesh(f);
    if (!mesh.ok()) {
      std::fprintf(stderr, "voxelize_bench: %s\n", mesh.status().message().c_str());
      return 2;
    }
    auto grid = svokit::GridTransform::FitResolution(mesh->Bounds(), resolution);
    const std::string name = std::filesystem::path(f).stem().string();
    g_scenes.push_back({name, std::move(mesh).value(), *grid});
  }
  for (const Scene& s : g_scenes) {
    using svokit::VoxelMethod;
    benchmark::RegisterBenchmark((s.name + "/triangle").c_str(), Run, &s, VoxelMethod::kTriangle,
                                 0.0)
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
    benchmark::RegisterBenchmark((s.name + "/fragment").c_str(), Run, &s, VoxelMethod::kFragment,
                                 0.0)
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
    for (double cutoff : {64.0, 1024.0, 4096.0, 16384.0}) {
      benchmark::RegisterBenchmark(
          (s.name + "/hybrid_cutoff_" + std::to_string(int(cutoff))).c_str(), Run, &s,
          VoxelMethod::kHybrid, cutoff)
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime();
    }
  }
  int n = static_cast<int>(rest.size());
  benchmark::Initialize(&n, rest.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
