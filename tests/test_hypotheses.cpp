// Ranked triangle matching, vertex-order ties, peeled pose hypotheses and whole-scan verification:
// the stages that let a query in a lattice of identical columns find the right lattice shift.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "arena_buffer.h"
#include "fuzz_seed_map.h"
#include "gsf/config.h"
#include "gsf/detail/max_clique.h"
#include "gsf/detail/pose_hypotheses.h"
#include "gsf/detail/semantic_grid.h"
#include "gsf/detail/triangle_index.h"
#include "gsf/detail/triangle_matcher.h"
#include "gsf/detail/voxel_layer.h"
#include "gsf/detail/wasserstein.h"
#include "gsf/map_format.h"
#include "mapping/semantic_layer.h"
#include "test_cloud.h"

using namespace gsf;
using gsf_test::ArenaBuffer;
using gsf_test::Cloud;

namespace {

// The map's triangles in key order (format v5) with their index; input(i) is the position in the
// builder's list of stored triangle i.
struct Index {
  std::vector<Triangle> tris;
  std::vector<uint64_t> keys, scratch;
  std::vector<uint32_t> offsets, ids;
  TriangleIndexView view;
  explicit Index(const std::vector<Triangle>& t, float bin) {
    const uint32_t n = static_cast<uint32_t>(t.size());
    tris.resize(n + 1);
    keys.resize(n + 1);
    scratch.resize(n + 1);
    offsets.resize(n + 2);
    ids.resize(n + 1);
    uint32_t kc = 0;
    REQUIRE(build_triangle_index(t.data(), n, bin, tris.data(), keys.data(), offsets.data(), &kc, scratch.data(),
                                 ids.data()) == Status::Ok);
    view.keys = keys.data();
    view.offsets = offsets.data();
    view.key_count = kc;
    view.triangle_count = n;
  }
  uint32_t input(uint32_t stored) const { return ids[stored]; }
};

Triangle triangle_with_sides(uint32_t id0, float s0, float s1, float s2) {
  Triangle t{};
  t.v[0] = id0;
  t.v[1] = id0 + 1;
  t.v[2] = id0 + 2;
  t.side[0] = s0;
  t.side[1] = s1;
  t.side[2] = s2;
  for (int k = 0; k < 3; ++k) t.label[k] = kPole;
  return t;
}

}  // namespace

TEST_CASE("Ranked matching keeps the best-fitting map triangle when a cap would have cut it in storage order") {
  // 300 map triangles in a lattice all fit the query within tolerance (1-2% off); the one exact copy is
  // stored last (map x order puts it at the end). A cap of 8 in storage order would drop it.
  std::vector<Triangle> map;
  for (uint32_t i = 0; i < 300; ++i) {
    const float e = 1.0f + 0.01f + 0.01f * float((i * 37) % 100) / 100.0f;
    map.push_back(triangle_with_sides(3 * i, 8.0f * e, 8.0f * 1.3f * e, 8.0f * 1.9f * e));
  }
  map.push_back(triangle_with_sides(900, 8.0f, 8.0f * 1.3f, 8.0f * 1.9f));
  Index idx(map, 1.0f);
  TriangleConfig tc;
  ArenaBuffer buf(TriangleMatcher::required_bytes(8));
  TriangleMatcher matcher;
  REQUIRE(matcher.bind(buf.arena, 8) == Status::Ok);
  const Triangle q = triangle_with_sides(0, 8.0f, 8.0f * 1.3f, 8.0f * 1.9f);
  const TriangleMatchStats st = matcher.match(q, idx.view, idx.tris.data(), tc, 0.0f);
  CHECK(st.accepted == 301);
  CHECK(st.kept == 8);
  CHECK(st.dropped() == 293);  // every drop is counted
  REQUIRE(matcher.size() == 8);
  CHECK(idx.input(matcher.match_at(0).map) == 300);  // the exact copy ranks first
  CHECK(matcher.match_at(0).residual == 0.0f);
  for (uint32_t i = 1; i < matcher.size(); ++i) CHECK(matcher.match_at(i - 1).residual <= matcher.match_at(i).residual);
}

TEST_CASE("Tied query sides are tried in both vertex orders") {
  // Isosceles map triangle: sides 5, 5.05, 8 (a lattice's right angles give such ties). The query's
  // noise put its two short sides the other way round, so its canonical order pairs the vertices
  // differently; only the tied order pairs them as the map does.
  std::vector<Triangle> map = {triangle_with_sides(0, 5.0f, 5.05f, 8.0f)};
  map[0].label[1] = kTrunk;  // labels (pole, trunk, pole), part of the key
  Index idx(map, 1.0f);
  TriangleConfig tc;
  ArenaBuffer buf(TriangleMatcher::required_bytes(16));
  TriangleMatcher matcher;
  REQUIRE(matcher.bind(buf.arena, 16) == Status::Ok);
  Triangle q = triangle_with_sides(10, 5.0f, 5.04f, 8.0f);  // canonical (a, b, c)
  q.label[0] = kPole;
  q.label[1] = kTrunk;
  q.label[2] = kPole;
  // Without ties only the canonical order is tried.
  TriangleMatchStats st = matcher.match(q, idx.view, idx.tris.data(), tc, 0.0f);
  CHECK(st.orders == 1);
  // With the tie tolerance the reversed order (c, b, a) with sides (5.04, 5, 8) is tried as well; both
  // pairings pass the 3% side check here and both are kept.
  st = matcher.match(q, idx.view, idx.tris.data(), tc, 0.06f);
  CHECK(st.orders == 2);
  REQUIRE(matcher.size() == 2);
  bool reversed = false;
  for (uint32_t i = 0; i < matcher.size(); ++i)
    if (matcher.match_at(i).order == 1) {
      reversed = true;
      CHECK(TriangleMatcher::query_vertex(q, 1, 0) == q.v[2]);
      CHECK(TriangleMatcher::query_vertex(q, 1, 2) == q.v[0]);
    }
  CHECK(reversed);
  // A scalene triangle gets no second order.
  const Triangle scalene = triangle_with_sides(20, 4.0f, 6.0f, 9.0f);
  CHECK(matcher.match(scalene, idx.view, idx.tris.data(), tc, 0.06f).orders == 1);
}

TEST_CASE("A mirror image has the same sides but the other sense: the matcher refuses it before the cap") {
  // Map: a scalene triangle A and its mirror image B (y -> -y, moved 50 m); same sides, opposite senses.
  std::vector<float> xyz = {0, 0, 0, 4, 0, 0, 1, 6, 0, 50, 0, 0, 54, 0, 0, 51, -6, 0};
  const std::vector<uint8_t> labels(16, kPole);
  std::vector<Triangle> map = {make_triangle(0, 1, 2, &xyz[0], &xyz[3], &xyz[6], labels.data()),
                               make_triangle(3, 4, 5, &xyz[9], &xyz[12], &xyz[15], labels.data())};
  REQUIRE(map[0].orientation != map[1].orientation);
  REQUIRE((map[0].orientation == kOrientationCounterClockwise || map[0].orientation == kOrientationClockwise));
  for (int k = 0; k < 3; ++k) REQUIRE(map[0].side[k] == Approx(map[1].side[k]));
  Index idx(map, 1.0f);
  const uint32_t id_a = idx.input(0) == 0 ? 0 : 1;  // stored position of A
  TriangleConfig tc;
  ArenaBuffer buf(TriangleMatcher::required_bytes(16));
  TriangleMatcher matcher;
  REQUIRE(matcher.bind(buf.arena, 16) == Status::Ok);
  // The query sees A turned by any yaw and moved: it matches A only; its mirror image matches B only.
  for (int deg = 0; deg < 360; deg += 15) {
    const float c = std::cos(float(deg) * 0.0174533f), s = std::sin(float(deg) * 0.0174533f);
    float q[9], m[9];
    for (int v = 0; v < 3; ++v) {
      const float x = xyz[3 * v], y = xyz[3 * v + 1];
      q[3 * v] = c * x - s * y + 7.0f;
      q[3 * v + 1] = s * x + c * y - 3.0f;
      m[3 * v] = c * x + s * y;  // the mirror image (y -> -y), turned
      m[3 * v + 1] = s * x - c * y;
      q[3 * v + 2] = m[3 * v + 2] = 0.2f;
    }
    INFO("yaw " << deg);
    const Triangle qt = make_triangle(10, 11, 12, q, q + 3, q + 6, labels.data());
    TriangleMatchStats st = matcher.match(qt, idx.view, idx.tris.data(), tc, 0.0f);
    CHECK(st.accepted == 1);
    CHECK(st.mirrored == 1);
    REQUIRE(matcher.size() == 1);
    CHECK(matcher.match_at(0).map == id_a);
    const Triangle mt = make_triangle(10, 11, 12, m, m + 3, m + 6, labels.data());
    st = matcher.match(mt, idx.view, idx.tris.data(), tc, 0.0f);
    CHECK(st.mirrored == 1);
    REQUIRE(matcher.size() == 1);
    CHECK(matcher.match_at(0).map == 1 - id_a);
    // Without the check both are candidates, as they were before senses were recorded.
    matcher.set_mirror_check(false);
    st = matcher.match(qt, idx.view, idx.tris.data(), tc, 0.0f);
    CHECK(st.accepted == 2);
    CHECK(st.mirrored == 0);
    matcher.set_mirror_check(true);
  }
  // A map without recorded senses (orientation 0: maps built before) and a near-collinear triangle
  // (apex 0.5 m off its longest side: flat) are never refused.
  std::vector<Triangle> old_map = map;
  for (Triangle& t : old_map) t.orientation = kOrientationUnknown;
  Index old_idx(old_map, 1.0f);
  const Triangle qa = make_triangle(10, 11, 12, &xyz[0], &xyz[3], &xyz[6], labels.data());
  CHECK(matcher.match(qa, old_idx.view, old_idx.tris.data(), tc, 0.0f).accepted == 2);
  const float flat[9] = {0, 0, 0, 10, 0, 0, 5, 0.5f, 0};
  CHECK(make_triangle(0, 1, 2, flat, flat + 3, flat + 6, labels.data()).orientation == kOrientationFlat);
  CHECK(triangle_orientation(flat, flat + 3, flat + 6, 10.0f) == kOrientationFlat);
  const float apex[9] = {0, 0, 0, 10, 0, 0, 5, 1.2f, 0};
  CHECK(triangle_orientation(apex, apex + 3, apex + 6, 10.0f) == kOrientationCounterClockwise);
  CHECK(triangle_orientation(apex, apex + 6, apex + 3, 10.0f) == kOrientationClockwise);
  // An isosceles triangle is its own mirror image up to a turn: its vertex order with the tied sides
  // swapped (an odd permutation) matches the mirror image with the senses agreeing.
  const float iso[9] = {0, 0, 0, 4, 0, 0, 2, 7, 0}, iso_m[9] = {0, 0, 0, 4, 0, 0, 2, -7, 0};
  std::vector<Triangle> iso_map = {make_triangle(0, 1, 2, iso, iso + 3, iso + 6, labels.data())};
  Index iso_idx(iso_map, 1.0f);
  const Triangle iq = make_triangle(10, 11, 12, iso_m, iso_m + 3, iso_m + 6, labels.data());
  TriangleMatchStats st = matcher.match(iq, iso_idx.view, iso_idx.tris.data(), tc, 0.06f);
  CHECK(st.orders == 2);
  CHECK(st.mirrored == 1);
  REQUIRE(matcher.size() == 1);
  const uint8_t o = matcher.match_at(0).order;
  CHECK((o >= 1 && o <= 3));
}

namespace {

// A 1-D lattice of columns every 8 m along x; correspondences of 6 query columns to map columns shifted
// by `shift` periods.
void lattice_correspondences(int shift, float noise, std::vector<float>* a, std::vector<float>* b) {
  for (int k = 0; k < 6; ++k) {
    const float x = 8.0f * k, y = (k % 2) ? 4.0f : -4.0f;
    a->insert(a->end(), {x + noise * (k % 3), y, 0.0f});
    b->insert(b->end(), {x + 8.0f * shift + 100.0f, y + 50.0f, 0.0f});
  }
}

}  // namespace

TEST_CASE("Peeling yields one hypothesis per lattice shift, the largest clique first") {
  std::vector<float> a, b;
  lattice_correspondences(0, 0.02f, &a, &b);  // the true shift: 6 correspondences
  std::vector<float> a2, b2;
  lattice_correspondences(2, 0.0f, &a2, &b2);  // a competing shift: its first 4 only
  a.insert(a.end(), a2.begin(), a2.begin() + 12);
  b.insert(b.end(), b2.begin(), b2.begin() + 12);
  const uint32_t n = static_cast<uint32_t>(a.size() / 3);
  std::vector<float> w(n, 1.0f);
  HypothesisConfig hc;
  ArenaBuffer buf(PoseHypotheses::required_bytes(64, 8));
  PoseHypotheses hyp;
  REQUIRE(hyp.bind(buf.arena, 64, 8) == Status::Ok);
  HypothesisStats st;
  REQUIRE(hyp.generate(a.data(), b.data(), w.data(), n, hc, &st) == Status::Ok);
  REQUIRE(hyp.size() >= 2);
  CHECK(hyp[0].clique_size == 6);
  CHECK(hyp[0].map_T_scan.translation().isApprox(Eigen::Vector3d(100, 50, 0), 0.05));
  CHECK(hyp[1].clique_size == 4);
  CHECK(hyp[1].map_T_scan.translation().isApprox(Eigen::Vector3d(116, 50, 0), 0.05));
  for (uint32_t i = 0; i < 6; ++i) CHECK(hyp.in_clique(0, i));
  CHECK(st.searches >= 2);
  CHECK_FALSE(st.budget_exhausted);
  // Too few correspondences: no hypothesis, a clear status.
  CHECK(hyp.generate(a.data(), b.data(), w.data(), 2, hc, &st) == Status::NoSolution);
  CHECK(hyp.size() == 0);
}

namespace {

// The map's semantic layer over a 64 x 32 m patch: road everywhere, a column every 8 m along y = 0,
// and ONE bush (vegetation) beside the column at x = 24.
struct LatticeLayer {
  std::vector<uint32_t> keys, cells;  // cells: dense masks, stored with a palette per tile as the map does
  std::vector<uint32_t> palette_offsets, palette, neighbours;
  std::vector<uint8_t> indices;
  SemanticGridView view;
  LatticeLayer() {
    const uint32_t T = 16;
    for (int tx = 0; tx < 4; ++tx)
      for (int ty = -1; ty < 1; ++ty) {
        uint32_t k;
        semantic_tile_key(tx, ty, &k);
        keys.push_back(k);
      }
    std::sort(keys.begin(), keys.end());
    cells.assign(keys.size() * T * T, kCellObserved | class_bit(kRoad));
    view.cell = 1.0f;
    view.tile_cells = T;
    view.tile_count = static_cast<uint32_t>(keys.size());
    view.tile_keys = keys.data();
    for (int c = 0; c < 8; ++c) set(8.0f * c + 0.5f, 0.5f, class_bit(kPole));
    for (float x = 26.0f; x < 28.5f; x += 1.0f)
      for (float y = 2.0f; y < 4.5f; y += 1.0f) set(x, y, class_bit(kVegetation));
    REQUIRE(mapping::palette_semantic_layer(cells, view.tile_count, T, &palette_offsets, &palette, &indices) ==
            Status::Ok);
    REQUIRE(mapping::add_semantic_neighbours(keys, T, &palette_offsets, &palette, &indices, &neighbours) == Status::Ok);
    view.palette_count = static_cast<uint32_t>(palette.size());
    view.palette_offsets = palette_offsets.data();
    view.palette = palette.data();
    view.cells = indices.data();
    view.neighbours = neighbours.data();
  }
  void set(float x, float y, uint32_t bits) {
    const int tx = static_cast<int>(std::floor(x / 16)), ty = static_cast<int>(std::floor(y / 16));
    uint32_t k;
    semantic_tile_key(tx, ty, &k);
    const size_t t = std::lower_bound(keys.begin(), keys.end(), k) - keys.begin();
    const int cx = static_cast<int>(x - 16.0f * tx), cy = static_cast<int>(y - 16.0f * ty);
    cells[t * 256 + cy * 16 + cx] |= bits;
  }
};

// The query scan seen from (sx, 0): road, the columns, and the bush if it is in the world at all.
Cloud lattice_scan(float sx, bool with_bush) {
  Cloud c;
  for (float x = -20; x <= 20; x += 0.3f)
    for (float y = -10; y <= 10; y += 0.3f) c.add(x, y, 0.0f, 40);
  for (int col = 0; col < 8; ++col)
    for (float z = 0.3f; z < 4.0f; z += 0.2f) c.add(8.0f * col + 0.5f - sx, 0.5f, z, 80);
  if (with_bush)
    for (float x = 26.0f; x < 28.5f; x += 0.2f)
      for (float y = 2.0f; y < 4.5f; y += 0.2f)
        for (float z = 0.3f; z < 1.2f; z += 0.3f) c.add(x - sx, y, z, 70);
  return c;
}

}  // namespace

namespace {

// The lattice layer, a voxel layer for scans of it (min_range 0: they start at the sensor) and the
// stability weights: what every verification test below starts from.
struct LatticeVerification {
  LatticeLayer layer;
  VoxelConfig config;
  ArenaBuffer buf;
  VoxelLayer voxels;
  float weights[kNumClasses];
  LatticeVerification() : config(scan_config()), buf(VoxelLayer::required_bytes(config)) {
    REQUIRE(voxels.bind(buf.arena, config) == Status::Ok);
    stability_weights(weights);
  }
  void build(const Cloud& scan) { REQUIRE(voxels.build(scan.view(), nullptr) == Status::Ok); }
  static VoxelConfig scan_config() {
    VoxelConfig c;
    c.min_range = 0.0f;
    return c;
  }
};

}  // namespace

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
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(-10.0, 70.0), yaw(-3.2, 3.2), frac(0.0, 1.0);
  uint32_t compared = 0, with_disagreement = 0;
  const SemanticGridView* grids[] = {&layer.view, &odd};
  for (const SemanticGridView* g : grids) {
    for (int k = 0; k < 60; ++k) {
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      // Half the poses on whole or half metres, where a voxel can sit exactly on a cell or tile edge.
      const double x = k % 2 ? pos(rng) : std::round(pos(rng) * 2.0) / 2.0, y = frac(rng) * 6.0 - 3.0;
      T.translation() = Eigen::Vector3d(x, y, 0.0);
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
  CHECK(compared == 240);
  CHECK(with_disagreement > 20);  // the neighbour lookups ran too
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

TEST_CASE("Heading-diverse cliques give the true heading a hypothesis when the largest cliques share a wrong one") {
  // 8 correspondences agree on a wrong pose W (a lattice's 180 deg turn), 6 on the truth T (yaw 12 deg).
  // With one peeled clique, every hypothesis (the clique and its shift votes) has W's heading; the
  // heading-diverse search removes the edges at that heading and finds T's clique.
  const double yaw_t = 12.0 * M_PI / 180.0, yaw_w = yaw_t + M_PI;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity(), W = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw_t, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(100, 50, 0);
  W.linear() = Eigen::AngleAxisd(yaw_w, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  W.translation() = Eigen::Vector3d(140, 70, 0);
  const float true_pts[6][3] = {{3, 1, 0.5f}, {-7, 4, 1}, {12, -5, 0.2f}, {-2, -14, 1.5f}, {18, 9, 0.7f}, {-15, -3, 1}};
  const float wrong_pts[8][3] = {{5, 17, 1},    {-19, 11, 0.5f}, {22, -13, 1.2f}, {-9, -21, 0.3f},
                                 {9, -2, 0.9f}, {-4, 8, 1.1f},   {14, 3, 0.4f},   {-24, -9, 0.8f}};
  std::vector<float> a, b;
  auto add = [&](const float* p, const Eigen::Isometry3d& pose) {
    const Eigen::Vector3d q(p[0], p[1], p[2]), m = pose * q;
    for (int d = 0; d < 3; ++d) {
      a.push_back(float(q[d]));
      b.push_back(float(m[d]));
    }
  };
  for (const auto& p : wrong_pts) add(p, W);
  for (const auto& p : true_pts) add(p, T);
  const uint32_t n = static_cast<uint32_t>(a.size() / 3);
  std::vector<float> w(n, 1.0f);
  HypothesisConfig hc;
  hc.max_peeled = 1;
  hc.shift_headings = 2;
  ArenaBuffer buf(PoseHypotheses::required_bytes(64, 16));
  PoseHypotheses hyp;
  REQUIRE(hyp.bind(buf.arena, 64, 16) == Status::Ok);
  auto has_pose = [&](const Eigen::Isometry3d& pose) {
    for (uint32_t h = 0; h < hyp.size(); ++h) {
      const Eigen::Isometry3d d = pose.inverse() * hyp[h].map_T_scan;
      if (d.translation().norm() < 0.1 && Eigen::AngleAxisd(d.linear()).angle() < 0.01) return true;
    }
    return false;
  };
  auto has_heading = [&](double yaw) {
    for (uint32_t h = 0; h < hyp.size(); ++h) {
      const Eigen::Matrix3d R = hyp[h].map_T_scan.linear();
      if (std::fabs(std::remainder(std::atan2(R(1, 0), R(0, 0)) - yaw, 2 * M_PI)) < 5.0 * M_PI / 180.0) return true;
    }
    return false;
  };
  HypothesisStats st;
  hc.heading_cliques = 0;
  REQUIRE(hyp.generate(a.data(), b.data(), w.data(), n, hc, &st) == Status::Ok);
  CHECK(hyp[0].clique_size == 8);
  CHECK(has_pose(W));
  CHECK_FALSE(has_heading(yaw_t));  // the truth's heading is never tried
  hc.heading_cliques = 3;
  REQUIRE(hyp.generate(a.data(), b.data(), w.data(), n, hc, &st) == Status::Ok);
  CHECK(hyp[0].clique_size == 8);  // the paper's answer stays first
  CHECK(has_pose(W));
  CHECK(has_pose(T));
  CHECK(st.heading_cliques == 1);
}

TEST_CASE("Removing the edges at a heading removes exactly the pairs that turn by it") {
  // Three correspondences turned by 90 deg (pairwise consistent), one pair of which is too short to
  // tell a heading, and one correspondence consistent with all but turned by 0 deg relative to the first.
  const float a[4 * 3] = {0, 0, 0, 10, 0, 0, 10, 0.5f, 0, 0, 10, 0};
  const float b[4 * 3] = {0, 0, 0, 0, 10, 0, -0.5f, 10, 0, 0, 10, 0};
  ArenaBuffer buf(ConsistencyGraph::required_bytes(8));
  ConsistencyGraph g;
  REQUIRE(g.bind(buf.arena, 8) == Status::Ok);
  REQUIRE(g.build(a, b, 4, 0.1f) == Status::Ok);
  REQUIRE(g.adjacent(0, 1));
  REQUIRE(g.adjacent(0, 2));
  REQUIRE(g.adjacent(1, 2));
  REQUIRE(g.adjacent(0, 3));
  const uint32_t removed = g.remove_edges_at_heading(a, b, M_PI / 2, 5.0 * M_PI / 180.0, 1.0f);
  CHECK(removed == 2);  // (0,1) and (0,2); (1,2) is 0.5 m long
  CHECK_FALSE(g.adjacent(0, 1));
  CHECK_FALSE(g.adjacent(1, 0));
  CHECK_FALSE(g.adjacent(0, 2));
  CHECK(g.adjacent(1, 2));
  CHECK(g.adjacent(0, 3));  // (0,3) turns by 0 deg
}

namespace {

// Correspondences for the shift-vote tests: one heading (the first clique's: 8 correspondences at
// translation (100, 50)), then six lattice shifts 8 m apart with 3 votes each in one bin; `x` is where
// the next query point goes.
struct ShiftVoteScene {
  std::vector<float> a, b;
  float x = 30.0f;
  void add(float qx, float qy, float qz, float tx, float ty) {
    a.insert(a.end(), {qx, qy, qz});
    b.insert(b.end(), {qx + tx, qy + ty, qz});
  }
  ShiftVoteScene() {
    const float clique_pts[8][2] = {{3, 1}, {-7, 4}, {12, -5}, {-2, -14}, {18, 9}, {-15, -3}, {6, 11}, {-11, 7}};
    for (const auto& p : clique_pts) add(p[0], p[1], 0.5f, 100.0f, 50.0f);
    for (int k = 1; k <= 6; ++k)  // bins well inside
      for (int j = 0; j < 3; ++j, x += 1.7f) add(x, -20.0f + 3.0f * j, 1.0f, 100.0f + 8.0f * k + 1.0f, 50.5f);
  }
  uint32_t size() const { return static_cast<uint32_t>(a.size() / 3); }
  // One peeled clique, no heading-diverse search: the hypotheses are the clique and its shift votes.
  static HypothesisConfig one_heading(uint32_t max_hypotheses) {
    HypothesisConfig hc;
    hc.max_peeled = 1;
    hc.heading_cliques = 0;
    hc.max_hypotheses = max_hypotheses;
    return hc;
  }
};

}  // namespace

TEST_CASE("Shift votes rank bins by their support: a translation split across a bin edge still becomes a hypothesis") {
  // The clique and the lattice shifts (ShiftVoteScene), and the truth with 4 votes that straddle the
  // bin edge at x = 160 (2 + 2).
  ShiftVoteScene sc;
  for (int j = 0; j < 4; ++j, sc.x += 1.9f)
    sc.add(sc.x, 25.0f + 2.0f * j, 1.0f, 160.0f + (j % 2 ? 0.05f : -0.05f), 51.0f);
  const std::vector<float>&a = sc.a, &b = sc.b;
  const uint32_t n = sc.size();
  std::vector<float> w(n, 1.0f);
  HypothesisConfig hc = ShiftVoteScene::one_heading(4);  // the clique and 3 shift votes
  ArenaBuffer buf(PoseHypotheses::required_bytes(64, 8));
  PoseHypotheses hyp;
  REQUIRE(hyp.bind(buf.arena, 64, 8) == Status::Ok);
  auto has_translation = [&](double tx, double ty) {
    for (uint32_t h = 0; h < hyp.size(); ++h)
      if ((hyp[h].map_T_scan.translation().head<2>() - Eigen::Vector2d(tx, ty)).norm() < 0.2) return true;
    return false;
  };
  HypothesisStats st;
  hc.shift_vote_support = 0;  // each bin on its own: the truth's bins hold 2 votes each, below min_inliers
  REQUIRE(hyp.generate(a.data(), b.data(), w.data(), n, hc, &st) == Status::Ok);
  CHECK(hyp.size() == 4);
  CHECK(has_translation(100, 50));
  CHECK_FALSE(has_translation(160, 51));
  hc.shift_vote_support = 1;
  REQUIRE(hyp.generate(a.data(), b.data(), w.data(), n, hc, &st) == Status::Ok);
  CHECK(hyp.size() == 4);
  CHECK(has_translation(100, 50));
  CHECK(has_translation(160, 51));
  // A bad radius is a configuration error, not a slow query.
  LocalizerConfig cfg;
  cfg.hypotheses.shift_vote_support = 2;
  CHECK(validate(cfg) == Status::InvalidArgument);
  cfg.hypotheses.shift_vote_support = 1;
  cfg.hypotheses.tls_threshold = 2.5f;  // a support radius beyond the 3 x 3 bins searched
  CHECK(validate(cfg) == Status::InvalidArgument);
}

TEST_CASE("Shift votes over the pairs ranked out of the graph find the true shift the graph holds one pair of") {
  // The graph's pairs: a clique of 8 at translation (100, 50), six lattice shifts with 3 pairs each, and
  // one pair of the truth (160, 51). Ranked after them, outside the graph: 5 more pairs of the truth and
  // 2 more of one lattice shift. In a lattice the graph's cap keeps a few true pairs of many.
  ShiftVoteScene sc;
  const float x = sc.x;
  sc.add(x, 25.0f, 1.0f, 160.0f, 51.0f);
  const uint32_t n = sc.size();
  const float truth_dx[5] = {0.1f, -0.1f, 0.05f, -0.05f, 0.0f};
  for (int j = 0; j < 5; ++j) sc.add(x + 2.0f + 1.9f * j, 27.0f + 2.0f * j, 1.0f, 160.0f + truth_dx[j], 51.0f);
  for (int j = 0; j < 2; ++j) sc.add(x - 12.0f + 2.3f * j, -30.0f, 1.0f, 100.0f + 8.0f + 1.0f, 50.5f);
  const std::vector<float>&a = sc.a, &b = sc.b;
  const uint32_t total = sc.size();
  std::vector<float> w(total, 1.0f);
  HypothesisConfig hc = ShiftVoteScene::one_heading(3);  // the clique and the two best shift bins
  ArenaBuffer buf(PoseHypotheses::required_bytes(64, 8, 128));
  PoseHypotheses hyp;
  REQUIRE(hyp.bind(buf.arena, 64, 8, 128) == Status::Ok);
  auto find_translation = [&](double tx, double ty) {
    for (uint32_t h = 0; h < hyp.size(); ++h)
      if ((hyp[h].map_T_scan.translation().head<2>() - Eigen::Vector2d(tx, ty)).norm() < 0.2) return int(h);
    return -1;
  };
  HypothesisStats st;
  // The graph's pairs alone: the truth has one vote, below min_inliers.
  REQUIRE(hyp.generate(a.data(), b.data(), w.data(), n, hc, &st) == Status::Ok);
  CHECK(st.vote_pairs == n);
  CHECK(find_translation(100, 50) == 0);
  CHECK(find_translation(160, 51) < 0);
  // All of them: the truth's 6 pairs make the best shift bin, fitted on its own votes only (translation
  // the mean of the six, exactly), and the cliques are unchanged.
  REQUIRE(hyp.generate(a.data(), b.data(), w.data(), n, hc, &st, total) == Status::Ok);
  CHECK(st.vote_pairs == total);
  CHECK(find_translation(100, 50) == 0);
  const int h = find_translation(160, 51);
  REQUIRE(h == 1);
  CHECK(hyp[uint32_t(h)].inliers == 6);
  CHECK(std::fabs(hyp[uint32_t(h)].map_T_scan.translation().x() - 160.0) < 1e-4);
  CHECK(hyp[uint32_t(h)].clique_size == 0);
  // More votes than bound, or a graph larger than the votes' capacity: refused, nothing kept.
  CHECK(hyp.generate(a.data(), b.data(), w.data(), n, hc, &st, 129) == Status::CapacityExceeded);
  ArenaBuffer small(PoseHypotheses::required_bytes(64, 8, 128));
  PoseHypotheses bad;
  CHECK(bad.bind(small.arena, 64, 8, 32) == Status::InvalidArgument);
}
