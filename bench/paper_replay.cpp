// The straightforward reproduction of the paper (paper_reproduction.hpp) as a whole program
// over a TUM sequence, PNG decoding included: the other side of the whole-process comparison
// in bench/MEASUREMENTS.md#speed-on-x86-64 (both pinned to one core with taskset).
//   paper_replay TUM_DIR CONFIG.yaml
#include <cstdio>

#include "paper_reproduction.hpp"
#include "rgbd_odometry/app/config_file.hpp"
#include "rgbd_odometry/io/tum_sequence.hpp"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: paper_replay TUM_DIR CONFIG.yaml\n");
    return 2;
  }
  try {
    const rgbdo::Config config = rgbdo::load_config(argv[2]);
    const rgbdo::TumSequence seq = rgbdo::open_tum_sequence(argv[1]);
    rgbdo::PaperReproduction reproduction(config);
    int ok = 0, frames = 0;
    for (const auto& ref : seq.frames) {
      const rgbdo::RgbdFrame f = rgbdo::load_tum_frame(ref, config.depth.units_per_m, config.camera.width, config.camera.height);
      if (f.status != rgbdo::Status::Ok) continue;
      ++frames;
      Eigen::Isometry3d motion;
      rgbdo::Matrix6d covariance;
      ok += reproduction.process(f, motion, covariance) ? 1 : 0;
    }
    std::printf("%d frames, %d pairs ok\n", frames, ok);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "paper_replay: %s\n", e.what());
    return 1;
  }
  return 0;
}
