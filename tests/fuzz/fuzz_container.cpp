// One fuzz target per svokit file format: SVOKIT_FUZZ_FORMAT is svm, vfrag or svo. Each input is
// decoded twice: as it is (the frame's checks), and with its checksums recomputed (the decoders
// behind them). What decodes must encode back to a file that decodes to the same thing (an
// octree: the lenient reader reads it as the strict one does); a mesh must also pass the mesh
// targets' checks.

#include <string_view>

#include "svokit/core/parallel.hpp"

#include "svokit/formats/svm/svm.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/vfrag/vfrag.hpp"
#include "tests/fuzz/fuzz_target.hpp"

namespace svokit::fuzz {
namespace {

constexpr std::string_view kFormat = SVOKIT_FUZZ_FORMAT;

void Decode(std::span<const std::uint8_t> bytes) {
  if constexpr (kFormat == "svm") {
    StatusOr<Mesh> mesh = DecodeSvm(bytes, "fuzz.svm");
    ExpectAccepted(mesh.status(), bytes.size());
    if (mesh.ok()) CheckMesh(*mesh);
  } else if constexpr (kFormat == "vfrag") {
    VfragMetadata meta;
    StatusOr<VoxelSet> set = DecodeVfrag(bytes, "fuzz.vfrag", &meta);
    ExpectAccepted(set.status(), bytes.size());
    if (set.ok()) {
      const std::vector<std::uint8_t> encoded = EncodeVfrag(*set, meta);
      StatusOr<VoxelSet> again = DecodeVfrag(encoded, "again.vfrag");
      if (!again.ok() || EncodeVfrag(*again, meta) != encoded)
        Fail("a decoded .vfrag does not round-trip");
    }
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
