#include "peak_rss.h"

#include <sys/resource.h>

namespace gsf::cli {

uint64_t peak_rss_bytes() {
  struct rusage u {};
  if (getrusage(RUSAGE_SELF, &u) != 0 || u.ru_maxrss < 0) return 0;
  return static_cast<uint64_t>(u.ru_maxrss) * 1024u;  // Linux reports kilobytes
}

}  // namespace gsf::cli
