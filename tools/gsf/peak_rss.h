// The process's peak resident set size so far (Linux getrusage ru_maxrss): what `gsf build-map` reports
// as the builder's memory high-water mark. Host tool only; 0 where the platform does not say.
#pragma once
#include <cstdint>

namespace gsf::cli {

uint64_t peak_rss_bytes();

}  // namespace gsf::cli
