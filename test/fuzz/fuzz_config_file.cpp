// The YAML configuration file (--config) and the OpenCV calibration file it may name: any
// bytes give a Config or a ConfigError naming the problem; nothing else may escape.
// Input: the configuration file, optionally followed by 0x00 and a calibration file (which a
// configuration reaches as camera.calibration_file: calibration.yaml).
#include <cstdint>

#include "fuzz_input.hpp"
#include "rgbd_odometry/app/config.hpp"
#include "rgbd_odometry/app/config_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace rgbdo;
  const auto parts = fuzz::parts_of(fuzz::text_of(data, size), 2);
  const auto dir = fuzz::scratch_directory();
  fuzz::write_file(dir / "config.yaml", parts[0]);
  if (parts.size() > 1) fuzz::write_file(dir / "calibration.yaml", parts[1]);
  try {
    const Config c = load_config((dir / "config.yaml").string());
    validate(c);
  } catch (const ConfigError&) {
  }
  return 0;
}
