#include "rgbd_odometry/sensor/frame_feed.hpp"

#include <algorithm>
#include <sstream>

namespace rgbdo {

TumFeed::TumFeed(TumSequence sequence, const Config& config, int max_frames)
    : seq_(std::move(sequence)), config_(config),
      end_(max_frames > 0 ? std::min(seq_.frames.size(), static_cast<size_t>(max_frames)) : seq_.frames.size()) {}

FeedState TumFeed::next(RgbdFrame& frame, std::string& problem) {
  if (interrupted_) {
    problem = "interrupted";
    return FeedState::End;
  }
  if (i_ >= end_) return FeedState::End;
  frame = load_tum_frame(seq_.frames[i_++], config_.depth.units_per_m, config_.camera.width, config_.camera.height);
  return FeedState::Frame;
}

std::string TumFeed::description() const {
  return "TUM RGB-D sequence " + seq_.directory + " (" + std::to_string(end_) + " frames)";
}

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
  if (source->next(frame, problem)) {
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
  replaced_before_ += source_->replaced_colour_frames();
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

int OpenNiFeed::replaced_frames() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return replaced_before_ + (source_ ? source_->replaced_colour_frames() : 0);
}

std::unique_ptr<FrameFeed> open_frame_feed(const std::string& source, const Config& config, int max_frames) {
  const std::string tum_scheme = "tum:", openni_scheme = "openni://", oni_scheme = "oni:";
  if (source.rfind(tum_scheme, 0) == 0)
    return std::make_unique<TumFeed>(open_tum_sequence(source.substr(tum_scheme.size())), config, max_frames);
  const bool file = source.rfind(oni_scheme, 0) == 0;
  if (!file && source.rfind(openni_scheme, 0) != 0)
    throw SourceSpecError("unsupported source '" + source +
                          "': expected tum:DIR (a TUM RGB-D sequence directory), openni://[DEVICE-URI] or oni:FILE.oni");
  OpenNiOptions o;
  o.uri = source.substr(file ? oni_scheme.size() : openni_scheme.size());
  if (file && (o.uri.size() < 5 || o.uri.compare(o.uri.size() - 4, 4, ".oni") != 0))
    throw SourceSpecError("oni:FILE needs a file ending in .oni, got '" + o.uri + "'");
  o.width = config.camera.width;
  o.height = config.camera.height;
  o.fps = config.sensor.fps;
  o.registration = config.sensor.registration;
  o.frame_timeout_ms = config.sensor.frame_timeout_ms;
  o.pairing_wait_ms = config.sensor.pairing_wait_ms;
  o.record_path = config.sensor.record_oni;
  return std::make_unique<OpenNiFeed>(o, max_frames);
}

}  // namespace rgbdo
