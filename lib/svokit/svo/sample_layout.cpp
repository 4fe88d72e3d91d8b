#include "svokit/svo/sample_layout.hpp"

namespace svokit {

namespace layout_detail {
namespace {

constexpr SideTable MakeSideTable(int side) {
  SideTable t;
  t.side = static_cast<std::uint32_t>(side);
  const int top = side - 1;
  t.home_count = static_cast<std::uint32_t>(top * top * top);
  int homes = 0, others = 0;
  for (int s = 0; s < side * side * side; ++s) {
    const int k[3] = {s % side, s / side % side, s / (side * side)};
    for (int a = 0; a < 3; ++a) t.coord[s][a] = static_cast<std::uint8_t>(k[a]);
    t.is_home[s] = k[0] < top && k[1] < top && k[2] < top;
    t.index[s] = static_cast<std::uint8_t>(t.is_home[s] ? homes++ : others++);
    if (!t.is_home[s]) continue;
    HomeSample& home = t.home[t.index[s]];
    for (int f = 1; f < 8; ++f) {
      const int fa[3] = {f & 1, f >> 1 & 1, f >> 2 & 1};
      bool holds = true;
      for (int a = 0; a < 3; ++a) holds = holds && (fa[a] == 0 || k[a] == 0);
      if (!holds) continue;
      home.f[home.candidates] = static_cast<std::uint8_t>(f);
      home.brick_sample[home.candidates] = static_cast<std::uint8_t>(
          (k[0] + top * fa[0]) + side * ((k[1] + top * fa[1]) + side * (k[2] + top * fa[2])));
      ++home.candidates;
    }
  }
  return t;
}

constexpr SideTable kSide2 = MakeSideTable(2), kSide3 = MakeSideTable(3);

}  // namespace

const SideTable& TableFor(std::uint32_t side) {
  return side == 2 ? kSide2 : kSide3;
}

}  // namespace layout_detail

namespace {

// Brick sample s of a node: its home's offset e (bit a set where k_a = side − 1) and its home
// sample k − (side − 1)·e.
struct HomeOf {
  unsigned e, home_sample;
};
constexpr HomeOf HomeOfSample(std::uint32_t side, unsigned s) {
  const unsigned top = side - 1;
  unsigned k[3] = {s % side, s / side % side, s / (side * side)};
  unsigned e = 0;
  for (unsigned a = 0; a < 3; ++a) {
    if (k[a] == top) {
      e |= 1u << a;
      k[a] = 0;
    }
  }
  return {e, k[0] + side * (k[1] + side * k[2])};
}

// Slot in a node's neighbourhood of the node at offset e − f from it (e, f ∈ {0,1}³ as bits).
constexpr int SlotOf(unsigned e, unsigned f) {
  const auto d = [&](unsigned a) {
    return static_cast<int>(e >> a & 1u) - static_cast<int>(f >> a & 1u);
  };
  return NeighbourSlot(d(0), d(1), d(2));
}

// Per non-home brick sample: its bit in the orphan mask, the neighbourhood slot of its home node,
// and the slots of the nodes that may store it in their order, this node at `self`.
struct OrphanRule {
  std::uint8_t bit = 0, home_slot = 0, candidates = 0, self = 0xff;
  std::uint8_t slot[7] = {};
};
struct OrphanRules {
  int count = 0;
  OrphanRule rule[27];
};

constexpr OrphanRules MakeOrphanRules(std::uint32_t side) {
  const layout_detail::SideTable t = layout_detail::MakeSideTable(static_cast<int>(side));
  OrphanRules rules;
  for (unsigned s = 0; s < side * side * side; ++s) {
    if (t.is_home[s]) continue;
    const HomeOf h = HomeOfSample(side, s);
    const layout_detail::HomeSample& home = t.home[t.index[h.home_sample]];
    OrphanRule& r = rules.rule[rules.count++];
    r.bit = t.index[s];
    r.home_slot = static_cast<std::uint8_t>(SlotOf(h.e, 0));
    r.candidates = home.candidates;
    for (int c = 0; c < home.candidates; ++c) {
      r.slot[c] = static_cast<std::uint8_t>(SlotOf(h.e, home.f[c]));
      if (home.f[c] == h.e) r.self = static_cast<std::uint8_t>(c);
    }
  }
  return rules;
}

constexpr OrphanRules kOrphans2 = MakeOrphanRules(2), kOrphans3 = MakeOrphanRules(3);

// Per brick sample: its point's home sample, and the neighbourhood slot of node home − f for each
// f ∈ {0,1}³ (x + 2y + 4z), as PointIndex asks for them.
struct SampleHome {
  std::uint8_t home_sample = 0;
  std::uint8_t slot[8] = {};
};
struct SampleHomes {
  SampleHome sample[27];
};

constexpr SampleHomes MakeSampleHomes(std::uint32_t side) {
  SampleHomes homes;
  for (unsigned s = 0; s < side * side * side; ++s) {
    const HomeOf h = HomeOfSample(side, s);
    homes.sample[s].home_sample = static_cast<std::uint8_t>(h.home_sample);
    for (unsigned f = 0; f < 8; ++f) {
      homes.sample[s].slot[f] = static_cast<std::uint8_t>(SlotOf(h.e, f));
    }
  }
  return homes;
}

constexpr SampleHomes kHomes2 = MakeSampleHomes(2), kHomes3 = MakeSampleHomes(3);

}  // namespace

std::uint32_t OrphanMask(std::uint32_t side, const Neighbourhood& nb) {
  const OrphanRules& rules = side == 2 ? kOrphans2 : kOrphans3;
  std::uint32_t mask = 0;
  for (int i = 0; i < rules.count; ++i) {
    const OrphanRule& r = rules.rule[i];
    if (nb[r.home_slot] >= 0) continue;
    // The first existing candidate stores it; this node is one of them.
    for (int c = 0; c < r.candidates; ++c) {
      if (nb[r.slot[c]] < 0) continue;
      if (c == r.self) mask |= 1u << r.bit;
      break;
    }
  }
  return mask;
}

SampleLayout LayOutSamples(const MaskTree& tree, std::uint32_t level, std::uint32_t side) {
  SampleLayout layout;
  layout.side = side;
  const std::uint64_t n = tree.NodeCount(level);
  layout.orphans.resize(n);
  ForEachNeighbourhood(tree, level, [&](std::uint64_t i, const Neighbourhood& nb) {
    layout.orphans[i] = OrphanMask(side, nb);
  });
  layout.first.resize(n + 1);
  const std::uint64_t home = layout_detail::TableFor(side).home_count;
  std::uint64_t next = 0;
  for (std::uint64_t i = 0; i < n; ++i) {
    layout.first[i] = next;
    next += home + CountBits32(layout.orphans[i]);
  }
  layout.first[n] = next;
  return layout;
}

std::uint64_t SampleIndex(const SampleLayout& layout, const Neighbourhood& nb, unsigned sample) {
  const SampleHome& h = (layout.side == 2 ? kHomes2 : kHomes3).sample[sample];
  return PointIndex(layout, h.home_sample, [&](unsigned f) { return nb[h.slot[f]]; });
}

}  // namespace svokit
