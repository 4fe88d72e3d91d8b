#include "svokit/core/half.hpp"

template class std::vector<svokit::Half, svokit::DefaultInitAllocator<svokit::Half>>;
template class std::vector<svokit::HalfRgba, svokit::DefaultInitAllocator<svokit::HalfRgba>>;
