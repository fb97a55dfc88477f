#pragma once
// Counts heap allocations: replaces malloc/calloc/realloc/free and the global operator
// new/delete of the test binary. Include in exactly ONE translation unit of a test binary (it
// defines those functions). Only allocations on a thread inside a CountAllocations scope count.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <new>

extern "C" void* __libc_malloc(std::size_t size);
extern "C" void __libc_free(void* ptr);
extern "C" void* __libc_calloc(std::size_t n, std::size_t size);
extern "C" void* __libc_realloc(void* ptr, std::size_t size);

namespace concert::test {

inline thread_local bool t_counting_allocations = false;
inline std::atomic<std::uint64_t> g_counted_allocations{0};

/// Where a debugger breaks to see who allocated while counting.
[[gnu::noinline]] inline void counted_allocation() {
  g_counted_allocations.fetch_add(1, std::memory_order_relaxed);
}

inline void note_allocation() {
  if (t_counting_allocations) {
    counted_allocation();
  }
}

/// Counts the calling thread's allocations from construction until count() / destruction.
class CountAllocations {
 public:
  CountAllocations() : before_(g_counted_allocations.load()) { t_counting_allocations = true; }
  ~CountAllocations() { t_counting_allocations = false; }
  CountAllocations(const CountAllocations&) = delete;
  CountAllocations& operator=(const CountAllocations&) = delete;
  /// Allocations since construction (of every counting thread).
  [[nodiscard]] std::uint64_t count() const { return g_counted_allocations.load() - before_; }

 private:
  std::uint64_t before_;
};

}  // namespace concert::test

extern "C" void* malloc(std::size_t size) {
  concert::test::note_allocation();
  return __libc_malloc(size);
}
extern "C" void* calloc(std::size_t n, std::size_t size) {
  concert::test::note_allocation();
  return __libc_calloc(n, size);
}
extern "C" void* realloc(void* ptr, std::size_t size) {
  concert::test::note_allocation();
  return __libc_realloc(ptr, size);
}
extern "C" void free(void* ptr) { __libc_free(ptr); }

void* operator new(std::size_t size) {
  concert::test::note_allocation();
  if (void* p = __libc_malloc(size == 0 ? 1 : size)) {
    return p;
  }
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
void operator delete(void* p) noexcept { __libc_free(p); }
void operator delete[](void* p) noexcept { __libc_free(p); }
void operator delete(void* p, std::size_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::size_t) noexcept { __libc_free(p); }
