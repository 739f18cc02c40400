#pragma once
// The analyzer's large buffers: the held records (held_engines.cpp, the record kept for the total
// family), the lag sums' workspaces (total_analysis.hpp) and the PSD's transform buffer (psd.cpp).
// From 4 MiB on they are aligned to 2 MiB and offered to transparent huge pages (madvise; the
// system's default is to be asked): a first touch faults once a 2 MiB page instead of 512 times,
// and the FFTs' and the Theo1 terms' far-apart reads miss the TLB far less (BENCHMARKS.md, "Huge
// pages for the workspaces").
// Uninitialized: every element is written before it is read.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

#include <sys/mman.h>

namespace gyrochar {

/// `bytes` of uninitialized memory, to be freed with std::free. Throws std::bad_alloc.
inline void* allocate_held(std::size_t bytes) {
  constexpr std::size_t huge_page = std::size_t{1} << 21;
  if (bytes < 2 * huge_page) {
    void* p = std::malloc(bytes ? bytes : 1);
    if (p == nullptr) throw std::bad_alloc();
    return p;
  }
  if (bytes > SIZE_MAX - huge_page) throw std::bad_alloc();
  const std::size_t whole = (bytes + huge_page - 1) / huge_page * huge_page;
  void* p = std::aligned_alloc(huge_page, whole);
  if (p == nullptr) throw std::bad_alloc();
  madvise(p, whole, MADV_HUGEPAGE);  // a hint: without it, 4 KiB pages
  return p;
}

/// n uninitialized doubles from allocate_held(), freed with the pointer. Throws std::bad_alloc.
struct FreeDoubles {
  void operator()(double* p) const noexcept { std::free(p); }
};
using UninitializedDoubles = std::unique_ptr<double[], FreeDoubles>;
inline UninitializedDoubles uninitialized_doubles(std::size_t n) {
  if (n > SIZE_MAX / sizeof(double)) throw std::bad_alloc();
  return UninitializedDoubles(static_cast<double*>(allocate_held(n * sizeof(double))));
}

/// A vector's allocator from allocate_held(); resize() leaves the new elements uninitialized.
template <class T>
struct HeldAllocator {
  static_assert(std::is_trivially_copyable_v<T>);
  using value_type = T;
  HeldAllocator() = default;
  template <class U>
  HeldAllocator(const HeldAllocator<U>&) {}
  T* allocate(std::size_t n) {
    if (n > SIZE_MAX / sizeof(T)) throw std::bad_alloc();
    return static_cast<T*>(allocate_held(n * sizeof(T)));
  }
  void deallocate(T* p, std::size_t) { std::free(p); }
  template <class U>
  void construct(U* p) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  template <class U>
  bool operator==(const HeldAllocator<U>&) const {
    return true;
  }
};
template <class T>
using Held = std::vector<T, HeldAllocator<T>>;

}  // namespace gyrochar
