// The answer's height alone (core/include/gsf/detail/answer_height.h): the weighted median vertical
// offset of the correspondences the answer places within the radius, worked by hand; fewer than min_count
// leave the pose alone. The answer's roll and pitch: the scan's own ground levelled in the map.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

#include "arena_buffer.h"
#include "gsf/config.h"
#include "gsf/detail/answer_height.h"
#include "gsf/detail/voxel_layer.h"
#include "test_cloud.h"

namespace test_answer_height {

using namespace gsf;
using gsf_test::ArenaBuffer;

TEST_CASE("The answer's height is the weighted median vertical offset of the correspondences it explains") {
  // A pose at the right place and heading but 5 m too high, as a shift vote of three cut-off trunks
  // gives it. Seven correspondences agree in x and y: offsets 1.0 (weight 1), 1.1 (2), 1.2 (1), 1.3 (1),
  // and three cut-off trunks at 3.0, 3.2, 3.4 (weight 1 each); the running weight in offset order (1, 3,
  // 4, ...) reaches half the total (8 / 2) at 1.2, the weighted median. Two more lie 2 m off in x and carry offsets of
  // -20: beyond the radius, ignored.
  const double yaw = 0.7;
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();
  truth.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  truth.translation() = Eigen::Vector3d(40.0, -12.0, 1.3);
  const float offsets[9] = {3.4f, 1.0f, 3.0f, 1.2f, 1.1f, 3.2f, 1.3f, -20.0f, -20.0f};
  const float weights[9] = {1, 1, 1, 1, 2, 1, 1, 5, 5};
  float a[27], b[27];
  for (int i = 0; i < 9; ++i) {
    const Eigen::Vector3d q(3.0 * i - 10.0, 0.5 * i * i - 7.0, 0.25 * i);
    const Eigen::Vector3d m = truth.linear() * q + Eigen::Vector3d(40.0, -12.0, 0.0);
    for (int k = 0; k < 3; ++k) a[3 * i + k] = float(q[k]);
    b[3 * i] = float(m.x() + (i >= 7 ? 2.0 : 0.0));
    b[3 * i + 1] = float(m.y());
    b[3 * i + 2] = float(m.z() + offsets[i]);
  }
  Eigen::Isometry3d T = truth;
  T.translation().z() = 6.3;
  HeightSample scratch[9];
  CHECK(consensus_height(a, b, weights, 9, 1.5f, 3, scratch, &T) == 7);
  CHECK(T.translation().z() == Approx(1.2).margin(1e-5));
  CHECK(T.translation().x() == 40.0);  // x, y and the rotation are verification's: untouched
  CHECK(T.translation().y() == -12.0);
  CHECK(T.linear().isApprox(truth.linear()));
  // With the trunks weighted 3 each (total 13, half 6.5: 1, 2, 3, 4, then 7 at 3.0) the median moves up.
  float heavy[9];
  for (int i = 0; i < 9; ++i) heavy[i] = (offsets[i] >= 3.0f && i < 7) ? 3.0f : 1.0f;
  T.translation().z() = 6.3;
  CHECK(consensus_height(a, b, heavy, 9, 1.5f, 3, scratch, &T) == 7);
  CHECK(T.translation().z() == Approx(3.0).margin(1e-5));
  // Fewer agreeing correspondences than min_count: the pose keeps its own height.
  T.translation().z() = 6.3;
  CHECK(consensus_height(a, b, weights, 9, 1.5f, 8, scratch, &T) == 0);
  CHECK(T.translation().z() == 6.3);
  // A pose 30 m away explains none of them.
  T.translation().x() += 30.0;
  CHECK(consensus_height(a, b, weights, 9, 1.5f, 3, scratch, &T) == 0);
  CHECK(T.translation().z() == 6.3);
}

TEST_CASE("Levelling keeps verification's yaw and the position and maps the scan's up to the vertical") {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  // A TLS pose leaning 7 deg at the right place, as a row's few mid-height centroids gave it.
  T.linear() = Eigen::AngleAxisd(7.0 / 57.29577951308232, Eigen::Vector3d(0.6, 0.8, 0.0)).toRotationMatrix() *
               Eigen::AngleAxisd(2.5, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(40.0, -12.0, 9.5);
  const double yaw = std::atan2(T.linear()(1, 0), T.linear()(0, 0));  // what verification read
  for (const Eigen::Vector3d& up : {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0.05, -0.02, 1).normalized(),
                                    Eigen::Vector3d(-0.1, 0.08, 1).normalized()}) {
    Eigen::Isometry3d L = T;
    level_answer(up, Eigen::Vector3d::UnitZ(), &L);
    INFO("up " << up.transpose());
    CHECK((L.linear() * up - Eigen::Vector3d::UnitZ()).norm() < 1e-12);
    CHECK(std::atan2(L.linear()(1, 0), L.linear()(0, 0)) == Approx(yaw).margin(1e-12));
    CHECK(L.translation() == T.translation());  // turned about the sensor
    CHECK(L.linear().determinant() == Approx(1.0).margin(1e-12));
  }
  // An upside-down up (no ground fit gives one, but the function takes any): still a rotation that
  // maps it to the vertical, not a reflection or NaN.
  Eigen::Isometry3d F = T;
  level_answer(-Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitZ(), &F);
  CHECK((F.linear() * -Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitZ()).norm() < 1e-12);
  CHECK(F.linear().determinant() == Approx(1.0).margin(1e-12));
  CHECK((F.linear().transpose() * F.linear() - Eigen::Matrix3d::Identity()).norm() < 1e-12);
}

namespace {

// A street seen from a sensor 1.8 m above it whose frame leans by `lean` (axis x angle, sensor frame):
// road and sidewalk 0.15 m higher (a kerb) out to 30 m, walls and poles, the near ground given wrong
// heights by a parked car's floor (labelled parking) at 0.5 m.
gsf_test::Cloud leaning_street(const Eigen::Vector3d& lean) {
  gsf_test::Cloud c;
  const Eigen::Matrix3d R = lean.norm() > 0 ? Eigen::AngleAxisd(lean.norm(), lean.normalized()).toRotationMatrix()
                                            : Eigen::Matrix3d::Identity();
  auto add = [&](double x, double y, double z, uint32_t label) {
    const Eigen::Vector3d p = R.transpose() * Eigen::Vector3d(x, y, z);  // world (level) to sensor frame
    c.add(float(p.x()), float(p.y()), float(p.z()), label);
  };
  for (double x = -30; x <= 30; x += 0.4)
    for (double y = -12; y <= 12; y += 0.4) {
      const bool sidewalk = std::fabs(y) > 5.0;
      add(x, y, -1.8 + (sidewalk ? 0.15 : 0.0), sidewalk ? 48u : 40u);
    }
  for (double x = 3; x <= 7; x += 0.25)
    for (double y = -4.5; y <= -3; y += 0.25) add(x, y, -1.3, 44u);  // a car's floor, labelled parking
  for (double x = -30; x <= 30; x += 0.3)
    for (double z = -1.8; z <= 6; z += 0.3) add(x, 12.5, z, 50u);  // a wall
  return c;
}

}  // namespace

TEST_CASE("The scan's ground gives the sensor's lean; too little ground gives none") {
  VoxelConfig vc;
  ArenaBuffer buf(VoxelLayer::required_bytes(vc));
  VoxelLayer layer;
  REQUIRE(layer.bind(buf.arena, vc) == Status::Ok);
  for (const Eigen::Vector3d& lean :
       {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, 3.0 / 57.29577951308232, 0), Eigen::Vector3d(0.03, -0.05, 0)}) {
    const gsf_test::Cloud c = leaning_street(lean);
    REQUIRE(layer.build(c.view(), nullptr) == Status::Ok);
    Eigen::Vector3d up(0, 0, 0);
    REQUIRE(scan_ground_up(layer, &up));
    // The world's vertical in the sensor frame is R^T z.
    const Eigen::Matrix3d R = lean.norm() > 0 ? Eigen::AngleAxisd(lean.norm(), lean.normalized()).toRotationMatrix()
                                              : Eigen::Matrix3d::Identity();
    const Eigen::Vector3d truth = R.transpose() * Eigen::Vector3d::UnitZ();
    INFO("lean " << lean.transpose() << ": up " << up.transpose());
    CHECK(std::acos(std::min(1.0, up.dot(truth))) * 57.29577951308232 < 0.2);
    // Levelled on it, an upright-yawed answer of this scan has the true roll and pitch.
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    level_answer(up, Eigen::Vector3d::UnitZ(), &T);
    CHECK(Eigen::AngleAxisd(T.linear().transpose() * R).angle() * 57.29577951308232 < 0.2);
  }
  // Only the wall and a few ground voxels: no ground to tell.
  gsf_test::Cloud wall;
  for (double x = -30; x <= 30; x += 0.3)
    for (double z = -1.8; z <= 6; z += 0.3) wall.add(float(x), 12.5f, float(z), 50u);
  for (int k = 0; k < 20; ++k) wall.add(float(k), 0.0f, -1.8f, 40u);
  REQUIRE(layer.build(wall.view(), nullptr) == Status::Ok);
  Eigen::Vector3d up(1, 2, 3);
  CHECK_FALSE(scan_ground_up(layer, &up));
  CHECK(up == Eigen::Vector3d(1, 2, 3));
}

}  // namespace test_answer_height
