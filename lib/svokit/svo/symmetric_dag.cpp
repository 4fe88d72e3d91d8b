#include "svokit/svo/symmetric_dag.hpp"

#include <algorithm>
#include <array>
#include <span>

#include "svokit/core/bit_count.hpp"

namespace svokit {

namespace {

constexpr std::uint32_t kMaxOffset = (1u << 29) - 1;

// A child mask with child c moved to c ^ m.
constexpr std::array<std::array<std::uint8_t, 256>, 8> kReflectedMask = [] {
  std::array<std::array<std::uint8_t, 256>, 8> t{};
  for (unsigned m = 0; m < 8; ++m) {
    for (unsigned mask = 0; mask < 256; ++mask) {
      for (unsigned c = 0; c < 8; ++c) {
        if (mask >> c & 1u) t[m][mask] = static_cast<std::uint8_t>(t[m][mask] | 1u << (c ^ m));
      }
    }
  }
  return t;
}();

// The least mirror equivalent to m for a node left unchanged by the mirrors in `symmetries`.
constexpr std::array<std::array<std::uint8_t, 8>, 256> kLeastMirror = [] {
  std::array<std::array<std::uint8_t, 8>, 256> t{};
  for (unsigned s = 0; s < 256; ++s) {
    for (unsigned m = 0; m < 8; ++m) {
      unsigned least = m;
      for (unsigned g = 0; g < 8; ++g) {
        if (s >> g & 1u) least = std::min(least, m ^ g);
      }
      t[s][m] = static_cast<std::uint8_t>(least);
    }
  }
  return t;
}();

// The node's reflection by m and its least form among them: words and mirrors.
struct Canonical {
  std::array<std::uint32_t, 9> words;
  std::size_t size = 0;
  DagMirror mirror = 0;         // the node is the stored form reflected by this
  std::uint8_t symmetries = 1;  // mirrors that leave the stored form unchanged
};

}  // namespace

std::uint64_t ReflectLeaf(std::uint64_t bits, DagMirror m) {
  std::uint64_t out = 0;
  for (unsigned c = 0; c < 8; ++c) {
    const unsigned byte = static_cast<std::uint8_t>(bits >> (8 * c));
    out |= std::uint64_t{kReflectedMask[m][byte]} << (8 * (c ^ m));
  }
  return out;
}

StatusOr<SymmetricDag> ReduceSymmetries(VoxelDag dag) {
  const std::uint32_t leaf = dag.leaf_level();
  SymmetricDag out;
  dag_detail::DagLevels levels(0, dag.depth);
  out.symmetries.resize(dag.levels.size());
  // Per node of the level below (by its offset in `dag`): its child word in the new DAG.
  std::vector<std::uint32_t> below, refs;

  const auto store = [&](std::uint32_t level, const Canonical& c) -> StatusOr<std::uint32_t> {
    const std::uint32_t offset = levels.Insert(level, std::span(c.words.data(), c.size));
    if (levels.overflow || offset > kMaxOffset) {
      return Status::BadInput("a symmetric DAG has a level of more than 2^29 words");
    }
    std::vector<std::uint8_t>& symmetries = out.symmetries[level];
    if (symmetries.size() < levels.levels[level].words.size()) {
      symmetries.resize(levels.levels[level].words.size(), 0);
    }
    symmetries[offset] = c.symmetries;
    return offset << 3 | c.mirror;
  };

  // Leaves: the least of the 8 reflections of the mask.
  {
    const std::vector<std::uint32_t>& words = dag.levels[leaf].words;
    refs.assign(words.size(), 0);
    for (std::size_t offset = 0; offset < words.size(); offset += 2) {
      const std::uint64_t bits = DagLeafMask(dag.levels[leaf], static_cast<std::uint32_t>(offset));
      std::array<std::uint64_t, 8> reflected;
      for (DagMirror m = 0; m < 8; ++m) reflected[m] = ReflectLeaf(bits, m);
      Canonical c;
      c.size = 2;
      const auto least = std::min_element(reflected.begin(), reflected.end());
      c.mirror = static_cast<DagMirror>(least - reflected.begin());
      c.symmetries = 0;
      for (unsigned m = 0; m < 8; ++m) {
        if (reflected[m] == *least) c.symmetries |= static_cast<std::uint8_t>(1u << (m ^ c.mirror));
      }
      c.words = {static_cast<std::uint32_t>(*least), static_cast<std::uint32_t>(*least >> 32)};
      StatusOr<std::uint32_t> ref = store(leaf, c);
      if (!ref.ok()) return ref.status();
      refs[offset] = *ref;
    }
    below.swap(refs);
    dag.levels[leaf] = DagLevel{};
  }

  // Inner levels: each reflection's children moved and their mirrors composed (and reduced by
  // their own symmetries), the least kept; the root as it is.
  for (std::uint32_t l = leaf; l-- > 0;) {
    const std::vector<std::uint32_t>& words = dag.levels[l].words;
    const std::vector<std::uint8_t>& child_symmetries = out.symmetries[l + 1];
    refs.assign(words.size(), 0);
    for (std::size_t offset = 0; offset < words.size();) {
      const unsigned mask = words[offset], n = CountBits8(mask);
      std::array<std::uint32_t, 8> children{};  // by child index: the child's word
      for (unsigned c = 0, k = 0; c < 8; ++c) {
        if (mask >> c & 1u) children[c] = below[words[offset + 1 + k++]];
      }
      const auto reflect = [&](DagMirror m) {
        Canonical r;
        r.words[r.size++] = kReflectedMask[m][mask];
        for (unsigned c = 0; c < 8; ++c) {  // the reflection's child c is the node's c ^ m
          if (!(mask >> (c ^ m) & 1u)) continue;
          const std::uint32_t child = children[c ^ m], child_offset = child >> 3;
          const unsigned mirror = (child & 7u) ^ m;
          r.words[r.size++] =
              child_offset << 3 | kLeastMirror[child_symmetries[child_offset]][mirror];
        }
        return r;
      };
      Canonical c = reflect(0);
      if (l > 0) {
        std::array<Canonical, 8> all;
        for (DagMirror m = 0; m < 8; ++m) all[m] = reflect(m);
        const auto less = [&](const Canonical& a, const Canonical& b) {
          return std::lexicographical_compare(a.words.begin(), a.words.begin() + a.size,
                                              b.words.begin(), b.words.begin() + b.size);
        };
        const auto least = std::min_element(all.begin(), all.end(), less);
        c = *least;
        c.mirror = static_cast<DagMirror>(least - all.begin());
        c.symmetries = 0;
        for (unsigned m = 0; m < 8; ++m) {
          if (!less(all[m], *least) && !less(*least, all[m])) {
            c.symmetries |= static_cast<std::uint8_t>(1u << (m ^ c.mirror));
          }
        }
      }
      StatusOr<std::uint32_t> ref = store(l, c);
      if (!ref.ok()) return ref.status();
      refs[offset] = *ref;
      offset += 1 + n;
    }
    below.swap(refs);
    dag.levels[l] = DagLevel{};
  }
  out.dag.depth = dag.depth;
  out.dag.levels = std::move(levels.levels);
  return out;
}

std::vector<std::uint64_t> SymmetricDagVoxelKeys(const SymmetricDag& dag) {
  std::vector<std::uint64_t> keys;
  const std::uint32_t leaf = dag.dag.leaf_level();
  // Node `offset` of `level` seen through mirror m at `key`: its world child c is its stored
  // child c ^ m, seen through the composed mirror.
  const auto visit = [&](const auto& self, std::uint32_t level, std::uint32_t offset, DagMirror m,
                         std::uint64_t key) -> void {
    const std::vector<std::uint32_t>& words = dag.dag.levels[level].words;
    if (level == leaf) {
      const std::uint64_t bits = ReflectLeaf(DagLeafMask(dag.dag.levels[level], offset), m);
      for (unsigned b = 0; b < 64; ++b) {
        if (bits >> b & 1u) keys.push_back(key << 6 | b);
      }
      return;
    }
    const unsigned mask = words[offset];
    for (unsigned c = 0; c < 8; ++c) {
      const unsigned stored = c ^ m;
      if (!(mask >> stored & 1u)) continue;
      const std::uint32_t child = words[offset + 1 + RankInByte(mask, stored)];
      self(self, level + 1, child >> 3, static_cast<DagMirror>((child & 7u) ^ m), key << 3 | c);
    }
  };
  visit(visit, 0, 0, 0, 0);
  return keys;
}

}  // namespace svokit
