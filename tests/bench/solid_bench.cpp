#include <chrono>
#include <cstdio>
#include <cstdlib>
#include "svokit/formats/mesh_import.hpp"
#include "svokit/voxelize/solid_fill.hpp"
#include "svokit/voxelize/voxelize.hpp"
using namespace svokit;
int main(int, char** argv) {
  auto mesh = ImportMesh(argv[1]);
  if (!mesh.ok()) {
    std::puts(mesh.status().message().c_str());
    return 1;
  }
  const auto grid = GridTransform::FitResolution(mesh->Bounds(), std::atoi(argv[2]));
  VoxelizeOptions o;
  o.colors = o.normals = argv[3] != nullptr;
  auto t0 = std::chrono::steady_clock::now();
  auto vs = Voxelize(*mesh, *grid, o);
  auto t1 = std::chrono::steady_clock::now();
  Progress progress(Progress::Style::kLines);
  auto in = FillInterior(
      *mesh, *grid, std::span<const std::uint64_t>(vs->keys.data(), vs->keys.size()), {}, progress);
  auto t2 = std::chrono::steady_clock::now();
  if (!in.ok()) {
    std::puts(in.status().message().c_str());
    return 1;
  }
  std::printf("surface %zu voxels %.3f s; fill %.3f s method %d open %llu cubes %llu voxels %llu\n",
              vs->size(), std::chrono::duration<double>(t1 - t0).count(),
              std::chrono::duration<double>(t2 - t1).count(), (int)in->method,
              (unsigned long long)in->open_edges, (unsigned long long)in->cube_count(),
              (unsigned long long)in->voxel_count());
  for (size_t l = 0; l < in->levels.size(); ++l) std::printf(" L%zu:%zu", l, in->levels[l].size());
  std::puts("");
}
