// Refinement alone (core/include/gsf/detail/refine.h): it pulls a nearby global pose onto the map's point
// layer (built as the map builder builds it: mapping/refine_layer_builder.h), refuses corrections beyond
// its limit, refuses a layer of another cell size, and ignores map points without a reliable normal.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "arena_buffer.h"
#include "gsf/detail/refine.h"
#include "gsf/detail/voxel_layer.h"
#include "gsf/semantic_classes.h"
#include "mapping/refine_layer_builder.h"
#include "test_cloud.h"

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
