// The answer's height alone (core/include/gsf/detail/answer_height.h): the weighted median vertical
// offset of the correspondences the answer places within the radius, worked by hand; fewer than min_count
// leave the pose alone.
#include <catch2/catch.hpp>

#include <Eigen/Geometry>

#include "gsf/config.h"
#include "gsf/detail/answer_height.h"

using namespace gsf;

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
