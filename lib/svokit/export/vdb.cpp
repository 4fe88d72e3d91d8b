// The only translation unit that sees OpenVDB's headers: they are heavy to compile, and the rest
// of svokit stays free of them.

#include <mutex>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include "svokit/core/file_io.hpp"
#include "svokit/export/voxel_writers.hpp"

namespace svokit {

namespace {

// OpenVDB's grid type registry must be filled before any grid is written.
void InitializeOpenVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

}  // namespace

Status WriteVoxelsVdb(const VoxelSet& voxels, const std::filesystem::path& path) {
  InitializeOpenVdb();
  const double h = voxels.grid.voxel_size();
  const Vec3d& o = voxels.grid.origin();
  // OpenVDB's index coordinates are voxel centres: index (i, j, k) ↦ origin + (i + ½)·h.
  openvdb::math::Transform::Ptr transform = openvdb::math::Transform::createLinearTransform(h);
  transform->postTranslate(openvdb::Vec3d(o.x + 0.5 * h, o.y + 0.5 * h, o.z + 0.5 * h));

  auto occupancy = openvdb::BoolGrid::create(false);
  occupancy->setName("occupancy");
  auto color = openvdb::Vec3fGrid::create(openvdb::Vec3f(0.f));
  color->setName("color");
  color->setVectorType(openvdb::VEC_INVARIANT);
  color->insertMeta("color_space", openvdb::StringMetadata("linear sRGB"));
  auto normal = openvdb::Vec3fGrid::create(openvdb::Vec3f(0.f));
  normal->setName("normal");
  normal->setVectorType(openvdb::VEC_COVARIANT_NORMALIZE);

  auto occupied = occupancy->getAccessor();
  auto colored = color->getAccessor();
  auto oriented = normal->getAccessor();
  for (std::size_t i = 0; i < voxels.size(); ++i) {
    const MortonCoord c = MortonDecode(voxels.keys[i]);
    const openvdb::Coord ijk(static_cast<openvdb::Int32>(c.x), static_cast<openvdb::Int32>(c.y),
                             static_cast<openvdb::Int32>(c.z));
    occupied.setValueOn(ijk, true);
    if (voxels.has_colors()) {
      const Rgba rgba = voxels.color(i);
      colored.setValueOn(ijk, openvdb::Vec3f(rgba.r, rgba.g, rgba.b));
    }
    if (voxels.has_normals()) {
      const Vec3f& n = voxels.normals[i];
      oriented.setValueOn(ijk, openvdb::Vec3f(n.x, n.y, n.z));
    }
  }

  openvdb::GridPtrVec grids{occupancy};
  if (voxels.has_colors()) grids.push_back(color);
  if (voxels.has_normals()) grids.push_back(normal);
  for (const openvdb::GridBase::Ptr& grid : grids) grid->setTransform(transform);

  AtomicFileWriter temp(path);
  SVOKIT_RETURN_IF_ERROR(temp.Open());
  try {
    openvdb::io::File file(temp.temp_path());
    openvdb::MetaMap meta;
    meta.insertMeta("creator", openvdb::StringMetadata(std::string("svokit ") + SVOKIT_VERSION));
    file.write(grids, meta);
    file.close();
  } catch (const openvdb::Exception& e) {
    return Status::Internal("{}: OpenVDB could not write the file ({})", path.string(), e.what());
  }
  return temp.Commit();
}

}  // namespace svokit
