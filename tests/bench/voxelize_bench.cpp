// Voxelization work split: the triangle-parallel, fragment-parallel and hybrid methods on the same
// meshes and grid, in one process (the voxel sets are identical; only the time differs), and the
// hybrid cutoff swept to choose its default.
//
//   voxelize_bench --resolution N MESH... [benchmark flags]

#include <string>
#include <vector>

#include "bench_main.hpp"
#include "svokit/voxelize/voxelize.hpp"

namespace {

using svokit::bench::Scene;
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
  return svokit::bench::Main(argc, argv, true, [](const svokit::bench::Inputs& inputs) {
    for (const std::string& f : inputs.files) {
      auto scene = svokit::bench::LoadScene(f, inputs.resolution);
      if (!scene.ok()) return scene.status();
      g_scenes.push_back(std::move(scene).value());
    }
    using svokit::VoxelMethod;
    using svokit::bench::Register;
    for (const Scene& s : g_scenes) {
      Register(s.name + "/triangle", Run, &s, VoxelMethod::kTriangle, 0.0);
      Register(s.name + "/fragment", Run, &s, VoxelMethod::kFragment, 0.0);
      for (double cutoff : {64.0, 1024.0, 4096.0, 16384.0}) {
        Register(s.name + "/hybrid_cutoff_" + std::to_string(int(cutoff)), Run, &s,
                 VoxelMethod::kHybrid, cutoff);
      }
    }
    return svokit::Status::Ok();
  });
}
