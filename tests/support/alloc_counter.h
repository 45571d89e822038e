// Counting allocator for the "no heap after init" tests.
//
// Linked only into test_*_noheap executables: it replaces every C++17 operator new/delete form and
// wraps malloc/calloc/realloc/free/aligned_alloc/posix_memalign/memalign (-Wl,--wrap), so any heap
// use - ours, Eigen's, the standard library's - is counted. While `forbid` is set, an allocation is
// also recorded as a violation (not aborted, so Catch2 can report it).
#pragma once
#include <cstddef>
#include <cstdint>

namespace gsf_test {

struct AllocStats {
  uint64_t allocations = 0;  // calls that obtained memory (new, malloc, calloc, realloc, ...)
  uint64_t frees = 0;
};

AllocStats alloc_stats();

// Counts allocations made between construction and `allocations()`. Not thread-safe by design:
// the library is single-threaded per Localizer and the tests measure one thread.
class AllocationScope {
 public:
  AllocationScope();
  uint64_t allocations() const;
  uint64_t frees() const;

 private:
  AllocStats start_;
};

// Keep the optimiser from eliding an allocation pair in negative-control tests.
inline void escape(void* p) { asm volatile("" : : "g"(p) : "memory"); }

}  // namespace gsf_test
