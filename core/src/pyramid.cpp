// Explicit instantiations: compiles the pyramid once under core's freestanding flags.
#include "gyrochar/pyramid.hpp"

namespace gyrochar {
template class Pyramid<CountArith>;
template class Pyramid<FloatArith>;
}  // namespace gyrochar
