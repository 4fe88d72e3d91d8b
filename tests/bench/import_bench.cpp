// Import throughput on ≥1 M-triangle meshes: svokit's importers against OpenMesh's readers on
// the same files, in the same run. scripts/bench makes the inputs (a real mesh refined by Loop
// subdivision, written by OpenMesh as OBJ, binary PLY and ASCII PLY).
//
//   import_bench FILE... [benchmark flags]

#include <benchmark/benchmark.h>

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include <filesystem>
#include <string>
#include <vector>

#include "svokit/formats/mesh_import.hpp"

namespace {

using OmMesh = OpenMesh::TriMesh_ArrayKernelT<>;

void SvokitImport(benchmark::State& state, const std::filesystem::path& path) {
  std::size_t triangles = 0;
  for (auto _ : state) {
    auto mesh = svokit::ImportMesh(path);
    if (!mesh.ok()) {
      state.SkipWithError(mesh.status().message().c_str());
      return;
    }
    triangles = mesh->triangle_count();
    benchmark::DoNotOptimize(mesh->positions.data());
  }
  state.counters["triangles"] = static_cast<double>(triangles);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(triangles));
  state.SetBytesProcessed(state.iterations() *
                          static_cast<std::int64_t>(std::filesystem::file_size(path)));
}

void OpenMeshRead(benchmark::State& state, const std::filesystem::path& path) {
  std::size_t triangles = 0;
  for (auto _ : state) {
    OmMesh mesh;
    if (!OpenMesh::IO::read_mesh(mesh, path.string())) {
      state.SkipWithError("OpenMesh could not read the file");
      return;
    }
    triangles = mesh.n_faces();
    benchmark::DoNotOptimize(mesh.points());
  }
  state.counters["triangles"] = static_cast<double>(triangles);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(triangles));
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<char*> rest = {argv[0]};
  std::vector<std::filesystem::path> files;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]).rfind("--", 0) == 0) {
      rest.push_back(argv[i]);
    } else {
      files.emplace_back(argv[i]);
    }
  }
  for (const auto& f : files) {
    const std::string name = f.filename().string();
    benchmark::RegisterBenchmark(("svokit_import/" + name).c_str(), SvokitImport, f)
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
    benchmark::RegisterBenchmark(("openmesh_read/" + name).c_str(), OpenMeshRead, f)
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
  }
  int n = static_cast<int>(rest.size());
  benchmark::Initialize(&n, rest.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
