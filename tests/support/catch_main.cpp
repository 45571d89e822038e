// The tests' main: Catch2's session, plus the skip exit code (skip.h): a run in which a test case
// skipped for an absent input and no assertion failed exits with kSkipReturnCode, which ctest reports
// as skipped.
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include <cstdio>

#include "skip.h"

namespace gsf_test {
namespace {
int skipped = 0;
}  // namespace

void note_skip(const std::string& reason) {
  ++skipped;
  std::printf("gsf_test: skipped (%s)\n", reason.c_str());
  std::fflush(stdout);
}

int skips() { return skipped; }

}  // namespace gsf_test

int main(int argc, char** argv) {
  const int result = Catch::Session().run(argc, argv);
  if (result == 0 && gsf_test::skips() > 0) {
    std::printf("gsf_test: %d test case(s) skipped, none failed: exit code %d (ctest: Skipped)\n", gsf_test::skips(),
                gsf_test::kSkipReturnCode);
    return gsf_test::kSkipReturnCode;
  }
  return result;
}
