// Explicit instantiation: compiles the counts characterizer once under core's freestanding flags.
// (Not the floating one: clang 14 instantiates its exact-only members, constrained by
// requires(Arith::exact), which C++20 exempts; the tests and the analyzer instantiate it.)
#include "gyrochar/characterizer.hpp"

namespace gyrochar {
template class Characterizer<CountArith>;
}  // namespace gyrochar
