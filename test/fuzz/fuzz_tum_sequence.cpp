// A TUM RGB-D directory's index files (rgb.txt, depth.txt, groundtruth.txt, separated by 0x00
// in the input): open_tum_sequence gives a sequence or a SourceError naming the file; each
// frame then loads as an image pair or a frame flagged bad (the images named do not exist or
// are the fuzzer's bytes); the ground truth interpolates or says there is none.
#include <cstdint>

#include "fuzz_input.hpp"
#include "rgbd_odometry/io/tum_sequence.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace rgbdo;
  const auto parts = fuzz::parts_of(fuzz::text_of(data, size), 4);
  const auto dir = fuzz::scratch_directory();
  const char* names[3] = {"rgb.txt", "depth.txt", "groundtruth.txt"};
  for (std::size_t i = 0; i < 3 && i < parts.size(); ++i) fuzz::write_file(dir / names[i], parts[i]);
  // A fourth part, when present, is what every image path in the index points to.
  if (parts.size() > 3) {
    std::filesystem::create_directories(dir / "rgb");
    fuzz::write_file(dir / "rgb" / "1.png", parts[3]);
  }
  try {
    const TumSequence seq = open_tum_sequence(dir.string());
    int loaded = 0;
    for (const TumFrameRef& ref : seq.frames) {
      if (++loaded > 4) break;
      const RgbdFrame f = load_tum_frame(ref, 5000, 640, 480);
      (void)f;
      (void)seq.groundtruth.at(ref.t_colour_ns);
    }
  } catch (const SourceError&) {
  }
  return 0;
}
