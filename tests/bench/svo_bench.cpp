// Octree build stages in one process, on voxels made once: the structure alone, 3³ bricks,
// contours, and all together (what mesh2svo's "bricks" and "contours" stages time, without the
// process, import, voxelization and write around them).
//
//   svo_bench --resolution N MESH... [benchmark flags]

#include <string>
#include <vector>

#include "bench_main.hpp"
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
  return svokit::bench::Main(argc, argv, true, [](const svokit::bench::Inputs& inputs) {
    for (const std::string& f : inputs.files) {
      auto scene = svokit::bench::LoadScene(f, inputs.resolution);
      if (!scene.ok()) return scene.status();
      auto voxels = svokit::Voxelize(scene->mesh, scene->grid, svokit::VoxelizeOptions{});
      if (!voxels.ok()) return voxels.status();
      g_scenes.push_back({scene->name, std::move(scene->mesh), std::move(voxels).value()});
    }
    for (const Scene& s : g_scenes) {
      const struct {
        const char* name;
        std::uint32_t brick_side;
        bool contours;
      } variants[] = {
          {"octree", 0, false}, {"bricks", 3, false}, {"contours", 0, true}, {"full", 3, true}};
      for (const auto& v : variants) {
        svokit::bench::Register(s.name + "/" + v.name, Build, &s, v.brick_side, v.contours);
      }
    }
    return svokit::Status::Ok();
  });
}
