// What the program sends to the flight computer, decoded by a MAVLink implementation nobody
// here wrote (node-mavlink, test/mavlink_check): over a real UDP socket and over a real
// pseudo-terminal, every frame must pass its CRC and ids, and every field must match the
// odometry log of the same run, recomputed by the checker's own maths. A link whose peer is
// not there must not cost the log a single row.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/core.hpp>
#include <algorithm>
#include <pty.h>
#include <sys/wait.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "node_checker.hpp"
#include "rgbd_odometry/app/run.hpp"

namespace rgbdo {
namespace {

namespace fs = std::filesystem;
const std::string kCheckDir = RGBDO_MAVLINK_CHECK_DIR;
constexpr int kPairs = 39;  // the 40 bundled frames

ScratchDir scratch(const std::string& name) { return ScratchDir("rgbdo_link", name); }

// Starts the decoder; `inherit_fd` (if >= 0) becomes its fd 3. Returns the child's pid.
pid_t start_decoder(const std::vector<std::string>& args, int inherit_fd) {
  return start_node(kCheckDir, "decode.mjs", args, inherit_fd);
}

std::string wait_for_ready(const fs::path& ready_file) {
  for (int i = 0; i < 300 && !fs::exists(ready_file); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  std::ifstream in(ready_file);
  std::string line;
  std::getline(in, line);
  return line;
}

int wait_exit(pid_t pid) {
  int status = 0;
  for (int i = 0; i < 600; ++i) {  // 30 s at most: a stuck decoder fails the test, not the suite
    if (::waitpid(pid, &status, WNOHANG) == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ::kill(pid, SIGKILL);
  ::waitpid(pid, &status, 0);
  return -1;
}

// The message sets: ODOMETRY (PX4, ArduPilot), or VISION_POSITION_DELTA alone (ArduPilot's
// body odometry, composed over at least 50 ms): never both, which EKF3 would fuse twice.
const std::vector<std::string> kOdometry{};
const std::vector<std::string> kDeltas{"link.odometry=false", "link.vision_position_delta=true",
                                       "link.delta_min_interval_ms=50"};

int run_program(const std::string& link, const fs::path& log, std::string& output,
                const std::vector<std::string>& messages = kOdometry) {
  RunOptions o;
  o.source = std::string("tum:") + RGBDO_TEST_DATA_DIR;
  o.config_path = RGBDO_CONFIG_DIR "/tum-fr1.yaml";
  o.log_path = log.string();
  o.link = link;
  o.overrides = messages;
  o.quiet = true;
  std::ostringstream out, err;
  const int rc = run_odometry(o, out, err);
  output = out.str() + err.str();
  return rc;
}

int check(const fs::path& decoded, const fs::path& log, std::string& report, const std::string& messages = "") {
  const fs::path out = decoded.parent_path() / "check.txt";
  const std::string cmd = "node " + kCheckDir + "/check.mjs --decoded " + decoded.string() + " --log " + log.string() +
                          " " + messages + " --velocity-frame current --jacobians exact > " + out.string() + " 2>&1";
  const int rc = std::system(cmd.c_str());
  std::ifstream in(out);
  report.assign(std::istreambuf_iterator<char>(in), {});
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : 128;
}

TEST(FlightLinkDecoded, OverUdpEveryFrameDecodesAndMatchesTheLog) {
  ASSERT_TRUE(fs::exists(kCheckDir + "/node_modules/node-mavlink"))
      << "run: npm ci --prefix test/mavlink_check (deploy/setup.sh test does)";
  const ScratchDir scratch_dir = scratch("udp");
  const fs::path& dir = scratch_dir.path();
  const pid_t decoder = start_decoder({"--udp", "0", "--ready-file", (dir / "ready").string(), "--count",
                                       std::to_string(kPairs), "--timeout-ms", "10000", "--out",
                                       (dir / "decoded.jsonl").string()},
                                      -1);
  const std::string ready = wait_for_ready(dir / "ready");
  const auto colon = ready.rfind(':');
  ASSERT_NE(colon, std::string::npos) << "decoder not ready: '" << ready << "'";
  const std::string port = ready.substr(colon + 1);
  std::string output;
  ASSERT_EQ(run_program("udp://127.0.0.1:" + port, dir / "odometry.csv", output), 0) << output;
  EXPECT_EQ(wait_exit(decoder), 0) << "the decoder met a bad frame or too few messages";
  std::string report;
  EXPECT_EQ(check(dir / "decoded.jsonl", dir / "odometry.csv", report), 0) << report;
}

TEST(FlightLinkDecoded, OverAPseudoTerminalEveryFrameDecodesAndMatchesTheLog) {
  ASSERT_TRUE(fs::exists(kCheckDir + "/node_modules/node-mavlink"));
  const ScratchDir scratch_dir = scratch("pty");
  const fs::path& dir = scratch_dir.path();
  int master = -1, slave = -1;
  char slave_path[256] = {};
  ASSERT_EQ(::openpty(&master, &slave, slave_path, nullptr, nullptr), 0) << "openpty: " << std::strerror(errno);
  termios raw{};
  ::tcgetattr(master, &raw);
  ::cfmakeraw(&raw);
  ::tcsetattr(master, TCSANOW, &raw);
  const pid_t decoder = start_decoder({"--fd", "3", "--ready-file", (dir / "ready").string(), "--timeout-ms", "10000",
                                       "--out", (dir / "decoded.jsonl").string()},
                                      master);
  ::close(master);  // the decoder has its own copy
  ASSERT_FALSE(wait_for_ready(dir / "ready").empty());
  std::string output;
  ASSERT_EQ(run_program(std::string("serial://") + slave_path + ":921600", dir / "odometry.csv", output, kDeltas), 0)
      << output;
  ::close(slave);
  EXPECT_EQ(wait_exit(decoder), 0) << "the decoder met a bad frame or the port did not close";
  std::string report;
  EXPECT_EQ(check(dir / "decoded.jsonl", dir / "odometry.csv", report, "--vpd-only --delta-min-ms 50"), 0) << report;
  // 39 pairs at ~33 ms: every delta spans two pairs, 66 ms, above EKF3's 50-ms floor.
  EXPECT_NE(report.find("\"visionPositionDelta\":19"), std::string::npos) << report;
}

// `recording` replayed with the shipped fr1 configuration over real UDP to the independent
// decoder, which writes dir/decoded.jsonl (`messages` ODOMETRY expected); the log is
// dir/odometry.csv, the summary in out.
void replay_over_udp(const fs::path& recording, const fs::path& dir, std::string& out, int messages = kPairs) {
  const pid_t decoder = start_decoder({"--udp", "0", "--ready-file", (dir / "ready").string(), "--count",
                                       std::to_string(messages), "--timeout-ms", "10000", "--out",
                                       (dir / "decoded.jsonl").string()},
                                      -1);
  const std::string ready = wait_for_ready(dir / "ready");
  ASSERT_NE(ready.rfind(':'), std::string::npos) << "decoder not ready: '" << ready << "'";
  RunOptions o;
  o.source = "tum:" + recording.string();
  o.config_path = RGBDO_CONFIG_DIR "/tum-fr1.yaml";
  o.log_path = (dir / "odometry.csv").string();
  o.link = "udp://127.0.0.1:" + ready.substr(ready.rfind(':') + 1);
  o.quiet = true;
  std::ostringstream summary, err;
  ASSERT_EQ(run_odometry(o, summary, err), 0) << err.str();
  EXPECT_EQ(wait_exit(decoder), 0);
  out = summary.str();
}

// The odometry log's lines, and those of them with `status`.
struct LogRows {
  int rows = 0, with_status = 0;
};
LogRows log_rows(const fs::path& path, const std::string& status) {
  std::ifstream log(path);
  LogRows r;
  for (std::string line; std::getline(log, line); ++r.rows) r.with_status += line.find("," + status + ",") != std::string::npos;
  return r;
}

// GIVEN a recording that lists one colour frame twice, WHEN replayed over UDP, THEN the
// repeat is logged as stamp_not_increasing and counted, never paired as an ok pair with zero
// dt nor sent: every ODOMETRY's time_usec is after the one before (check.mjs asserts it).
TEST(FlightLinkDecoded, AFrameListedTwiceIsFlaggedAndNeverSent) {
  const ScratchDir scratch_dir = scratch("duplicate");
  const fs::path& dir = scratch_dir.path();
  const fs::path recording = dir / "recording";
  fs::create_directories(recording);
  for (const char* item : {"rgb", "depth", "depth.txt", "groundtruth.txt"})
    fs::create_symlink(fs::path(RGBDO_TEST_DATA_DIR) / item, recording / item);
  {
    std::ifstream in(fs::path(RGBDO_TEST_DATA_DIR) / "rgb.txt");
    std::ofstream out(recording / "rgb.txt");
    int frame = 0;
    for (std::string line; std::getline(in, line);) {
      out << line << "\n";
      if (!line.empty() && line[0] != '#' && ++frame == 10) out << line << "\n";  // the 10th frame twice
    }
  }
  std::string out;
  ASSERT_NO_FATAL_FAILURE(replay_over_udp(recording, dir, out));
  const LogRows log = log_rows(dir / "odometry.csv", "stamp_not_increasing");
  EXPECT_EQ(log.rows, kPairs + 2) << "the header, 39 pairs and the flagged repeat";
  EXPECT_EQ(log.with_status, 1);
  EXPECT_NE(out.find("39 pairs, 39 ok"), std::string::npos) << out;
  EXPECT_NE(out.find("1 dropped for a capture time not after the previous frame's"), std::string::npos) << out;
  std::string report;
  EXPECT_EQ(check(dir / "decoded.jsonl", dir / "odometry.csv", report), 0) << report;
}

// GIVEN a recording whose 10th frame has an empty depth image, WHEN replayed over UDP, THEN
// that frame is logged as no_depth and dropped, never sent, and the next pair spans it: 38 ok
// pairs, 38 ODOMETRY messages, no reset (check.mjs recomputes every message from the log).
TEST(FlightLinkDecoded, AFrameWithoutDepthIsBridgedNotSent) {
  const ScratchDir scratch_dir = scratch("depthless");
  const fs::path& dir = scratch_dir.path();
  const fs::path recording = dir / "recording";
  fs::create_directories(recording / "depth");
  for (const char* item : {"rgb", "rgb.txt", "groundtruth.txt"})
    fs::create_symlink(fs::path(RGBDO_TEST_DATA_DIR) / item, recording / item);
  {
    std::ifstream in(fs::path(RGBDO_TEST_DATA_DIR) / "depth.txt");
    std::ofstream out(recording / "depth.txt");
    int frame = 0;
    for (std::string line; std::getline(in, line);) {
      std::istringstream fields(line);
      std::string stamp, file;
      if (line.empty() || line[0] == '#' || !(fields >> stamp >> file)) {
        out << line << "\n";
        continue;
      }
      const fs::path to = recording / file;
      if (++frame == 10)
        cv::imwrite(to.string(), cv::Mat(480, 640, CV_16UC1, cv::Scalar::all(0)));
      else
        fs::create_symlink(fs::path(RGBDO_TEST_DATA_DIR) / file, to);
      out << line << "\n";
    }
  }
  std::string out;
  ASSERT_NO_FATAL_FAILURE(replay_over_udp(recording, dir, out, kPairs - 1));
  const LogRows log = log_rows(dir / "odometry.csv", "no_depth");
  EXPECT_EQ(log.rows, kPairs + 1) << "the header, 38 pairs and the dropped frame";
  EXPECT_EQ(log.with_status, 1);
  EXPECT_NE(out.find("38 pairs, 38 ok, 0 failed"), std::string::npos) << out;
  EXPECT_NE(out.find("1 without depth bridged"), std::string::npos) << out;
  std::string report;
  EXPECT_EQ(check(dir / "decoded.jsonl", dir / "odometry.csv", report), 0) << report;
  EXPECT_NE(report.find("\"odometry\":38"), std::string::npos) << report;
}

// GIVEN a recording whose colour goes black for 10 frames (a lens covered, a light failing),
// WHEN replayed over UDP, THEN every failed pair's ODOMETRY carries no pose at all (NaN; PX4
// at EKF2_EV_QMIN 0 fuses any finite one), every ok pair is sent, and the pose resumes with
// reset_counter incremented (check.mjs recomputes all of it from the log).
TEST(FlightLinkDecoded, BlackedOutFramesSendNoPose) {
  const ScratchDir scratch_dir = scratch("blackout");
  const fs::path& dir = scratch_dir.path();
  const fs::path recording = dir / "recording";
  fs::create_directories(recording / "rgb");
  for (const char* item : {"depth", "depth.txt", "groundtruth.txt", "rgb.txt"})
    fs::create_symlink(fs::path(RGBDO_TEST_DATA_DIR) / item, recording / item);
  std::vector<fs::path> images;
  for (const auto& entry : fs::directory_iterator(fs::path(RGBDO_TEST_DATA_DIR) / "rgb")) images.push_back(entry.path());
  std::sort(images.begin(), images.end());
  for (std::size_t i = 0; i < images.size(); ++i) {
    const fs::path to = recording / "rgb" / images[i].filename();
    if (i >= 15 && i < 25)
      cv::imwrite(to.string(), cv::Mat(480, 640, CV_8UC3, cv::Scalar::all(0)));
    else
      fs::create_symlink(images[i], to);
  }
  std::string out;
  ASSERT_NO_FATAL_FAILURE(replay_over_udp(recording, dir, out));
  // Pairs into, inside and out of the dark: 11 fail (ten dark frames, and the first bright one
  // after them pairs with a dark one); the others are ok.
  EXPECT_NE(out.find("39 pairs, 28 ok, 11 failed"), std::string::npos) << out;
  std::string report;
  EXPECT_EQ(check(dir / "decoded.jsonl", dir / "odometry.csv", report), 0) << report;
  EXPECT_NE(report.find("\"odometry\":39"), std::string::npos) << report;
}

// Nothing listens: the link reports it, and odometry and its log are untouched.
TEST(FlightLinkDecoded, AnUnreachablePeerCostsTheLogNothing) {
  const ScratchDir scratch_dir = scratch("unreachable");
  const fs::path& dir = scratch_dir.path();
  std::string output;
  // Port 9 (discard) on loopback: nothing listens, the kernel refuses every datagram.
  ASSERT_EQ(run_program("udp://127.0.0.1:9", dir / "odometry.csv", output), 0) << output;
  std::ifstream log(dir / "odometry.csv");
  int rows = 0;
  for (std::string line; std::getline(log, line);) ++rows;
  EXPECT_EQ(rows, kPairs + 1);
  EXPECT_NE(output.find("39 pairs, 39 ok"), std::string::npos) << output;
  EXPECT_NE(output.find("refused"), std::string::npos) << "the loss is reported: " << output;
}

}  // namespace
}  // namespace rgbdo
