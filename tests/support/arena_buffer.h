// Test helper: an 8-byte aligned heap block with an Arena over it (the caller-buffer pattern).
#pragma once
#include <cstdint>
#include <vector>

#include "gsf/detail/arena.h"

namespace gsf_test {

struct ArenaBuffer {
  std::vector<uint64_t> words;
  gsf::Arena arena;
  explicit ArenaBuffer(size_t bytes) : words(bytes / 8 + 2), arena(words.data(), words.size() * 8) {}
};

}  // namespace gsf_test
