#pragma once
// A writer of version-1 .svo files (formats/svo.md, "Version 1"), which svokit reads but
// no longer writes: the suite makes them to test that reader, and to hand the validator octrees
// damaged on purpose (a version-1 file stores every node's brick as it is).

#include <cstdint>
#include <span>
#include <vector>

#include "svokit/core/bytes.hpp"
#include "svokit/formats/container/container.hpp"
#include "svokit/formats/container/grid_section.hpp"
#include "svokit/formats/svo/svo_file.hpp"

namespace svokit::test {

inline std::vector<std::uint8_t> EncodeSvoV1(const Svo& svo) {
  const container::FormatId v1{kSvoFormat.magic, 1, kSvoFormat.name};
  container::Writer file(v1, 0);
  const auto bytes = [](const auto& v) {
    const auto* p = reinterpret_cast<const std::uint8_t*>(v.data());
    return std::vector<std::uint8_t>(p, p + v.size() * sizeof(v[0]));
  };
  const auto tag = [](const char(&kind)[3], std::uint32_t level) {
    return container::Tag{kind[0], kind[1], static_cast<char>('0' + level / 10),
                          static_cast<char>('0' + level % 10)};
  };
  file.AddSection(container::MakeTag("GRID"), EncodeGridSection(svo.grid, svo.mode));
  ByteWriter head;
  head.Put(svo.depth);
  head.Put(svo.brick_side);
  head.Put((svo.has_color ? 1u : 0u) | (svo.has_normal ? 2u : 0u) | (svo.has_contours ? 4u : 0u));
  head.Put(static_cast<std::uint32_t>(svo.levels.size()));
  for (const SvoLevel& lv : svo.levels) {
    head.Put(lv.node_count);
    head.Put(static_cast<std::uint64_t>(lv.contours.size()));
  }
  file.AddSection(container::MakeTag("HEAD"), std::move(head.bytes()));
  for (std::uint32_t l = 0; l < svo.levels.size(); ++l) {
    const SvoLevel& lv = svo.levels[l];
    if (!lv.nodes.empty()) file.AddSection(tag("ND", l), bytes(lv.nodes));
    if (!lv.opacity.empty()) file.AddSection(tag("OP", l), bytes(lv.opacity));
    if (!lv.color.empty()) file.AddSection(tag("CL", l), bytes(lv.color));
    if (!lv.normal.empty()) file.AddSection(tag("NM", l), bytes(lv.normal));
    if (!lv.contours.empty()) file.AddSection(tag("CT", l), bytes(lv.contours));
  }
  file.AddSection(container::MakeTag("META"),
                  std::vector<std::uint8_t>(svo.metadata.begin(), svo.metadata.end()));
  return file.Serialize();
}

}  // namespace svokit::test
