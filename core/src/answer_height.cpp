#include "gsf/detail/answer_height.h"

#include <algorithm>

namespace gsf {

uint32_t consensus_height(const float* a, const float* b, const float* w, uint32_t n, float radius, uint32_t min_count,
                          HeightSample* scratch, Eigen::Isometry3d* T) {
  if (!T || !scratch || n == 0 || !(radius > 0.0f)) return 0;
  const Eigen::Matrix3d R = T->linear();
  const Eigen::Vector3d t = T->translation();
  const double r2 = double(radius) * radius;
  uint32_t m = 0;
  double total = 0.0;
  for (uint32_t i = 0; i < n; ++i) {
    const Eigen::Vector3d q = R * Eigen::Vector3d(a[3 * i], a[3 * i + 1], a[3 * i + 2]);
    const double dx = q.x() + t.x() - b[3 * i], dy = q.y() + t.y() - b[3 * i + 1];
    if (dx * dx + dy * dy > r2 || !(w[i] > 0.0f)) continue;
    scratch[m++] = HeightSample{static_cast<float>(double(b[3 * i + 2]) - q.z()), w[i], i};
    total += w[i];
  }
  if (m == 0 || m < min_count) return 0;
  std::sort(scratch, scratch + m, [](const HeightSample& x, const HeightSample& y) {
    return x.offset < y.offset || (x.offset == y.offset && x.index < y.index);
  });
  // The weighted median: the first offset at which the running weight reaches half the total.
  double running = 0.0;
  uint32_t k = 0;
  for (; k + 1 < m; ++k) {
    running += scratch[k].weight;
    if (running >= 0.5 * total) break;
  }
  T->translation().z() = scratch[k].offset;
  return m;
}

}  // namespace gsf
