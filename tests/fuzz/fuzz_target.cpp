#include "tests/fuzz/fuzz_target.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>

#include "svokit/core/crc32c.hpp"
#include "svokit/core/grid_transform.hpp"
#include "svokit/formats/container/container.hpp"
#include "svokit/formats/svm/svm.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/mesh/mesh_report.hpp"
#include "svokit/svo/build_options.hpp"
#include "svokit/svo/compact_build.hpp"
#include "svokit/svo/compact_svo.hpp"
#include "svokit/voxelize/voxelize.hpp"

namespace svokit::fuzz {

namespace {

std::uint64_t Load64(const std::uint8_t* p) {
  std::uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}

}  // namespace

const std::filesystem::path& ScratchDir() {
  // Never destroyed: the exit handler that removes the folder runs after static destructors.
  static const std::filesystem::path* const dir = [] {
    std::string templ = (std::filesystem::temp_directory_path() / "svokit-fuzz-XXXXXX").string();
    if (::mkdtemp(templ.data()) == nullptr) Fail("cannot make a scratch folder");
    auto* path = new std::filesystem::path(templ);
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(ScratchDir(), ec);
    });
    return path;
  }();
  return *dir;
}

std::filesystem::path WriteScratch(const std::string& name, std::span<const std::uint8_t> bytes) {
  const std::filesystem::path path = ScratchDir() / name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
  if (!out.flush()) Fail("cannot write to the scratch folder");
  return path;
}

std::pair<std::span<const std::uint8_t>, std::span<const std::uint8_t>> SplitAtLine(
    std::span<const std::uint8_t> input, const std::string& marker) {
  const std::string line = "\n" + marker + "\n";
  const auto at = std::search(input.begin(), input.end(), line.begin(), line.end());
  if (at == input.end()) return {input, {}};
  const auto split = static_cast<std::size_t>(at - input.begin());
  return {input.first(split + 1), input.subspan(split + line.size())};
}

std::vector<std::uint8_t> WithChecksumsFixed(std::span<const std::uint8_t> bytes) {
  std::vector<std::uint8_t> out(bytes.begin(), bytes.end());
  using container::kHeaderSize;
  using container::kSectionEntrySize;
  if (out.size() < kHeaderSize) return out;
  std::uint32_t count;
  std::memcpy(&count, out.data() + 24, 4);
  if (count > (out.size() - kHeaderSize) / kSectionEntrySize) return out;
  for (std::uint32_t i = 0; i < count; ++i) {
    std::uint8_t* entry = out.data() + kHeaderSize + std::size_t{i} * kSectionEntrySize;
    const std::uint64_t offset = Load64(entry + 8), size = Load64(entry + 16);
    if (offset > out.size() || size > out.size() - offset) continue;
    const std::uint32_t crc = Crc32c(out.data() + offset, static_cast<std::size_t>(size));
    std::memcpy(entry + 24, &crc, 4);
  }
  std::uint32_t crc = Crc32c(out.data(), 28);
  crc = Crc32c(out.data() + kHeaderSize, std::size_t{count} * kSectionEntrySize, crc);
  std::memcpy(out.data() + 28, &crc, 4);
  return out;
}

void CheckOctreeFile(const CompactSvo& svo) {
  const std::vector<std::uint8_t> bytes = EncodeSvo(svo);
  StatusOr<Svo> back = DecodeSvo(bytes, "round-trip.svo");
  if (!back.ok()) Fail("an octree's own file does not decode");
  if (!(*back == AssembleSvo(svo))) Fail("an octree's own file decodes to another octree");
  if (EncodeSvo(svo) != bytes) Fail("an octree's file is not the same twice");
}

void CheckMesh(const Mesh& mesh) {
  (void)AnalyzeMesh(mesh, "fuzz", ReportOptions{});
  const std::vector<std::uint8_t> svm = EncodeSvm(mesh, "fuzz");
  StatusOr<Mesh> again = DecodeSvm(svm, "round-trip.svm");
  if (!again.ok()) Fail("an imported mesh's .svm does not decode");
  if (EncodeSvm(*again, "fuzz") != svm) Fail("an imported mesh's .svm round trip differs");

  StatusOr<GridTransform> grid = GridTransform::FitResolution(mesh.Bounds(), 8);
  if (!grid.ok()) return;
  VoxelizeOptions voxelize;
  voxelize.colors = voxelize.normals = true;
  StatusOr<VoxelSet> voxels = Voxelize(mesh, *grid, voxelize);
  if (!voxels.ok()) return;
  StatusOr<CompactSvo> svo = BuildCompactSvo(*voxels, &mesh, BuildOptions{});
  if (!svo.ok()) return;
  CheckOctreeFile(*svo);
}

void ExpectAccepted(const Status& status, std::size_t size) {
  if (status.ok() || size == 0 || std::getenv("SVOKIT_FUZZ_VALID_INPUTS") == nullptr) return;
  std::fprintf(stderr, "a seed is refused: %s\n", status.message().c_str());
  std::abort();
}

void Fail(const char* what) {
  std::fprintf(stderr, "fuzz check failed: %s\n", what);
  std::abort();
}

}  // namespace svokit::fuzz
