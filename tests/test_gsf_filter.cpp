// The GSF filter alone (core/include/gsf/detail/gsf_filter.h): the yaw bin of a rotated triangle, a known
// similarity (a field compared with itself seen from a rotated frame), and the caches: hits, and the
// full-cache paths that compute into scratch without remembering.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "arena_buffer.h"
#include "gsf/detail/angles.h"
#include "gsf/detail/gaussian_field.h"
#include "gsf/detail/gsf_filter.h"
#include "gsf/detail/map_quantization.h"
#include "gsf/detail/wasserstein.h"
#include "gsf/map_format.h"

namespace test_gsf_filter {

using namespace gsf;

namespace {

void rotate_xy(const float* p, double yaw, float* out) {
  const double c = std::cos(yaw), s = std::sin(yaw);
  out[0] = static_cast<float>(c * p[0] - s * p[1]);
  out[1] = static_cast<float>(s * p[0] + c * p[1]);
  out[2] = p[2];
}

// An asymmetric neighbourhood around an instance at the origin (instance-local): a wall to +x, a hedge
// to -y, road in a strip, 30 points (fewer than the 32 inducing points, so Algorithm 1 keeps all).
struct Neighbourhood {
  std::vector<float> xyz, targets;
  std::vector<uint8_t> labels;
  Neighbourhood() {
    auto add = [&](float x, float y, int c) {
      xyz.insert(xyz.end(), {x, y, 0.0f});
      std::vector<float> t(kNumClasses, 0.0f);
      t[c] = 1.0f;
      targets.insert(targets.end(), t.begin(), t.end());
      labels.push_back(static_cast<uint8_t>(c));
    };
    for (int i = 0; i < 10; ++i) add(3.0f, -2.0f + 0.5f * i, kBuilding);
    for (int i = 0; i < 8; ++i) add(-3.0f + 0.7f * i, -3.5f, kVegetation);
    for (int i = 0; i < 12; ++i) add(-4.0f + 0.6f * i, 2.0f + 0.3f * (i % 3), kRoad);
  }
  uint32_t n() const { return static_cast<uint32_t>(labels.size()); }
};

// One fitted query field (arrays for QueryFields, instance 0) or the map's probed grid of it.
struct Fitted {
  std::vector<float> inputs, alpha, chol;
  uint32_t m = 0;
};

Fitted fit(FieldSolver& solver, const FieldConfig& fc, const Neighbourhood& nb, double yaw) {
  const uint32_t M = fc.inducing_points;
  std::vector<float> xyz(nb.xyz.size());
  for (uint32_t i = 0; i < nb.n(); ++i) rotate_xy(&nb.xyz[3 * i], yaw, &xyz[3 * i]);
  Fitted f;
  f.inputs.assign(size_t(M) * 3, 0.0f);
  f.alpha.assign(size_t(M) * kNumClasses, 0.0f);
  f.chol.assign(size_t(M) * M, 0.0f);
  REQUIRE(solver.fit(xyz.data(), nb.targets.data(), nb.labels.data(), nb.n(), f.inputs.data(), f.alpha.data(),
                     f.chol.data(), &f.m) == Status::Ok);
  REQUIRE(f.m == nb.n());
  return f;
}

// A map of `instances` copies of the neighbourhood at yaw 0, each probed on the canonical grid.
struct OneMap {
  std::vector<float> mean, var;
  std::vector<MapInstance> instances;
  std::vector<uint8_t> q_mean;
  std::vector<uint16_t> q_var;
  MapView view;
};

OneMap make_map(FieldSolver& solver, const FieldConfig& fc, const Neighbourhood& nb, uint32_t instances) {
  const uint32_t G = grid_points(fc);
  const Fitted f = fit(solver, fc, nb, 0.0);
  std::vector<float> grid(size_t(G) * 3);
  make_probe_grid(fc, 0.0f, grid.data());
  OneMap map;
  map.mean.resize(size_t(instances) * G * kNumClasses);
  map.var.resize(size_t(instances) * G);
  for (uint32_t i = 0; i < instances; ++i) {
    FieldView v{f.inputs.data(), f.alpha.data(), f.m};
    REQUIRE(solver.probe(v, f.chol.data(), grid.data(), G, map.mean.data() + size_t(i) * G * kNumClasses,
                         map.var.data() + size_t(i) * G, nullptr) == Status::Ok);
  }
  // Stored as the map format stores them: quantised per instance (map_quantization.h).
  map.instances.assign(instances, MapInstance{});
  map.q_mean.resize(map.mean.size());
  map.q_var.resize(map.var.size());
  for (uint32_t i = 0; i < instances; ++i)
    quantize_instance_grid(map.mean.data() + size_t(i) * G * kNumClasses, map.var.data() + size_t(i) * G, G,
                           kNumClasses, &map.instances[i], map.q_mean.data() + size_t(i) * G * kNumClasses,
                           map.q_var.data() + size_t(i) * G);
  map.view.instances = map.instances.data();
  map.view.grid_mean = map.q_mean.data();
  map.view.grid_var = map.q_var.data();
  map.view.params.num_classes = kNumClasses;
  map.view.params.grid_nx = fc.grid_nx;
  map.view.params.grid_ny = fc.grid_ny;
  map.view.params.grid_layers = fc.grid_layers;
  map.view.counts.instances = instances;
  return map;
}

// A filter (36 yaw bins) over a solver and a one-instance map of the neighbourhood, on field config fc.
struct OneInstanceFilter {
  FieldConfig fc;
  GsfFilterConfig gc;
  gsf_test::ArenaBuffer buf;
  FieldSolver solver;
  GsfFilter filter;
  Neighbourhood nb;
  OneMap map;
  explicit OneInstanceFilter(const FieldConfig& field)
      : fc(field), buf(FieldSolver::required_bytes(fc, 64) + GsfFilter::required_bytes(gc, fc) + 256) {
    REQUIRE(solver.bind(buf.arena, fc, 64) == Status::Ok);
    REQUIRE(filter.bind(buf.arena, gc, fc, &solver) == Status::Ok);
    map = make_map(solver, fc, nb, 1);
  }
};

}  // namespace

TEST_CASE("triangle_yaw_bin: a triangle rotated by yaw lands in round(yaw / bin width)") {
  const float m0[3] = {0, 0, 1}, m1[3] = {7, 1, 2}, m2[3] = {2, 5, 0};
  const float* m[3] = {m0, m1, m2};
  struct Case {
    double deg;
    uint32_t bin;
  };
  for (const Case c : {Case{0, 0}, Case{50, 5}, Case{123, 12}, Case{181, 18}, Case{359, 0}, Case{-94, 27}}) {
    // map = R(yaw) query + t, so the query vertices are R(-yaw) (m - t).
    float q[3][3];
    for (int v = 0; v < 3; ++v) {
      const float shifted[3] = {m[v][0] - 40.0f, m[v][1] + 12.0f, m[v][2]};
      rotate_xy(shifted, -c.deg * kPi / 180.0, q[v]);
    }
    const float* qp[3] = {q[0], q[1], q[2]};
    INFO("yaw " << c.deg << " deg");
    CHECK(triangle_yaw_bin(qp, m, 36) == c.bin);
    CHECK(triangle_yaw_bin(qp, m, 72) == uint32_t((std::llround(c.deg / 5.0) % 72 + 72) % 72));
  }
}

TEST_CASE("GSF similarity: a field against itself seen from a rotated frame is ~1 at its yaw, lower elsewhere") {
  OneInstanceFilter one{FieldConfig()};
  const FieldConfig& fc = one.fc;
  GsfFilter& filter = one.filter;
  const OneMap& map = one.map;
  // The scan sees the neighbourhood rotated: map = R(50 deg) scan, so scan = R(-50 deg) map.
  const Fitted q = fit(one.solver, fc, one.nb, -50.0 * kPi / 180.0);
  const QueryFields qf{q.inputs.data(), q.alpha.data(), q.chol.data(), &q.m, fc.inducing_points};
  const float at_yaw = filter.similarity(qf, 0, map.view, 0, 5);     // 50 deg
  const float near_yaw = filter.similarity(qf, 0, map.view, 0, 4);   // 40 deg
  const float quarter = filter.similarity(qf, 0, map.view, 0, 14);   // 140 deg
  const float opposite = filter.similarity(qf, 0, map.view, 0, 23);  // 230 deg
  INFO("omega at 50 deg " << at_yaw << ", 40 deg " << near_yaw << ", 140 deg " << quarter << ", 230 deg " << opposite);
  CHECK(at_yaw > 0.99f);
  CHECK(at_yaw <= 1.0f);
  CHECK(near_yaw < at_yaw);
  CHECK(quarter < 0.5f * at_yaw);
  CHECK(opposite < 0.5f * at_yaw);
  // A query instance without a field compares as 0 (never as a match).
  const uint32_t none = 0;
  const QueryFields empty{q.inputs.data(), q.alpha.data(), q.chol.data(), &none, fc.inducing_points};
  filter.reset();
  CHECK(filter.similarity(empty, 0, map.view, 0, 5) == 0.0f);
}

// The omega of (query instance 0, map instance 0) at yaw_bin, the regression run at that bin's turned grid
// (GsfFilter::similarity without its shared probes).
float fresh_omega(FieldSolver& solver, const FieldConfig& fc, const GsfFilterConfig& gc, const Fitted& q,
                  const MapView& map, uint32_t yaw_bin) {
  const uint32_t G = grid_points(fc);
  std::vector<float> grid(size_t(G) * 3), mean(size_t(G) * kNumClasses), var(G), map_mean(mean.size()), map_var(G);
  make_probe_grid(fc, -static_cast<float>(kTwoPi * yaw_bin / gc.yaw_bins), grid.data());
  const float max_var = gc.observed_variance * fc.signal_variance;
  FieldView f{q.inputs.data(), q.alpha.data(), q.m};
  REQUIRE(solver.probe(f, q.chol.data(), grid.data(), G, mean.data(), var.data(), nullptr, max_var) == Status::Ok);
  dequantize_instance_grid(map, 0, map_mean.data(), map_var.data());
  float weights[kNumClasses];
  stability_weights(weights);
  const ObservedW2 r = w2_squared_diag_observed(mean.data(), var.data(), map_mean.data(), map_var.data(), G, weights,
                                                max_var, gc.covariance_weight);
  REQUIRE(r.used >= 4);
  return static_cast<float>(std::exp(-(r.w2 / r.used) / gc.tau));
}

TEST_CASE("A yaw bin a whole turn of the probe grid from another reuses its regression, re-indexed") {
  for (const uint32_t ny : {6u, 4u}) {  // square grid: quarter turns; 6 x 4: half turns only
    FieldConfig grid;
    grid.grid_ny = ny;
    OneInstanceFilter one(grid);  // 36 yaw bins: a quarter turn is 9 bins
    const FieldConfig& fc = one.fc;
    GsfFilter& filter = one.filter;
    const OneMap& map = one.map;
    // Seen at 140 deg (bin 14, a quarter turn past bin 5), 230 deg (bin 23, a half turn) and 320 deg.
    for (const double deg : {140.0, 230.0, 320.0}) {
      const Fitted q = fit(one.solver, fc, one.nb, -deg * kPi / 180.0);
      const QueryFields qf{q.inputs.data(), q.alpha.data(), q.chol.data(), &q.m, fc.inducing_points};
      const uint32_t bin = static_cast<uint32_t>(deg / 10.0);
      filter.reset();
      const float shared = filter.similarity(qf, 0, map.view, 0, bin);
      const bool quarter = ny == fc.grid_nx, whole_turn = quarter || bin % 18 == 5;
      INFO("grid 6 x " << ny << ", " << deg << " deg");
      // One regression: the base bin's (5), re-indexed; or none shared (the bin's own).
      CHECK(filter.probes() == 1);
      CHECK(filter.probe_ready(qf, 0, 5) == whole_turn);
      CHECK(shared > 0.99f);  // the field against itself at its yaw
      CHECK(std::fabs(shared - fresh_omega(one.solver, fc, one.gc, q, map.view, bin)) < 1e-4f);
      // The other bins of the same base cost no regression; a bin of another base does.
      for (uint32_t turn = 0; turn < 4; ++turn) filter.similarity(qf, 0, map.view, 0, 5 + 9 * turn);
      CHECK(filter.probes() == (quarter ? 1u : 2u));  // 6 x 4: bins 5 and 23 share, 14 and 32 do too
      filter.similarity(qf, 0, map.view, 0, 6);
      CHECK(filter.probes() == (quarter ? 2u : 3u));
    }
  }
}

TEST_CASE("GSF filter caches: hits cost nothing, full caches compute into scratch with the same values") {
  FieldConfig fc;
  GsfFilterConfig big;
  GsfFilterConfig tiny = big;
  tiny.probe_cache_slots = 1;
  tiny.similarity_cache_slots = 1;
  gsf_test::ArenaBuffer buf(FieldSolver::required_bytes(fc, 64) + GsfFilter::required_bytes(big, fc) +
                            GsfFilter::required_bytes(tiny, fc) + 512);
  FieldSolver solver;
  REQUIRE(solver.bind(buf.arena, fc, 64) == Status::Ok);
  GsfFilter a, b;
  REQUIRE(a.bind(buf.arena, big, fc, &solver) == Status::Ok);
  REQUIRE(b.bind(buf.arena, tiny, fc, &solver) == Status::Ok);
  const Neighbourhood nb;
  const OneMap map = make_map(solver, fc, nb, 3);
  const Fitted q = fit(solver, fc, nb, -20.0 * kPi / 180.0);
  const QueryFields qf{q.inputs.data(), q.alpha.data(), q.chol.data(), &q.m, fc.inducing_points};

  // Hits: the same (query, map, bin) twice is one comparison; another map instance at the same bin
  // reuses the query's probe.
  const float s0 = a.similarity(qf, 0, map.view, 0, 2);
  CHECK(a.similarity(qf, 0, map.view, 0, 2) == s0);
  CHECK(a.comparisons() == 1);
  CHECK(a.probes() == 1);
  CHECK(a.similarity(qf, 0, map.view, 1, 2) == s0);  // identical map instances
  CHECK(a.comparisons() == 2);
  CHECK(a.probes() == 1);
  // The cost queries the localizer orders vertices by: a cached omega, a cached probe; neither computes.
  CHECK(a.cached_similarity(0, 0, 2) != nullptr);
  CHECK(*a.cached_similarity(0, 0, 2) == s0);
  CHECK(a.cached_similarity(0, 2, 9) == nullptr);
  CHECK(a.probe_ready(qf, 0, 2));
  CHECK_FALSE(a.probe_ready(qf, 0, 9));
  CHECK(a.probes() == 1);
  CHECK(a.comparisons() == 2);
  const float s_other_bin = a.similarity(qf, 0, map.view, 2, 9);
  CHECK(a.probes() == 2);
  CHECK(a.probe_ready(qf, 0, 9));
  CHECK(*a.cached_similarity(0, 2, 9) == s_other_bin);
  // Each map instance's grid is dequantised once, whatever the bins and query instances it meets.
  CHECK(a.map_grids() == 3);  // instances 0, 1 and 2
  CHECK(a.similarity(qf, 0, map.view, 1, 9) == s_other_bin);
  CHECK(a.comparisons() == 4);
  CHECK(a.map_grids() == 3);

  // Full caches: one probe slot and one similarity slot. The second bin's probe goes to scratch and a
  // repeated similarity is computed again, with the same values as the big caches give.
  CHECK(b.similarity(qf, 0, map.view, 0, 2) == s0);
  CHECK(b.similarity(qf, 0, map.view, 2, 9) == s_other_bin);
  CHECK(b.probes() == 2);  // one cached, one into scratch
  CHECK(b.similarity(qf, 0, map.view, 2, 9) == s_other_bin);
  CHECK(b.comparisons() == 3);                       // the similarity cache is full: not remembered
  CHECK(b.similarity(qf, 0, map.view, 0, 2) == s0);  // the one remembered
  CHECK(b.comparisons() == 3);
  // reset() forgets everything.
  b.reset();
  CHECK(b.probes() == 0);
  CHECK(b.comparisons() == 0);
  CHECK(b.map_grids() == 0);
  CHECK(b.similarity(qf, 0, map.view, 0, 2) == s0);
  CHECK(b.comparisons() == 1);
}

}  // namespace test_gsf_filter
