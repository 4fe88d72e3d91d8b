#include "svokit/svo/compact_svo.hpp"

#include <iterator>

#include <fmt/format.h>

#include "svokit/svo/svo_assembler.hpp"

namespace svokit {

Svo AssembleSvo(const CompactSvo& in) {
  SvoAssembler assembler(in.frame.shape, in.depth());
  assembler.Append(in.whole);
  return assembler.Finish(in.frame.grid, in.frame.mode, in.frame.metadata);
}

std::string LevelTable(const CompactSvo& svo) {
  std::string out = fmt::format("{:>5} {:>12} {:>12} {:>10} {:>12}\n", "level", "node size",
                                "nodes", "contours", "samples");
  std::uint64_t nodes = 0, contours = 0, samples = 0;
  for (std::uint32_t l = 0; l <= svo.depth(); ++l) {
    std::uint64_t c = 0;
    for (const std::uint32_t w : svo.whole.contours[l]) c += w != 0;
    const std::uint64_t s = l < svo.whole.layouts.size() ? svo.whole.layouts[l].size() : 0;
    const double size =
        svo.frame.grid.voxel_size() * static_cast<double>(std::uint64_t{1} << (svo.depth() - l));
    fmt::format_to(std::back_inserter(out), "{:>5} {:>12.6g} {:>12} {:>10} {:>12}\n", l, size,
                   svo.NodeCount(l), c, s);
    nodes += svo.NodeCount(l);
    contours += c;
    samples += s;
  }
  fmt::format_to(std::back_inserter(out), "{:>5} {:>12} {:>12} {:>10} {:>12}\n", "all", "", nodes,
                 contours, samples);
  return out;
}

}  // namespace svokit
