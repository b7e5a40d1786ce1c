#include "rgbd_odometry/eval/groundtruth_noise.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "rgbd_odometry/core/geometry.hpp"

namespace rgbdo {
namespace {
constexpr double kChi2_1_Median = 0.454936;

double median_of(std::vector<double> v) {
  if (v.empty()) return 0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}
}  // namespace

GroundTruthNoise estimate_groundtruth_noise(const std::vector<StampedPose>& poses, int half_window) {
  GroundTruthNoise noise;
  const int n = static_cast<int>(poses.size());
  const int h = std::max(2, half_window);
  if (n < 2 * h + 1) return noise;
  const auto max_interval = static_cast<double>(groundtruth_gap_ns(poses));

  std::vector<double> position_sq, rotation_sq;  // r^2 / (1 - leverage), one per coordinate
  const int m = 2 * h + 1;
  Eigen::MatrixXd A(m, 3);
  Eigen::MatrixXd Y(m, 6);
  for (int i = h; i + h < n; ++i) {
    bool gap = false;
    for (int j = i - h + 1; j <= i + h; ++j) gap |= static_cast<double>(poses[j].t_ns - poses[j - 1].t_ns) > max_interval;
    if (gap) continue;
    const double span = static_cast<double>(poses[i + h].t_ns - poses[i - h].t_ns);
    const Eigen::Isometry3d& centre = poses[i].pose;
    for (int j = 0; j < m; ++j) {
      const StampedPose& p = poses[i - h + j];
      const double tau = static_cast<double>(p.t_ns - poses[i].t_ns) / span;  // well conditioned
      A.row(j) << 1.0, tau, tau * tau;
      Y.row(j).head<3>() = p.pose.translation().transpose();
      // Orientation relative to the centre sample, in its body frame: small, so a vector space.
      Y.row(j).tail<3>() = rotation_vector(centre.linear().transpose() * p.pose.linear()).transpose();
    }
    const Eigen::Matrix3d normal = A.transpose() * A;
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(normal);
    if (ldlt.info() != Eigen::Success) continue;
    const Eigen::Vector3d a_centre = A.row(h).transpose();
    const double leverage = a_centre.dot(ldlt.solve(a_centre));
    if (!(leverage < 0.999)) continue;
    const Eigen::MatrixXd coef = ldlt.solve(A.transpose() * Y);
    const Eigen::VectorXd residual = Y.row(h).transpose() - coef.transpose() * a_centre;
    for (int c = 0; c < 6; ++c) {
      const double r2 = residual(c) * residual(c) / (1 - leverage);
      (c < 3 ? position_sq : rotation_sq).push_back(r2);
    }
    ++noise.samples;
  }
  if (noise.samples == 0) return noise;
  noise.position_m = std::sqrt(median_of(position_sq) / kChi2_1_Median);
  noise.rotation_rad = std::sqrt(median_of(rotation_sq) / kChi2_1_Median);
  return noise;
}

GroundTruthAllowance allowance_from(const GroundTruthNoise& noise) {
  GroundTruthAllowance a;
  a.translation_m = std::sqrt(2.0) * noise.position_m;
  a.rotation_rad = std::sqrt(2.0) * noise.rotation_rad;
  std::ostringstream s;
  s.precision(2);
  s << "estimated from " << noise.samples << " ground-truth samples: jitter " << noise.position_m * 1e3 << " mm, "
    << noise.rotation_rad * 180.0 / M_PI << " deg per sample";
  a.origin = s.str();
  return a;
}

GroundTruthAllowance parse_allowance(const std::string& text, const GroundTruth& groundtruth) {
  if (text == "auto") return allowance_from(estimate_groundtruth_noise(groundtruth.poses()));
  if (text == "none") return {0, 0, "none"};
  const auto comma = text.find(',');
  GroundTruthAllowance a;
  try {
    if (comma == std::string::npos) throw std::invalid_argument("no comma");
    size_t used_t = 0, used_r = 0;
    const std::string t = text.substr(0, comma), r = text.substr(comma + 1);
    a.translation_m = std::stod(t, &used_t);
    a.rotation_rad = std::stod(r, &used_r);
    if (used_t != t.size() || used_r != r.size()) throw std::invalid_argument("trailing characters");
  } catch (const std::exception&) {
    throw std::invalid_argument("ground-truth allowance '" + text +
                                "' is not 'auto', 'none' or 'T_M,R_RAD' (e.g. 0.0003,0.0015)");
  }
  if (!(a.translation_m >= 0) || !(a.rotation_rad >= 0) || !std::isfinite(a.translation_m) ||
      !std::isfinite(a.rotation_rad))
    throw std::invalid_argument("ground-truth allowance '" + text + "' must be two finite numbers >= 0");
  a.origin = "given";
  return a;
}

}  // namespace rgbdo
