#include "rgbd_odometry/sensor/usb_devices.hpp"

#include <libusb.h>

#include <chrono>
#include <cstdio>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace rgbdo {
namespace {

struct KnownSensor {
  std::uint16_t vendor, product;  // product 0: any of the vendor's
  const char* name;
};
constexpr KnownSensor kKnownSensors[] = {
    {0x1d27, 0, "PrimeSense / Asus Xtion"},
    {0x045e, 0x02ae, "Microsoft Kinect v1 (camera)"},
    {0x045e, 0x02bf, "Microsoft Kinect v1 (camera, 1473)"},
    {0x2bc5, 0, "Orbbec"},
};

void speed_of(int speed, UsbDevice& d) {
  switch (speed) {
    case LIBUSB_SPEED_LOW: d.speed_mbps = 1; d.speed_name = "low speed (USB 1.0, 1.5 Mbit/s)"; break;
    case LIBUSB_SPEED_FULL: d.speed_mbps = 12; d.speed_name = "full speed (USB 1.1, 12 Mbit/s)"; break;
    case LIBUSB_SPEED_HIGH: d.speed_mbps = 480; d.speed_name = "high speed (USB 2.0, 480 Mbit/s)"; break;
    case LIBUSB_SPEED_SUPER: d.speed_mbps = 5000; d.speed_name = "super speed (USB 3, 5 Gbit/s)"; break;
#if defined(LIBUSB_API_VERSION) && LIBUSB_API_VERSION >= 0x01000106
    case LIBUSB_SPEED_SUPER_PLUS: d.speed_mbps = 10000; d.speed_name = "super speed+ (USB 3, 10 Gbit/s)"; break;
#endif
    default: d.speed_mbps = 0; d.speed_name = "unknown speed"; break;
  }
}

std::string libusb_problem(const char* what, int rc) {
  return std::string(what) + ": " + libusb_error_name(rc) + " (" + libusb_strerror(static_cast<libusb_error>(rc)) +
         ")";
}

UsbDevice describe(libusb_device* dev) {
  UsbDevice d;
  libusb_device_descriptor desc{};
  if (libusb_get_device_descriptor(dev, &desc) == 0) {
    d.vendor_id = desc.idVendor;
    d.product_id = desc.idProduct;
  }
  d.bus = libusb_get_bus_number(dev);
  d.address = libusb_get_device_address(dev);
  std::uint8_t ports[8];
  const int n = libusb_get_port_numbers(dev, ports, sizeof ports);
  std::ostringstream path;
  path << d.bus;
  for (int i = 0; i < n; ++i) path << (i == 0 ? "-" : ".") << static_cast<int>(ports[i]);
  d.port_path = path.str();
  speed_of(libusb_get_device_speed(dev), d);
  d.known_as = rgbd_sensor_name(d.vendor_id, d.product_id);
  return d;
}

}  // namespace

std::string rgbd_sensor_name(std::uint16_t vendor_id, std::uint16_t product_id) {
  for (const auto& k : kKnownSensors)
    if (k.vendor == vendor_id && (k.product == 0 || k.product == product_id)) return k.name;
  return {};
}

std::vector<UsbDevice> list_usb_devices() {
  libusb_context* ctx = nullptr;
  if (const int rc = libusb_init(&ctx); rc != 0) throw std::runtime_error(libusb_problem("libusb cannot start", rc));
  libusb_device** list = nullptr;
  const ssize_t n = libusb_get_device_list(ctx, &list);
  if (n < 0) {
    libusb_exit(ctx);
    throw std::runtime_error(libusb_problem("libusb cannot list the USB devices", static_cast<int>(n)));
  }
  std::vector<UsbDevice> out;
  for (ssize_t i = 0; i < n; ++i) out.push_back(describe(list[i]));
  libusb_free_device_list(list, 1);
  libusb_exit(ctx);
  return out;
}

UsbBandwidth check_usb_bandwidth(int speed_mbps, int width, int height, int fps) {
  UsbBandwidth b;
  const double pixels_per_s = static_cast<double>(width) * height * fps;
  b.needed_mbps = pixels_per_s * (11.0 + 16.0) / 1e6;  // depth 11-bit packed + colour YUV422
  if (speed_mbps <= 0) {
    b.usable_mbps = 0;
    return b;  // unknown speed: nothing to say
  }
  // USB 2.0: one high-bandwidth isochronous endpoint carries at most 3 x 1024 bytes per 125 us
  // microframe (196.6 Mbit/s), which is what a sensor gets in practice; faster buses: 80 %
  // of the signalling rate for periodic transfers; slower ones: nothing worth trying.
  b.usable_mbps = speed_mbps >= 5000 ? 0.8 * speed_mbps : speed_mbps >= 480 ? 3 * 1024 * 8 * 8000 / 1e6 : 0.0;
  b.sufficient = b.needed_mbps <= b.usable_mbps;
  if (!b.sufficient) {
    std::ostringstream m;
    m.precision(0);
    m << std::fixed << "colour + depth at " << width << "x" << height << "@" << fps << " need about "
      << b.needed_mbps << " Mbit/s of isochronous bandwidth; this " << speed_mbps << " Mbit/s port gives about "
      << b.usable_mbps << ". Expect dropped frames or no stream (a known failure of the Odroid-XU3's USB 2.0 "
      << "ports): use the USB 3.0 port, or a lower rate or resolution.";
    b.message = m.str();
  }
  return b;
}

// --- watching ---------------------------------------------------------------------------

struct UsbWatcher::Impl {
  UsbWatcher& owner;
  libusb_context* ctx = nullptr;
  libusb_hotplug_callback_handle handle = 0;
  std::atomic<bool> stop{false};
  std::thread thread;
  mutable std::mutex mutex;
  std::string problem;

  explicit Impl(UsbWatcher& w) : owner(w) {}

  static int LIBUSB_CALL on_hotplug(libusb_context*, libusb_device* dev, libusb_hotplug_event event, void* self) {
    auto* impl = static_cast<Impl*>(self);
    libusb_device_descriptor desc{};
    if (libusb_get_device_descriptor(dev, &desc) != 0 || rgbd_sensor_name(desc.idVendor, desc.idProduct).empty())
      return 0;
    if (event == LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED) ++impl->owner.arrivals_;
    if (event == LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT) ++impl->owner.departures_;
    return 0;  // stay registered
  }

  // Where the platform has no hot-plug support: compare the sensors present every 500 ms.
  void poll_loop() {
    std::set<std::string> before = sensors_present();
    while (!stop) {
      for (int i = 0; i < 10 && !stop; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
      const std::set<std::string> now = sensors_present();
      for (const auto& s : now)
        if (!before.count(s)) ++owner.arrivals_;
      for (const auto& s : before)
        if (!now.count(s)) ++owner.departures_;
      before = now;
    }
  }
  std::set<std::string> sensors_present() {
    std::set<std::string> out;
    libusb_device** list = nullptr;
    const ssize_t n = libusb_get_device_list(ctx, &list);
    for (ssize_t i = 0; i < n; ++i) {
      const UsbDevice d = describe(list[i]);
      if (!d.known_as.empty()) out.insert(d.port_path + "/" + std::to_string(d.address));
    }
    if (n >= 0) libusb_free_device_list(list, 1);
    return out;
  }
  void event_loop() {
    while (!stop) {
      timeval tv{0, 100'000};  // bounded: the destructor waits at most this long
      libusb_handle_events_timeout_completed(ctx, &tv, nullptr);
    }
  }
};

UsbWatcher::UsbWatcher() : impl_(std::make_unique<Impl>(*this)) {
  auto& s = *impl_;
  if (const int rc = libusb_init(&s.ctx); rc != 0) {
    s.ctx = nullptr;
    s.problem = libusb_problem("USB watching is off: libusb cannot start", rc);
    return;
  }
  if (libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG)) {
    const int rc = libusb_hotplug_register_callback(
        s.ctx,
        static_cast<libusb_hotplug_event>(LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED | LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT),
        LIBUSB_HOTPLUG_NO_FLAGS, LIBUSB_HOTPLUG_MATCH_ANY, LIBUSB_HOTPLUG_MATCH_ANY, LIBUSB_HOTPLUG_MATCH_ANY,
        &Impl::on_hotplug, &s, &s.handle);
    if (rc == 0) {
      hotplug_ = true;
      s.thread = std::thread([&s] { s.event_loop(); });
      return;
    }
  }
  s.thread = std::thread([&s] { s.poll_loop(); });
}

UsbWatcher::~UsbWatcher() {
  auto& s = *impl_;
  s.stop = true;
  if (s.ctx && hotplug_) libusb_hotplug_deregister_callback(s.ctx, s.handle);  // also wakes the event loop
  if (s.thread.joinable()) s.thread.join();
  if (s.ctx) libusb_exit(s.ctx);
}

std::string UsbWatcher::problem() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->problem;
}

}  // namespace rgbdo
