// svo-v1-writer IN.svo -o OUT.svo: IN's octree written again as a version-1 .svo, which no tool
// writes any more; the maker of the golden version-1 file (formats/golden/commands).

#include <cstdio>
#include <string>

#include "svokit/core/file_io.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/svo/svo_reader.hpp"
#include "tests/formats/svo_v1_writer.hpp"

int main(int argc, char** argv) {
  if (argc != 4 || std::string(argv[2]) != "-o") {
    std::fprintf(stderr, "usage: svo-v1-writer IN.svo -o OUT.svo\n");
    return 2;
  }
  const svokit::StatusOr<svokit::Svo> svo = svokit::ReadSvo(argv[1]);
  if (!svo.ok()) {
    std::fprintf(stderr, "svo-v1-writer: %s\n", svo.status().message().c_str());
    return 1;
  }
  // Version 1's bricks are by filter 1: a newer file's would be mislabelled.
  if (const auto reader = svokit::SvoReader::Open(argv[1]);
      reader.ok() && svokit::BrickFilterOfVersion(reader->version()) != 1) {
    std::fprintf(stderr,
                 "svo-v1-writer: %s is a version-%u file, whose bricks version 1 cannot "
                 "hold\n",
                 argv[1], reader->version());
    return 1;
  }
  // Version 1 has neither full leaves nor AO: such an octree would lose them.
  if (svo->solid || svo->has_ao) {
    std::fprintf(stderr, "svo-v1-writer: %s has full leaves or AO, which version 1 cannot hold\n",
                 argv[1]);
    return 1;
  }
  const svokit::Status written = svokit::WriteFileAtomic(argv[3], svokit::test::EncodeSvoV1(*svo));
  if (!written.ok()) {
    std::fprintf(stderr, "svo-v1-writer: %s\n", written.message().c_str());
    return 1;
  }
  return 0;
}
