// Explicit instantiations: compiles the characterizer once under core's freestanding flags.
#include "gyrochar/characterizer.hpp"

namespace gyrochar {
template class Characterizer<CountArith>;
template class Characterizer<FloatArith>;
}  // namespace gyrochar
