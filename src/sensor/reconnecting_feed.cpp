#include "rgbd_odometry/sensor/reconnecting_feed.hpp"

#include <chrono>
#include <thread>

namespace rgbdo {

ReconnectingFeed::ReconnectingFeed(std::unique_ptr<OpenNiFeed> inner, const SensorConfig& config)
    : inner_(std::move(inner)), timeout_s_(config.reconnect_timeout_s), interval_ms_(config.reconnect_interval_ms) {
  // USB hot-plug tells when a sensor comes back sooner than the next re-open attempt would.
  if (inner_->live()) usb_ = std::make_unique<UsbWatcher>();
}

bool ReconnectingFeed::wait_for_return(const std::atomic<bool>& stopping, std::string& problem) {
  using Clock = std::chrono::steady_clock;
  if (timeout_s_ == 0) return false;
  const auto deadline =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(
                         timeout_s_ < 0 ? 1e9 : timeout_s_));
  std::string why;
  while (!stopping && Clock::now() < deadline) {
    if (inner_->reopen(why)) return true;
    const auto until = Clock::now() + std::chrono::milliseconds(interval_ms_);
    const std::uint64_t arrivals = usb_ ? usb_->arrivals() : 0;
    // Looks every 10 ms: a stop request is answered within that.
    while (!stopping && Clock::now() < until && (!usb_ || usb_->arrivals() == arrivals))
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  if (!stopping) problem = "sensor did not come back within " + std::to_string(timeout_s_) + " s: " + why;
  return false;
}

std::string ReconnectingFeed::news() {
  if (!usb_) return {};
  if (!usb_problem_told_) {
    usb_problem_told_ = true;
    if (std::string problem = usb_->problem(); !problem.empty()) return problem;
  }
  if (usb_->departures() != usb_departures_) {
    usb_departures_ = usb_->departures();
    return "USB: an RGB-D sensor left the bus";
  }
  return {};
}

}  // namespace rgbdo
