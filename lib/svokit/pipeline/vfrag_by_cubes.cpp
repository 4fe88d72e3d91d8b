#include "svokit/pipeline/vfrag_by_cubes.hpp"

#include <memory>

#include "svokit/core/morton.hpp"
#include "svokit/core/parallel.hpp"

namespace svokit {

StatusOr<std::uint64_t> WriteVfragByCubes(const RegionVoxelizer& voxelizer, const Provenance& meta,
                                          const std::filesystem::path& path,
                                          std::uint64_t memory_limit, Progress& progress) {
  constexpr int kCubeBits = 7;
  RegionVoxelizer::Bins bins;
  {
    Progress::Stage stage(progress, "bin", 1);
    bins = voxelizer.BinTriangles(kCubeBits, 0);
  }
  // Held whatever the cube: the snapped mesh and the bins; then per cube in flight at most a
  // surface's voxels across it with their keys and attributes (~24 B a voxel).
  const std::uint64_t fixed = voxelizer.bytes() + bins.bytes();
  const std::uint64_t cube = std::uint64_t{24} * 4 << (2 * kCubeBits);
  const StatusOr<std::size_t> in_flight = InFlightWithin(
      memory_limit, fixed, cube, cube, "this mesh and grid", "its bins and one cube");
  if (!in_flight.ok()) return in_flight.status();

  const VoxelizeOptions& options = voxelizer.options();
  const std::optional<HalfRgba> shared =
      voxelizer.shared_color() ? std::optional<HalfRgba>(HalfRgba(*voxelizer.shared_color()))
                               : std::nullopt;
  StatusOr<std::unique_ptr<VfragStreamWriter>> file = VfragStreamWriter::Create(
      path, voxelizer.grid(), options.mode, options.colors, options.normals, shared, meta);
  if (!file.ok()) return file.status();
  {
    Progress::Stage stage(progress, "cubes", bins.cells.size());
    struct Cube {
      StatusOr<VoxelSet> voxels = Status::Ok();
    };
    SVOKIT_RETURN_IF_ERROR(ParallelInOrder<Cube>(
        0, bins.cells.size(), *in_flight,
        [&](std::size_t i) {
          const MortonCoord c = MortonDecode(bins.cells[i]);
          const std::int64_t s = std::int64_t{1} << kCubeBits;
          const IBox3 box{{c.x * s, c.y * s, c.z * s}, {c.x * s + s, c.y * s + s, c.z * s + s}};
          return Cube{voxelizer.Voxelize(box, bins.Of(i))};
        },
        [&](Cube made) -> Status {
          stage.Advance(1);
          if (!made.voxels.ok()) return made.voxels.status();
          StatusOr<std::uint64_t> bytes = (*file)->Append(*made.voxels);
          if (!bytes.ok()) return bytes.status();
          stage.AddBytes(*bytes);
          return Status::Ok();
        }));
  }
  // No voxels: Commit() refuses, naming the file, and no write stage begins.
  if ((*file)->voxel_count() == 0) return (*file)->Commit();
  Progress::Stage stage(progress, "write", 1);
  SVOKIT_RETURN_IF_ERROR((*file)->Commit());
  return (*file)->voxel_count();
}

}  // namespace svokit
