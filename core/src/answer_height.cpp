#include "gsf/detail/answer_height.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

#include "gsf/detail/angles.h"
#include "gsf/detail/semantic_grid.h"
#include "gsf/detail/voxel_layer.h"

namespace gsf {

uint32_t consensus_height(const float* a, const float* b, const float* w, uint32_t n, float radius, uint32_t min_count,
                          HeightSample* scratch, Eigen::Isometry3d* T) {
  if (!T || !scratch || n == 0 || !(radius > 0.0f)) return 0;
  const Eigen::Matrix3d R = T->linear();
  const Eigen::Vector3d t = T->translation();
  const double r2 = double(radius) * radius;
  uint32_t m = 0;
  double total = 0.0;
  for (uint32_t i = 0; i < n; ++i) {
    const Eigen::Vector3d q = R * Eigen::Vector3d(a[3 * i], a[3 * i + 1], a[3 * i + 2]);
    const double dx = q.x() + t.x() - b[3 * i], dy = q.y() + t.y() - b[3 * i + 1];
    if (dx * dx + dy * dy > r2 || !(w[i] > 0.0f)) continue;
    scratch[m++] = HeightSample{static_cast<float>(double(b[3 * i + 2]) - q.z()), w[i], i};
    total += w[i];
  }
  if (m == 0 || m < min_count) return 0;
  std::sort(scratch, scratch + m, [](const HeightSample& x, const HeightSample& y) {
    return x.offset < y.offset || (x.offset == y.offset && x.index < y.index);
  });
  // The weighted median: the first offset at which the running weight reaches half the total.
  double running = 0.0;
  uint32_t k = 0;
  for (; k + 1 < m; ++k) {
    running += scratch[k].weight;
    if (running >= 0.5 * total) break;
  }
  T->translation().z() = scratch[k].offset;
  return m;
}

namespace {

// The shortest rotation taking unit vector a onto unit vector b (Rodrigues). Eigen's
// Quaternion::FromTwoVectors does the same but pulls in JacobiSVD for the opposite case, which
// tripled this file's compile time; up vectors are never opposite here (both have z > 0), and for
// a.b near -1 a half turn about an axis across a is returned.
Eigen::Matrix3d rotation_onto(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d v = a.cross(b);
  const double c = a.dot(b);
  if (c < -1.0 + 1e-9) {
    const Eigen::Vector3d axis =
        (std::fabs(a.x()) < 0.9 ? a.cross(Eigen::Vector3d::UnitX()) : a.cross(Eigen::Vector3d::UnitY())).normalized();
    return 2.0 * axis * axis.transpose() - Eigen::Matrix3d::Identity();
  }
  Eigen::Matrix3d vx;
  vx << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return Eigen::Matrix3d::Identity() + vx + vx * vx / (1.0 + c);
}

// Plane through the ground voxels near the sensor (with band > 0: only those within band of `plane`):
// its normal (pointing up) and offset into *out (n . p + d = 0). Returns how many voxels it fitted.
uint32_t fit_ground(const VoxelLayer& voxels, const Eigen::Vector4d& plane, double band, Eigen::Vector4d* out) {
  const double r2 = double(kGroundRadiusM) * kGroundRadiusM;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
  uint32_t m = 0;
  for (uint32_t i = 0; i < voxels.size(); ++i) {
    const Voxel& v = voxels.voxel(i);
    if (!(class_bit(v.label) & kGroundClasses)) continue;
    const Eigen::Vector3d p(v.centroid[0], v.centroid[1], v.centroid[2]);
    if (p.x() * p.x() + p.y() * p.y() > r2) continue;
    if (band > 0.0 && std::fabs(plane.head<3>().dot(p) + plane.w()) > band) continue;
    sum += p;
    outer += p * p.transpose();
    ++m;
  }
  if (m < kGroundMinVoxels) return m;
  const Eigen::Vector3d mean = sum / double(m);
  const Eigen::Matrix3d cov = outer / double(m) - mean * mean.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Eigen::Vector3d n = eig.eigenvectors().col(0);  // the smallest eigenvalue's: the plane's normal
  if (n.z() < 0.0) n = -n;
  *out << n, -n.dot(mean);
  return m;
}

}  // namespace

bool scan_ground_up(const VoxelLayer& voxels, Eigen::Vector3d* up) {
  Eigen::Vector4d first, second;
  if (!up || fit_ground(voxels, Eigen::Vector4d::Zero(), 0.0, &first) < kGroundMinVoxels ||
      fit_ground(voxels, first, kGroundBandM, &second) < kGroundMinVoxels)
    return false;
  *up = second.head<3>();
  return true;
}

void level_answer(const Eigen::Vector3d& scan_up, const Eigen::Vector3d& map_up, Eigen::Isometry3d* T) {
  if (!T) return;
  const double yaw = std::atan2(T->linear()(1, 0), T->linear()(0, 0));
  // Level the scan (its up to the vertical), turn about the vertical, tilt the vertical onto map_up; the
  // turn is solved so the result reads verification's yaw (a few fixed-point steps: the tilt is small).
  const Eigen::Matrix3d level = rotation_onto(scan_up.normalized(), Eigen::Vector3d::UnitZ());
  const Eigen::Matrix3d lean = rotation_onto(Eigen::Vector3d::UnitZ(), map_up.normalized());
  auto turned = [&](double turn) -> Eigen::Matrix3d {
    return lean * Eigen::AngleAxisd(turn, Eigen::Vector3d::UnitZ()).toRotationMatrix() * level;
  };
  double turn = yaw;
  for (int k = 0; k < 4; ++k) {
    const Eigen::Matrix3d R = turned(turn);
    turn += std::remainder(yaw - std::atan2(R(1, 0), R(0, 0)), 2.0 * kPi);
  }
  T->linear() = turned(turn);
}

}  // namespace gsf
