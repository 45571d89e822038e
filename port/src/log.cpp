#include "gsf/port/log.h"

#include <cstdarg>
#include <cstdio>
#include <cstring>

namespace gsf::port {

void StderrLogSink::write(LogLevel level, const char* message) {
  if (level < min_) return;
  static const char* names[] = {"debug", "info", "warn", "error"};
  std::fprintf(stderr, "[gsf %s] %s\n", names[static_cast<int>(level)], message);
}

void logf(LogSink& sink, LogLevel level, const char* fmt, ...) {
  char buf[512];
  va_list ap;
  va_start(ap, fmt);
  const int n = std::vsnprintf(buf, sizeof(buf), fmt, ap);
  va_end(ap);
  if (n >= static_cast<int>(sizeof(buf))) std::memcpy(buf + sizeof(buf) - 4, "...", 4);
  sink.write(level, buf);
}

}  // namespace gsf::port
