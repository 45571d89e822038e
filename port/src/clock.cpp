#include "gsf/port/clock.h"

#include <chrono>

namespace gsf::port {

uint64_t SteadyClock::now_ns() {
  return static_cast<uint64_t>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
          .count());
}

}  // namespace gsf::port
