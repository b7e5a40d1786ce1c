#pragma once
// The re-open policy around an OpenNI2 feed: after a loss it tries to open the device again
// every sensor.reconnect_interval_ms until sensor.reconnect_timeout_s has passed (negative: for
// ever, as on the vehicle; 0: not at all) or the run stops, sooner when USB hot-plug tells that
// a sensor arrived. Its news: a sensor leaving the bus, or libusb unusable (said once).
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "rgbd_odometry/sensor/sensor_config.hpp"
#include "rgbd_odometry/io/frame_feed.hpp"
#include "rgbd_odometry/sensor/openni_feed.hpp"
#include "rgbd_odometry/sensor/usb_devices.hpp"

namespace rgbdo {

class ReconnectingFeed : public FrameFeed {
 public:
  // A live feed also watches USB (a recording has no bus to watch).
  ReconnectingFeed(std::unique_ptr<OpenNiFeed> inner, const SensorConfig& config);
  FeedState next(RgbdFrame& frame, std::string& problem) override { return inner_->next(frame, problem); }
  bool live() const override { return inner_->live(); }
  bool wait_for_return(const std::atomic<bool>& stopping, std::string& problem) override;
  std::string news() override;
  void interrupt() override { inner_->interrupt(); }
  std::string description() const override { return inner_->description(); }
  int dropped_frames() const override { return inner_->dropped_frames(); }
  int frames_without_depth() const override { return inner_->frames_without_depth(); }

 private:
  std::unique_ptr<OpenNiFeed> inner_;
  double timeout_s_;
  int interval_ms_;
  std::unique_ptr<UsbWatcher> usb_;
  std::uint64_t usb_departures_ = 0;  // as last told
  bool usb_problem_told_ = false;
};

}  // namespace rgbdo
