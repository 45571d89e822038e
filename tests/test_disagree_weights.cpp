// The per-scan disagree weights (core/include/gsf/detail/disagree_weights.h) and the verdicts they are
// counted from (semantic_grid.h): which disagreement costs which weight, the estimate's closed form and
// its limits, and on the lattice fixture: a whole object given the wrong class ties the lattice shifts
// under one fixed weight, and the scan's own weights separate them again.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "gsf/detail/disagree_weights.h"
#include "gsf/detail/semantic_grid.h"
#include "lattice_layer.h"

namespace test_disagree_weights {

using namespace gsf;
using gsf_test::Cloud;
using gsf_test::LatticeLayer;
using gsf_test::LatticeVerification;

TEST_CASE("A voxel on another class's cell costs other_class; one the map contradicts costs contradicted") {
  const LatticeLayer layer;  // road everywhere, columns (pole) every 8 m on y = 0, a bush at x 26-28, y 2-4
  const VerifyPoint points[] = {
      {26.5f, 2.5f, uint32_t(kVegetation)},   // on the bush: agrees
      {8.5f, 0.5f, uint32_t(kVegetation)},    // on a column: the map saw another above-ground class there
      {12.5f, 8.5f, uint32_t(kVegetation)},   // on bare road: the map saw nothing above ground there
      {12.5f, 8.5f, uint32_t(kRoad)},         // ground on ground: agrees (and is not counted below)
      {500.0f, 0.0f, uint32_t(kVegetation)},  // off the layer: unknown
  };
  float ones[kNumClasses];
  for (float& w : ones) w = 1.0f;
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  float evidence[5];
  const PoseVerification v =
      verify_pose_evidence(points, 5, layer.view, I, 64, ones, DisagreeWeights(3.0f, 0.5f), evidence);
  CHECK(v.agree == 2.0f);
  CHECK(v.disagree == 2.0f);
  CHECK(v.scored == 4);
  CHECK(v.unknown == 1);
  CHECK(v.score == Approx(2.0 - 3.0 - 0.5));
  const float expected[] = {1.0f, -0.5f, -3.0f, 1.0f, 0.0f};
  for (int k = 0; k < 5; ++k) CHECK(evidence[k] == expected[k]);
  // One weight is both: the score every disagreement pays alike.
  CHECK(verify_pose(points, 5, layer.view, I, 64, ones, 3.0f).score == Approx(2.0 - 3.0 - 3.0));
  const VerdictCounts c = count_verdicts(points, 5, layer.view, I, 64);
  CHECK(c.agree == 1);
  CHECK(c.other_class == 1);
  CHECK(c.contradicted == 1);
  CHECK(count_verdicts(points, 5, SemanticGridView(), I, 64).agree == 0);  // no layer: nothing counted
}

TEST_CASE("The other-class weight is the log-likelihood ratio of other-class landings over contradictions") {
  auto counts = [](uint32_t agree, uint32_t other, uint32_t contradicted) {
    VerdictCounts c;
    c.agree = agree;
    c.other_class = other;
    c.contradicted = contradicted;
    return c;
  };
  const VerdictCounts best = counts(800, 100, 60), competitors = counts(2000, 1000, 1000);
  const double tp = 963.0, tq = 4003.0;  // totals with one extra of each verdict
  const double l_other = std::log((101.0 / tp) / (1001.0 / tq)), l_contra = std::log((61.0 / tp) / (1001.0 / tq));
  const DisagreeWeights w = estimate_disagree_weights(best, competitors, 3.0f);
  CHECK(w.contradicted == 3.0f);
  CHECK(w.other_class == Approx(3.0 * l_other / l_contra));
  // Other-class landings are rarer at the best pose than at its competitors, but less so than contradictions.
  CHECK(w.other_class > 1.5f);
  CHECK(w.other_class < 2.5f);
  // As common at the best pose as at its competitors: no evidence either way, no penalty.
  CHECK(estimate_disagree_weights(counts(1000, 500, 50), counts(1000, 500, 500), 3.0f).other_class == 0.0f);
  // Rarer at the best pose than contradictions are: clipped to the full penalty.
  CHECK(estimate_disagree_weights(counts(1000, 1, 50), counts(1000, 500, 500), 3.0f).other_class == 3.0f);
  // The best pose no better than its competitors even by contradictions: nothing to measure against.
  const DisagreeWeights flat = estimate_disagree_weights(counts(1000, 50, 500), counts(1000, 500, 500), 3.0f);
  CHECK(flat.other_class == 3.0f);
  CHECK(flat.contradicted == 3.0f);
  CHECK(estimate_disagree_weights(VerdictCounts(), VerdictCounts(), 3.0f).other_class == 3.0f);
}

TEST_CASE("A whole object given the wrong class: the scan's own weights separate the lattice shifts again") {
  LatticeVerification fixture;
  const float sensor_x = 24.0f;
  // The lattice scan with its bush labelled pole (raw 80) instead of vegetation: a whole object confused.
  Cloud scan;
  for (float x = -20; x <= 20; x += 0.3f)
    for (float y = -10; y <= 10; y += 0.3f) scan.add(x, y, 0.0f, 40);
  for (int col = 0; col < 8; ++col)
    for (float z = 0.3f; z < 4.0f; z += 0.2f) scan.add(8.0f * col + 0.5f - sensor_x, 0.5f, z, 80);
  for (float x = 26.0f; x < 28.5f; x += 0.2f)
    for (float y = 2.0f; y < 4.5f; y += 0.2f)
      for (float z = 0.3f; z < 1.2f; z += 0.3f) scan.add(x - sensor_x, y, z, 80);
  fixture.build(scan);
  std::vector<VerifyPoint> points(fixture.voxels.size());
  fill_verify_points(fixture.voxels, points.data());
  const uint32_t n = fixture.voxels.size();
  auto at = [](float x) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation().x() = x;
    return T;
  };
  const Eigen::Isometry3d shifts[] = {at(sensor_x - 8.0f), at(sensor_x + 8.0f), at(sensor_x + 16.0f)};
  auto margin = [&](DisagreeWeights w) {  // the truth's score over the best shift's
    float best_shift = -1e30f;
    for (const Eigen::Isometry3d& T : shifts)
      best_shift =
          std::max(best_shift, verify_pose(points.data(), n, fixture.layer.view, T, 4096, fixture.weights, w).score);
    return verify_pose(points.data(), n, fixture.layer.view, at(sensor_x), 4096, fixture.weights, w).score - best_shift;
  };
  // At the truth the bush lands on the bush's cells under the wrong class, at a shift on bare road: one
  // fixed penalty makes both cost the same, and only the road's edge effects are left between them.
  const float fixed = margin(DisagreeWeights(3.0f));
  const DisagreeWeights own =
      scan_disagree_weights(points.data(), n, fixture.layer.view, at(sensor_x), shifts, 3, 4096, 3.0f);
  CHECK(own.contradicted == 3.0f);
  CHECK(own.other_class < 0.5f);
  const float separated = margin(own);
  INFO("fixed " << fixed << ", the scan's own " << separated);
  CHECK(separated > fixed + 10.0f);
  CHECK(separated > 0.0f);
  // Without competitors the probes stand in (8 m along each axis, turned 180 deg): the same verdict here.
  CHECK(scan_disagree_weights(points.data(), n, fixture.layer.view, at(sensor_x), nullptr, 0, 4096, 3.0f).other_class <
        0.5f);
}

}  // namespace test_disagree_weights
