// Import throughput on ≥1 M-triangle meshes, svokit's importers against OpenMesh's readers in the
// same run. The inputs are a real mesh (CGAL's bunny by default) refined by Loop subdivision and
// written as OBJ, binary PLY and ASCII PLY — all by OpenMesh, so the peer reads its own output.
//
//   build/tests/bench/import_bench [--mesh M.off] [--levels 2] [--cache DIR] [benchmark flags]

#include <benchmark/benchmark.h>

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Subdivider/Uniform/LoopT.hh>

#include <cstdio>
#include <filesystem>
#include <string>

#include "svokit/mesh/import.hpp"

namespace {

using OmMesh = OpenMesh::TriMesh_ArrayKernelT<>;

std::filesystem::path g_cache = "build/bench-data";
std::filesystem::path g_source = SVOKIT_CGAL_MESHES "/bunny00.off";
int g_levels = 2;

std::filesystem::path BenchFile(const std::string& ext) {
  return g_cache / (g_source.stem().string() + "-loop" + std::to_string(g_levels) + ext);
}

// Writes the subdivided mesh once; later runs reuse the files.
bool PrepareInputs() {
  std::filesystem::create_directories(g_cache);
  if (std::filesystem::exists(BenchFile(".ascii.ply"))) return true;
  OmMesh mesh;
  if (!OpenMesh::IO::read_mesh(mesh, g_source.string())) {
    std::fprintf(stderr, "import_bench: cannot read %s\n", g_source.c_str());
    return false;
  }
  OpenMesh::Subdivider::Uniform::LoopT<OmMesh> loop;
  loop.attach(mesh);
  loop(static_cast<std::size_t>(g_levels));
  loop.detach();
  std::fprintf(stderr, "import_bench: %s refined to %zu triangles\n", g_source.c_str(),
               mesh.n_faces());
  OpenMesh::IO::Options binary(OpenMesh::IO::Options::Binary);
  return OpenMesh::IO::write_mesh(mesh, BenchFile(".obj").string()) &&
         OpenMesh::IO::write_mesh(mesh, BenchFile(".ply").string(), binary) &&
         OpenMesh::IO::write_mesh(mesh, BenchFile(".ascii.ply").string());
}

void SvokitImport(benchmark::State& state, const std::string& ext) {
  const auto path = BenchFile(ext);
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

void OpenMeshRead(benchmark::State& state, const std::string& ext) {
  const auto path = BenchFile(ext).string();
  std::size_t triangles = 0;
  for (auto _ : state) {
    OmMesh mesh;
    if (!OpenMesh::IO::read_mesh(mesh, path)) {
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
  // Our own flags first; the rest go to Google Benchmark.
  std::vector<char*> rest = {argv[0]};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--mesh" && i + 1 < argc) {
      g_source = argv[++i];
    } else if (a == "--levels" && i + 1 < argc) {
      g_levels = std::stoi(argv[++i]);
    } else if (a == "--cache" && i + 1 < argc) {
      g_cache = argv[++i];
    } else {
      rest.push_back(argv[i]);
    }
  }
  if (!PrepareInputs()) return 2;
  for (const std::string ext : {".obj", ".ply", ".ascii.ply"}) {
    benchmark::RegisterBenchmark(("svokit_import" + ext).c_str(), SvokitImport, ext)
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
    benchmark::RegisterBenchmark(("openmesh_read" + ext).c_str(), OpenMeshRead, ext)
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
  }
  int n = static_cast<int>(rest.size());
  benchmark::Initialize(&n, rest.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
