#include "rgbd_odometry/app/odometry_sinks.hpp"

#include <iomanip>
#include <ostream>

#include "rgbd_odometry/app/report.hpp"
#include "rgbd_odometry/eval/evaluate.hpp"
#include "rgbd_odometry/io/odometry_log.hpp"
#include "rgbd_odometry/link/flight_link.hpp"

namespace rgbdo {

void LogSink::dropped(const PairOutput& item) { log_.write(item.result); }

void LogSink::pair(const PairOutput& item, std::size_t /*index*/, const Eigen::Isometry3d& /*pose*/) {
  log_.write(item.result);
}

void TrajectorySink::frame(const PairOutput& item, const Eigen::Isometry3d& pose) {
  trajectory_.write(item.t_frame_host_ns(), pose);
}

void TrajectorySink::pair(const PairOutput& item, std::size_t /*index*/, const Eigen::Isometry3d& pose) {
  trajectory_.write(item.t_frame_host_ns(), pose);
}

void FlightLinkSink::pair(const PairOutput& item, std::size_t /*index*/, const Eigen::Isometry3d& /*pose*/) {
  link_.send_pair(item.result);
}

void EvaluationSink::pair(const PairOutput& item, std::size_t /*index*/, const Eigen::Isometry3d& pose) {
  evaluator_.add(item.result, origin_inverse_ * pose);
}

void ConsoleSink::pair(const PairOutput& item, std::size_t index, const Eigen::Isometry3d& /*pose*/) {
  out_ << pair_line(item.result, index, verbose_);
  if (item.skipped > 0) out_ << "  (" << item.skipped << " frames skipped)";
  if (verbose_) out_ << std::fixed << std::setprecision(1) << " | latency " << item.latency_ms << " ms";
  out_ << "\n";
}

}  // namespace rgbdo
