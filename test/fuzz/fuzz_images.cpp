// Images of any size, type and content into the pipeline, two ways:
//  - as files the TUM reader decodes (a colour and a depth file of any bytes: PNG, another
//    format OpenCV reads, or garbage), the program's path for recordings;
//  - as decoded images of any size and pixel type handed straight to the pipeline, as a
//    faulty source could.
// Every frame must come out processed or flagged (BadFrame, NoDepth, ...): no crash, no
// exception. Input: byte 0 chooses the way; then either a 4-byte length of the colour file
// followed by both files, or width, height and two type selectors followed by pixel bytes.
#include <cstdint>
#include <cstring>
#include <opencv2/core.hpp>

#include "fuzz_input.hpp"
#include "rgbd_odometry/app/config.hpp"
#include "rgbd_odometry/io/tum_sequence.hpp"
#include "rgbd_odometry/pipeline/odometry.hpp"

namespace {

const rgbdo::Config& config() {
  static const rgbdo::Config c = [] {
    rgbdo::Config c;
    c.features.max_features = 300;  // the same code, fewer features: more inputs per second
    return c;
  }();
  return c;
}

rgbdo::RgbdFrame from_files(std::string_view colour, std::string_view depth, int index) {
  const auto dir = rgbdo::fuzz::scratch_directory();
  rgbdo::fuzz::write_file(dir / "colour.png", colour);
  rgbdo::fuzz::write_file(dir / "depth.png", depth);
  rgbdo::TumFrameRef ref;
  ref.t_colour_ns = 1'000'000'000 + index * 33'000'000LL;
  ref.colour_path = (dir / "colour.png").string();
  ref.t_depth_ns = ref.t_colour_ns;
  ref.depth_path = (dir / "depth.png").string();
  return rgbdo::load_tum_frame(ref, 5000, 640, 480);
}

cv::Mat filled(int rows, int cols, int type, std::string_view bytes) {
  cv::Mat m(rows, cols, type);
  const std::size_t n = m.total() * m.elemSize();
  auto* out = m.ptr<std::uint8_t>();
  for (std::size_t i = 0; i < n; ++i) out[i] = bytes.empty() ? 0 : static_cast<std::uint8_t>(bytes[i % bytes.size()]);
  return m;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace rgbdo;
  if (size < 1) return 0;
  const std::string_view rest = fuzz::text_of(data + 1, size - 1);
  OdometryPipeline pipeline(config());
  if (data[0] % 2 == 0) {
    if (rest.size() < 4) return 0;
    std::uint32_t colour_bytes = 0;
    std::memcpy(&colour_bytes, rest.data(), 4);
    const std::string_view files = rest.substr(4);
    const std::size_t cut = std::min<std::size_t>(colour_bytes, files.size());
    for (int i = 0; i < 2; ++i) (void)pipeline.process(from_files(files.substr(0, cut), files.substr(cut), i));
    return 0;
  }
  if (rest.size() < 6) return 0;
  const auto u8 = [&](std::size_t i) { return static_cast<std::uint8_t>(rest[i]); };
  // Up to 704 x 544 (bigger than the configured 640 x 480), down to 1 x 1.
  const int cols = 1 + (u8(0) | u8(1) << 8) % 704, rows = 1 + (u8(2) | u8(3) << 8) % 544;
  const int types[] = {CV_8UC1, CV_8UC3, CV_16UC1, CV_32FC1, CV_64FC1, CV_32FC3};
  const std::string_view pixels = rest.substr(6);
  for (int i = 0; i < 2; ++i) {
    RgbdFrame f;
    f.t_colour_ns = f.t_depth_ns = 1'000'000'000 + i * 33'000'000LL;
    f.gray = filled(rows, cols, types[u8(4) % 6], pixels);
    f.depth_m = filled(rows, cols, types[u8(5) % 6], pixels.substr(std::min<std::size_t>(pixels.size(), 7)));
    (void)pipeline.process(f);
  }
  return 0;
}
