// Import throughput on ≥1 M-triangle meshes: svokit's importers against OpenMesh's readers on
// the same files, in the same run. scripts/bench makes the inputs (a real mesh refined by Loop
// subdivision, written by OpenMesh as OBJ, binary PLY and ASCII PLY).
//
//   import_bench FILE... [benchmark flags]

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include <filesystem>
#include <string>
#include <vector>

#include "bench_main.hpp"
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
  return svokit::bench::Main(argc, argv, false, [](const svokit::bench::Inputs& inputs) {
    for (const std::filesystem::path f : inputs.files) {
      const std::string name = f.filename().string();
      svokit::bench::Register("svokit_import/" + name, SvokitImport, f);
      svokit::bench::Register("openmesh_read/" + name, OpenMeshRead, f);
    }
    return svokit::Status::Ok();
  });
}
