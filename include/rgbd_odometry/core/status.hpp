#pragma once
// Why a frame or a frame pair produced no odometry. Every pair yields a row; a failed one
// carries one of these, so a user can tell "blank wall" from "sensor gave no depth".
#include <string_view>

namespace rgbdo {

enum class Status {
  Ok,
  BadFrame,           // the colour or depth image could not be read or has the wrong size
  NoDepth,            // no depth image was associated with the colour frame (a frame after a
                      // good one is dropped and bridged: PairEstimator::estimate)
  TooFewFeatures,     // detector found fewer keypoints than a pose needs (no texture)
  TooFewMatches,      // the symmetric ratio test kept fewer matches than a pose needs
  DegenerateSample,   // every RANSAC sample was collinear or violated rigidity
  RansacFailed,       // the best hypothesis has too few inliers
  CovarianceFailed,   // the perturbation covariance was not finite and positive definite
  SensorLost,         // the sensor went away between the two frames (unplugged, re-opened)
  // The frame's capture time is not after the previous frame's (a frame listed twice, frames
  // out of order, a clock step): no motion over no time. Logged, never sent; the frame is
  // dropped and the next one pairs with the previous one, so tracking goes on.
  StampNotIncreasing,
};

// The lower-case word written in the odometry log's `status` column.
constexpr std::string_view status_word(Status s) {
  switch (s) {
    case Status::Ok: return "ok";
    case Status::BadFrame: return "bad_frame";
    case Status::NoDepth: return "no_depth";
    case Status::TooFewFeatures: return "too_few_features";
    case Status::TooFewMatches: return "too_few_matches";
    case Status::DegenerateSample: return "degenerate_sample";
    case Status::RansacFailed: return "ransac_failed";
    case Status::CovarianceFailed: return "covariance_failed";
    case Status::SensorLost: return "sensor_lost";
    case Status::StampNotIncreasing: return "stamp_not_increasing";
  }
  return "unknown";
}

}  // namespace rgbdo
