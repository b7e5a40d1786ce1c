#pragma once
// Live RGB-D frames from an OpenNI2 device: a PrimeSense-class sensor (Asus Xtion, Kinect v1)
// or the project's virtual sensor (src/virtual_sensor), read through the same code.
//
// Colour and depth arrive as separate streams. Each colour frame is paired with the depth
// frame nearest in device time (at most 20 ms apart, as the TUM association), device time is
// mapped onto the host's monotonic clock (DeviceClock: anchored at the first frame, biased by
// its transport delay, following the crystal's drift), and gaps in the colour frame indices
// count as dropped frames.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "rgbd_odometry/pipeline/frame.hpp"

namespace rgbdo {

struct OpenNiOptions {
  std::string uri;  // empty: the first device found; a path ending in .oni: play that recording
  int width = 640, height = 480, fps = 30;
  bool registration = true;  // hardware depth-to-colour registration (the paper's set-up)
  int frame_timeout_ms = 2000;  // no frame for this long: the device is reported lost
  // How long a colour frame waits for a depth frame at or after its time (at 30 Hz the
  // nearest depth can follow by up to one frame, 33 ms, plus transport).
  int pairing_wait_ms = 70;
  std::string record_path;  // non-empty: record both streams there (openni::Recorder, lossless)
};

struct DeviceDescription {
  std::string uri, vendor, name;
  std::uint16_t usb_vendor_id = 0, usb_product_id = 0;
};

// The OpenNI2 devices present now (initialises OpenNI2 if needed).
std::vector<DeviceDescription> list_openni_devices();

class OpenNiSource {
 public:
  // Opens the device and sets its streams up; throws SourceError naming the device and the
  // problem. The streams start at the first next().
  explicit OpenNiSource(const OpenNiOptions& options);
  ~OpenNiSource();
  OpenNiSource(const OpenNiSource&) = delete;
  OpenNiSource& operator=(const OpenNiSource&) = delete;

  // The next colour frame with its depth. False when the device stopped delivering (no frame
  // within the timeout, or disconnected); `problem` then says which. The first call starts the
  // streams, and throws SourceError if they cannot start.
  bool next(RgbdFrame& out, std::string& problem);

  // Makes a next() in progress (or the next one) return false promptly; thread-safe.
  void interrupt();

  int dropped_colour_frames() const;   // indices the sensor skipped (thread-safe)
  int colour_frames_without_depth() const;  // given up: no depth within 20 ms before newer ones came (thread-safe)
  std::string description() const;  // device name, URI and the modes in use

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rgbdo
