#include "gsf/detail/sparsify.h"

#include <algorithm>

#include "gsf/detail/rng.h"
#include "gsf/semantic_classes.h"

namespace gsf {

uint32_t sparsify_random(uint32_t n, uint32_t target, uint64_t seed, uint32_t* out, uint32_t* scratch) {
  const uint32_t k = std::min(n, target);
  for (uint32_t i = 0; i < n; ++i) scratch[i] = i;
  Rng rng(seed);
  for (uint32_t i = 0; i < k; ++i) {
    const uint32_t j = i + rng.uniform(n - i);
    std::swap(scratch[i], scratch[j]);
    out[i] = scratch[i];
  }
  std::sort(out, out + k);
  return k;
}

uint32_t sparsify_semantic(const uint8_t* labels, uint32_t n, uint32_t target, uint64_t seed, uint32_t* out,
                           uint32_t* scratch) {
  const uint32_t total = std::min(n, target);
  if (total == 0) return 0;
  if (total == n) {
    for (uint32_t i = 0; i < n; ++i) out[i] = i;
    return n;
  }
  // Labels >= kNumClasses share one extra bucket so every point belongs somewhere.
  constexpr int kBuckets = kNumClasses + 1;
  uint32_t count[kBuckets] = {};
  for (uint32_t i = 0; i < n; ++i) count[labels[i] < kNumClasses ? labels[i] : kNumClasses]++;
  // Quotas: floor of the exact share, then the remaining slots to the largest remainders
  // (ties to the lower class index) - this is round(p_c N) corrected to sum to N.
  uint32_t quota[kBuckets];
  uint64_t remainder[kBuckets];
  uint32_t assigned = 0;
  for (int c = 0; c < kBuckets; ++c) {
    const uint64_t num = uint64_t(count[c]) * total;
    quota[c] = static_cast<uint32_t>(num / n);
    remainder[c] = num % n;
    assigned += quota[c];
  }
  while (assigned < total) {
    int best = -1;
    for (int c = 0; c < kBuckets; ++c)
      if (quota[c] < count[c] && (best < 0 || remainder[c] > remainder[best])) best = c;
    quota[best]++;
    remainder[best] = 0;
    assigned++;
  }
  // Group indices by class (counting sort), then a partial Fisher-Yates inside each class.
  uint32_t start[kBuckets + 1];
  start[0] = 0;
  for (int c = 0; c < kBuckets; ++c) start[c + 1] = start[c] + count[c];
  uint32_t fill[kBuckets];
  for (int c = 0; c < kBuckets; ++c) fill[c] = start[c];
  for (uint32_t i = 0; i < n; ++i) scratch[fill[labels[i] < kNumClasses ? labels[i] : kNumClasses]++] = i;
  Rng rng(seed);
  uint32_t written = 0;
  for (int c = 0; c < kBuckets; ++c) {
    uint32_t* group = scratch + start[c];
    for (uint32_t i = 0; i < quota[c]; ++i) {
      const uint32_t j = i + rng.uniform(count[c] - i);
      std::swap(group[i], group[j]);
      out[written++] = group[i];
    }
  }
  std::sort(out, out + written);
  return written;
}

}  // namespace gsf
