#include "svokit/core/default_init.hpp"

template class std::vector<std::uint8_t, svokit::DefaultInitAllocator<std::uint8_t>>;
template class std::vector<std::uint16_t, svokit::DefaultInitAllocator<std::uint16_t>>;
template class std::vector<std::uint32_t, svokit::DefaultInitAllocator<std::uint32_t>>;
template class std::vector<std::uint64_t, svokit::DefaultInitAllocator<std::uint64_t>>;
