// Refinement alone (core/include/gsf/detail/refine.h): it pulls a nearby global pose onto the map's point
// layer (built as the map builder builds it: mapping/refine_layer_builder.h), refuses corrections beyond
// its limit, refuses a layer of another cell size, ignores map points without a reliable normal (but for
// a pole voxel's horizontal offset from one), and picks
// the same nearest map points as the plain 27-cell search (reference_refine below), ties included.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "arena_buffer.h"
#include "gsf/detail/refine.h"
#include "gsf/detail/voxel_layer.h"
#include "gsf/semantic_classes.h"
#include "mapping/refine_layer_builder.h"
#include "test_cloud.h"

namespace test_refine {

using namespace gsf;
using gsf_test::ArenaBuffer;
using gsf_test::Cloud;

namespace {

// A corner of a street: ground, two perpendicular walls and a pole, as (x, y, z, dense label) samples.
std::vector<float> street_corner(float step) {
  std::vector<float> p;
  auto add = [&](float x, float y, float z, int cls) { p.insert(p.end(), {x, y, z, float(cls)}); };
  for (float x = -20; x <= 20; x += step)
    for (float y = -20; y <= 20; y += step) add(x, y, 0.0f, kRoad);
  for (float x = -20; x <= 20; x += step)
    for (float z = step; z <= 6; z += step) add(x, 12.0f, z, kBuilding);
  for (float y = -20; y <= 12; y += step)
    for (float z = step; z <= 6; z += step) add(-15.0f, y, z, kBuilding);
  for (float z = step; z <= 5; z += step) add(4.0f, -3.0f, z, kPole);
  return p;
}

// The map's refinement layer from (x, y, z, label) samples, as the map builder writes it.
struct Layer {
  std::vector<MapRefineTile> tiles;
  std::vector<MapRefinePoint> points;
  RefineLayerView view;
  Layer(const std::vector<float>& xyzl, float cell) {
    std::vector<float> xyz;
    for (size_t i = 0; i < xyzl.size(); i += 4) xyz.insert(xyz.end(), {xyzl[i], xyzl[i + 1], xyzl[i + 2]});
    REQUIRE(mapping::build_refine_layer(xyz.data(), uint32_t(xyz.size() / 3), cell, &tiles, &points) == Status::Ok);
    view.cell = cell;
    view.tile_count = uint32_t(tiles.size());
    view.point_count = uint32_t(points.size());
    view.tiles = tiles.data();
    view.points = points.data();
    REQUIRE(view.validate() == Status::Ok);
  }
};

Eigen::Isometry3d pose(double x, double y, double yaw_deg) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(x, y, 1.7);
  return t;
}

struct Fixture {
  RefineConfig rc;
  VoxelConfig vc;
  ArenaBuffer vbuf{VoxelLayer::required_bytes(VoxelConfig())};
  VoxelLayer voxels;
  Eigen::Isometry3d truth = pose(3.0, -2.0, 25.0);
  Fixture() {
    rc.enabled = true;
    vc.min_range = 0.0f;
    REQUIRE(voxels.bind(vbuf.arena, vc) == Status::Ok);
    // The query: the same corner sampled densely, seen from `truth` (scan frame = truth^-1 * world).
    const std::vector<float> world = street_corner(0.2f);
    Cloud scan;
    const Eigen::Isometry3d inv = truth.inverse();
    for (size_t i = 0; i < world.size(); i += 4) {
      const Eigen::Vector3d q = inv * Eigen::Vector3d(world[i], world[i + 1], world[i + 2]);
      scan.add(float(q.x()), float(q.y()), float(q.z()), kitti_from_class(int(world[i + 3])));
    }
    REQUIRE(voxels.build(scan.view(), nullptr) == Status::Ok);
  }
  Eigen::Isometry3d run(Refiner& r, const Eigen::Isometry3d& initial, RefineStats* st) {
    Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
    REQUIRE(r.refine(voxels, initial, &out, st) == Status::Ok);
    return out;
  }
};

// The truth moved 0.8 m / -0.5 m in its own frame and turned 2 degrees: a typical global-pose error.
Eigen::Isometry3d perturbed(const Eigen::Isometry3d& truth) {
  Eigen::Isometry3d d = Eigen::Isometry3d::Identity();
  d.linear() = Eigen::AngleAxisd(2.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  d.translation() = Eigen::Vector3d(0.8, -0.5, 0.0);
  return truth * d;
}

double metres(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm();
}
double degrees(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle() * 180.0 / M_PI;
}

}  // namespace

TEST_CASE("Refinement pulls a nearby pose onto the map and is accepted") {
  Fixture f;
  const Layer map(street_corner(1.0f), f.rc.cell);
  ArenaBuffer buf(Refiner::required_bytes(f.rc));
  Refiner r;
  REQUIRE(r.bind(buf.arena, f.rc) == Status::Ok);
  REQUIRE(r.set_map(map.view) == Status::Ok);
  const Eigen::Isometry3d initial = perturbed(f.truth);
  REQUIRE(metres(initial, f.truth) > 0.5);
  RefineStats st;
  const Eigen::Isometry3d refined = f.run(r, initial, &st);
  INFO("inliers " << st.inliers << ", rmse " << st.rmse << ", error " << metres(refined, f.truth) << " m / "
                  << degrees(refined, f.truth) << " deg");
  CHECK(st.accepted);
  CHECK(st.inliers >= f.rc.min_inliers);
  CHECK(metres(refined, f.truth) < 0.15);
  CHECK(degrees(refined, f.truth) < 0.5);
}

TEST_CASE("Refinement that starts on the truth settles and goes straight to the last radius") {
  // From the truth the first update is tiny: the middle radii would find the same pairs again, so the
  // refiner runs the first and the last iteration only and stays on the truth. From 1 m off it needs
  // more than those two.
  Fixture f;
  REQUIRE(f.rc.iterations >= 4);
  const Layer map(street_corner(1.0f), f.rc.cell);
  ArenaBuffer buf(Refiner::required_bytes(f.rc));
  Refiner r;
  REQUIRE(r.bind(buf.arena, f.rc) == Status::Ok);
  REQUIRE(r.set_map(map.view) == Status::Ok);
  RefineStats st;
  const Eigen::Isometry3d refined = f.run(r, f.truth, &st);
  CHECK(st.accepted);
  CHECK(st.iterations == 2);
  CHECK(metres(refined, f.truth) < 0.05);
  CHECK(degrees(refined, f.truth) < 0.2);
  RefineStats far_st;
  f.run(r, perturbed(f.truth), &far_st);
  CHECK(far_st.iterations > 2);
}

namespace {

// A car park: flat ground and columns (r 0.3 m, 4.5 m) every 8 m, as (x, y, z, dense label) samples,
// the columns labelled `column`.
std::vector<float> car_park(int column) {
  std::vector<float> p;
  auto add = [&](float x, float y, float z, int cls) { p.insert(p.end(), {x, y, z, float(cls)}); };
  for (float x = -30; x <= 30; x += 0.25f)
    for (float y = -30; y <= 30; y += 0.25f) add(x, y, 0.0f, kParking);
  for (float cx = -28; cx <= 28; cx += 8)
    for (float cy = -28; cy <= 28; cy += 8)
      for (float z = 0.2f; z <= 4.5f; z += 0.2f)
        for (int k = 0; k < 16; ++k) {
          const float a = float(k) * float(M_PI) / 8.0f;
          add(cx + 0.3f * std::cos(a), cy + 0.3f * std::sin(a), z, column);
        }
  return p;
}

}  // namespace

TEST_CASE("Pole voxels hold the horizontal pose where the map has no plane but the ground") {
  // Columns have no normal in the 1 m layer, and the ground holds height, roll and pitch only: without
  // the pole rows nothing pulls x, y or heading (a column labelled building stays where it started).
  for (const int column : {int(kPole), int(kBuilding)}) {
    Fixture f;
    const std::vector<float> world = car_park(column);
    const Layer map(world, f.rc.cell);
    Cloud scan;
    const Eigen::Isometry3d inv = f.truth.inverse();
    for (size_t i = 0; i < world.size(); i += 4) {
      const Eigen::Vector3d q = inv * Eigen::Vector3d(world[i], world[i + 1], world[i + 2]);
      scan.add(float(q.x()), float(q.y()), float(q.z()), kitti_from_class(int(world[i + 3])));
    }
    REQUIRE(f.voxels.build(scan.view(), nullptr) == Status::Ok);
    ArenaBuffer buf(Refiner::required_bytes(f.rc));
    Refiner r;
    REQUIRE(r.bind(buf.arena, f.rc) == Status::Ok);
    REQUIRE(r.set_map(map.view) == Status::Ok);
    Eigen::Isometry3d d = Eigen::Isometry3d::Identity();
    d.linear() = Eigen::AngleAxisd(1.5 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    d.translation() = Eigen::Vector3d(0.4, -0.3, 0.0);
    const Eigen::Isometry3d initial = f.truth * d;
    RefineStats st;
    const Eigen::Isometry3d refined = f.run(r, initial, &st);
    INFO("column class " << column << ": error " << metres(refined, f.truth) << " m / " << degrees(refined, f.truth)
                         << " deg, inliers " << st.inliers);
    REQUIRE(st.accepted);
    if (column == kPole) {
      CHECK(metres(refined, f.truth) < 0.1);
      CHECK(degrees(refined, f.truth) < 0.3);
    } else {
      CHECK(metres(refined, f.truth) > 0.4);
      CHECK(degrees(refined, f.truth) > 1.2);
    }
  }
}

TEST_CASE("Refinement refuses a correction beyond max_correction and returns the initial pose") {
  Fixture f;
  f.rc.max_correction = 0.3f;  // the needed correction is about 1 m
  const Layer map(street_corner(1.0f), f.rc.cell);
  ArenaBuffer buf(Refiner::required_bytes(f.rc));
  Refiner r;
  REQUIRE(r.bind(buf.arena, f.rc) == Status::Ok);
  REQUIRE(r.set_map(map.view) == Status::Ok);
  const Eigen::Isometry3d initial = perturbed(f.truth);
  RefineStats st;
  const Eigen::Isometry3d out = f.run(r, initial, &st);
  CHECK_FALSE(st.accepted);
  CHECK(out.isApprox(initial));
}

TEST_CASE("Refinement refuses a layer of another cell size and ignores points without normals") {
  Fixture f;
  ArenaBuffer buf(Refiner::required_bytes(f.rc));
  Refiner r;
  REQUIRE(r.bind(buf.arena, f.rc) == Status::Ok);
  const Layer coarse(street_corner(1.0f), 2.0f * f.rc.cell);
  CHECK(r.set_map(coarse.view) == Status::ConfigMismatch);
  // Isolated points 6 m apart have no neighbourhood to fit a plane in: no normals, nothing to pull on.
  std::vector<float> sparse;
  for (float x = -18; x <= 18; x += 6)
    for (float y = -18; y <= 18; y += 6) sparse.insert(sparse.end(), {x, y, 0.0f, float(kRoad)});
  const Layer sparse_layer(sparse, f.rc.cell);
  for (const MapRefinePoint& p : sparse_layer.points) CHECK((p.normal[0] == 0 && p.normal[1] == 0 && p.normal[2] == 0));
  REQUIRE(r.set_map(sparse_layer.view) == Status::Ok);
  const Eigen::Isometry3d initial = perturbed(f.truth);
  RefineStats st;
  const Eigen::Isometry3d out = f.run(r, initial, &st);
  CHECK_FALSE(st.accepted);
  CHECK(out.isApprox(initial));
  CHECK(st.inliers < f.rc.min_inliers);
}

namespace {

// The refiner's search stated plainly: per query point the 27 cells of p + (dx, dy, dz) cell, in that
// order, no cell skipped and nothing remembered, the first strictly nearest point within the radius.
// The same Gauss-Newton steps and acceptance as Refiner::refine (core/src/refine.cpp), which must give
// the same pose: its skipping, caching and visiting order may only save work.
Eigen::Isometry3d reference_refine(const VoxelLayer& layer, const RefineLayerView& map, const RefineConfig& c,
                                   const Eigen::Isometry3d& initial, RefineStats* st) {
  *st = RefineStats();
  std::vector<float> query;
  uint32_t eligible = 0;
  for (uint32_t i = 0; i < layer.size(); ++i) eligible += stability_weight(layer.voxel(i).label) >= 1.0f;
  const uint32_t stride = eligible > c.max_points ? (eligible + c.max_points - 1) / c.max_points : 1;
  uint32_t seen = 0;
  std::vector<bool> pole;
  for (uint32_t i = 0; i < layer.size() && query.size() < size_t(c.max_points) * 3; ++i) {
    const Voxel& v = layer.voxel(i);
    if (stability_weight(v.label) < 1.0f || seen++ % stride) continue;
    query.insert(query.end(), {v.centroid[0], v.centroid[1], v.centroid[2]});
    pole.push_back(v.label == kPole || v.label == kTrunk);
  }
  st->query_points = uint32_t(query.size() / 3);
  const float inv = 1.0f / c.cell, step = map.cell / 256.0f;
  Eigen::Isometry3d t = initial;
  for (uint32_t it = 0; it < c.iterations; ++it) {
    const float frac = c.iterations > 1 ? float(it) / float(c.iterations - 1) : 1.0f;
    const float radius = c.radius_start + (c.radius_end - c.radius_start) * frac;
    Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
    uint32_t inl = 0;
    double err = 0;
    for (size_t i = 0; i < query.size(); i += 3) {
      const Eigen::Vector3d p = t * Eigen::Vector3d(query[i], query[i + 1], query[i + 2]);
      const float pf[3] = {float(p.x()), float(p.y()), float(p.z())};
      float best = radius * radius, nearest[3] = {0, 0, 0};
      const MapRefinePoint* nearest_point = nullptr;
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            const RefineCell cell{int32_t(std::floor((pf[0] + dx * c.cell) * inv)),
                                  int32_t(std::floor((pf[1] + dy * c.cell) * inv)),
                                  int32_t(std::floor((pf[2] + dz * c.cell) * inv))};
            uint32_t begin, end;
            map.find(cell, &begin, &end, nullptr);
            const float corner[3] = {float(cell.x) * map.cell, float(cell.y) * map.cell, float(cell.z) * map.cell};
            for (uint32_t id = begin; id < end; ++id) {
              const MapRefinePoint& mp = map.points[id];
              float m[3], d2 = 0;
              for (int k = 0; k < 3; ++k) m[k] = corner[k] + (float(mp.offset[k]) + 0.5f) * step;
              const float ex = m[0] - pf[0], ey = m[1] - pf[1], ez = m[2] - pf[2];
              d2 = ex * ex + ey * ey + ez * ez;
              if (d2 < best) {
                best = d2;
                nearest_point = &mp;
                for (int k = 0; k < 3; ++k) nearest[k] = m[k];
              }
            }
          }
      if (nearest_point == nullptr) continue;
      float n[3];
      RefineLayerView::normal(*nearest_point, n);
      const Eigen::Vector3d nrm(n[0], n[1], n[2]), m(nearest[0], nearest[1], nearest[2]);
      // Rows about the sensor: point to plane, or a pole voxel's x and y offsets from a point without one.
      auto add_row = [&](const Eigen::Vector3d& dir, double r) {
        Eigen::Matrix<double, 6, 1> J;
        J.head<3>() = (p - t.translation()).cross(dir);
        J.tail<3>() = dir;
        H += J * J.transpose();
        g += J * r;
        err += r * r;
      };
      if (nrm.squaredNorm() >= 0.5) {
        add_row(nrm, nrm.dot(p - m));
      } else if (pole[i / 3]) {
        add_row(Eigen::Vector3d::UnitX(), p.x() - m.x());
        add_row(Eigen::Vector3d::UnitY(), p.y() - m.y());
      } else {
        continue;
      }
      ++inl;
    }
    ++st->iterations;
    st->inliers = inl;
    st->rmse = inl ? std::sqrt(err / inl) : 0;
    if (inl < 6) break;
    const Eigen::Matrix<double, 6, 1> dx = H.ldlt().solve(-g);
    if (!dx.allFinite()) break;
    Eigen::Isometry3d s = Eigen::Isometry3d::Identity();
    const double angle = dx.head<3>().norm();
    if (angle > 1e-12) s.linear() = Eigen::AngleAxisd(angle, dx.head<3>() / angle).toRotationMatrix();
    s.translation() = t.translation() - s.linear() * t.translation() + dx.tail<3>();  // about the sensor
    t = s * t;
    // Settled (a move under 1 cm and a turn under 0.05 deg): straight to the last radius.
    if (dx.tail<3>().norm() < 0.01 && angle < 0.05 * M_PI / 180.0 && it + 2 < c.iterations) it = c.iterations - 2;
  }
  st->accepted = st->inliers >= c.min_inliers && (t.translation() - initial.translation()).norm() <= c.max_correction;
  return st->accepted ? t : initial;
}

}  // namespace

TEST_CASE("Refinement finds the same nearest points as the plain 27-cell search (dense layer, ties)") {
  // A 0.2 m layer holds up to 25 points a cell, on a lattice, so equal distances are common: the
  // refiner's skipping, per-point caching and nearest-first visiting must keep the plain search's answer.
  Fixture f;
  const Layer map(street_corner(0.2f), f.rc.cell);
  ArenaBuffer buf(Refiner::required_bytes(f.rc));
  Refiner r;
  REQUIRE(r.bind(buf.arena, f.rc) == Status::Ok);
  REQUIRE(r.set_map(map.view) == Status::Ok);
  Eigen::Isometry3d nudge = Eigen::Isometry3d::Identity();
  nudge.translation() = Eigen::Vector3d(0.35, 0.1, -0.2);
  for (const Eigen::Isometry3d& initial : {f.truth, perturbed(f.truth), f.truth * nudge, pose(4.0, -2.5, 22.0)}) {
    RefineStats st, ref_st;
    const Eigen::Isometry3d out = f.run(r, initial, &st);
    const Eigen::Isometry3d ref = reference_refine(f.voxels, map.view, f.rc, initial, &ref_st);
    CHECK(st.query_points == ref_st.query_points);
    CHECK(st.accepted == ref_st.accepted);
    CHECK((out.matrix() - ref.matrix()).cwiseAbs().maxCoeff() < 1e-4);
#if defined(__x86_64__) && !defined(__FMA__)
    // Same operations in the same order: the same bits. (Elsewhere the two translation units may
    // contract to FMA differently, which can flip a near tie: only close poses are required there.)
    CHECK(std::memcmp(out.matrix().data(), ref.matrix().data(), sizeof(double) * 16) == 0);
    CHECK(st.iterations == ref_st.iterations);
    CHECK(st.inliers == ref_st.inliers);
    CHECK(st.rmse == ref_st.rmse);
#endif
  }
}

TEST_CASE("A tie between cells goes to the lower (dx, dy, dz) index, as in the plain search") {
  // Query points exactly on the face x = 1 between cells 0 and 1, each with one map point either side
  // at the same distance (2^-9 m): the cell below (dx = -1) comes first in the plain order, though the
  // refiner visits the own cell (x = 1) first. Their normals differ, so the residuals tell them apart.
  Fixture f;
  f.rc.iterations = 1;
  f.rc.min_inliers = 1;
  std::vector<MapRefineTile> tiles(1);
  int32_t tx, ty;
  REQUIRE(refine_tile_of(RefineCell{0, 0, 0}, &tx, &ty, &tiles[0].key));
  tiles[0].first_point = 0;
  tiles[0].z_base = 0;
  std::vector<MapRefinePoint> points;
  Cloud scan;
  for (uint16_t y = 0; y < 16; y += 2) {
    for (uint16_t x = 0; x < 2; ++x) {
      MapRefinePoint p{};
      p.cell = uint16_t(y << 4 | x);
      p.offset[0] = x == 0 ? 255 : 0;  // 1 - 2^-9 and 1 + 2^-9
      p.offset[1] = p.offset[2] = 128;
      p.normal[x == 0 ? 0 : 2] = 127;  // below: along x; above: along z
      points.push_back(p);
    }
    scan.add(1.0f, float(y) + 128.5f / 256.0f, 128.5f / 256.0f, kitti_from_class(kBuilding));
  }
  // And one query point exactly the last radius (0.5 m) from its only map point: not a correspondence.
  MapRefinePoint edge{};
  edge.cell = uint16_t(15 << 4 | 1);
  edge.offset[0] = edge.offset[1] = edge.offset[2] = 128;
  edge.normal[0] = 127;
  points.push_back(edge);
  scan.add(1.0f + 0.5f / 256.0f, 15.0f + 128.5f / 256.0f, 128.5f / 256.0f, kitti_from_class(kBuilding));
  RefineLayerView view;
  view.cell = f.rc.cell;
  view.tile_count = 1;
  view.point_count = uint32_t(points.size());
  view.tiles = tiles.data();
  view.points = points.data();
  REQUIRE(view.validate() == Status::Ok);
  REQUIRE(f.voxels.build(scan.view(), nullptr) == Status::Ok);
  ArenaBuffer buf(Refiner::required_bytes(f.rc));
  Refiner r;
  REQUIRE(r.bind(buf.arena, f.rc) == Status::Ok);
  REQUIRE(r.set_map(view) == Status::Ok);
  RefineStats st, ref_st;
  const Eigen::Isometry3d initial = Eigen::Isometry3d::Identity();
  f.run(r, initial, &st);
  reference_refine(f.voxels, view, f.rc, initial, &ref_st);
  CHECK(st.query_points == 9);
  CHECK(st.inliers == 8);
  CHECK(ref_st.inliers == 8);
  CHECK(st.rmse == Approx(1.0 / 512).epsilon(1e-6));  // the x-normal points below, not the z-normal ones
  CHECK(st.rmse == ref_st.rmse);
}

TEST_CASE("The map's ground under a point: the plane of its level points, kerbs, walls and a roof left out") {
  // A street on a 5% grade along x (2.86 deg), a kerb 0.15 m up beyond |y| > 6, walls at y = +-12, a
  // flat roof 5 m above the street on one side, at 0.25 m spacing.
  const double grade = 0.05;
  std::vector<float> xyzl;
  auto add = [&](double x, double y, double z) { xyzl.insert(xyzl.end(), {float(x), float(y), float(z), 0.0f}); };
  for (double x = -30; x <= 30; x += 0.25)
    for (double y = -11.5; y <= 11.5; y += 0.25) add(x, y, grade * x + (std::fabs(y) > 6 ? 0.15 : 0.0));
  for (double x = -30; x <= 30; x += 0.25)
    for (double z = 0.25; z <= 6; z += 0.25) {
      add(x, 12.0, grade * x + z);
      add(x, -12.0, grade * x + z);
    }
  for (double x = 5; x <= 15; x += 0.25)
    for (double y = 8; y <= 11.5; y += 0.25) add(x, y, grade * x + 5.0);
  const Layer layer(xyzl, 1.0f);
  float up[3] = {0, 0, 0};
  REQUIRE(layer.view.ground_near(3.0f, 1.0f, 20.0f, 50, up) > 1000);
  const Eigen::Vector3d truth = Eigen::Vector3d(-grade, 0.0, 1.0).normalized();
  const double err = std::acos(std::min(1.0, Eigen::Vector3d(up[0], up[1], up[2]).dot(truth))) * 180.0 / M_PI;
  INFO("up " << up[0] << " " << up[1] << " " << up[2] << ", " << err << " deg off the street's normal");
  CHECK(err < 0.2);
  // Away from the layer's tiles, or asking for more points than there are: nothing, up untouched.
  float none[3] = {7, 8, 9};
  CHECK(layer.view.ground_near(500.0f, 500.0f, 20.0f, 50, none) == 0);
  CHECK(layer.view.ground_near(3.0f, 1.0f, 20.0f, 1u << 30, none) == 0);
  CHECK(none[0] == 7.0f);
}

TEST_CASE("The map's ground lookup refuses a disc wider than its tile limit (bounded work)") {
  std::vector<float> xyzl;
  for (double x = -40; x <= 40; x += 0.5)
    for (double y = -40; y <= 40; y += 0.5) xyzl.insert(xyzl.end(), {float(x), float(y), 0.0f, 0.0f});
  const Layer layer(xyzl, 1.0f);
  float up[3] = {7, 8, 9};
  CHECK(layer.view.ground_near(0.0f, 0.0f, 20.0f, 50, up) > 0);  // 20 m at 16 m tiles: 3-4 a side
  CHECK(up[2] > 0.999f);
  float none[3] = {7, 8, 9};
  CHECK(layer.view.ground_near(0.0f, 0.0f, 40.0f, 50, none) == 0);  // 80 m across: 6 tiles a side
  CHECK(none[0] == 7.0f);
}

}  // namespace test_refine
