// Host monotonic clock (std::chrono::steady_clock) implementing gsf::Clock.
#pragma once
#include "gsf/platform.h"

namespace gsf::port {

class SteadyClock final : public Clock {
 public:
  uint64_t now_ns() override;
};

}  // namespace gsf::port
