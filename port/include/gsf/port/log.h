// Host log sink (stderr) and a printf-style helper that formats into a fixed stack buffer (no heap).
#pragma once
#include "gsf/platform.h"

namespace gsf::port {

class StderrLogSink final : public LogSink {
 public:
  explicit StderrLogSink(LogLevel min_level = LogLevel::Info) : min_(min_level) {}
  void write(LogLevel level, const char* message) override;

 private:
  LogLevel min_;
};

// Formats into a 512-byte stack buffer; a truncated message ends with "...".
void logf(LogSink& sink, LogLevel level, const char* fmt, ...) __attribute__((format(printf, 3, 4)));

}  // namespace gsf::port
