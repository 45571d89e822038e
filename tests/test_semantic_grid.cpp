// The semantic grid alone (core/include/gsf/detail/semantic_grid.h): whole-scan verification of a pose
// against the map's semantic layer (the true lattice shift wins by one bush; the fast paths equal the
// plain rule bit for bit; the pattern search's sample sizes), the layer's validation and its neighbour
// masks.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "arena_buffer.h"
#include "fuzz_seed_map.h"
#include "gsf/detail/angles.h"
#include "gsf/detail/semantic_grid.h"
#include "gsf/detail/voxel_layer.h"
#include "gsf/map_format.h"
#include "lattice_layer.h"
#include "mapping/semantic_layer.h"
#include "test_cloud.h"

namespace test_semantic_grid {

using namespace gsf;
using gsf_test::Cloud;
using gsf_test::lattice_scan;
using gsf_test::LatticeLayer;
using gsf_test::LatticeVerification;

TEST_CASE("Verification picks the true lattice shift given one distinguishing bush") {
  LatticeVerification fixture;
  const LatticeLayer& layer = fixture.layer;
  VoxelLayer& voxels = fixture.voxels;
  const float* weights = fixture.weights;
  REQUIRE(layer.view.validate(kNumClasses) == Status::Ok);
  const float sensor_x = 24.0f;
  fixture.build(lattice_scan(sensor_x, true));
  auto score_at = [&](float x) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(x, 0, 0);
    return verify_pose(voxels, layer.view, T, 4096, weights);
  };
  const PoseVerification truth = score_at(sensor_x);
  // Every other lattice shift agrees on road and columns alike; only the bush separates them.
  for (int k = -2; k <= 2; ++k) {
    if (k == 0) continue;
    const PoseVerification shifted = score_at(sensor_x + 8.0f * k);
    INFO("shift " << k << ": " << shifted.score << " vs " << truth.score);
    CHECK(shifted.score < truth.score);
  }
  CHECK(truth.disagree == 0.0f);
  // Without the bush in the scan the shifts tie within the road's edge effects: nothing to choose by.
  const Cloud bare = lattice_scan(sensor_x, false);
  REQUIRE(voxels.build(bare.view(), nullptr) == Status::Ok);
  const PoseVerification bare_truth = score_at(sensor_x), bare_shift = score_at(sensor_x + 8.0f);
  CHECK(bare_truth.disagree == 0.0f);
  CHECK(bare_shift.disagree == 0.0f);
  // Off the layer nothing is scored (no evidence either way), and a NaN pose is not a crash.
  const PoseVerification off = score_at(5000.0f);
  CHECK(off.scored == 0);
  Eigen::Isometry3d nan_pose = Eigen::Isometry3d::Identity();
  nan_pose.translation().x() = std::nan("");
  CHECK(verify_pose(voxels, layer.view, nan_pose, 4096, weights).scored == 0);
}

TEST_CASE("count_observed counts the points a pose puts on the map's observed cells") {
  const LatticeLayer layer;  // observed everywhere over x in [0, 64), y in [-16, 16)
  const float nan = std::nanf("");
  const float xyz[] = {10, 0, 1, 30, 5, 0, 63.5f, -15.5f, 2, 100, 0, 0, -0.5f, 3, 0, nan, 0, 0};
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  CHECK(count_observed(layer.view, T, xyz, 6) == 3);
  CHECK(count_observed(layer.view, T, xyz, 1) == 1);  // only the first n points are read
  T.translation().x() = 40.0;  // (10, 0) -> (50, 0) stays, (-0.5, 3) -> (39.5, 3) comes in, the others leave
  CHECK(count_observed(layer.view, T, xyz, 6) == 2);
  // A half turn about (32, 0): (x, y) -> (64 - x, -y). The first three stay on the layer, (100, 0) and
  // (-0.5, 3) land at (-36, 0) and (64.5, -3), off it.
  T.linear() = Eigen::AngleAxisd(kPi, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation().x() = 64.0;
  CHECK(count_observed(layer.view, T, xyz, 6) == 3);
  CHECK(count_observed(SemanticGridView(), Eigen::Isometry3d::Identity(), xyz, 6) == 0);  // no layer: none
}

TEST_CASE("The pattern search's sample sizes: defaults as before, coarse to fine, and no re-score when it stays") {
  LatticeVerification fixture;
  const LatticeLayer& layer = fixture.layer;
  const VoxelLayer& voxels = fixture.voxels;
  const float* weights = fixture.weights;
  fixture.build(lattice_scan(24.0f, true));
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(24.3, 0.2, 0);  // a fraction of a metre off the truth
  Eigen::Isometry3d a, b, c;
  const PoseVerification d = verify_pose_refined(voxels, layer.view, T, 4096, weights, 3, 0.4f, 0.8f, &a);
  const PoseVerification e = verify_pose_refined(voxels, layer.view, T, 4096, weights, 3, 0.4f, 0.8f, &b, 4, 4);
  CHECK(d.score == e.score);
  CHECK(a.isApprox(b, 0.0));
  // Coarse to fine still ends with the full score (all points) of the pose it found.
  const PoseVerification f = verify_pose_refined(voxels, layer.view, T, 4096, weights, 3, 0.4f, 0.8f, &c, 8, 4);
  const PoseVerification at_c = verify_pose(voxels, layer.view, c, 4096, weights);
  CHECK(f.score == at_c.score);
  CHECK(f.scored == at_c.scored);
  // No rounds: the search cannot move, so the caller's full score comes back as given.
  PoseVerification given;
  given.score = 12345.0f;
  CHECK(verify_pose_refined(voxels, layer.view, T, 4096, weights, 0, 0.4f, 0.8f, &c, 4, 4, &given).score == 12345.0f);
  CHECK(c.isApprox(T, 0.0));
}

namespace {

// The pattern search written plainly: every round halves the steps, each pass probes all six moves
// (+-x, +-y, +-yaw about the sensor) on max_points / 4 samples and takes any that scores higher, at most
// two passes a round. The library skips the probe that undoes the last move (its pose was scored already,
// lower); the poses it ends at must be these.
Eigen::Isometry3d plain_pattern_search(const VoxelLayer& voxels, const SemanticGridView& grid,
                                       const Eigen::Isometry3d& T, const float* weights) {
  Eigen::Isometry3d best = T;
  float best_score = verify_pose(voxels, grid, best, 1024, weights).score;
  double step = double(0.4f), turn = deg_to_rad(double(0.8f));  // the library takes float steps
  for (int r = 0; r < 3; ++r, step *= 0.5, turn *= 0.5) {
    bool moved = true;
    for (int pass = 0; pass < 2 && moved; ++pass) {
      moved = false;
      for (int k = 0; k < 6; ++k) {
        Eigen::Isometry3d c = best;
        if (k < 4) {
          c.translation().x() += (k == 0 ? step : k == 1 ? -step : 0.0);
          c.translation().y() += (k == 2 ? step : k == 3 ? -step : 0.0);
        } else {
          c.linear() =
              c.linear() * Eigen::AngleAxisd(k == 4 ? turn : -turn, Eigen::Vector3d::UnitZ()).toRotationMatrix();
        }
        const float sc = verify_pose(voxels, grid, c, 1024, weights).score;
        if (sc > best_score) best_score = sc, best = c, moved = true;
      }
    }
  }
  return best;
}

}  // namespace

TEST_CASE("The pattern search ends where the plain search of every move does") {
  LatticeVerification fixture;
  fixture.build(lattice_scan(24.0f, true));
  int moved = 0;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> metres(-1.5, 1.5), radians(-0.04, 0.04);
  for (int trial = 0; trial < 40; ++trial) {
    const Eigen::Vector3d off(metres(rng), metres(rng), radians(rng));
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(off.z(), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(24.0 + off.x(), off.y(), 0.0);
    Eigen::Isometry3d found;
    verify_pose_refined(fixture.voxels, fixture.layer.view, T, 4096, fixture.weights, 3, 0.4f, 0.8f, &found, 4, 4);
    const Eigen::Isometry3d plain = plain_pattern_search(fixture.voxels, fixture.layer.view, T, fixture.weights);
    INFO("start offset " << off.transpose());
    CHECK((found.matrix() - plain.matrix()).norm() < 1e-9);
    moved += !found.isApprox(T, 1e-12);
  }
  CHECK(moved >= 30);  // the searches moved: the check compares searches, not start poses
}

namespace {

// The verification rule of semantic_grid.h written plainly over SemanticGridView::cell_at (std::floor,
// divisions, one call per cell): the reference the optimised scorer must match bit for bit.
PoseVerification plain_verify(const VoxelLayer& voxels, const SemanticGridView& g, const Eigen::Isometry3d& T,
                              uint32_t max_points, const float* weights) {
  PoseVerification v;
  const uint32_t n = voxels.size(), stride = (n + max_points - 1) / max_points;
  const float yaw = static_cast<float>(std::atan2(T.linear()(1, 0), T.linear()(0, 0)));
  const Eigen::Matrix3f R = Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix();
  const Eigen::Vector3f t = T.translation().cast<float>();
  for (uint32_t i = 0; i < n; i += stride) {
    const Voxel& vx = voxels.voxel(i);
    const Eigen::Vector3f p = R * Eigen::Vector3f(vx.centroid[0], vx.centroid[1], vx.centroid[2]) + t;
    const uint32_t mask = g.cell_at(p.x(), p.y(), nullptr), bit = class_bit(vx.label);
    int verdict = 0;
    if (bit & kGroundClasses) {
      if (mask & kGroundClasses) verdict = (mask & bit) ? 1 : -1;
    } else if (mask & kCellObserved) {
      verdict = (mask & bit) ? 1 : -1;
    }
    if (verdict < 0 &&
        ((g.cell_at(p.x() - g.cell, p.y(), nullptr) & bit) || (g.cell_at(p.x() + g.cell, p.y(), nullptr) & bit) ||
         (g.cell_at(p.x(), p.y() - g.cell, nullptr) & bit) || (g.cell_at(p.x(), p.y() + g.cell, nullptr) & bit)))
      verdict = 1;
    if (verdict == 0) {
      ++v.unknown;
      continue;
    }
    ++v.scored;
    if (verdict > 0) v.agree += weights[vx.label];
    else v.disagree += weights[vx.label];
  }
  v.score = v.agree - v.disagree;
  return v;
}

bool same_bits(const PoseVerification& a, const PoseVerification& b) {
  return a.score == b.score && a.agree == b.agree && a.disagree == b.disagree && a.scored == b.scored &&
         a.unknown == b.unknown;
}

}  // namespace

TEST_CASE("Verification's fast paths (compact points, exact reciprocals) give the plain rule's scores bit for bit") {
  LatticeVerification fixture;
  const LatticeLayer& layer = fixture.layer;
  VoxelLayer& voxels = fixture.voxels;
  const float* weights = fixture.weights;
  fixture.build(lattice_scan(24.0f, true));
  std::vector<VerifyPoint> points(voxels.size());
  fill_verify_points(voxels, points.data());
  // 1 m cells in 16 m tiles (powers of two: the multiply path) and 0.85 m cells (the division path).
  SemanticGridView odd = layer.view;
  odd.cell = 0.85f;
  // The 1 m layer again 6 tiles west and 3 south (96 m, 48 m): tiles -6..-3 and -4..-3, negative tiles,
  // where the floor of the tile quotient and the remainder take their other branches.
  std::vector<uint32_t> shifted_keys(layer.keys);
  for (uint32_t& key : shifted_keys) key = (((key >> 16) - 6) << 16) | ((key & 0xFFFFu) - 3);
  SemanticGridView shifted = layer.view;
  shifted.tile_keys = shifted_keys.data();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(-10.0, 70.0), yaw(-3.2, 3.2), frac(0.0, 1.0);
  uint32_t compared = 0, with_disagreement = 0;
  const SemanticGridView* grids[] = {&layer.view, &odd, &shifted};
  for (const SemanticGridView* g : grids) {
    const Eigen::Vector3d offset = g == &shifted ? Eigen::Vector3d(-96.0, -48.0, 0.0) : Eigen::Vector3d::Zero();
    for (int k = 0; k < 60; ++k) {
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      // Half the poses on whole or half metres, where a voxel can sit exactly on a cell or tile edge.
      const double x = k % 2 ? pos(rng) : std::round(pos(rng) * 2.0) / 2.0, y = frac(rng) * 6.0 - 3.0;
      T.translation() = Eigen::Vector3d(x, y, 0.0) + offset;
      T.linear() = Eigen::AngleAxisd(k % 3 ? yaw(rng) : 0.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      for (uint32_t max_points : {4096u, 512u}) {
        const PoseVerification ref = plain_verify(voxels, *g, T, max_points, weights);
        const PoseVerification fast = verify_pose(voxels, *g, T, max_points, weights);
        const PoseVerification compact = verify_pose(points.data(), voxels.size(), *g, T, max_points, weights);
        INFO("pose " << k << " cell " << g->cell << " points " << max_points);
        CHECK(same_bits(ref, fast));
        CHECK(same_bits(ref, compact));
        ++compared;
        with_disagreement += ref.disagree > 0.0f;
      }
    }
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(24.3, 0.2, 0);
    Eigen::Isometry3d a, b;
    const PoseVerification r1 = verify_pose_refined(voxels, *g, T, 4096, weights, 3, 0.4f, 0.8f, &a);
    const PoseVerification r2 =
        verify_pose_refined(points.data(), voxels.size(), *g, T, 4096, weights, 3, 0.4f, 0.8f, &b);
    CHECK(same_bits(r1, r2));
    CHECK(a.isApprox(b, 0.0));
  }
  CHECK(compared == 360);
  CHECK(with_disagreement > 30);  // the neighbour lookups ran too
  // Poses beyond the representable tiles (|x / tile| past 32768: 524 km at 16 m tiles) and partly so:
  // the block arithmetic computes those samples on 0 and marks them outside, as the plain rule reads them.
  for (double far : {6.0e5, -5.2427e5, 1.0e12}) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(far, 2.0, 0.0);
    const PoseVerification ref = plain_verify(voxels, layer.view, T, 4096, weights);
    INFO("x " << far);
    CHECK(same_bits(ref, verify_pose(points.data(), voxels.size(), layer.view, T, 4096, weights)));
    if (std::fabs(far) > 5.3e5) CHECK(ref.scored == 0);
  }
  // Where x / tile and x * (1 / tile) floor to different tiles (0.85 m cells: 13.6 m tiles, so 1 / tile
  // is inexact), the scorer must follow the division: a one-voxel scan at the layer's far edge (tile 3
  // stored, tile 4 not) is scored or unknown exactly as the plain rule says.
  const float tile = odd.cell * 16.0f, inv_tile = 1.0f / tile;
  uint32_t edges = 0;
  for (float x = 4.0f * tile - 1e-4f; x < 4.0f * tile + 1e-4f && edges < 4; x = std::nextafter(x, 100.0f)) {
    if (std::floor(x / tile) == std::floor(x * inv_tile)) continue;
    Cloud one;
    one.add(x, 0.3f, 0.0f, 40);
    REQUIRE(voxels.build(one.view(), nullptr) == Status::Ok);
    const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
    INFO("x " << x);
    CHECK(same_bits(plain_verify(voxels, odd, I, 4096, weights), verify_pose(voxels, odd, I, 4096, weights)));
    ++edges;
  }
  CHECK(edges > 0);
}

// In tile -1 the plain rule's x - f tile rounds for a small |x|: x = -3.00000024 gives 12.99999976 ->
// 13.0, cell 13 of tile -1 (global cell -3), where floor(x) is -4. A fast path must follow the rule
// there (one that split floor(x / cell) into tile and cell would not: tried 2026-12-06, and it was not
// cheaper either): vegetation at global cell -2 agrees with a vegetation voxel in cell -3 (a neighbour)
// and not in cell -4.
TEST_CASE("Verification's multiply path follows the plain rule's rounding in tile -1") {
  gsf_test::DenseSemanticLayer layer(-1, 0, 0, 1, kCellObserved | class_bit(kRoad));
  for (int cy = 0; cy < 16; ++cy) layer.set(-1.5f, cy + 0.5f, class_bit(kVegetation));  // global x cell -2
  const SemanticGridView& g = layer.finish();
  LatticeVerification fixture;
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  uint32_t agreeing = 0;
  bool rounded_in = false;
  for (float x : {-3.00000024f, -2.5f, -3.5f, -4.5f}) {
    Cloud one;
    one.add(x, 5.3f, 0.5f, 70);
    fixture.build(one);
    REQUIRE(fixture.voxels.size() == 1);
    REQUIRE(fixture.voxels.voxel(0).centroid[0] == x);
    const PoseVerification plain = plain_verify(fixture.voxels, g, I, 4096, fixture.weights);
    INFO("x " << x);
    CHECK(same_bits(plain, verify_pose(fixture.voxels, g, I, 4096, fixture.weights)));
    agreeing += plain.agree > 0.0f;
    if (x == -3.00000024f) rounded_in = plain.agree > 0.0f;
  }
  CHECK(rounded_in);     // the rule puts -3.00000024 in cell -3, beside the vegetation
  CHECK(agreeing == 2);  // ... as -2.5; -3.5 and -4.5 lie in cells -4 and -5
}

TEST_CASE("Semantic layer validation rejects unsorted keys, foreign bits and bad shapes") {
  LatticeLayer layer;
  SemanticGridView v = layer.view;
  CHECK(v.validate(kNumClasses) == Status::Ok);
  std::vector<uint32_t> keys = layer.keys;
  std::swap(keys[0], keys[1]);
  v.tile_keys = keys.data();
  CHECK(v.validate(kNumClasses) == Status::CorruptData);
  v = layer.view;
  std::vector<uint32_t> palette = layer.palette;
  palette[1] |= 1u << 25;  // no class 25
  v.palette = palette.data();
  CHECK(v.validate(kNumClasses) == Status::CorruptData);
  v = layer.view;
  std::vector<uint8_t> cells = layer.indices;
  cells[300] = uint8_t(layer.palette_offsets[2] - layer.palette_offsets[1]);  // one past tile 1's palette
  v.cells = cells.data();
  CHECK(v.validate(kNumClasses) == Status::CorruptData);
  v = layer.view;
  std::vector<uint32_t> offsets = layer.palette_offsets;
  offsets[3] = offsets[2];  // an empty palette
  v.palette_offsets = offsets.data();
  CHECK(v.validate(kNumClasses) == Status::CorruptData);
  v = layer.view;
  v.tile_cells = 0;
  CHECK(v.validate(kNumClasses) == Status::CorruptData);
  v = layer.view;
  v.cell = std::nanf("");
  CHECK(v.validate(kNumClasses) == Status::CorruptData);
  v = layer.view;
  std::vector<uint32_t> near = layer.neighbours;
  near[2] |= 1u << 25;  // a neighbour mask with no class 25 either
  v.neighbours = near.data();
  CHECK(v.validate(kNumClasses) == Status::CorruptData);
  v = layer.view;
  v.neighbours = nullptr;  // a layer without its neighbour masks (format v6 requires them)
  CHECK(v.validate(kNumClasses) == Status::CorruptData);
  uint32_t k;
  CHECK_FALSE(semantic_tile_key(40000, 0, &k));
  CHECK(semantic_tile_key(-32767, 32767, &k));
}

TEST_CASE("Each palette entry's neighbour mask is the union of its cell's four edge neighbours, across tiles") {
  // A random layer of 1 m cells in 16 m tiles with holes (tiles not stored), written densely, then
  // paletted and given neighbour masks as the map builder does; every cell's neighbour mask must equal
  // the union of cell_at at the four neighbour cells' centres, and its own mask must be unchanged.
  std::mt19937 rng(11);
  std::vector<uint32_t> keys;
  for (int tx = -2; tx < 2; ++tx)
    for (int ty = -1; ty < 2; ++ty) {
      if ((tx + 2) * 3 + ty == 4) continue;  // a hole in the middle: tile (-1, 0)
      uint32_t key;
      REQUIRE(semantic_tile_key(tx, ty, &key));
      keys.push_back(key);
    }
  std::sort(keys.begin(), keys.end());
  const uint32_t T = 16,
                 kinds[] = {0u, kCellObserved, kCellObserved | class_bit(kRoad), kCellObserved | class_bit(kPole),
                            kCellObserved | class_bit(kVegetation) | class_bit(kTerrain)};
  std::vector<uint32_t> dense(keys.size() * T * T);
  for (uint32_t& m : dense) m = kinds[rng() % 5];
  std::vector<uint32_t> offsets, palette, near;
  std::vector<uint8_t> indices;
  REQUIRE(mapping::palette_semantic_layer(dense, uint32_t(keys.size()), T, &offsets, &palette, &indices) == Status::Ok);
  const uint32_t masks_only = uint32_t(palette.size());
  REQUIRE(mapping::add_semantic_neighbours(keys, T, &offsets, &palette, &indices, &near) == Status::Ok);
  REQUIRE(near.size() == palette.size());
  CHECK(palette.size() > masks_only);  // pairs: more entries than distinct masks
  SemanticGridView g;
  g.cell = 1.0f;
  g.tile_cells = T;
  g.tile_count = uint32_t(keys.size());
  g.palette_count = uint32_t(palette.size());
  g.tile_keys = keys.data();
  g.palette_offsets = offsets.data();
  g.palette = palette.data();
  g.cells = indices.data();
  g.neighbours = near.data();
  REQUIRE(g.validate(kNumClasses) == Status::Ok);
  uint32_t checked = 0, with_hole = 0;
  for (size_t t = 0; t < keys.size(); ++t) {
    const float tx = float(int(keys[t] >> 16) - 32768), ty = float(int(keys[t] & 0xFFFF) - 32768);
    for (uint32_t c = 0; c < T * T; ++c) {
      const float x = tx * 16.0f + float(c % T) + 0.5f, y = ty * 16.0f + float(c / T) + 0.5f;
      CHECK(g.cell_at(x, y, nullptr) == dense[t * T * T + c]);
      const uint32_t expect = g.cell_at(x - 1, y, nullptr) | g.cell_at(x + 1, y, nullptr) |
                              g.cell_at(x, y - 1, nullptr) | g.cell_at(x, y + 1, nullptr);
      CHECK(g.neighbours_at(x, y) == expect);
      ++checked;
      with_hole += (x == -16.5f || x == 0.5f) && y > 0.0f && y < 16.0f;
    }
  }
  CHECK(checked == keys.size() * 256);
  CHECK(with_hole == 32);  // the cells beside the hole were among them
  // The fuzz seed map's hand-written neighbour masks are what the builder computes.
  size_t seed_bytes = 0;
  const std::vector<uint64_t> seed = gsf_test::fuzz_seed_map(&seed_bytes);
  MapView sv;
  REQUIRE(load_map(seed.data(), seed_bytes, &sv) == Status::Ok);
  const uint32_t st = sv.counts.semantic_tiles, stc = sv.params.semantic_tile_cells;
  std::vector<uint32_t> skeys(sv.semantic_tile_keys, sv.semantic_tile_keys + st);
  std::vector<uint32_t> soff(sv.semantic_palette_offsets, sv.semantic_palette_offsets + st + 1);
  std::vector<uint32_t> spal(sv.semantic_palette, sv.semantic_palette + sv.counts.semantic_palette);
  std::vector<uint8_t> scells(sv.semantic_cells, sv.semantic_cells + size_t(st) * stc * stc);
  std::vector<uint32_t> snear;
  REQUIRE(mapping::add_semantic_neighbours(skeys, stc, &soff, &spal, &scells, &snear) == Status::Ok);
  CHECK(std::equal(snear.begin(), snear.end(), sv.semantic_neighbours));
  CHECK(std::equal(spal.begin(), spal.end(), sv.semantic_palette));
  CHECK(std::equal(scells.begin(), scells.end(), sv.semantic_cells));
}

TEST_CASE("The pattern search's cell memo changes no result, bit for bit, and falls back when too small") {
  LatticeVerification fixture;
  fixture.build(lattice_scan(24.0f, true));
  const uint32_t n = fixture.voxels.size();
  std::vector<VerifyPoint> points(n);
  fill_verify_points(fixture.voxels, points.data());
  const uint32_t capacity = 4096;
  std::vector<SearchMemo::Sample> records(2 * capacity);
  SearchMemo memo;
  memo.slot[0] = records.data();
  memo.slot[1] = records.data() + capacity;
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> metres(-1.5, 1.5), radians(-0.04, 0.04);
  const DisagreeWeights disagree(2.0f, 0.5f);
  int moved = 0;
  for (int trial = 0; trial < 30; ++trial) {
    const Eigen::Vector3d off(metres(rng), metres(rng), radians(rng));
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(off.z(), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(24.0 + off.x(), off.y(), 0.0);
    // Coarse and polish samples of different sizes (the last round records its own), and (search
    // divisor 1: 2,587 samples of the 5,173 voxels) a memo that holds the polish sample but not the
    // coarse one: no memo then.
    for (uint32_t search_divisor : {4u, 1u}) {
      memo.capacity = search_divisor == 1 ? 2048 : capacity;
      Eigen::Isometry3d plain, remembered;
      const PoseVerification a = verify_pose_refined(points.data(), n, fixture.layer.view, T, 4096, fixture.weights, 3,
                                                     0.4f, 0.8f, &plain, search_divisor, 2, nullptr, disagree);
      const PoseVerification b =
          verify_pose_refined(points.data(), n, fixture.layer.view, T, 4096, fixture.weights, 3, 0.4f, 0.8f,
                              &remembered, search_divisor, 2, nullptr, disagree, &memo);
      INFO("trial " << trial << " search divisor " << search_divisor);
      CHECK(same_bits(a, b));
      CHECK(plain.isApprox(remembered, 0.0));
      moved += !plain.isApprox(T, 1e-12);
    }
  }
  CHECK(n == 5173);  // the sample sizes above
  INFO(moved << " of 60 searches moved");
  CHECK(moved >= 30);  // the searches moved: probes read the memo and its slots swapped (39 under qemu-aarch64)
}

}  // namespace test_semantic_grid
