#pragma once
// A paged .svo of a real mesh that several test programs read: the textured torus at 512³ (pages
// of 128³: a few dozen), 3³ bricks, colour, normal and contours, written once per test program.

#include <unistd.h>

#include <filesystem>
#include <string>

#include "svokit/formats/mesh_import.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/voxelize/voxelize.hpp"
#include "tests/test_util.hpp"

namespace svokit::test {

struct PagedFile {
  VoxelSet voxels;
  std::filesystem::path path;  ///< removed when the test program ends
  PagedFile() = default;
  PagedFile(PagedFile&&) = default;
  ~PagedFile() {
    std::error_code ec;
    if (!path.empty()) std::filesystem::remove(path, ec);
  }
};

/// `mesh_path` voxelized at `resolution` with colour and normal, built with 3³ bricks and
/// contours, written to a temporary named after `name` and the process (removed with the result).
inline PagedFile BuildPagedFile(const std::filesystem::path& mesh_path, std::uint32_t resolution,
                                const std::string& name) {
  PagedFile out;
  auto mesh = ImportMesh(mesh_path);
  EXPECT_TRUE(mesh.ok()) << mesh.status().message();
  auto grid = GridTransform::FitResolution(mesh->Bounds(), resolution);
  VoxelizeOptions vo;
  vo.colors = vo.normals = true;
  auto voxels = Voxelize(*mesh, *grid, vo);
  EXPECT_TRUE(voxels.ok());
  out.voxels = std::move(*voxels);
  BuildOptions bo;
  bo.brick_side = 3;
  auto svo = BuildCompactSvo(out.voxels, &*mesh, bo, R"({"source":"test"})");
  EXPECT_TRUE(svo.ok());
  // Every test process (ctest runs them side by side) writes its own.
  out.path = std::filesystem::temp_directory_path() /
             ("svokit_" + name + "_" + std::to_string(::getpid()) + ".svo");
  EXPECT_TRUE(WriteSvo(*svo, out.path).ok());
  return out;
}

inline const PagedFile& PagedTorus() {
  static const PagedFile f = BuildPagedFile(test::DataDir() / "uv-torus.obj", 512, "paged_torus");
  return f;
}

inline SvoReader OpenPagedTorus() {
  StatusOr<SvoReader> r = SvoReader::Open(PagedTorus().path);
  EXPECT_TRUE(r.ok()) << r.status().message();
  return std::move(*r);
}

}  // namespace svokit::test
