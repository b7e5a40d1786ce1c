#include <gtest/gtest.h>

#include <iterator>

#include <filesystem>
#include <fstream>

#include "rgbd_odometry/app/config.hpp"
#include "rgbd_odometry/app/config_file.hpp"

namespace rgbdo {
namespace {

namespace fs = std::filesystem;

class ConfigFile : public ::testing::Test {
 protected:
  fs::path dir = fs::temp_directory_path() / ("rgbdo_config_" + std::to_string(::getpid()));
  void SetUp() override { fs::create_directories(dir); }
  void TearDown() override { fs::remove_all(dir); }
  std::string write(const std::string& name, const std::string& text) {
    const fs::path p = dir / name;
    std::ofstream(p) << text;
    return p.string();
  }
};

// The message must name the key, so a user can find the line.
void expect_error_naming(const std::function<void()>& f, const std::string& needle) {
  try {
    f();
    FAIL() << "expected ConfigError mentioning " << needle;
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(Config, DefaultsAreThePapersTable1) {
  const Config c;
  EXPECT_EQ(c.features.detector, "GRID_ORB");
  EXPECT_EQ(c.features.descriptor, "GRID_ORB");
  EXPECT_DOUBLE_EQ(c.matching.ratio, 0.8);
  EXPECT_DOUBLE_EQ(c.ransac.inlier_threshold_m, 0.05);
  EXPECT_EQ(c.ransac.max_iterations, 200);
  EXPECT_EQ(c.covariance.perturbations, 100);
  EXPECT_DOUBLE_EQ(c.covariance.depth_noise_coeff, 1.425e-3);
  // No factor fitted to a recording: the noise model as it stands
  // (src/pipeline/README.md#noise-model-and-covariance).
  EXPECT_EQ(c.covariance.model, "physical");
  EXPECT_DOUBLE_EQ(c.covariance.scale, 1.0);
  EXPECT_NO_THROW(validate(c));
}

TEST(Config, ShippedFr1ConfigLoadsWithTumCalibration) {
  const Config c = load_config(RGBDO_CONFIG_DIR "/tum-fr1.yaml");
  EXPECT_DOUBLE_EQ(c.camera.fx, 517.306408);
  EXPECT_DOUBLE_EQ(c.camera.cy, 255.313989);
  EXPECT_DOUBLE_EQ(c.camera.distortion[0], 0.262383);
  EXPECT_DOUBLE_EQ(c.camera.distortion[4], 1.163314);
  EXPECT_DOUBLE_EQ(c.depth.units_per_m, 5000);
  EXPECT_DOUBLE_EQ(c.covariance.scale, 1.0);
  EXPECT_EQ(c.covariance.model, "physical");
  EXPECT_NO_THROW(validate(c));
}

TEST_F(ConfigFile, UnknownKeyIsRejectedByName) {
  const auto p = write("a.yaml", "%YAML:1.0\n---\nransac:\n  max_iteration: 5\n");
  expect_error_naming([&] { load_config(p); }, "ransac.max_iteration");
}

TEST_F(ConfigFile, OutOfRangeAndWrongTypeAreRejectedByName) {
  expect_error_naming([&] { load_config(write("b.yaml", "%YAML:1.0\n---\nmatching:\n  ratio: 1.5\n")); },
                      "matching.ratio");
  expect_error_naming([&] { load_config(write("c.yaml", "%YAML:1.0\n---\nfeatures:\n  max_features: many\n")); },
                      "features.max_features");
  expect_error_naming([&] { load_config(write("d.yaml", "%YAML:1.0\n---\nransac:\n  max_iterations: 2.5\n")); },
                      "ransac.max_iterations");
  expect_error_naming([&] { load_config(write("e.yaml", "%YAML:1.0\n---\ncamera:\n  distortion: [1, 2]\n")); },
                      "camera.distortion");
}

TEST_F(ConfigFile, TrailingCommentsAfterStringsAndBooleansAreIgnored) {
  const Config c = load_config(write("comments.yaml",
                                     "%YAML:1.0\n---\nfeatures:\n  detector: AKAZE   # the detector\n"
                                     "  descriptor: AKAZE # and its descriptor\nransac:\n  adaptive_stop: false  # 99.9 %\n"));
  EXPECT_EQ(c.features.detector, "AKAZE");
  EXPECT_EQ(c.features.descriptor, "AKAZE");
  EXPECT_FALSE(c.ransac.adaptive_stop);
}

TEST_F(ConfigFile, MissingAndCorruptFilesAreNamed) {
  expect_error_naming([&] { load_config((dir / "none.yaml").string()); }, "none.yaml");
  expect_error_naming([&] { load_config(write("bad.yaml", "%YAML:1.0\n---\ncamera: [1, {\n")); }, "bad.yaml");
}

TEST_F(ConfigFile, WhatOpenCvsReaderCannotTakeIsRefusedByLine) {
  // Each of these once hung OpenCV's YAML reader for ever or escaped it as an exception other
  // than a ConfigError (found by test/fuzz/fuzz_config_file; the inputs are kept there too).
  expect_error_naming([&] { load_config(write("i.yaml", "%YAML:1.0\n---\n  width: 640\n----\n")); }, "line 3");
  expect_error_naming([&] { load_config(write("d.yaml", "%YAML:1.0\n-----\ncamera:\n  fx: 500\n")); }, "line 2");
  expect_error_naming([&] { load_config(write("t.yaml", "%YAML:1.0\n---\ncamera:\n  fx: 500\n---\nseed: 2\n")); },
                      "line 5");
  expect_error_naming([&] { load_config(write("s.yaml", "%YAML:1.0\n---\ncamera: 5\n")); }, "s.yaml");
  // A second directive line, taken for the first entry, let an indented one through.
  expect_error_naming([&] { load_config(write("p.yaml", "%YAML:1.\n%\n x:3\nran-\n")); }, "p.yaml' line 3");
  expect_error_naming([&] { load_config(write("q.yaml", "%YAML:1.0\n---\nseed: 2\n%\n")); }, "q.yaml' line 4");
}

TEST_F(ConfigFile, ACalibrationFileOpenCvsReaderCannotTakeIsRefusedByLine) {
  // Text after the document marker, then a line OpenCV's reader takes for the next marker: it
  // looped for ever on this calibration file (found by test/fuzz/fuzz_config_file, kept there).
  write("loop.yaml", "%YAML:1.0\n---s: l\n1, -\n");
  const auto p = write("uses_loop.yaml", "%YAML:1.0\n---\ncamera:\n  calibration_file: loop.yaml\n");
  expect_error_naming([&] { load_config(p); }, "camera.calibration_file");
  expect_error_naming([&] { load_config(p); }, "loop.yaml' line 2");
  write("indented.yaml", "%YAML:1.0\n---\n  camera_matrix: 1\n");
  expect_error_naming([&] { load_config(write("uses_indented.yaml", "%YAML:1.0\n---\ncamera:\n  calibration_file: indented.yaml\n")); },
                      "indented.yaml' line 3");
}

TEST_F(ConfigFile, ACalibrationMatrixDeclaringAHugeSizeIsRefusedBeforeItIsRead) {
  write("huge.yaml", "%YAML:1.0\n---\ncamera_matrix: !!opencv-matrix\n  rows: 1000000000\n  cols: 3\n  dt: d\n"
                     "  data: [1., 0., 0.]\n");
  const auto p = write("m.yaml", "%YAML:1.0\n---\ncamera:\n  calibration_file: huge.yaml\n");
  expect_error_naming([&] { load_config(p); }, "1000000000 x 3");
}

TEST_F(ConfigFile, IntrinsicsFromAnOpenCvCalibrationFile) {
  write("calib.yaml",
        "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\ncamera_matrix: !!opencv-matrix\n  rows: 3\n  cols: 3\n"
        "  dt: d\n  data: [600., 0., 320., 0., 601., 240., 0., 0., 1.]\ndistortion_coefficients: !!opencv-matrix\n"
        "  rows: 1\n  cols: 5\n  dt: d\n  data: [0.1, -0.2, 0.001, 0.002, 0.3]\n");
  const auto p = write("main.yaml", "%YAML:1.0\n---\ncamera:\n  calibration_file: calib.yaml\n  cy: 241.0\n");
  const Config c = load_config(p);
  EXPECT_DOUBLE_EQ(c.camera.fx, 600);
  EXPECT_DOUBLE_EQ(c.camera.fy, 601);
  EXPECT_DOUBLE_EQ(c.camera.cy, 241.0);  // the file's own key wins over the calibration
  EXPECT_DOUBLE_EQ(c.camera.distortion[4], 0.3);
}

// The EKF origin as ArduPilot users write it: a list in the file, a text on the command line;
// every digit kept (1e-7 degree is 1 cm), nonsense refused by name.
TEST_F(ConfigFile, EkfOriginFromAListOrATextAndRefusedWhenWrong) {
  const Config c = load_config(
      write("o.yaml", "%YAML:1.0\n---\nlink:\n  ekf_origin: [47.397742, 8.545594, 488.0]\n"));
  const auto origin = parse_ekf_origin(c.link.ekf_origin);
  ASSERT_TRUE(origin);
  EXPECT_DOUBLE_EQ(origin->latitude_deg, 47.397742);
  EXPECT_DOUBLE_EQ(origin->longitude_deg, 8.545594);
  EXPECT_DOUBLE_EQ(origin->altitude_m, 488.0);
  Config d;
  apply_overrides(d, {"link.ekf_origin=-33.8568, 151.2153, 3"});
  EXPECT_DOUBLE_EQ(parse_ekf_origin(d.link.ekf_origin)->latitude_deg, -33.8568);
  EXPECT_FALSE(parse_ekf_origin(Config{}.link.ekf_origin)) << "none by default";
  for (const char* bad : {"47.3, 8.5", "91, 8.5, 400", "47, 181, 400", "47, 8, x", "47, 8, 20000"}) {
    Config e;
    apply_overrides(e, {std::string("link.ekf_origin=") + bad});
    expect_error_naming([&] { validate(e); }, "link.ekf_origin");
  }
  expect_error_naming(
      [&] { load_config(write("p.yaml", "%YAML:1.0\n---\nlink:\n  ekf_origin: [47.3, north, 488]\n")); },
      "link.ekf_origin");
}

// ODOMETRY and VISION_POSITION_DELTA together would have ArduPilot's EKF3 fuse each motion twice.
TEST(ConfigValidation, BothMessageSetsAtOnceAreRefused) {
  Config c;
  apply_overrides(c, {"link.vision_position_delta=true"});
  expect_error_naming([&] { validate(c); }, "link.vision_position_delta");
  apply_overrides(c, {"link.odometry=false"});
  EXPECT_NO_THROW(validate(c));
}

// --print-config: every key, read back by load_config to the very same configuration.
TEST_F(ConfigFile, ThePrintedConfigurationReadsBackToTheSameValues) {
  Config c = load_config(RGBDO_CONFIG_DIR "/xtion.yaml");
  apply_overrides(c, {"link.ekf_origin=47.397742, 8.545594, 488", "covariance.timing_sigma_s=0.0015",
                      "link.uri=udpin://:14540", "ransac.adaptive_stop=false", "seed=2147483647"});
  const std::string printed = config_yaml(c);
  const Config back = load_config(write("printed.yaml", printed));
  const auto a = describe_config(c), b = describe_config(back);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_GE(a.size(), 60u);
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i].value, b[i].value) << a[i].key;
  EXPECT_EQ(config_yaml(back), printed);
  for (const ConfigKeyInfo& k : a) EXPECT_FALSE(k.help.empty()) << k.key << " has no help line";
}

// deploy/config/README.md is the table in the code, word for word: it cannot drift.
TEST(ConfigReference, TheShippedReferenceIsTheTableInTheCode) {
  std::ifstream in(RGBDO_CONFIG_DIR "/README.md");
  const std::string shipped((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(shipped, config_reference_markdown())
      << "regenerate it: rgbd-odometry --print-config-reference > deploy/config/README.md";
  for (const std::string& key : config_keys())
    EXPECT_NE(shipped.find("| `" + key + "` |"), std::string::npos) << key << " is not in deploy/config/README.md";
}

TEST(ConfigOverrides, CommandLineValuesWinAndAreChecked) {
  Config c;
  apply_overrides(c, {"ransac.max_iterations=300", "features.detector=AKAZE", "depth.compensate_timing=false", "seed=9"});
  EXPECT_EQ(c.ransac.max_iterations, 300);
  EXPECT_EQ(c.features.detector, "AKAZE");
  EXPECT_FALSE(c.depth.compensate_timing);
  EXPECT_EQ(c.seed, 9u);
  expect_error_naming([&] { apply_overrides(c, {"ransac.max_iterations"}); }, "KEY=VALUE");
  expect_error_naming([&] { apply_overrides(c, {"nope.key=1"}); }, "nope.key");
  expect_error_naming([&] { apply_overrides(c, {"covariance.perturbations=2"}); }, "covariance.perturbations");
}

TEST(ConfigValidation, CrossFieldChecksNameTheKey) {
  Config c;
  c.depth.min_m = 5;
  expect_error_naming([&] { validate(c); }, "depth.min_m");
  c = Config{};
  c.features.detector = "SURF";
  expect_error_naming([&] { validate(c); }, "features.detector");
  c = Config{};
  c.features.detector = "ORB";
  c.features.descriptor = "AKAZE";
  expect_error_naming([&] { validate(c); }, "features.descriptor");
  c = Config{};
  c.features.border_px = 400;
  expect_error_naming([&] { validate(c); }, "features.border_px");
  c = Config{};
  c.covariance.model = "gaussian";
  expect_error_naming([&] { validate(c); }, "covariance.model");
  c = Config{};
  c.covariance.timing_sigma_s = 5;  // seconds: a unit mistake
  expect_error_naming([&] { validate(c); }, "covariance.timing_sigma_s");
  c = Config{};
  c.covariance.resample_cell_px = -1;
  expect_error_naming([&] { validate(c); }, "covariance.resample_cell_px");
  c = Config{};
  c.covariance.depth_latency_sigma_s = 25;  // milliseconds given for seconds
  expect_error_naming([&] { validate(c); }, "covariance.depth_latency_sigma_s");
  c = Config{};
  c.covariance.colour_latency_sigma_s = -0.01;
  expect_error_naming([&] { validate(c); }, "covariance.colour_latency_sigma_s");
}

TEST(ConfigValidation, KeysWhereZeroIsSingularRefuseZero) {
  // pixel_sigma_px = 0 made the final fit's point covariances singular (4.91 -> 9.27 mm RPE
  // on the bundled frames); a zero velocity-error floor tells the autopilot a velocity is
  // exact. Refused from the command line, a file and a built Config alike; any positive value
  // is taken.
  for (const std::string key : {"covariance.pixel_sigma_px", "link.velocity_error_min_mps"}) {
    Config c;
    expect_error_naming([&] { apply_overrides(c, {key + "=0"}); }, key);
    expect_error_naming([&] { apply_overrides(c, {key + "=-0.1"}); }, key);
    EXPECT_NO_THROW(apply_overrides(c, {key + "=1e-9"})) << key;
  }
  Config c;
  c.covariance.pixel_sigma_px = 0;
  expect_error_naming([&] { validate(c); }, "covariance.pixel_sigma_px");
}

TEST_F(ConfigFile, AZeroWhereZeroIsSingularIsRefusedByName) {
  expect_error_naming([&] { load_config(write("z.yaml", "%YAML:1.0\n---\ncovariance:\n  pixel_sigma_px: 0\n")); },
                      "covariance.pixel_sigma_px");
}

}  // namespace
}  // namespace rgbdo
