#include "bench_main.hpp"

#include <cstdio>
#include <filesystem>

#include "svokit/formats/mesh_import.hpp"

namespace svokit::bench {

StatusOr<Scene> LoadScene(const std::string& path, std::uint32_t resolution) {
  StatusOr<Mesh> mesh = ImportMesh(path);
  if (!mesh.ok()) return mesh.status();
  StatusOr<GridTransform> grid = GridTransform::FitResolution(mesh->Bounds(), resolution);
  if (!grid.ok()) return grid.status();
  return Scene{std::filesystem::path(path).stem().string(), std::move(mesh).value(), *grid};
}

int Main(int argc, char** argv, bool with_resolution,
         const std::function<Status(const Inputs&)>& setup) {
  std::vector<char*> flags = {argv[0]};
  Inputs inputs;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (with_resolution && a == "--resolution" && i + 1 < argc) {
      inputs.resolution = static_cast<std::uint32_t>(std::stoul(argv[++i]));
    } else if (a.rfind("--", 0) == 0) {
      flags.push_back(argv[i]);
    } else {
      inputs.files.push_back(a);
    }
  }
  if (Status s = setup(inputs); !s.ok()) {
    std::fprintf(stderr, "%s: %s\n", std::filesystem::path(argv[0]).filename().c_str(),
                 s.message().c_str());
    return 2;
  }
  int n = static_cast<int>(flags.size());
  benchmark::Initialize(&n, flags.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

}  // namespace svokit::bench
