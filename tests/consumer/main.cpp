#include <cstdio>
#include "gsf/localizer.h"
#include "gsf/port/clock.h"
int main() {
  gsf::LocalizerConfig cfg;
  gsf::port::SteadyClock clock;  // links gsf::port
  const uint64_t t0 = clock.now_ns();
  const gsf::Status s = clock.now_ns() >= t0 ? gsf::Status::Ok : gsf::Status::InvalidArgument;
  std::printf("%zu %s\n", gsf::Localizer::required_bytes(cfg), gsf::to_string(s));
  return 0;
}
