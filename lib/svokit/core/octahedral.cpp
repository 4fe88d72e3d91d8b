#include "svokit/core/octahedral.hpp"

namespace svokit {

template std::uint32_t EncodeOctSnorm<8>(float);
template std::uint32_t EncodeOctSnorm<16>(float);
template float DecodeOctSnorm<8>(std::uint32_t);
template float DecodeOctSnorm<16>(std::uint32_t);
template std::uint32_t OctahedralEncodePoint<8>(float, float, float);
template std::uint32_t OctahedralEncodePoint<16>(float, float, float);
template std::uint32_t OctahedralEncode<8>(const Vec3f&);
template std::uint32_t OctahedralEncode<16>(const Vec3f&);
template Vec3f OctahedralDecode<8>(std::uint32_t);
template Vec3f OctahedralDecode<16>(std::uint32_t);

}  // namespace svokit

template class std::vector<svokit::OctNormal, svokit::DefaultInitAllocator<svokit::OctNormal>>;
