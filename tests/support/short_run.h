// Test helper: whether this run is a slow build's (ASan+UBSan, or ARM64 under qemu), where the same
// code paths run on fewer repetitions. The asan and aarch64 test presets set GSF_TEST_SHORT (the
// aarch64 one also GSF_UNDER_EMULATOR, which a test reads only where the ISA itself matters). The host
// release run keeps the full counts; a shortened test still asserts every property, on less data.
#pragma once
#include <cstdlib>

namespace gsf_test {

inline bool short_run() {
  return std::getenv("GSF_TEST_SHORT") != nullptr || std::getenv("GSF_UNDER_EMULATOR") != nullptr;
}

}  // namespace gsf_test
