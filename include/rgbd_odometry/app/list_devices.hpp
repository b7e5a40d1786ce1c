#pragma once
// --list-devices: what a user checks first when the sensor does not show up.
#include <iosfwd>

namespace rgbdo {

// Prints the OpenNI2 devices and the RGB-D sensors on USB (port, link speed, and a warning
// when the link cannot carry colour + depth at this size and rate); returns the exit code.
int list_devices(std::ostream& out, int width = 640, int height = 480, int fps = 30);

}  // namespace rgbdo
