#include "baselines/scan_context.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace gsf::bench {

ScanContext make_scan_context(const ScanContextConfig& cfg, const float* points, uint32_t stride, uint32_t count) {
  ScanContext sc;
  sc.cells.assign(static_cast<size_t>(cfg.rings) * cfg.sectors, 0.0f);
  const float two_pi = 6.283185307179586f;
  for (uint32_t i = 0; i < count; ++i) {
    const float* p = points + static_cast<size_t>(i) * stride;
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) continue;
    const float r = std::sqrt(p[0] * p[0] + p[1] * p[1]);
    if (r < cfg.min_range || r >= cfg.max_range) continue;
    float a = std::atan2(p[1], p[0]);
    if (a < 0) a += two_pi;
    int ring = static_cast<int>(r / cfg.max_range * cfg.rings);
    int sector = static_cast<int>(a / two_pi * cfg.sectors);
    ring = std::min(ring, cfg.rings - 1);
    sector = std::min(sector, cfg.sectors - 1);
    float& cell = sc.cells[static_cast<size_t>(ring) * cfg.sectors + sector];
    cell = std::max(cell, std::max(0.0f, p[2] + cfg.height_offset));
  }
  sc.ring_key.assign(cfg.rings, 0.0f);
  for (int r = 0; r < cfg.rings; ++r) {  // ring key: mean cell value of each ring, as in the original
    float sum = 0.0f;
    for (int s = 0; s < cfg.sectors; ++s) sum += sc.cells[static_cast<size_t>(r) * cfg.sectors + s];
    sc.ring_key[r] = sum / cfg.sectors;
  }
  return sc;
}

float scan_context_distance(const ScanContextConfig& cfg, const ScanContext& q, const ScanContext& m, int* best_shift) {
  const int R = cfg.rings, S = cfg.sectors;
  // Column norms once.
  std::vector<float> qn(S, 0.0f), mn(S, 0.0f);
  for (int s = 0; s < S; ++s)
    for (int r = 0; r < R; ++r) {
      qn[s] += q.cells[r * S + s] * q.cells[r * S + s];
      mn[s] += m.cells[r * S + s] * m.cells[r * S + s];
    }
  float best = 2.0f;
  int arg = 0;
  for (int shift = 0; shift < S; ++shift) {
    float sum = 0.0f;
    int used = 0;
    for (int s = 0; s < S; ++s) {
      const int ms = (s + shift) % S;
      if (qn[s] == 0.0f || mn[ms] == 0.0f) continue;
      float dot = 0.0f;
      for (int r = 0; r < R; ++r) dot += q.cells[r * S + s] * m.cells[r * S + ms];
      sum += 1.0f - dot / std::sqrt(qn[s] * mn[ms]);
      ++used;
    }
    const float d = used ? sum / used : 2.0f;
    if (d < best) {
      best = d;
      arg = shift;
    }
  }
  if (best_shift) *best_shift = arg;
  return best;
}

void ScanContextDatabase::add(ScanContext sc, const Eigen::Isometry3d& pose) {
  entries_.push_back(Entry{std::move(sc), pose});
}

ScanContextDatabase::Match ScanContextDatabase::query(const ScanContext& sc) const {
  Match out;
  if (entries_.empty()) return out;
  // Ring-key retrieval: k nearest by L2 (brute force over the map drive; a kd-tree in the original).
  std::vector<std::pair<float, int>> keyd(entries_.size());
  for (size_t i = 0; i < entries_.size(); ++i) {
    float d = 0.0f;
    for (int r = 0; r < cfg_.rings; ++r) {
      const float e = sc.ring_key[r] - entries_[i].sc.ring_key[r];
      d += e * e;
    }
    keyd[i] = {d, static_cast<int>(i)};
  }
  const size_t k = std::min<size_t>(static_cast<size_t>(cfg_.candidates), keyd.size());
  std::partial_sort(keyd.begin(), keyd.begin() + k, keyd.end());
  struct Cand {
    float dist;
    int index;
    int shift;
  };
  std::vector<Cand> cands;
  for (size_t c = 0; c < k; ++c) {
    int shift = 0;
    const float d = scan_context_distance(cfg_, sc, entries_[keyd[c].second].sc, &shift);
    cands.push_back({d, keyd[c].second, shift});
  }
  std::sort(cands.begin(), cands.end(),
            [](const Cand& a, const Cand& b) { return a.dist < b.dist || (a.dist == b.dist && a.index < b.index); });
  const Cand& best = cands.front();
  out.found = true;
  out.index = best.index;
  out.distance = best.dist;
  const Eigen::Vector3d best_pos = entries_[best.index].pose.translation();
  for (const Cand& c : cands)
    if ((entries_[c.index].pose.translation() - best_pos).norm() > 10.0) {
      out.second_distance = c.dist;
      break;
    }
  // Query sector j sees the direction map sector j+shift sees: yaw_query = yaw_map + shift * sector angle.
  const double yaw = 2.0 * M_PI * best.shift / cfg_.sectors;
  out.pose = entries_[best.index].pose * Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ());
  return out;
}

}  // namespace gsf::bench
