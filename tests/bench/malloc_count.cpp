// malloc_count.so: counts a program's heap allocations, for the bench's gyrochard-rss scenario
// (docs/bench.md). Preloaded (LD_PRELOAD) into the program; MALLOC_COUNT_FILE names a file of 8
// bytes that the library maps shared and in which it keeps the running number of calls to malloc,
// calloc, realloc, aligned_alloc, posix_memalign and memalign (operator new calls malloc), so the
// scenario reads the count while the program runs (od -An -tu8 FILE). The calls go on to glibc's
// own functions (__libc_malloc, ...); free is not counted. Without MALLOC_COUNT_FILE it counts
// nothing.
#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>

using std::size_t;

extern "C" {
void* __libc_malloc(size_t);
void* __libc_calloc(size_t, size_t);
void* __libc_realloc(void*, size_t);
void* __libc_memalign(size_t, size_t);
}

namespace {

volatile std::uint64_t* count = nullptr;

__attribute__((constructor)) void map_counter() {
  const char* path = std::getenv("MALLOC_COUNT_FILE");
  if (path == nullptr) return;
  int fd = open(path, O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return;
  if (ftruncate(fd, sizeof(std::uint64_t)) == 0) {
    void* p = mmap(nullptr, sizeof(std::uint64_t), PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    if (p != MAP_FAILED) count = static_cast<volatile std::uint64_t*>(p);
  }
  close(fd);
}

void counted() {
  if (count != nullptr) __atomic_add_fetch(count, 1, __ATOMIC_RELAXED);
}

}  // namespace

extern "C" {

void* malloc(size_t n) noexcept {
  counted();
  return __libc_malloc(n);
}
void* calloc(size_t k, size_t n) noexcept {
  counted();
  return __libc_calloc(k, n);
}
void* realloc(void* p, size_t n) noexcept {
  counted();
  return __libc_realloc(p, n);
}
void* memalign(size_t a, size_t n) noexcept {
  counted();
  return __libc_memalign(a, n);
}
void* aligned_alloc(size_t a, size_t n) noexcept {
  counted();
  return __libc_memalign(a, n);
}
int posix_memalign(void** out, size_t a, size_t n) noexcept {
  counted();
  void* p = __libc_memalign(a, n);
  if (p == nullptr) return 12;  // ENOMEM
  *out = p;
  return 0;
}

}  // extern "C"
