// The default GYROCHAR_ASSERT handler (mode 2): weak, so that an integrator's or a test's own
// definition of gyrochar::assert_failed() takes its place at link time. The core cannot print
// (it is freestanding): it stops the program where the invariant broke.
#include "gyrochar/assert.hpp"

namespace gyrochar {

[[gnu::weak]] void assert_failed(const char*, const char*, int) { __builtin_trap(); }

}  // namespace gyrochar
