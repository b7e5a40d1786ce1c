#pragma once
// The sensor as USB sees it, through libusb: where it is plugged in (bus, port path), at
// what link speed, whether that link can carry the chosen streams, and when it leaves or
// comes back (hot-plug events, or polling where the platform has none).
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace rgbdo {

struct UsbDevice {
  std::uint16_t vendor_id = 0, product_id = 0;
  int bus = 0, address = 0;
  std::string port_path;    // "1-2.3": bus, then the hub ports from the root
  int speed_mbps = 0;       // the negotiated link speed; 0 when libusb cannot tell
  std::string speed_name;   // "high speed (USB 2.0, 480 Mbit/s)"
  std::string known_as;     // "PrimeSense / Asus Xtion", ... empty for other devices
};

// Every USB device present. Throws std::runtime_error naming the problem when libusb cannot
// be used at all (no USB on this machine, no permission for /dev/bus/usb).
std::vector<UsbDevice> list_usb_devices();

// Whether the device is a known RGB-D sensor (PrimeSense/Asus, Microsoft Kinect v1, Orbbec).
std::string rgbd_sensor_name(std::uint16_t vendor_id, std::uint16_t product_id);

// Can a link of this speed carry colour + depth at this size and rate? The sensor sends depth
// as 11-bit packed values and colour as YUV422 (2 bytes a pixel) in isochronous transfers; a
// USB 2.0 high-speed bus gives periodic transfers at most 80 % of 480 Mbit/s, and in practice
// (the Odroid-XU3 shares its USB 2.0 ports behind one hub) far less: above 60 % it is refused.
struct UsbBandwidth {
  double needed_mbps = 0, usable_mbps = 0;
  bool sufficient = true;
  std::string message;  // non-empty when not sufficient, saying what to do
};
UsbBandwidth check_usb_bandwidth(int speed_mbps, int width, int height, int fps);

// Watches for RGB-D sensors arriving and leaving. Never throws: when libusb is unusable it
// reports that once through `problem()` and watches nothing.
class UsbWatcher {
 public:
  UsbWatcher();
  ~UsbWatcher();
  UsbWatcher(const UsbWatcher&) = delete;
  UsbWatcher& operator=(const UsbWatcher&) = delete;

  std::uint64_t arrivals() const { return arrivals_; }
  std::uint64_t departures() const { return departures_; }
  bool hotplug() const { return hotplug_; }  // false: polling (or nothing, see problem())
  std::string problem() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::atomic<std::uint64_t> arrivals_{0}, departures_{0};
  std::atomic<bool> hotplug_{false};
  friend struct Impl;
};

}  // namespace rgbdo
