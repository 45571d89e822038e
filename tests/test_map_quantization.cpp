// Map format v4's quantisation (docs/map-format.md): every dequantised value is within the closed-form
// bound the format states - grid means and variances (map_quantization.h), refinement positions and
// normals (refine_layer.h) - and the bounds are not vacuous (the worst error seen is a sizeable part).
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "gsf/detail/map_quantization.h"
#include "gsf/detail/refine_layer.h"
#include "gsf/map_format.h"
#include "gsf/semantic_classes.h"
#include "mapping/refine_layer_builder.h"

namespace test_map_quantization {

using namespace gsf;

namespace {

// Deterministic uniform numbers in [0, 1).
struct Lcg {
  uint64_t s;
  explicit Lcg(uint64_t seed) : s(seed) {}
  double next() {
    s = s * 6364136223846793005ull + 1442695040888963407ull;
    return double(s >> 11) / double(1ull << 53);
  }
};

}  // namespace

TEST_CASE("Grid means and variances dequantise within step / 2 + 2^-20 (|min| + |max|)") {
  const uint32_t G = 36, D = kNumClasses;
  MapView view;
  view.params.num_classes = D;
  view.params.grid_nx = 6;
  view.params.grid_ny = 6;
  view.params.grid_layers = 1;
  struct Range {
    float lo, hi;  // mean values; variances use [lo^2, hi^2 + 0.01]
  };
  const Range ranges[] = {{-0.2f, 1.2f}, {0.0f, 1e-3f}, {-50.0f, 80.0f}, {0.3f, 0.3f}, {1000.0f, 1000.5f}};
  Lcg rng(7);
  for (const Range& r : ranges) {
    INFO("range " << r.lo << " .. " << r.hi);
    std::vector<float> mean(size_t(G) * D), var(G), mean_back(mean.size()), var_back(G);
    for (float& m : mean) m = r.lo + float(rng.next()) * (r.hi - r.lo);
    for (float& v : var) v = r.lo * r.lo + float(rng.next()) * (r.hi * r.hi - r.lo * r.lo + 0.01f);
    MapInstance in{};
    std::vector<uint8_t> q_mean(mean.size());
    std::vector<uint16_t> q_var(G);
    quantize_instance_grid(mean.data(), var.data(), G, D, &in, q_mean.data(), q_var.data());
    view.instances = &in;
    view.grid_mean = q_mean.data();
    view.grid_var = q_var.data();
    view.counts.instances = 1;
    dequantize_instance_grid(view, 0, mean_back.data(), var_back.data());
    // Only some grid points (the GSF filter's observed ones): those rows the same, the others untouched.
    std::vector<uint8_t> only(G);
    for (uint32_t s = 0; s < G; ++s) only[s] = s % 3 == 1;
    std::vector<float> mean_only(mean.size(), -7.0f), var_only(G);
    dequantize_instance_grid(view, 0, mean_only.data(), var_only.data(), only.data());
    for (size_t k = 0; k < mean.size(); ++k) CHECK(mean_only[k] == (only[k / D] ? mean_back[k] : -7.0f));
    for (uint32_t s = 0; s < G; ++s) CHECK(var_only[s] == var_back[s]);
    const float mean_bound = quantization_error_bound(in.mean_min, in.mean_step, kGridMeanLevels);
    const float var_bound = quantization_error_bound(in.var_min, in.var_step, kGridVarLevels);
    float worst_mean = 0.0f, worst_var = 0.0f;
    for (size_t k = 0; k < mean.size(); ++k) worst_mean = std::max(worst_mean, std::fabs(mean_back[k] - mean[k]));
    for (uint32_t k = 0; k < G; ++k) {
      worst_var = std::max(worst_var, std::fabs(var_back[k] - var[k]));
      CHECK(var_back[k] >= 0.0f);  // a variance stays a variance
    }
    CHECK(worst_mean <= mean_bound);
    CHECK(worst_var <= var_bound);
    if (r.lo == r.hi) {
      CHECK(in.mean_step == 0.0f);
      CHECK(worst_mean == 0.0f);  // a constant grid is exact
    } else {
      CHECK(in.mean_step == Approx((r.hi - r.lo) / 255.0f).epsilon(0.02));
      CHECK(worst_mean > 0.25f * in.mean_step);  // 684 uniform values: the bound is nearly reached
    }
  }
}

TEST_CASE("Refinement positions dequantise within cell / 512 per axis, inside their own cell") {
  for (const float cell : {1.0f, 0.5f, 2.0f}) {
    INFO("cell " << cell);
    Lcg rng(11);
    std::vector<float> xyz;
    for (int i = 0; i < 3000; ++i)
      for (const float extent : {120.0f, 120.0f, 30.0f}) xyz.push_back(float(rng.next() * 2.0 - 1.0) * extent);
    const uint32_t n = uint32_t(xyz.size() / 3);
    std::vector<MapRefineTile> tiles;
    std::vector<MapRefinePoint> points;
    REQUIRE(mapping::build_refine_layer(xyz.data(), n, cell, &tiles, &points) == Status::Ok);
    REQUIRE(points.size() == n);
    {  // the same layer from the points in uneven chunks (as the map builder hands them over), chunks freed
      std::vector<std::vector<float>> chunks;
      for (size_t at = 0, len = 3; at < xyz.size(); at += len, len = len * 2 + 3)
        chunks.emplace_back(xyz.begin() + at, xyz.begin() + std::min(xyz.size(), at + len));
      std::vector<MapRefineTile> chunked_tiles;
      std::vector<MapRefinePoint> chunked_points;
      REQUIRE(mapping::build_refine_layer(&chunks, cell, &chunked_tiles, &chunked_points) == Status::Ok);
      CHECK(chunks.empty());
      REQUIRE(chunked_tiles.size() == tiles.size());
      REQUIRE(chunked_points.size() == points.size());
      CHECK(std::memcmp(chunked_tiles.data(), tiles.data(), tiles.size() * sizeof(MapRefineTile)) == 0);
      CHECK(std::memcmp(chunked_points.data(), points.data(), points.size() * sizeof(MapRefinePoint)) == 0);
    }
    {  // points in x order (as the builder's come, cell-key order): the chunks are placed one tile column at
      // a time, the same layer as the whole sort over the same input order
      std::vector<std::array<float, 3>> sorted(n);
      for (uint32_t i = 0; i < n; ++i) sorted[i] = {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
      std::stable_sort(sorted.begin(), sorted.end(),
                       [](const std::array<float, 3>& a, const std::array<float, 3>& b) { return a[0] < b[0]; });
      std::vector<float> flat;
      for (const auto& p : sorted) flat.insert(flat.end(), p.begin(), p.end());
      std::vector<MapRefineTile> whole_tiles, column_tiles;
      std::vector<MapRefinePoint> whole_points, column_points;
      REQUIRE(mapping::build_refine_layer(flat.data(), n, cell, &whole_tiles, &whole_points) == Status::Ok);
      std::vector<std::vector<float>> chunks;
      for (size_t at = 0; at < flat.size(); at += 300)
        chunks.emplace_back(flat.begin() + at, flat.begin() + std::min(flat.size(), at + 300));
      REQUIRE(mapping::build_refine_layer(&chunks, cell, &column_tiles, &column_points) == Status::Ok);
      REQUIRE(column_tiles.size() == whole_tiles.size());
      REQUIRE(column_points.size() == whole_points.size());
      CHECK(std::memcmp(column_tiles.data(), whole_tiles.data(), whole_tiles.size() * sizeof(MapRefineTile)) == 0);
      CHECK(std::memcmp(column_points.data(), whole_points.data(), whole_points.size() * sizeof(MapRefinePoint)) == 0);
    }
    RefineLayerView layer;
    layer.cell = cell;
    layer.tile_count = uint32_t(tiles.size());
    layer.point_count = n;
    layer.tiles = tiles.data();
    layer.points = points.data();
    REQUIRE(layer.validate() == Status::Ok);
    // Every input point is found in its own cell, dequantised within the bound (plus float rounding of the
    // cell corner, at most 2^-23 of |x| + cell).
    float worst = 0.0f;
    uint32_t hint = 0;
    for (uint32_t i = 0; i < n; ++i) {
      const float* p = &xyz[3 * i];
      const RefineCell c{int32_t(std::floor(p[0] * (1.0f / cell))), int32_t(std::floor(p[1] * (1.0f / cell))),
                         int32_t(std::floor(p[2] * (1.0f / cell)))};
      uint32_t b = 0, e = 0;
      layer.find(c, &b, &e, &hint);
      REQUIRE(e > b);
      float best = 1e9f;
      for (uint32_t k = b; k < e; ++k) {
        float q[3];
        layer.position_in(c, points[k], q);
        float err = 0.0f;
        for (int a = 0; a < 3; ++a) {
          err = std::max(err, std::fabs(q[a] - p[a]));
          // Inside the cell the refiner searched (its pruning relies on it).
          CHECK(q[a] > float(a == 0 ? c.x : a == 1 ? c.y : c.z) * cell);
          CHECK(q[a] < float((a == 0 ? c.x : a == 1 ? c.y : c.z) + 1) * cell);
        }
        best = std::min(best, err);
      }
      const float bound = cell / 512.0f + (std::fabs(p[0]) + std::fabs(p[1]) + std::fabs(p[2]) + cell) * 1.2e-7f;
      CHECK(best <= bound);
      worst = std::max(worst, best);
    }
    CHECK(worst > 0.5f * cell / 512.0f);  // the bound is nearly reached
  }
}

TEST_CASE("Refinement normals dequantise within 0.4 degrees and stay unit length") {
  Lcg rng(5);
  double worst_deg = 0.0;
  for (int i = 0; i < 20000; ++i) {
    // Uniform on the sphere.
    const double z = rng.next() * 2.0 - 1.0, phi = rng.next() * 6.283185307179586, r = std::sqrt(1.0 - z * z);
    const double n[3] = {r * std::cos(phi), r * std::sin(phi), z};
    MapRefinePoint p{};
    for (int a = 0; a < 3; ++a) p.normal[a] = quantize_normal_component(float(n[a]));
    const int32_t len2 = p.normal[0] * p.normal[0] + p.normal[1] * p.normal[1] + p.normal[2] * p.normal[2];
    CHECK(len2 >= 120 * 120);  // what the loader accepts as a normal
    CHECK(len2 <= 130 * 130);
    float back[3];
    RefineLayerView::normal(p, back);
    const double dot = back[0] * n[0] + back[1] * n[1] + back[2] * n[2];
    const double norm = std::sqrt(double(back[0]) * back[0] + double(back[1]) * back[1] + double(back[2]) * back[2]);
    CHECK(norm == Approx(1.0).epsilon(1e-6));
    worst_deg = std::max(worst_deg, std::acos(std::min(1.0, dot / norm)) * 180.0 / 3.141592653589793);
  }
  INFO("worst " << worst_deg << " deg");
  CHECK(worst_deg <= 0.4);
  CHECK(worst_deg > 0.1);  // the bound is not vacuous
  MapRefinePoint none{};
  float back[3];
  RefineLayerView::normal(none, back);
  CHECK((back[0] == 0.0f && back[1] == 0.0f && back[2] == 0.0f));  // no normal stays no normal
}

}  // namespace test_map_quantization
