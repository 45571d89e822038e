// Host-side memory for the map builder's arena-backed stages (the heap is allowed here, not on board).
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>

#include "gsf/detail/arena.h"

namespace gsf::mapping {

// An arena over [data, data + bytes) starting at its first 16-byte aligned address, the alignment the
// stages' allocations assume, so any host buffer can back one (up to 15 bytes are lost to it).
inline Arena aligned_arena(void* data, size_t bytes) {
  const uintptr_t p = reinterpret_cast<uintptr_t>(data), a = (p + 15) & ~uintptr_t(15);
  return Arena(reinterpret_cast<void*>(a), a - p <= bytes ? bytes - (a - p) : 0);
}

// Byte every new Workspace is filled with, or -1 to leave it as the allocator gives it. Tests only: a map
// built on 0x00- and on 0xA5-filled workspaces must be the same bytes (no stage reads what it did not write).
inline int workspace_fill_for_tests = -1;

// Arena-backed stage objects on the heap, with at least `bytes` usable. Not zeroed: the stages initialise
// what they use, as on board (a caller's buffer is not zeroed either); test_map_builder holds them to it
// through workspace_fill_for_tests.
struct Workspace {
  std::unique_ptr<uint64_t[]> memory;
  Arena arena;
  explicit Workspace(size_t bytes)
      : memory(new uint64_t[words(bytes)]), arena(aligned_arena(memory.get(), words(bytes) * 8)) {
    if (workspace_fill_for_tests >= 0) std::memset(memory.get(), workspace_fill_for_tests, words(bytes) * 8);
  }
  // 8-byte words holding `bytes` and the up to 15 bytes lost to the 16-byte alignment.
  static size_t words(size_t bytes) { return bytes / 8 + 3; }
};

}  // namespace gsf::mapping
