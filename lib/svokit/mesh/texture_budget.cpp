#include "svokit/mesh/texture_budget.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "svokit/core/byte_size.hpp"
#include "svokit/core/parallel.hpp"
#include "svokit/mesh/image_codec.hpp"

namespace svokit {

namespace {

constexpr std::uint64_t kBytesPerTexel = 16;  // linear RGBA floats

std::int64_t Shrunk(std::int64_t size, int shrink) {
  return (size + (std::int64_t{1} << shrink) - 1) >> shrink;
}

}  // namespace

std::uint64_t DecodedTextureBytes(std::int64_t width, std::int64_t height) {
  // TextureSampler's pyramid: each level halves each side, rounding up, down to 1 × 1.
  std::uint64_t texels = 0;
  for (std::int64_t w = width, h = height;; w = (w + 1) / 2, h = (h + 1) / 2) {
    texels += static_cast<std::uint64_t>(w) * static_cast<std::uint64_t>(h);
    if (w <= 1 && h <= 1) break;
  }
  return texels * kBytesPerTexel;
}

BudgetedTextures DecodeTexturesWithinBudget(const std::vector<Texture>& textures,
                                            const std::vector<std::size_t>& used,
                                            std::uint64_t budget) {
  BudgetedTextures out;
  out.images.resize(textures.size());
  out.errors.resize(textures.size());
  out.shrink.assign(textures.size(), 0);
  std::vector<std::size_t> planned;
  std::uint64_t held = 0;       // the decoded images (with pyramids) of the textures so far
  std::uint64_t peaks_sum = 0;  // the peaks of all, as if decoded at once
  for (const std::size_t t : used) {
    const Texture& texture = textures[t];
    StatusOr<ImageHeader> header = ReadImageHeader(texture.name(), texture.encoded());
    if (!header.ok()) {
      out.errors[t] = header.status();
      continue;
    }
    // While decoding: the decoder's working memory (its output included), then its output and the
    // converted image together; after: the image and its pyramid.
    const std::uint64_t working = ImageDecodeBytes(*header, texture.encoded().size());
    const std::uint64_t samples = static_cast<std::uint64_t>(header->width) *
                                  static_cast<std::uint64_t>(header->height) *
                                  static_cast<std::uint64_t>(header->channels) *
                                  static_cast<std::uint64_t>(header->bytes_per_sample);
    int shrink = 0;
    std::uint64_t peak = 0, kept = 0;
    for (;; ++shrink) {
      const std::int64_t w = Shrunk(header->width, shrink), h = Shrunk(header->height, shrink);
      kept = DecodedTextureBytes(w, h);
      peak =
          std::max({working, samples + static_cast<std::uint64_t>(w * h) * kBytesPerTexel, kept});
      if (held + peak <= budget || (w == 1 && h == 1)) break;
    }
    if (held + peak > budget) {
      out.errors[t] = Status::BadInput(
          "texture '{}' ({}x{}) does not fit in what is left of the texture memory budget ({} of "
          "{})",
          texture.name(), header->width, header->height,
          ByteSizeText(static_cast<double>(budget - held)),
          ByteSizeText(static_cast<double>(budget)));
      continue;
    }
    if (shrink > 0) {
      out.warnings.push_back(fmt::format(
          "texture '{}' ({}x{}) is downsampled to {}x{} to fit the texture memory budget of {}",
          texture.name(), header->width, header->height, Shrunk(header->width, shrink),
          Shrunk(header->height, shrink), ByteSizeText(static_cast<double>(budget))));
    }
    out.shrink[t] = shrink;
    out.planned_bytes = std::max(out.planned_bytes, held + peak);
    held += kept;
    peaks_sum += peak;
    planned.push_back(t);
  }
  const auto decode = [&](std::size_t i) {
    const std::size_t t = planned[i];
    StatusOr<Image> image = textures[t].Decode(out.shrink[t]);
    if (image.ok()) {
      out.images[t] = std::move(image).value();
    } else {
      out.errors[t] = image.status();
    }
  };
  if (peaks_sum <= budget) {
    ParallelChunks(planned.size(), 1, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) decode(i);
    });
  } else {
    for (std::size_t i = 0; i < planned.size(); ++i) decode(i);
  }
  return out;
}

}  // namespace svokit
