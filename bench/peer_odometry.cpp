// A second estimate of every pair, made independently of ours, for the consistency check of
// bench/peer_check.py (bench/README.md#peer-check-whose-error-it-is): OpenCV's
// RgbdICPOdometry (opencv_contrib rgbd:
// dense photometric and point-to-plane alignment, no features) on the same TUM frames, with the
// same colour/depth association and intrinsics as the program. A diagnostic, not the product.
//
//   peer_odometry TUM_DIR CONFIG.yaml > peer.csv
//
// One row per consecutive pair of loadable frames: t_prev,t_curr (colour stamps, s), ok, and
// xi = (t [m], rotation vector [rad]) of T_prev_curr, the convention of the odometry log.
#include <cstdio>
#include <exception>
#include <limits>
#include <opencv2/rgbd.hpp>
#include <optional>

#include "rgbd_odometry/app/config.hpp"
#include "rgbd_odometry/core/geometry.hpp"
#include "rgbd_odometry/app/config_file.hpp"
#include "rgbd_odometry/io/tum_sequence.hpp"

namespace {

// The program marks a missing reading 0; OpenCV's odometry expects NaN there.
cv::Mat depth_for_opencv(const cv::Mat& depth_m) {
  cv::Mat d = depth_m.clone();
  d.setTo(std::numeric_limits<float>::quiet_NaN(), depth_m <= 0);
  return d;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: peer_odometry TUM_DIR CONFIG.yaml > peer.csv\n");
    return 2;
  }
  try {
    const rgbdo::Config config = rgbdo::load_config(argv[2]);
    const rgbdo::TumSequence seq = rgbdo::open_tum_sequence(argv[1]);
    const auto& cam = config.camera;
    const cv::Mat K = (cv::Mat_<float>(3, 3) << cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
    const cv::Ptr<cv::rgbd::RgbdICPOdometry> odometry = cv::rgbd::RgbdICPOdometry::create(
        K, static_cast<float>(config.depth.min_m), static_cast<float>(config.depth.max_m));
    std::printf("t_prev,t_curr,ok,tx,ty,tz,rx,ry,rz\n");
    std::optional<rgbdo::RgbdFrame> prev;  // its depth_m already in OpenCV's form
    for (const auto& ref : seq.frames) {
      rgbdo::RgbdFrame f = rgbdo::load_tum_frame(ref, config.depth.units_per_m, cam.width, cam.height);
      if (f.status != rgbdo::Status::Ok) {
        std::fprintf(stderr, "peer_odometry: frame at %.6f skipped: %s\n", f.t_colour_ns * 1e-9, f.problem.c_str());
        prev.reset();
        continue;
      }
      f.depth_m = depth_for_opencv(f.depth_m);
      if (prev) {
        // dst_p = Rt src_p with the current frame as the source: Rt is T_prev_curr.
        cv::Mat Rt;
        const cv::Mat all_prev(prev->gray.size(), CV_8UC1, cv::Scalar(255)), all_curr(f.gray.size(), CV_8UC1, cv::Scalar(255));
        const bool ok = odometry->compute(f.gray, f.depth_m, all_curr, prev->gray, prev->depth_m, all_prev, Rt);
        rgbdo::Vector6d xi = rgbdo::Vector6d::Constant(std::numeric_limits<double>::quiet_NaN());
        if (ok) {
          Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
          for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 4; ++c) T.matrix()(r, c) = Rt.at<double>(r, c);
          xi = rgbdo::xi_from_transform(T);
        }
        std::printf("%.6f,%.6f,%d,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", prev->t_colour_ns * 1e-9, f.t_colour_ns * 1e-9,
                    ok ? 1 : 0, xi(0), xi(1), xi(2), xi(3), xi(4), xi(5));
      }
      prev = std::move(f);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "peer_odometry: %s\n", e.what());
    return 1;
  }
  return 0;
}
