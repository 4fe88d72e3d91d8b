// One fuzz target per svokit file format: SVOKIT_FUZZ_FORMAT is svm, vfrag or svo. Each input is
// decoded twice: as it is (the frame's checks), and with its checksums recomputed (the decoders
// behind them). What decodes must encode back to a file that decodes to the same thing (an
// octree: the lenient reader reads it as the strict one does); a mesh must also pass the mesh
// targets' checks.

#include <sys/mman.h>
#include <unistd.h>

#include <cstring>
#include <string>
#include <string_view>

#include "svokit/core/morton.hpp"
#include "svokit/core/thread_limit.hpp"

#include "svokit/formats/svm/svm.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/vfrag/vfrag.hpp"
#include "tests/fuzz/fuzz_target.hpp"

namespace svokit::fuzz {
namespace {

constexpr std::string_view kFormat = SVOKIT_FUZZ_FORMAT;

// The cube-by-cube reader (svo-build --memory-limit) accepts a version-5 file exactly when the
// whole reader does, and reads the same voxels from it, whole and a half at a time.
[[maybe_unused]] void CheckCubes(std::span<const std::uint8_t> bytes,
                                 const StatusOr<VoxelSet>& whole) {
  std::uint32_t version = 0;
  if (bytes.size() >= 12) std::memcpy(&version, bytes.data() + 8, sizeof version);
  if (version != kVfragFormat.version) return;
  const int fd = ::memfd_create("fuzz.vfrag", MFD_CLOEXEC);
  if (fd < 0) return;
  if (::write(fd, bytes.data(), bytes.size()) != static_cast<ssize_t>(bytes.size())) {
    ::close(fd);
    return;
  }
  StatusOr<std::unique_ptr<VfragCubes>> cubes =
      VfragCubes::Open("/proc/self/fd/" + std::to_string(fd), 2);
  ::close(fd);  // the reader holds a descriptor of its own
  if (cubes.ok() != whole.ok()) {
    Fail(whole.ok() ? "VfragCubes refuses a .vfrag ReadVfrag accepts"
                    : "VfragCubes accepts a .vfrag ReadVfrag refuses");
  }
  if (!cubes.ok() || !whole.ok()) return;
  const auto& d = whole->grid.dims();
  const std::int64_t half = (d[0] + 1) / 2;
  for (const IBox3& box :
       {IBox3{{0, 0, 0}, {d[0], d[1], d[2]}}, IBox3{{0, 0, 0}, {half, d[1], d[2]}}}) {
    StatusOr<VoxelSet> read = (*cubes)->Read(box);
    if (!read.ok()) Fail("VfragCubes cannot read a box of a file it opened");
    std::size_t k = 0;
    for (std::size_t i = 0; i < whole->keys.size(); ++i) {
      if (MortonDecode(whole->keys[i]).x >= static_cast<std::uint64_t>(box.hi.x)) continue;
      const bool same = k < read->keys.size() && read->keys[k] == whole->keys[i] &&
                        (whole->colors.empty() || read->color(k) == whole->color(i)) &&
                        (whole->normals.empty() || read->normals[k] == whole->normals[i]) &&
                        (whole->coverage.empty() || read->coverage[k] == whole->coverage[i]);
      if (!same) Fail("VfragCubes reads other voxels than ReadVfrag");
      ++k;
    }
    if (k != read->keys.size()) Fail("VfragCubes reads more voxels than ReadVfrag");
  }
}

void Decode(std::span<const std::uint8_t> bytes) {
  if constexpr (kFormat == "svm") {
    StatusOr<Mesh> mesh = DecodeSvm(bytes, "fuzz.svm");
    ExpectAccepted(mesh.status(), bytes.size());
    if (mesh.ok()) CheckMesh(*mesh);
  } else if constexpr (kFormat == "vfrag") {
    Provenance meta;
    StatusOr<VoxelSet> set = DecodeVfrag(bytes, "fuzz.vfrag", &meta);
    ExpectAccepted(set.status(), bytes.size());
    if (set.ok()) {
      const std::vector<std::uint8_t> encoded = EncodeVfrag(*set, meta);
      StatusOr<VoxelSet> again = DecodeVfrag(encoded, "again.vfrag");
      if (!again.ok() || EncodeVfrag(*again, meta) != encoded)
        Fail("a decoded .vfrag does not round-trip");
    }
    CheckCubes(bytes, set);
  } else {
    StatusOr<Svo> svo = DecodeSvo(bytes, "fuzz.svo");
    ExpectAccepted(svo.status(), bytes.size());
    StatusOr<LenientSvo> lenient = DecodeSvoLenient(bytes, "fuzz.svo");
    if (svo.ok() && (!lenient.ok() || !lenient->complete || !lenient->issues.empty() ||
                     !(lenient->svo == *svo))) {
      Fail("the lenient reader does not read a file the strict reader accepts the same way");
    }
  }
}

}  // namespace
}  // namespace svokit::fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static svokit::ThreadLimit one_thread(1);  // the same coverage for the same input
  const std::span<const std::uint8_t> input(data, size);
  svokit::fuzz::Decode(input);
  svokit::fuzz::Decode(svokit::fuzz::WithChecksumsFixed(input));
  return 0;
}
