#include "svokit/export/palette.hpp"

#include <algorithm>
#include <array>

namespace svokit {

namespace {

std::uint32_t Channel(std::uint32_t rgb, int channel) {
  return rgb >> (8 * channel) & 0xffu;
}

}  // namespace

Palette MedianCut(const std::vector<std::uint32_t>& rgb) {
  struct Entry {
    std::uint32_t rgb;
    std::uint64_t count;
    std::uint32_t box;
  };
  std::vector<std::uint32_t> sorted = rgb;
  std::sort(sorted.begin(), sorted.end());
  std::vector<Entry> entries;
  for (std::uint32_t c : sorted) {
    if (entries.empty() || entries.back().rgb != c) entries.push_back({c, 0, 0});
    ++entries.back().count;
  }
  struct Box {
    std::size_t begin, end;
    std::uint32_t range = 0;  ///< of its widest channel; 0 when it holds one colour
    int axis = 0;
  };
  auto measure = [&](Box& b) {
    b.range = 0;
    for (int ch = 0; ch < 3; ++ch) {
      std::uint32_t lo = 255, hi = 0;
      for (std::size_t i = b.begin; i < b.end; ++i) {
        lo = std::min(lo, Channel(entries[i].rgb, ch));
        hi = std::max(hi, Channel(entries[i].rgb, ch));
      }
      if (hi > lo && hi - lo > b.range) {
        b.range = hi - lo;
        b.axis = ch;
      }
    }
  };
  std::vector<Box> boxes;
  if (!entries.empty()) {
    boxes.push_back({0, entries.size()});
    measure(boxes[0]);
  }
  while (boxes.size() < 255) {
    std::size_t widest = 0;
    for (std::size_t i = 1; i < boxes.size(); ++i) {
      if (boxes[i].range > boxes[widest].range) widest = i;
    }
    if (boxes.empty() || boxes[widest].range == 0) break;
    Box low = boxes[widest];
    const int axis = low.axis;
    std::sort(entries.begin() + static_cast<std::ptrdiff_t>(low.begin),
              entries.begin() + static_cast<std::ptrdiff_t>(low.end),
              [axis](const Entry& a, const Entry& b) {
                const std::uint32_t ca = Channel(a.rgb, axis), cb = Channel(b.rgb, axis);
                return ca != cb ? ca < cb : a.rgb < b.rgb;
              });
    std::uint64_t total = 0, below = 0;
    for (std::size_t i = low.begin; i < low.end; ++i) total += entries[i].count;
    std::size_t split = low.begin + 1;
    while (split < low.end - 1 && 2 * (below + entries[split - 1].count) < total) {
      below += entries[split - 1].count;
      ++split;
    }
    Box high{split, low.end};
    low.end = split;
    measure(low);
    measure(high);
    boxes[widest] = low;
    boxes.push_back(high);
  }

  Palette palette;
  for (std::uint32_t b = 0; b < boxes.size(); ++b) {
    std::array<std::uint64_t, 3> sum{};
    std::uint64_t count = 0;
    for (std::size_t i = boxes[b].begin; i < boxes[b].end; ++i) {
      for (int ch = 0; ch < 3; ++ch) sum[ch] += Channel(entries[i].rgb, ch) * entries[i].count;
      count += entries[i].count;
      entries[i].box = b;
    }
    std::uint32_t mean = 0;
    for (int ch = 0; ch < 3; ++ch) {
      mean |= static_cast<std::uint32_t>((2 * sum[ch] + count) / (2 * count)) << (8 * ch);
    }
    palette.colors.push_back(mean);
  }
  std::sort(entries.begin(), entries.end(),
            [](const Entry& a, const Entry& b) { return a.rgb < b.rgb; });
  palette.index.reserve(rgb.size());
  for (std::uint32_t c : rgb) {
    const auto it = std::lower_bound(entries.begin(), entries.end(), c,
                                     [](const Entry& e, std::uint32_t v) { return e.rgb < v; });
    palette.index.push_back(static_cast<std::uint8_t>(it->box + 1));
  }
  return palette;
}

}  // namespace svokit
