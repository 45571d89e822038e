// Test helper: a ctest skip for a test case whose input is absent (the real sample data under
// GSF_DATA_DIR, the release build's cross-ISA reference). Catch2 v2 has no skip of its own, so
// GSF_SKIP_UNLESS(condition, reason) records the reason, prints it (a Catch2 warning) and returns from
// the test case; the test executable's main (catch_main.cpp) then exits with kSkipReturnCode when no
// assertion failed, and tests/CMakeLists.txt gives every test that code as its SKIP_RETURN_CODE, so ctest
// reports "Skipped", never "Passed". Test cases that may skip carry the tag [real-data] or [cross-isa],
// and tests/CMakeLists.txt runs each tag as a ctest entry of its own (e.g. test_port_real_data), so a
// skip never hides the executable's other test cases.
#pragma once
#include <catch2/catch.hpp>

#include <string>

namespace gsf_test {

constexpr int kSkipReturnCode = 77;

// Defined in catch_main.cpp.
void note_skip(const std::string& reason);
int skips();

}  // namespace gsf_test

#define GSF_SKIP_UNLESS(condition, reason)           \
  do {                                               \
    if (!(condition)) {                              \
      const std::string gsf_skip_reason_ = (reason); \
      WARN("SKIPPED: " << gsf_skip_reason_);         \
      gsf_test::note_skip(gsf_skip_reason_);         \
      return;                                        \
    }                                                \
  } while (0)
