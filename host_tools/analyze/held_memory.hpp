#pragma once
// The analyzer's large buffers: the held records (held_engines.cpp, the record kept for the total
// family), the lag sums' workspaces (total_analysis.hpp) and the PSD's transform buffer (psd.cpp).
// From 4 MiB on they are aligned to 2 MiB and offered to transparent huge pages (madvise; the
// system's default is to be asked): a first touch faults once a 2 MiB page instead of 512 times,
// and the FFTs' and the Theo1 terms' far-apart reads miss the TLB far less (BENCHMARKS.md, "Huge
// pages for the workspaces").
// Uninitialized: every element is written before it is read. Prefault brings a held record's pages in
// on a thread of its own ahead of the read pass that writes them.
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <mutex>
#include <new>
#include <thread>
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

/// Faults in the pages of a held buffer on a thread of its own, a little ahead of the thread that
/// writes it in order (the read pass): the kernel zeroes each fresh page at its first touch (on the
/// benchmark machine 0.6 to 4.2 s a GiB, BENCHMARKS.md), which then runs beside the writer instead
/// of stopping it. MADV_POPULATE_WRITE (Linux 5.14) faults pages in as a write would without
/// changing what they hold, so it is safe beside the writer; only `lead` bytes past what is
/// written, so the rest of a reserve sized from the file's bound still costs no memory. Best
/// effort: where the kernel refuses, the writer faults its own pages, as without it.
class Prefault {
 public:
  static constexpr std::size_t lead = std::size_t{8} << 20;
  Prefault() = default;
  Prefault(const Prefault&) = delete;
  Prefault& operator=(const Prefault&) = delete;
  ~Prefault() { stop(); }

  /// From now on, the buffer at `base`, `bytes` long (from allocate_held(); below 4 MiB nothing is
  /// done: it is not page-aligned, and small).
  void start(const void* base, std::size_t bytes) {
    stop();
    if (bytes < (std::size_t{4} << 20)) return;
    base_ = static_cast<char*>(const_cast<void*>(base));
    size_ = bytes / 4096 * 4096;
    target_ = done_ = 0;
    stopping_ = false;
    thread_ = std::thread([this] { run(); });
  }
  /// Its first `bytes` are written: the pages up to `lead` past them are faulted in (not waited for).
  void written(std::size_t bytes) {
    if (!thread_.joinable()) return;
    const std::size_t chunk = std::size_t{2} << 20, want = (bytes + lead + chunk - 1) / chunk * chunk;
    const std::size_t target = want < size_ ? want : size_;
    if (target <= seen_) return;
    seen_ = target;
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      target_ = target;
    }
    wake_.notify_one();
  }
  void stop() {
    if (!thread_.joinable()) return;
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
    }
    wake_.notify_one();
    thread_.join();
    seen_ = 0;
  }

 private:
  void run() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      wake_.wait(lock, [this] { return stopping_ || target_ > done_; });
      if (stopping_) return;
      const std::size_t from = done_, to = target_;
      lock.unlock();
      const bool faulted = madvise(base_ + from, to - from, MADV_POPULATE_WRITE) == 0;
      lock.lock();
      done_ = faulted ? to : size_;  // refused: nothing more is tried
    }
  }

  char* base_ = nullptr;
  std::size_t size_ = 0, seen_ = 0;  // seen_: the writer's last target (its thread's alone)
  std::mutex mutex_;
  std::condition_variable wake_;
  std::size_t target_ = 0, done_ = 0;  // under mutex_
  bool stopping_ = false;
  std::thread thread_;
};

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
