#include "rgbd_odometry/sensor/openni_feed.hpp"

#include <sstream>

#include "rgbd_odometry/io/tum_sequence.hpp"  // SourceError

namespace rgbdo {

namespace {
bool is_oni_file(const std::string& uri) {
  return uri.size() > 4 && uri.compare(uri.size() - 4, 4, ".oni") == 0;
}

// Each re-open records to a file of its own: capture.oni, capture.2.oni, ...
std::string recording_path(const std::string& path, int open_count) {
  if (path.empty() || open_count == 1) return path;
  const auto dot = path.rfind('.');
  std::ostringstream numbered;  // (GCC 12 warns falsely on the string-concatenation version)
  numbered << path.substr(0, dot) << '.' << open_count << (dot == std::string::npos ? "" : path.substr(dot));
  return numbered.str();
}
}  // namespace

OpenNiFeed::OpenNiFeed(const OpenNiOptions& options, int max_frames)
    : options_(options), max_frames_(max_frames), playback_(is_oni_file(options.uri)),
      source_(std::make_unique<OpenNiSource>(options)) {}

FeedState OpenNiFeed::next(RgbdFrame& frame, std::string& problem) {
  if (max_frames_ > 0 && delivered_ >= max_frames_) return FeedState::End;
  OpenNiSource* source = nullptr;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    source = source_.get();
  }
  if (interrupted_ || !source) {
    problem = interrupted_ ? "interrupted" : "the sensor is not open";
    return interrupted_ ? FeedState::End : FeedState::Lost;
  }
  bool delivered = false;
  try {
    delivered = source->next(frame, problem);
  } catch (const SourceError& e) {  // the streams would not start: lost like a sensor that stops
    problem = e.what();
  }
  if (delivered) {
    ++delivered_;
    return FeedState::Frame;
  }
  if (interrupted_) return FeedState::End;
  // A recording that stops delivering has ended; a sensor that does has been lost.
  if (playback_) {
    problem = "end of the recording (" + problem + ")";
    return FeedState::End;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  dropped_before_ += source_->dropped_colour_frames();
  without_depth_before_ += source_->colour_frames_without_depth();
  source_.reset();  // release the device: a replugged sensor must be opened afresh
  return FeedState::Lost;
}

bool OpenNiFeed::reopen(std::string& problem) {
  if (interrupted_) return false;
  OpenNiOptions o = options_;
  o.record_path = recording_path(options_.record_path, opens_ + 1);
  try {
    auto source = std::make_unique<OpenNiSource>(o);
    std::lock_guard<std::mutex> lock(mutex_);
    source_ = std::move(source);
    ++opens_;
    if (interrupted_) source_->interrupt();
    return true;
  } catch (const SourceError& e) {
    problem = e.what();
    return false;
  }
}

void OpenNiFeed::interrupt() {
  interrupted_ = true;
  std::lock_guard<std::mutex> lock(mutex_);
  if (source_) source_->interrupt();
}

std::string OpenNiFeed::description() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return source_ ? source_->description() : "OpenNI2 device " + options_.uri + " (not open)";
}

int OpenNiFeed::dropped_frames() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return dropped_before_ + (source_ ? source_->dropped_colour_frames() : 0);
}

int OpenNiFeed::frames_without_depth() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return without_depth_before_ + (source_ ? source_->colour_frames_without_depth() : 0);
}

}  // namespace rgbdo
