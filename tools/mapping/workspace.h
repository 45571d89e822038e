// Host-side memory for the map builder's arena-backed stages (the heap is allowed here, not on board).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "gsf/detail/arena.h"

namespace gsf::mapping {

// An arena over [data, data + bytes) starting at its first 16-byte aligned address, the alignment the
// stages' allocations assume, so any host buffer can back one (up to 15 bytes are lost to it).
inline Arena aligned_arena(void* data, size_t bytes) {
  const uintptr_t p = reinterpret_cast<uintptr_t>(data), a = (p + 15) & ~uintptr_t(15);
  return Arena(reinterpret_cast<void*>(a), a - p <= bytes ? bytes - (a - p) : 0);
}

// Arena-backed stage objects on the heap, with at least `bytes` usable.
struct Workspace {
  std::vector<uint64_t> memory;
  Arena arena;
  explicit Workspace(size_t bytes) : memory(bytes / 8 + 3), arena(aligned_arena(memory.data(), memory.size() * 8)) {}
};

}  // namespace gsf::mapping
