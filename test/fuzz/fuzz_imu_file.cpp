// A replay's gyro file (imu.txt, io/imu_file.hpp): ImuFile reads it or throws a SourceError
// naming the file and line; whatever it reads then goes through the capture-latency estimate
// (pipeline/capture_latency.hpp) with pairs stamped among its samples, which must answer or
// say it does not know, never crash or read outside its rings.
#include <array>
#include <cstdint>

#include "fuzz_input.hpp"
#include "rgbd_odometry/io/imu_file.hpp"
#include "rgbd_odometry/io/tum_sequence.hpp"
#include "rgbd_odometry/pipeline/capture_latency.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace rgbdo;
  const auto dir = fuzz::scratch_directory();
  fuzz::write_file(dir / "imu.txt", fuzz::text_of(data, size));
  try {
    ImuFile file((dir / "imu.txt").string());
    CaptureLatencyEstimator estimator(LatencyConfig{}, Eigen::Matrix3d::Identity());
    std::array<GyroSample, 64> taken;
    const auto& samples = file.samples();
    for (std::size_t i = 0; i + 1 < samples.size() && i < 200; ++i) {
      const std::size_t n = file.take(samples[i + 1].t_ns, taken);
      estimator.add_gyro(std::span<const GyroSample>(taken.data(), n));
      // A pair over the two samples, its rotation their rates' integral (an agreeing camera).
      const double dt = static_cast<double>(samples[i + 1].t_ns - samples[i].t_ns) * 1e-9;
      estimator.add_pair(samples[i].t_ns, samples[i + 1].t_ns, samples[i].rate * dt);
    }
    (void)estimator.estimate();
    (void)estimator.mount();
  } catch (const SourceError&) {
  }
  return 0;
}
