#pragma once
// GYROCHAR_ASSERT(cond): the core's check of an invariant that holds by construction (a
// caller's precondition, or what the code before it guarantees). It is not error handling: bad
// input gets a status, never an assertion. A failed assertion is a bug.
//
// What it does is chosen once per build, the same in every translation unit (the CMake option
// GYROCHAR_ASSERT_MODE sets GYROCHAR_ASSERT_MODE for gyrochar_core and everything that links it):
//   2 (handler)  calls gyrochar::assert_failed(expression, file, line), which must not return.
//                The core's definition is weak and traps; an integrator (or a test) overrides it
//                by defining the function. The default of host builds, tests and sanitizers.
//   1 (trap)     __builtin_trap(): no handler, no strings in the image.
//   0 (off)      nothing: the condition is not evaluated (it is still compiled). The default of
//                the microcontroller builds (GYROCHAR_CORE_ONLY).
// An integrator who wants another mechanism defines GYROCHAR_ASSERT(cond) before including any
// core header, in every translation unit alike (a compile definition), and the core takes it.

#ifndef GYROCHAR_ASSERT_MODE
#define GYROCHAR_ASSERT_MODE 2
#endif

namespace gyrochar {
/// Reports a failed GYROCHAR_ASSERT (mode 2). Must not return. The core's definition traps.
[[noreturn]] void assert_failed(const char* expression, const char* file, int line);
}  // namespace gyrochar

#ifndef GYROCHAR_ASSERT
#if GYROCHAR_ASSERT_MODE == 2
#define GYROCHAR_ASSERT(cond) \
  (__builtin_expect(!(cond), 0) ? ::gyrochar::assert_failed(#cond, __FILE__, __LINE__) : static_cast<void>(0))
#elif GYROCHAR_ASSERT_MODE == 1
#define GYROCHAR_ASSERT(cond) (__builtin_expect(!(cond), 0) ? __builtin_trap() : static_cast<void>(0))
#elif GYROCHAR_ASSERT_MODE == 0
#define GYROCHAR_ASSERT(cond) static_cast<void>(sizeof(!(cond)))
#else
#error "GYROCHAR_ASSERT_MODE: 0 (off), 1 (trap) or 2 (handler)"
#endif
#endif
