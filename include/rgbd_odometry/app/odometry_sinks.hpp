#pragma once
// Where each frame's outcome goes: the odometry log, the trajectory, the flight-computer link,
// the evaluation against ground truth and the console are all sinks of one interface, fed on
// the pipeline's output thread one frame at a time, in capture order (app/run.cpp). A new
// output is a new sink, not a new branch in the run.
#include <Eigen/Geometry>
#include <cstddef>
#include <iosfwd>

#include "rgbd_odometry/core/pair_output.hpp"

namespace rgbdo {

class AccuracyEvaluator;
class FlightLink;
class OdometryCsvWriter;
class TrajectoryWriter;

class OdometrySink {
 public:
  virtual ~OdometrySink() = default;
  // A frame that ends no pair (the very first): the pose stands where it was.
  virtual void frame(const PairOutput& item, const Eigen::Isometry3d& pose) {
    (void)item;
    (void)pose;
  }
  // A dropped frame (PairEstimator::dropped_frame: a capture time not after the previous
  // frame's, or no depth, bridged): no pose; the next pair spans it.
  virtual void dropped(const PairOutput& item) { (void)item; }
  // The index-th pair, good or failed, and the integrated pose after it.
  virtual void pair(const PairOutput& item, std::size_t index, const Eigen::Isometry3d& pose) = 0;
};

// Every pair and every dropped frame, one row each (io/odometry_log.hpp).
class LogSink : public OdometrySink {
 public:
  explicit LogSink(OdometryCsvWriter& log) : log_(log) {}
  void dropped(const PairOutput& item) override;
  void pair(const PairOutput& item, std::size_t index, const Eigen::Isometry3d& pose) override;

 private:
  OdometryCsvWriter& log_;
};

// The pose at every frame that has one (TUM trajectory format).
class TrajectorySink : public OdometrySink {
 public:
  explicit TrajectorySink(TrajectoryWriter& trajectory) : trajectory_(trajectory) {}
  void frame(const PairOutput& item, const Eigen::Isometry3d& pose) override;
  void pair(const PairOutput& item, std::size_t index, const Eigen::Isometry3d& pose) override;

 private:
  TrajectoryWriter& trajectory_;
};

// Every pair to the flight computer (link/flight_link.hpp decides what a failed one sends).
class FlightLinkSink : public OdometrySink {
 public:
  explicit FlightLinkSink(FlightLink& link) : link_(link) {}
  void pair(const PairOutput& item, std::size_t index, const Eigen::Isometry3d& pose) override;

 private:
  FlightLink& link_;
};

// Every pair against the ground truth, the pose taken back to the trajectory's own origin.
class EvaluationSink : public OdometrySink {
 public:
  EvaluationSink(AccuracyEvaluator& evaluator, const Eigen::Isometry3d& origin)
      : evaluator_(evaluator), origin_inverse_(origin.inverse()) {}
  void pair(const PairOutput& item, std::size_t index, const Eigen::Isometry3d& pose) override;

 private:
  AccuracyEvaluator& evaluator_;
  Eigen::Isometry3d origin_inverse_;
};

// One line per pair on standard output (app/report.hpp's pair_line); verbose adds the latency.
class ConsoleSink : public OdometrySink {
 public:
  ConsoleSink(std::ostream& out, bool verbose) : out_(out), verbose_(verbose) {}
  void pair(const PairOutput& item, std::size_t index, const Eigen::Isometry3d& pose) override;

 private:
  std::ostream& out_;
  bool verbose_;
};

}  // namespace rgbdo
