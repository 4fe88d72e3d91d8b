// svo-format-dump FILE [-o OUT.json]: what svokit's C++ readers make of a .svm, .vfrag or .svo, as
// the golden files' JSON (formats/golden/README.md, "The JSON"). Other readers of the formats
// (formats/python) are checked against it on files made in their tests.
#include <cstdio>
#include <fstream>
#include <string>

#include "tests/formats/golden_dump.hpp"

int main(int argc, char** argv) {
  if (argc != 2 && !(argc == 4 && std::string(argv[2]) == "-o")) {
    std::fprintf(stderr, "usage: %s FILE [-o OUT.json]\n", argv[0]);
    return 2;
  }
  svokit::StatusOr<svokit::test::Json> dump = svokit::test::DumpFormatFile(argv[1]);
  if (!dump.ok()) {
    std::fprintf(stderr, "%s\n", dump.status().message().c_str());
    return dump.status().exit_code();
  }
  const std::string text = svokit::test::FormatJson(*dump);
  if (argc == 2) {
    std::fwrite(text.data(), 1, text.size(), stdout);
    return 0;
  }
  std::ofstream out(argv[3], std::ios::binary);
  out << text;
  out.close();
  if (!out) {
    std::fprintf(stderr, "%s: cannot write\n", argv[3]);
    return 1;
  }
  return 0;
}
