#include "gsf/detail/pose_solver.h"

#include <cmath>

#include <Eigen/SVD>

namespace gsf {

Status kabsch(const float* a, const float* b, const float* w, uint32_t n, Eigen::Isometry3d* out) {
  if (n < 3) return Status::InvalidInput;
  double wsum = 0.0;
  Eigen::Vector3d ca = Eigen::Vector3d::Zero(), cb = Eigen::Vector3d::Zero();
  for (uint32_t i = 0; i < n; ++i) {
    const double wi = w ? w[i] : 1.0;
    if (!(wi >= 0.0) || !std::isfinite(wi)) return Status::InvalidInput;
    const Eigen::Vector3d pa(a[3 * i], a[3 * i + 1], a[3 * i + 2]), pb(b[3 * i], b[3 * i + 1], b[3 * i + 2]);
    if (!pa.allFinite() || !pb.allFinite()) return Status::InvalidInput;
    wsum += wi;
    ca += wi * pa;
    cb += wi * pb;
  }
  if (!(wsum > 0.0)) return Status::InvalidInput;
  ca /= wsum;
  cb /= wsum;
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (uint32_t i = 0; i < n; ++i) {
    const double wi = w ? w[i] : 1.0;
    const Eigen::Vector3d pa(a[3 * i], a[3 * i + 1], a[3 * i + 2]), pb(b[3 * i], b[3 * i + 1], b[3 * i + 2]);
    h += wi * (pa - ca) * (pb - cb).transpose();
  }
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d s = svd.singularValues();
  // Rank < 2: the weighted points are collinear (or coincident), rotation about that line is free.
  if (!(s(1) > 1e-9 * (s(0) + 1e-12))) return Status::InvalidInput;
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  const Eigen::Matrix3d r = svd.matrixV() * d * svd.matrixU().transpose();
  out->setIdentity();
  out->linear() = r;
  out->translation() = cb - r * ca;
  return Status::Ok;
}

Status fit_upright(const float* a, const float* b, const float* w, const uint8_t* mask, uint32_t n,
                   Eigen::Isometry3d* out) {
  double wsum = 0.0;
  uint32_t rows = 0;
  Eigen::Vector3d ca = Eigen::Vector3d::Zero(), cb = Eigen::Vector3d::Zero();
  for (uint32_t i = 0; i < n; ++i) {
    if (mask && !mask[i]) continue;
    const double wi = w ? w[i] : 1.0;
    const Eigen::Vector3d pa(a[3 * i], a[3 * i + 1], a[3 * i + 2]), pb(b[3 * i], b[3 * i + 1], b[3 * i + 2]);
    if (!(wi >= 0.0) || !std::isfinite(wi) || !pa.allFinite() || !pb.allFinite()) return Status::InvalidInput;
    wsum += wi;
    ca += wi * pa;
    cb += wi * pb;
    ++rows;
  }
  if (rows < 2 || !(wsum > 0.0)) return Status::InvalidInput;
  ca /= wsum;
  cb /= wsum;
  double sc = 0.0, ss = 0.0;  // sum w (a . b) and sum w (a x b)_z over centred x, y
  for (uint32_t i = 0; i < n; ++i) {
    if (mask && !mask[i]) continue;
    const double wi = w ? w[i] : 1.0;
    const double ax = a[3 * i] - ca.x(), ay = a[3 * i + 1] - ca.y(), bx = b[3 * i] - cb.x(), by = b[3 * i + 1] - cb.y();
    sc += wi * (ax * bx + ay * by);
    ss += wi * (ax * by - ay * bx);
  }
  if (!(std::fabs(sc) + std::fabs(ss) > 1e-12)) return Status::InvalidInput;
  out->setIdentity();
  out->linear() = Eigen::AngleAxisd(std::atan2(ss, sc), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  out->translation() = cb - out->linear() * ca;
  return Status::Ok;
}

static double residual2(const Eigen::Isometry3d& t, const float* a, const float* b, uint32_t i) {
  const Eigen::Vector3d pa(a[3 * i], a[3 * i + 1], a[3 * i + 2]), pb(b[3 * i], b[3 * i + 1], b[3 * i + 2]);
  return (pb - t * pa).squaredNorm();
}

Status solve_tls(const float* a, const float* b, const float* w, uint32_t n, double c, uint32_t max_iterations,
                 TlsResult* out, uint8_t* mask, float* gw) {
  *out = TlsResult();
  if (!(c > 0.0)) return Status::InvalidArgument;
  Eigen::Isometry3d t;
  Status s = kabsch(a, b, w, n, &t);
  if (s != Status::Ok) return s;
  const double c2 = c * c;
  // Initial mu from the largest residual (Yang et al.: mu0 = c^2 / (2 r_max^2 - c^2)).
  double rmax2 = 0.0;
  for (uint32_t i = 0; i < n; ++i) rmax2 = std::fmax(rmax2, residual2(t, a, b, i));
  double mu = rmax2 > c2 ? c2 / (2.0 * rmax2 - c2) : 1e6;
  uint32_t it = 0;
  for (; it < max_iterations && mu < 1e6; ++it) {
    for (uint32_t i = 0; i < n; ++i) {
      const double r2 = residual2(t, a, b, i);
      double g;
      if (r2 <= mu / (mu + 1.0) * c2) g = 1.0;
      else if (r2 >= (mu + 1.0) / mu * c2) g = 0.0;
      else g = c * std::sqrt(mu * (mu + 1.0) / r2) - mu;
      gw[i] = static_cast<float>(g * (w ? w[i] : 1.0));
    }
    Eigen::Isometry3d next;
    if (kabsch(a, b, gw, n, &next) != Status::Ok) break;  // too few weighted points: keep the last pose
    t = next;
    mu *= 1.4;
  }
  uint32_t inliers = 0;
  double cost = 0.0;
  for (uint32_t i = 0; i < n; ++i) {
    const double r2 = residual2(t, a, b, i);
    const bool in = r2 <= c2;
    inliers += in ? 1u : 0u;
    if (mask) mask[i] = in ? 1 : 0;
    cost += (w ? w[i] : 1.0) * std::fmin(r2, c2);
  }
  // Final polish: weighted Kabsch on the inliers alone.
  if (inliers >= 3) {
    for (uint32_t i = 0; i < n; ++i) gw[i] = residual2(t, a, b, i) <= c2 ? (w ? w[i] : 1.0f) : 0.0f;
    Eigen::Isometry3d polished;
    if (kabsch(a, b, gw, n, &polished) == Status::Ok) t = polished;
  }
  out->b_T_a = t;
  out->inliers = inliers;
  out->cost = cost;
  out->iterations = it;
  return Status::Ok;
}

}  // namespace gsf
