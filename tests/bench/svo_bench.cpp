// Octree build stages in one process, on voxels made once: the structure alone, 3³ bricks,
// contours, and all together (what mesh2svo's "bricks" and "contours" stages time, without the
// process, import, voxelization and write around them).
//
//   svo_bench --resolution N MESH... [benchmark flags]

#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "svokit/formats/mesh_import.hpp"
#include "svokit/svo/build.hpp"
#include "svokit/voxelize/voxelize.hpp"

namespace {

struct Scene {
  std::string name;
  svokit::Mesh mesh;
  svokit::VoxelSet voxels;
};
std::vector<Scene> g_scenes;

void Build(benchmark::State& state, const Scene* scene, std::uint32_t brick_side, bool contours) {
  svokit::BuildOptions options;
  options.brick_side = brick_side;
  options.contours = contours;
  std::size_t nodes = 0;
  for (auto _ : state) {
    auto svo = svokit::BuildSvo(scene->voxels, &scene->mesh, options);
    if (!svo.ok()) {
      state.SkipWithError(svo.status().message().c_str());
      return;
    }
    nodes = 0;
    for (const auto& level : svo->levels) nodes += level.node_count;
    benchmark::DoNotOptimize(svo->levels.data());
  }
  state.counters["voxels"] = static_cast<double>(scene->voxels.size());
  state.counters["nodes"] = static_cast<double>(nodes);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(scene->voxels.size()));
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
      std::fprintf(stderr, "svo_bench: %s\n", mesh.status().message().c_str());
      return 2;
    }
    auto grid = svokit::GridTransform::FitResolution(mesh->Bounds(), resolution);
    auto voxels = svokit::Voxelize(*mesh, *grid, svokit::VoxelizeOptions{});
    if (!voxels.ok()) {
      std::fprintf(stderr, "svo_bench: %s\n", voxels.status().message().c_str());
      return 2;
    }
    g_scenes.push_back({std::filesystem::path(f).stem().string(), std::move(mesh).value(),
                        std::move(voxels).value()});
  }
  for (const Scene& s : g_scenes) {
    const struct {
      const char* name;
      std::uint32_t brick_side;
      bool contours;
    } variants[] = {
        {"octree", 0, false}, {"bricks", 3, false}, {"contours", 0, true}, {"full", 3, true}};
    for (const auto& v : variants) {
      benchmark::RegisterBenchmark((s.name + "/" + v.name).c_str(), Build, &s, v.brick_side,
                                   v.contours)
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
