// The answer stage's closed-form parts: rarity weights (keep the total, scale by share^-e) and the
// ambiguity terms; the stage as a whole runs in test_localizer (golden, lattice verification tests).
#include <catch2/catch.hpp>

#include <cmath>

#include "arena_buffer.h"
#include "gsf/detail/answer_selection.h"
#include "test_cloud.h"

using namespace gsf;
using gsf_test::ArenaBuffer;

TEST_CASE("Rarity weights scale each class by its share^-e and keep the scan's total weight") {
  VoxelConfig vc;
  vc.voxel_size = 0.5f;
  ArenaBuffer buf(VoxelLayer::required_bytes(vc));
  VoxelLayer layer;
  REQUIRE(layer.bind(buf.arena, vc) == Status::Ok);
  gsf_test::Cloud c;  // 90 road voxels and 10 pole voxels, one point each, 1 m apart
  for (int i = 0; i < 100; ++i) c.add(5.0f + float(i % 10), float(i / 10) - 5.0f, 0.2f, i < 90 ? 40u : 80u);
  REQUIRE(layer.build(c.view(), nullptr) == Status::Ok);
  REQUIRE(layer.size() == 100);
  float base[kNumClasses];
  for (int k = 0; k < kNumClasses; ++k) base[k] = 0.5f + 0.01f * k;
  float out[kNumClasses];
  rarity_weights(layer, base, 0.5f, 4096, out);
  // total weight kept: 90 w_road + 10 w_pole = 90 b_road + 10 b_pole
  const double before = 90.0 * base[kRoad] + 10.0 * base[kPole];
  const double after = 90.0 * out[kRoad] + 10.0 * out[kPole];
  CHECK(after == Approx(before).epsilon(1e-6));
  // ratio: (0.1 / 0.9)^-0.5 = 3 times the base ratio
  CHECK(double(out[kPole]) / out[kRoad] == Approx(3.0 * base[kPole] / base[kRoad]).epsilon(1e-5));
  // classes absent from the scan get the normalisation only: road's factor without its 0.9^-0.5
  CHECK(double(out[kCar]) / base[kCar] == Approx(double(out[kRoad]) / base[kRoad] * std::sqrt(0.9)).epsilon(1e-5));
  rarity_weights(layer, base, 0.0f, 4096, out);  // exponent 0: the base weights
  for (int k = 0; k < kNumClasses; ++k) CHECK(out[k] == base[k]);
}

TEST_CASE("Ambiguity terms: agreement maps linearly between the thresholds; the largest term wins, capped at 1") {
  PoseVerification v;
  v.scored = 100;
  v.agree = 95.0f;
  v.disagree = 5.0f;  // q = 0.9
  CHECK(agreement_ambiguity(v, 0.8f, 0.95f) == Approx((0.95 - 0.9) / 0.15).epsilon(1e-5));
  v.agree = 100.0f;
  v.disagree = 0.0f;  // q = 1: better than quality_high, no ambiguity from agreement
  CHECK(agreement_ambiguity(v, 0.8f, 0.95f) < 0.0);
  v.agree = v.disagree = 0.0f;  // nothing scored with weight: q = -1
  CHECK(agreement_ambiguity(v, 0.8f, 0.95f) == Approx(1.95 / 0.15));
  v.scored = 0;
  CHECK(agreement_ambiguity(v, 0.8f, 0.95f) == 0.0);
  AmbiguityTerms t;
  t.rival = 0.2;
  t.support = 3.0 / 12.0;
  t.quality = -0.5;
  CHECK(t.value() == 0.25);
  t.quality = 4.0;
  CHECK(t.value() == 1.0);
}
