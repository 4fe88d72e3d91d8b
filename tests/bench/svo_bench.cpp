// Octree build stages in one process, on voxels made once (colours and normals): the structure
// alone, 3³ bricks, contours, and all together, as mesh2svo builds them (BuildCompactSvo: what its
// "octree", "bricks" and "contours" stages time, without the process, import, voxelization and
// write around them); and the per-node reference builder (BuildReferenceSvo, version 1's octree) in
// full.
//
//   svo_bench --resolution N MESH... [benchmark flags]

#include <string>
#include <vector>

#include "bench_main.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/svo/compact_svo.hpp"
#include "svokit/svo/reference_build.hpp"
#include "svokit/voxelize/voxelize.hpp"

namespace {

struct Scene {
  std::string name;
  svokit::Mesh mesh;
  svokit::VoxelSet voxels;
};
std::vector<Scene> g_scenes;

void Build(benchmark::State& state, const Scene* scene, std::uint32_t brick_side, bool contours,
           bool reference) {
  svokit::BuildOptions options;
  options.brick_side = brick_side;
  options.contours = contours;
  for (auto _ : state) {
    if (reference) {
      auto svo = svokit::BuildReferenceSvo(scene->voxels, &scene->mesh, options);
      if (!svo.ok()) {
        state.SkipWithError(svo.status().message().c_str());
        return;
      }
      benchmark::DoNotOptimize(svo->levels.data());
    } else {
      auto svo = svokit::BuildCompactSvo(scene->voxels, &scene->mesh, options);
      if (!svo.ok()) {
        state.SkipWithError(svo.status().message().c_str());
        return;
      }
      benchmark::DoNotOptimize(svo->whole.tree.masks.data());
    }
  }
  state.counters["voxels"] = static_cast<double>(scene->voxels.size());
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(scene->voxels.size()));
}

}  // namespace

int main(int argc, char** argv) {
  return svokit::bench::Main(argc, argv, true, [](const svokit::bench::Inputs& inputs) {
    for (const std::string& f : inputs.files) {
      auto scene = svokit::bench::LoadScene(f, inputs.resolution);
      if (!scene.ok()) return scene.status();
      svokit::VoxelizeOptions vo;
      vo.colors = vo.normals = true;
      auto voxels = svokit::Voxelize(scene->mesh, scene->grid, vo);
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
        svokit::bench::Register(s.name + "/" + v.name, Build, &s, v.brick_side, v.contours, false);
      }
      svokit::bench::Register(s.name + "/reference_full", Build, &s, 3u, true, true);
    }
    return svokit::Status::Ok();
  });
}
