// Scan Context (G. Kim, A. Kim, IROS 2018) as the place-recognition peer baseline: the LCD family row
// of the paper's Table II. Written from the published description:
//   - egocentric polar grid, N_r rings x N_s sectors up to max_range; cell = max point height (+offset),
//   - ring key = per-ring mean cell value (rotation invariant) for candidate retrieval (k nearest),
//   - column-shifted cosine distance between descriptors picks the best candidate and its yaw.
// A query's pose estimate is the retrieved map scan's pose rotated by the recovered yaw, so its
// translation error is at least the distance between the two scans (as for every LCD method).
#pragma once
#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

namespace gsf::bench {

struct ScanContextConfig {
  int rings = 20;
  int sectors = 60;
  float max_range = 80.0f;
  float height_offset = 2.0f;  // sensor height, so ground cells are > 0
  int candidates = 10;         // ring-key neighbours re-ranked by the full descriptor
  float min_range = 2.5f;      // drop ego-vehicle returns
};

struct ScanContext {
  std::vector<float> cells;     // rings x sectors, row-major by ring
  std::vector<float> ring_key;  // rings
};

ScanContext make_scan_context(const ScanContextConfig& cfg, const float* points, uint32_t stride, uint32_t count);

// Column-shift distance in [0, 2]; best_shift s means query sector j matches map sector (j + s) mod N_s.
float scan_context_distance(const ScanContextConfig& cfg, const ScanContext& query, const ScanContext& map,
                            int* best_shift);

class ScanContextDatabase {
 public:
  explicit ScanContextDatabase(const ScanContextConfig& cfg) : cfg_(cfg) {}
  void add(ScanContext sc, const Eigen::Isometry3d& world_T_lidar);
  struct Match {
    bool found = false;
    int index = -1;
    float distance = 2.0f;
    float second_distance = 2.0f;  // best distance among candidates farther than 10 m from the best
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // estimated world_T_query
  };
  Match query(const ScanContext& sc) const;
  size_t size() const { return entries_.size(); }

 private:
  struct Entry {
    ScanContext sc;
    Eigen::Isometry3d pose;
  };
  ScanContextConfig cfg_;
  std::vector<Entry> entries_;
};

}  // namespace gsf::bench
