// The platform seam: the only services core/ consumes from the outside world. Core declares the
// interfaces; port/ (host) or the firmware implements them. No OS header is needed to use them.
#pragma once
#include <cstdint>

namespace gsf {

// Monotonic time source for per-stage timings. Must not allocate or block.
class Clock {
 public:
  virtual ~Clock() = default;
  virtual uint64_t now_ns() = 0;
};

enum class LogLevel : uint8_t { Debug = 0, Info, Warn, Error };

// Log sink: receives finished, NUL-terminated messages. Formatting happens before the call in a
// fixed buffer (port/log.h has a printf-style helper), so a sink never has to allocate.
class LogSink {
 public:
  virtual ~LogSink() = default;
  virtual void write(LogLevel level, const char* message) = 0;
};

}  // namespace gsf
