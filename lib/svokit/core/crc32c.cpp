#include "svokit/core/crc32c.hpp"

#include <algorithm>
#include <array>
#include <cstring>
#include <vector>

#include "svokit/core/parallel.hpp"

#if defined(__x86_64__)
#include <nmmintrin.h>
#endif

namespace svokit {

namespace {

constexpr std::uint32_t kPoly = 0x82f63b78u;  // reflected Castagnoli polynomial

struct Tables {
  std::array<std::array<std::uint32_t, 256>, 8> t{};
  constexpr Tables() {
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? (c >> 1) ^ kPoly : c >> 1;
      t[0][i] = c;
    }
    for (std::uint32_t i = 0; i < 256; ++i) {
      for (int s = 1; s < 8; ++s) t[s][i] = (t[s - 1][i] >> 8) ^ t[0][t[s - 1][i] & 0xff];
    }
  }
};
constexpr Tables kTables;

std::uint32_t Crc32cPortable(const unsigned char* p, std::size_t n, std::uint32_t crc) {
  const auto& t = kTables.t;
  while (n >= 8) {
    std::uint64_t w;
    std::memcpy(&w, p, 8);  // little-endian hosts only (svokit's files are little-endian)
    w ^= crc;
    crc = t[7][w & 0xff] ^ t[6][(w >> 8) & 0xff] ^ t[5][(w >> 16) & 0xff] ^ t[4][(w >> 24) & 0xff] ^
          t[3][(w >> 32) & 0xff] ^ t[2][(w >> 40) & 0xff] ^ t[1][(w >> 48) & 0xff] ^
          t[0][(w >> 56) & 0xff];
    p += 8;
    n -= 8;
  }
  while (n--) crc = (crc >> 8) ^ t[0][(crc ^ *p++) & 0xff];
  return crc;
}

#if defined(__x86_64__)
__attribute__((target("sse4.2"))) std::uint32_t Crc32cHardware(const unsigned char* p,
                                                               std::size_t n, std::uint32_t crc) {
  std::uint64_t c = crc;
  while (n >= 8) {
    std::uint64_t w;
    std::memcpy(&w, p, 8);
    c = _mm_crc32_u64(c, w);
    p += 8;
    n -= 8;
  }
  auto c32 = static_cast<std::uint32_t>(c);
  while (n--) c32 = _mm_crc32_u8(c32, *p++);
  return c32;
}
#endif

}  // namespace

std::uint32_t Crc32c(const void* data, std::size_t size, std::uint32_t crc) {
  const auto* p = static_cast<const unsigned char*>(data);
  crc = ~crc;
#if defined(__x86_64__)
  static const bool kHasSse42 = __builtin_cpu_supports("sse4.2");
  crc = kHasSse42 ? Crc32cHardware(p, size, crc) : Crc32cPortable(p, size, crc);
#else
  crc = Crc32cPortable(p, size, crc);
#endif
  return ~crc;
}

namespace {

// Polynomials mod P in the reflected representation (bit 31 is x^0). a·b mod P.
std::uint32_t MultiplyModP(std::uint32_t a, std::uint32_t b) {
  std::uint32_t product = 0;
  for (std::uint32_t bit = 1u << 31; bit != 0; bit >>= 1) {
    if (a & bit) product ^= b;
    b = (b & 1) ? (b >> 1) ^ kPoly : b >> 1;  // b·x
  }
  return product;
}

// x^(8·bytes) mod P, by squaring: kPowers[k] = x^(2^k) mod P.
std::uint32_t ShiftByBytes(std::uint64_t bytes) {
  static const auto kPowers = [] {
    std::array<std::uint32_t, 67> p{};
    p[0] = 1u << 30;  // x^1
    for (std::size_t k = 1; k < p.size(); ++k) p[k] = MultiplyModP(p[k - 1], p[k - 1]);
    return p;
  }();
  std::uint32_t result = 1u << 31;  // x^0
  for (std::size_t k = 3; bytes != 0; bytes >>= 1, ++k) {
    if (bytes & 1) result = MultiplyModP(kPowers[k], result);
  }
  return result;
}

}  // namespace

std::uint32_t Crc32cCombine(std::uint32_t crc_a, std::uint32_t crc_b, std::uint64_t size_b) {
  // The register after A, run through size_b zero bytes, XOR B's own: the pre- and
  // post-inversions cancel (as in zlib's crc32_combine).
  return MultiplyModP(ShiftByBytes(size_b), crc_a) ^ crc_b;
}

std::uint32_t Crc32cParallel(const void* data, std::size_t size) {
  constexpr std::size_t kPiece = std::size_t{4} << 20;
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  const std::size_t pieces = (size + kPiece - 1) / kPiece;
  std::vector<std::uint32_t> crcs(pieces);
  ParallelChunks(pieces, 1, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      crcs[i] = Crc32c(bytes + i * kPiece, std::min(kPiece, size - i * kPiece));
    }
  });
  std::uint32_t crc = 0;
  for (std::size_t i = 0; i < pieces; ++i) {
    crc = Crc32cCombine(crc, crcs[i], std::min(kPiece, size - i * kPiece));
  }
  return crc;
}

}  // namespace svokit
