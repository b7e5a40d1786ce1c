#include "rgbd_odometry/io/odometry_log.hpp"

#include <cstdio>
#include <stdexcept>
#include "rgbd_odometry/core/time_format.hpp"

namespace rgbdo {
OdometryCsvWriter::OdometryCsvWriter(const std::string& path, std::uint64_t max_total_bytes)
    : file_(path, max_total_bytes, header()) {}

std::string OdometryCsvWriter::header() {
  std::string h = "t_prev,t_curr,status,inliers,tx,ty,tz,qx,qy,qz,qw";
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) h += ",c" + std::to_string(i) + std::to_string(j);
  h += ",chain";
  for (int i = 0; i < 6; ++i)
    for (int j = i; j < 6; ++j) h += ",pc" + std::to_string(i) + std::to_string(j);
  return h;
}

std::string OdometryCsvWriter::row(const PairResult& r) {
  const bool ok = r.status == Status::Ok;
  const Eigen::Isometry3d T = ok ? r.T_prev_curr : Eigen::Isometry3d::Identity();
  Eigen::Quaterniond q(T.linear());
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1;  // one sign convention for the same rotation
  std::string s = format_seconds(r.t_prev_ns) + "," + format_seconds(r.t_curr_ns) + "," +
                  std::string(status_word(r.status)) + "," + std::to_string(ok ? r.inliers : 0);
  char buf[64];
  // %.9g keeps sub-micrometre resolution on translations and ~1e-9 on quaternions.
  for (double v : {T.translation().x(), T.translation().y(), T.translation().z(), q.x(), q.y(), q.z(), q.w()}) {
    std::snprintf(buf, sizeof buf, ",%.9g", v);
    s += buf;
  }
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) {
      if (ok) std::snprintf(buf, sizeof buf, ",%.6e", r.covariance(i, j));
      else std::snprintf(buf, sizeof buf, ",nan");
      s += buf;
    }
  // The keyframe chain (pipeline/keyframes.hpp): 0 none, 1 begun at this frame, 2 going on;
  // then the upper triangle of the pose's covariance since it began.
  const int chain = !ok || r.keyframe.id == 0 ? 0 : r.keyframe.chain_started ? 1 : 2;
  std::snprintf(buf, sizeof buf, ",%d", chain);
  s += buf;
  for (int i = 0; i < 6; ++i)
    for (int j = i; j < 6; ++j) {
      if (chain > 0) std::snprintf(buf, sizeof buf, ",%.6e", r.keyframe.pose_covariance(i, j));
      else std::snprintf(buf, sizeof buf, ",nan");
      s += buf;
    }
  return s;
}

void OdometryCsvWriter::write(const PairResult& r) { file_.write_line(row(r)); }

TrajectoryWriter::TrajectoryWriter(const std::string& path, std::uint64_t max_total_bytes)
    : file_(path, max_total_bytes, "# timestamp tx ty tz qx qy qz qw (rgbd-odometry integrated trajectory)") {}

void TrajectoryWriter::write(std::int64_t t_ns, const Eigen::Isometry3d& pose) {
  Eigen::Quaterniond q(pose.linear());
  q.normalize();
  char buf[160];
  std::snprintf(buf, sizeof buf, " %.9f %.9f %.9f %.9f %.9f %.9f %.9f", pose.translation().x(),
                pose.translation().y(), pose.translation().z(), q.x(), q.y(), q.z(), q.w());
  file_.write_line(format_seconds(t_ns) + buf);
}

}  // namespace rgbdo
