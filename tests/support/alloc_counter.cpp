#include "alloc_counter.h"

#include <atomic>
#include <cstdlib>
#include <new>

extern "C" {
void* __real_malloc(size_t);
void* __real_calloc(size_t, size_t);
void* __real_realloc(void*, size_t);
void __real_free(void*);
void* __real_aligned_alloc(size_t, size_t);
int __real_posix_memalign(void**, size_t, size_t);
void* __real_memalign(size_t, size_t);
}

namespace {
std::atomic<uint64_t> g_allocs{0};
std::atomic<uint64_t> g_frees{0};
inline void* counted(void* p) {
  if (p) g_allocs.fetch_add(1, std::memory_order_relaxed);
  return p;
}
}  // namespace

extern "C" {
void* __wrap_malloc(size_t n) { return counted(__real_malloc(n)); }
void* __wrap_calloc(size_t a, size_t b) { return counted(__real_calloc(a, b)); }
void* __wrap_realloc(void* p, size_t n) { return counted(__real_realloc(p, n)); }
void __wrap_free(void* p) {
  if (p) g_frees.fetch_add(1, std::memory_order_relaxed);
  __real_free(p);
}
void* __wrap_aligned_alloc(size_t a, size_t n) { return counted(__real_aligned_alloc(a, n)); }
int __wrap_posix_memalign(void** out, size_t a, size_t n) {
  int rc = __real_posix_memalign(out, a, n);
  if (rc == 0) counted(*out);
  return rc;
}
void* __wrap_memalign(size_t a, size_t n) { return counted(__real_memalign(a, n)); }
}

// operator new/delete go through the wrapped malloc/free, so each is counted exactly once.
namespace {
void* new_impl(size_t n) {
  void* p = malloc(n ? n : 1);
  if (!p) std::abort();  // tests never run out of memory; core never calls new
  return p;
}
void* new_aligned(size_t n, std::align_val_t a) {
  void* p = nullptr;
  size_t al = static_cast<size_t>(a);
  if (al < sizeof(void*)) al = sizeof(void*);
  if (posix_memalign(&p, al, n ? n : 1) != 0) std::abort();
  return p;
}
}  // namespace

void* operator new(size_t n) { return new_impl(n); }
void* operator new[](size_t n) { return new_impl(n); }
void* operator new(size_t n, const std::nothrow_t&) noexcept { return malloc(n ? n : 1); }
void* operator new[](size_t n, const std::nothrow_t&) noexcept { return malloc(n ? n : 1); }
void* operator new(size_t n, std::align_val_t a) { return new_aligned(n, a); }
void* operator new[](size_t n, std::align_val_t a) { return new_aligned(n, a); }
void* operator new(size_t n, std::align_val_t a, const std::nothrow_t&) noexcept { return new_aligned(n, a); }
void* operator new[](size_t n, std::align_val_t a, const std::nothrow_t&) noexcept { return new_aligned(n, a); }
void operator delete(void* p) noexcept { free(p); }
void operator delete[](void* p) noexcept { free(p); }
void operator delete(void* p, size_t) noexcept { free(p); }
void operator delete[](void* p, size_t) noexcept { free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { free(p); }
void operator delete(void* p, std::align_val_t) noexcept { free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { free(p); }
void operator delete(void* p, size_t, std::align_val_t) noexcept { free(p); }
void operator delete[](void* p, size_t, std::align_val_t) noexcept { free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { free(p); }

namespace gsf_test {

AllocStats alloc_stats() {
  AllocStats s;
  s.allocations = g_allocs.load(std::memory_order_relaxed);
  s.frees = g_frees.load(std::memory_order_relaxed);
  return s;
}

AllocationScope::AllocationScope() : start_(alloc_stats()) {}
uint64_t AllocationScope::allocations() const { return alloc_stats().allocations - start_.allocations; }
uint64_t AllocationScope::frees() const { return alloc_stats().frees - start_.frees; }

}  // namespace gsf_test
