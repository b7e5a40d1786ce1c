#include "rgbd_odometry/app/list_devices.hpp"

#include <cstdio>
#include <ostream>
#include <string>
#include <vector>

#include "rgbd_odometry/io/tum_sequence.hpp"  // SourceError
#include "rgbd_odometry/sensor/sensor_openni.hpp"
#include "rgbd_odometry/sensor/usb_devices.hpp"

namespace rgbdo {

int list_devices(std::ostream& out, int width, int height, int fps) {
  // OpenNI2's view: the devices it can open (the real runtime, with every installed driver).
  std::vector<DeviceDescription> devices;
  int rc = 0;
  try {
    devices = list_openni_devices();
  } catch (const SourceError& e) {
    out << "cannot list OpenNI2 devices: " << e.what() << "\n";
    rc = 1;
  }
  // USB's view: where each sensor is plugged in and how fast (a sensor OpenNI2 does not
  // list, driver missing or no permission, still shows here).
  std::vector<UsbDevice> usb;
  std::string usb_problem;
  try {
    usb = list_usb_devices();
  } catch (const std::exception& e) {
    usb_problem = e.what();
  }
  std::vector<const UsbDevice*> sensors;
  for (const auto& u : usb)
    if (!u.known_as.empty()) sensors.push_back(&u);

  if (devices.empty()) out << "no OpenNI2 device found (is the sensor plugged in, and is its USB port powered?)\n";
  for (const auto& d : devices) {
    char ids[32];
    std::snprintf(ids, sizeof ids, "%04x:%04x", d.usb_vendor_id, d.usb_product_id);
    out << "OpenNI2: " << d.uri << "  " << d.vendor << " " << d.name << "  usb " << ids << "\n";
  }
  if (!usb_problem.empty()) {
    out << "USB: cannot look at the USB devices: " << usb_problem << "\n";
  } else if (sensors.empty()) {
    out << "USB: no RGB-D sensor on USB (" << usb.size() << " other USB devices)\n";
  }
  for (const UsbDevice* u : sensors) {
    char ids[32];
    std::snprintf(ids, sizeof ids, "%04x:%04x", u->vendor_id, u->product_id);
    out << "USB: " << u->known_as << "  " << ids << "  bus " << u->bus << " port " << u->port_path << " address "
        << u->address << "  " << u->speed_name << "\n";
    const UsbBandwidth b = check_usb_bandwidth(u->speed_mbps, width, height, fps);
    if (!b.sufficient) out << "  WARNING: " << b.message << "\n";
  }
  return rc;
}

}  // namespace rgbdo
