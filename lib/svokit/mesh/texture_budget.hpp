#pragma once
// One memory budget for all the textures of a mesh that are decoded together (the colour pass of
// a voxelization): headers first, then, in texture index order, each texture at full size if
// what it needs fits in what is left, otherwise downsampled by powers of two until it does, or
// refused when even its decoding does not fit. The decisions depend on the headers alone, so any
// thread count gives the same images.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "svokit/mesh/texture.hpp"

namespace svokit {

/// The most bytes the textures of one mesh may take: the decoded images as linear RGBA floats
/// (16 bytes a texel), their mip pyramids (a third more), and the decoder's working memory
/// (image_codec.hpp, ImageDecodeBytes) while each is decoded. One 8192² texture fits whole.
inline constexpr std::uint64_t kTextureMemoryBudget = std::uint64_t{2} << 30;

/// What the budget decided for each texture, and the images.
struct BudgetedTextures {
  std::vector<Image> images;          ///< by texture index; empty (width 0) when not decoded
  std::vector<Status> errors;         ///< by texture index: why a used texture has no image
  std::vector<int> shrink;            ///< by texture index: times downsampled by 2 × 2
  std::vector<std::string> warnings;  ///< one per downsampled texture
  std::uint64_t planned_bytes = 0;    ///< the most the plan lets decoding hold at once
};

/// The bytes a w × h texture holds once decoded with its pyramid (levels down to 1 × 1).
std::uint64_t DecodedTextureBytes(std::int64_t width, std::int64_t height);

/// Decodes textures[i] for each i in `used` (increasing) within `budget` bytes. Decoding runs in
/// parallel when the whole plan's peaks fit the budget together, else one texture at a time.
BudgetedTextures DecodeTexturesWithinBudget(const std::vector<Texture>& textures,
                                            const std::vector<std::size_t>& used,
                                            std::uint64_t budget = kTextureMemoryBudget);

}  // namespace svokit
