// The paper's Fig. 4 measurement as a reusable function: fit a field on M points chosen by Algorithm 1
// (semantic) or uniformly (random), take the argmax of the posterior mean at every neighbourhood point,
// and return the mIoU against the points' labels over the classes present.
#pragma once
#include <cstring>
#include <vector>

#include "gsf/detail/gaussian_field.h"
#include "gsf/detail/sparsify.h"

namespace gsf_test {

inline double reconstruction_miou(const gsf::FieldConfig& base, const float* xyz, const float* targets,
                                  const uint8_t* labels, uint32_t n, uint32_t m_target, bool semantic, uint64_t seed) {
  using namespace gsf;
  std::vector<uint32_t> sel(n), scratch(n);
  const uint32_t m = semantic ? sparsify_semantic(labels, n, m_target, seed, sel.data(), scratch.data())
                              : sparsify_random(n, m_target, seed, sel.data(), scratch.data());
  std::vector<float> sx(m * 3), sy(m * kNumClasses);
  std::vector<uint8_t> sl(m);
  for (uint32_t r = 0; r < m; ++r) {
    std::memcpy(&sx[3 * r], &xyz[3 * sel[r]], 12);
    std::memcpy(&sy[r * kNumClasses], &targets[size_t(sel[r]) * kNumClasses], kNumClasses * 4);
    sl[r] = labels[sel[r]];
  }
  FieldConfig fc = base;
  fc.inducing_points = m;
  std::vector<uint64_t> mem((FieldSolver::required_bytes(fc, m) + 64) / 8 + 2);
  Arena arena(mem.data(), mem.size() * 8);
  FieldSolver fs;
  if (fs.bind(arena, fc, m) != Status::Ok) return 0.0;
  std::vector<float> in(m * 3), al(m * kNumClasses), ch(m * m), mean(kMaxGridPoints * kNumClasses), var(kMaxGridPoints);
  uint32_t used = 0;
  if (fs.fit(sx.data(), sy.data(), sl.data(), m, in.data(), al.data(), ch.data(), &used) != Status::Ok) return 0.0;
  int inter[kNumClasses] = {}, uni[kNumClasses] = {};
  for (uint32_t s0 = 0; s0 < n; s0 += kMaxGridPoints) {
    const uint32_t g = n - s0 < kMaxGridPoints ? n - s0 : kMaxGridPoints;
    fs.probe(FieldView{in.data(), al.data(), used}, ch.data(), &xyz[3 * s0], g, mean.data(), var.data(), nullptr);
    for (uint32_t s = 0; s < g; ++s) {
      int best = 0;
      for (int d = 1; d < kNumClasses; ++d)
        if (mean[s * kNumClasses + d] > mean[s * kNumClasses + best]) best = d;
      const int truth = labels[s0 + s];
      if (best == truth) {
        inter[truth]++;
        uni[truth]++;
      } else {
        uni[truth]++;
        uni[best]++;
      }
    }
  }
  double sum = 0;
  int classes = 0;
  for (int d = 0; d < kNumClasses; ++d)
    if (uni[d]) {
      sum += double(inter[d]) / uni[d];
      ++classes;
    }
  return classes ? sum / classes : 0.0;
}

}  // namespace gsf_test
