// The link both ways, against a simulated PX4 nobody here wrote (test/mavlink_check/
// autopilot_sim.mjs, on node-mavlink) over real UDP (the program sending to a fixed peer, and
// listening as PX4's offboard convention has it) and a real pseudo-terminal. The program runs
// whole, on the virtual sensor (a live source, so capture times are on the steady clock), while
// the simulator sends HEARTBEAT, TIMESYNC requests at PX4's 10 Hz and noise, corrupted,
// truncated, reordered and lost frames. What must hold:
//   - PX4's timesync estimator, run by the simulator on our answers, converges (500 samples)
//     to the true offset within what the round trips allow (the simulator's clock is
//     CLOCK_MONOTONIC + 1234.567 s);
//   - every frame we sent still decodes and the ODOMETRY matches the odometry log field by
//     field (decode.mjs and check.mjs, unchanged; TIMESYNC is the one message id added);
//   - our own offset estimate finds the simulator's clock too, and the user is told the
//     autopilot is there (and when it goes, and comes back).
// No wall-clock deadline is asserted: waits are bounded timeouts, checks are counts and order.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <pty.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <regex>
#include <sstream>
#include <thread>

#include "node_checker.hpp"
#include "rgbd_odometry/app/run.hpp"
#include "rgbd_odometry/link/link_config.hpp"

namespace rgbdo {
namespace {

namespace fs = std::filesystem;
const std::string kCheckDir = RGBDO_MAVLINK_CHECK_DIR;
// Recorded pace: the device clock then runs at the host's rate, so capture stamps are comparable with
// arrival times (at another rate the virtual device's timestamps drift from the host's by design).
constexpr double kRate = 1.0;
constexpr long long kTrueOffsetNs = 1'234'567'000'000LL;  // the simulator's clock minus ours

ScratchDir scratch(const std::string& name) { return ScratchDir("rgbdo_autopilot", name); }


bool wait_for_file(const fs::path& file, int seconds) {
  for (int i = 0; i < seconds * 20 && !fs::exists(file); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  return fs::exists(file);
}

std::string read_text(const fs::path& file) {
  std::ifstream in(file);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

int wait_exit(pid_t pid, int seconds) {
  int status = 0;
  for (int i = 0; i < seconds * 20; ++i) {
    if (::waitpid(pid, &status, WNOHANG) == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ::kill(pid, SIGKILL);
  ::waitpid(pid, &status, 0);
  return -1;
}

// A number from the simulator's JSON result ("key": value), NaN when absent or null.
double json_number(const std::string& json, const std::string& key) {
  const std::regex re("\"" + key + "\": (-?[0-9.eE+-]+)");
  std::smatch m;
  return std::regex_search(json, m, re) ? std::stod(m[1]) : std::nan("");
}

// A port nothing listens on now (for the listening link; the simulator needs it first).
int free_udp_port() {
  const int s = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(s, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t length = sizeof a;
  ::getsockname(s, reinterpret_cast<sockaddr*>(&a), &length);
  ::close(s);
  return ntohs(a.sin_port);
}

struct ProgramRun {
  int rc = -1;
  std::string output;
};

// The program on the virtual sensor, until stop_when() or `limit_s`. The recording plays once
// (40 frames); afterwards the sensor stays away and the program waits for it, link running.
ProgramRun run_program(const std::string& link, const fs::path& log, const std::string& device_id,
                       const std::function<bool()>& stop_when, int limit_s,
                       const std::vector<std::string>& extra_overrides = {}, const std::string& sensor_faults = "") {
  RunOptions o;
  o.source = std::string("openni://rgbdo-virtual:") + RGBDO_TEST_DATA_DIR + "?rate=" + std::to_string(kRate) +
             "&id=" + device_id + sensor_faults;
  o.config_path = RGBDO_CONFIG_DIR "/tum-fr1.yaml";
  o.log_path = log.string();
  o.link = link;
  o.overrides = {"sensor.reconnect_timeout_s=-1",
                 "sensor.reconnect_interval_ms=500",
                 "sensor.pairing_wait_ms=" + std::to_string(static_cast<int>(100 / kRate))};
  o.overrides.insert(o.overrides.end(), extra_overrides.begin(), extra_overrides.end());
  o.quiet = true;
  ProgramRun run;
  std::ostringstream out, err;
  std::atomic<bool> done{false};
  std::thread program([&] {
    run.rc = run_odometry(o, out, err);
    done = true;
  });
  const auto start = std::chrono::steady_clock::now();
  while (!done) {
    if (stop_when() || std::chrono::steady_clock::now() - start > std::chrono::seconds(limit_s)) request_stop();
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  program.join();
  run.output = out.str() + err.str();
  return run;
}

int log_rows(const fs::path& log) {
  std::ifstream in(log);
  int rows = -1;  // the header
  for (std::string line; std::getline(in, line);) ++rows;
  return rows;
}

// The roll and pitch the program says it levelled its local frame with, for check.mjs; empty
// when it had no ATTITUDE at its first pair (then its frame starts at identity).
std::string levelled_with(const std::string& output) {
  std::smatch m;
  if (!std::regex_search(output, m, std::regex("local frame levelled with the autopilot's attitude[^(]*\\(([-0-9.e]+) rad, ([-0-9.e]+) rad\\)")))
    return "";
  return " --initial-rpy " + m[1].str() + "," + m[2].str();
}

// decode.mjs over the captured bytes, then check.mjs against the log, as for the send-only link.
void expect_capture_matches_log(const fs::path& dir, const std::string& output) {
  const std::string decode = "node " + kCheckDir + "/decode.mjs --file " + (dir / "capture.bin").string() + " --out " +
                             (dir / "decoded.jsonl").string() + " > " + (dir / "decode.txt").string() + " 2>&1";
  const int decode_rc = std::system(decode.c_str());
  EXPECT_EQ(WIFEXITED(decode_rc) ? WEXITSTATUS(decode_rc) : 128, 0)
      << "every frame we sent decodes: " << read_text(dir / "decode.txt");
  const std::string check = "node " + kCheckDir + "/check.mjs --decoded " + (dir / "decoded.jsonl").string() +
                            " --log " + (dir / "odometry.csv").string() +
                            " --velocity-frame current --jacobians exact --allow-msgid 111" + levelled_with(output) + " > " +
                            (dir / "check.txt").string() + " 2>&1";
  const int check_rc = std::system(check.c_str());
  EXPECT_EQ(WIFEXITED(check_rc) ? WEXITSTATUS(check_rc) : 128, 0) << read_text(dir / "check.txt");
}

struct OurOffset {
  double error_us = std::nan("");
  double round_trip_us = std::nan("");
};

// Our estimate of the simulator's clock, from the last status line:
// "clock offset +1234.567000123 s (round trip 0.41 ms, 57 samples)".
OurOffset our_offset(const std::string& output) {
  const std::regex re("link status: .*clock offset ([-+][0-9]+\\.[0-9]{9}) s \\(round trip ([0-9.]+) ms");
  OurOffset last;
  for (auto it = std::sregex_iterator(output.begin(), output.end(), re); it != std::sregex_iterator(); ++it) {
    last.error_us = (std::stod((*it)[1]) - static_cast<double>(kTrueOffsetNs) * 1e-9) * 1e6;
    last.round_trip_us = std::stod((*it)[2]) * 1e3;
  }
  return last;
}

// GIVEN the simulator on `transport_args`, WHEN the program runs until PX4 converged,
// THEN convergence within the round trips' bound, unchanged ODOMETRY, and the user told.
void converge_over(const std::string& name, const std::function<std::string(const fs::path&)>& link_for,
                   const std::vector<std::string>& transport_args, int inherit_fd, const std::function<void()>& after_start,
                   const std::function<void()>& after_run = [] {}) {
  ASSERT_TRUE(fs::exists(kCheckDir + "/node_modules/node-mavlink")) << "run: npm ci --prefix test/mavlink_check";
  const ScratchDir scratch_dir = scratch(name);
  const fs::path& dir = scratch_dir.path();
  std::vector<std::string> args = transport_args;
  const std::vector<std::string> common{"--ready-file", (dir / "ready").string(), "--result", (dir / "result.json").string(),
                                        "--capture", (dir / "capture.bin").string(), "--converged-file",
                                        (dir / "converged").string(), "--offset-ns", std::to_string(kTrueOffsetNs),
                                        "--expect-converged", "--loss", "0.05", "--reorder", "0.03", "--garbage", "0.3",
                                        "--seed", "7", "--idle-exit-ms", "3000", "--max-ms", "400000",
                                        // PX4 asks at 10 Hz; its estimator needs 500 used samples, which
                                        // at 100 Hz take 5 s instead of 50: the same rules, a tenth the wait.
                                        "--timesync-hz", "100"};
  args.insert(args.end(), common.begin(), common.end());
  const pid_t sim = start_node(kCheckDir, "autopilot_sim.mjs", args, inherit_fd);
  after_start();
  ASSERT_TRUE(wait_for_file(dir / "ready", 30)) << "simulator not ready";
  const std::string link = link_for(dir);
  // 500 used samples at 100 Hz take 5 s and more: the limit only ends a run that never converges.
  const ProgramRun run =
      run_program(link, dir / "odometry.csv", name, [&] { return fs::exists(dir / "converged"); }, 300);
  after_run();
  ASSERT_EQ(run.rc, 0) << run.output;
  const int sim_rc = wait_exit(sim, 60);
  const std::string result = read_text(dir / "result.json");
  EXPECT_EQ(sim_rc, 0) << result;

  // PX4's view: converged, every answer causal, the offset within what its round trips allow
  // (each sample within half its round trip, the filter's weights summing to about 3.9 in
  // absolute value: 0.85-0.99 ms on an idle machine, 1.6-1.9 ms under ThreadSanitizer beside a
  // build, at most 19 ms where PX4 drops round trips of 10 ms or more). The bound follows the
  // machine; the stamps' correctness does not.
  EXPECT_GE(json_number(result, "sequence"), 500) << result;
  const double error_us = json_number(result, "offsetErrorUs");
  const double bound_us = json_number(result, "offsetBoundUs");
  EXPECT_LE(std::abs(error_us), bound_us) << result;
  EXPECT_EQ(json_number(result, "causalityViolations"), 0) << result;
  EXPECT_GT(json_number(result, "garbageBytes"), 0) << "the link was unkind: " << result;
  EXPECT_GT(json_number(result, "corruptFrames"), 0) << result;
  // Noise with start bytes in it (false headers of any length and id) costs no request its
  // answer: the parser passes a false start over instead of skipping by its length field.
  EXPECT_GT(json_number(result, "startByteNoise"), 0) << result;
  const double delivered = json_number(result, "requestsDeliveredWhileHeard");
  EXPECT_GE(json_number(result, "answersReceived"), 0.99 * delivered) << "requests answered of those delivered: " << result;
  // Its converged offset carries our capture times onto its clock: each ODOMETRY stamp lands
  // before its arrival (a capture time is never after the frame reached us: the device
  // clock's lead, sensor/device_clock.hpp), to the offset's bound (asserted above),
  // and earlier by no more than our own capture-to-output latency (the summary's max; seconds
  // under ThreadSanitizer on a busy machine, where the virtual sensor itself falls behind)
  // plus the link's queue and transport. Another clock would be seconds off either way.
  const std::regex latency("\"odometryLatencyUs\": \\{\\s*\"min\": (-?[0-9.e+-]+),\\s*\"max\": (-?[0-9.e+-]+)");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(result, m, latency)) << result;
  EXPECT_GT(std::stod(m[1]), -bound_us) << "a stamp after its arrival: " << result;
  std::smatch ours;
  ASSERT_TRUE(std::regex_search(run.output, ours, std::regex("latency capture to output: .*max ([0-9.]+) ms")))
      << run.output;
  EXPECT_LT(std::stod(m[2]) / 1000, std::stod(ours[1]) + 1000) << "PX4's capture-to-arrival against ours: " << result;
  std::cout << "[ " << name << " ] PX4 estimator: " << json_number(result, "sequence") << " samples, offset error "
            << error_us << " us (bound " << bound_us << " us); ODOMETRY capture-to-arrival " << std::stod(m[1]) / 1000 << ".."
            << std::stod(m[2]) / 1000 << " ms\n";

  // Nothing lost from the log or the wire. Listening (udpin), the frames sent before the
  // autopilot's first frame have nobody to go to: counted as dropped while the link was down
  // (how many depends on which comes first, the first pair or the first heartbeat).
  const std::smatch down = [&] {
    std::smatch d;
    const std::regex dropped("([0-9]+) while the link was down");
    EXPECT_TRUE(std::regex_search(run.output, d, dropped)) << run.output;
    return d;
  }();
  const int dropped_while_down = down.empty() ? 0 : std::stoi(down[1]);
  if (name != "udpin") {
    EXPECT_EQ(dropped_while_down, 0) << run.output;
  }
  const double odometry_received = json_number(result, "odometry");
  // Rows of dropped frames are logged, never sent: a repeated stamp, or a frame without depth
  // bridged (a reader woken late on a loaded machine flags one NoDepth).
  std::smatch dropped;
  ASSERT_TRUE(std::regex_search(run.output, dropped,
                                std::regex("([0-9]+) dropped for a capture time not after the previous frame's, "
                                           "([0-9]+) without depth bridged")))
      << run.output;
  const int rows = log_rows(dir / "odometry.csv") - std::stoi(dropped[1]) - std::stoi(dropped[2]);
  EXPECT_LE(odometry_received, rows) << result;
  EXPECT_GE(odometry_received, rows - dropped_while_down) << result;
  // check.mjs pairs messages with log rows from the first row on (it integrates the pose over
  // every row); when the first pairs went out before the autopilot spoke (a loaded machine
  // makes that likelier) the counts above are what can be checked, the message contents are
  // checked by the other transports' runs.
  if (dropped_while_down == 0) {
    // Levelled with the simulator's ATTITUDE when one came before the first pair (a race here,
    // where the first frames come within 0.1 s of the start), else at identity: either way
    // check.mjs integrates from the attitude the program says it started at.
    expect_capture_matches_log(dir, run.output);
  } else {
    std::cout << "[ " << name << " ] " << dropped_while_down
              << " pair(s) sent before the autopilot spoke: contents not compared row by row\n";
  }

  // The user was told, and our own estimate found the simulator's clock too.
  EXPECT_NE(run.output.find("link: autopilot PX4 (system 1, component 1) heard"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("link: clock offset to the autopilot +1234.5"), std::string::npos) << run.output;
  // Ours is the sample with the shortest round trip: within half of it (+5 us, the printed
  // round trip's rounding), however loaded the machine, and a round trip the program takes
  // (link.timesync_max_rtt_ms, 100 ms by default).
  const OurOffset our_clock = our_offset(run.output);
  EXPECT_LE(std::abs(our_clock.error_us), our_clock.round_trip_us / 2 + 5) << run.output;
  EXPECT_LE(our_clock.round_trip_us, LinkConfig{}.timesync_max_rtt_ms * 1e3) << run.output;
  std::cout << "[ " << name << " ] our estimate of the autopilot's clock: error " << our_clock.error_us << " us, round trip "
            << our_clock.round_trip_us << " us\n";
}

TEST(FlightLinkAutopilot, OverUdpToAFixedPeerPx4ConvergesAndOdometryIsUnchanged) {
  converge_over(
      "udp", [](const fs::path& dir) {
        const std::string ready = read_text(dir / "ready");  // "READY udp 127.0.0.1:PORT"
        return "udp://127.0.0.1:" + std::to_string(std::stoi(ready.substr(ready.rfind(':') + 1)));
      },
      {"--udp-listen", "0"}, -1, [] {});
}

TEST(FlightLinkAutopilot, ListeningOnUdpPx4ConvergesAndOdometryIsUnchanged) {
  const int port = free_udp_port();
  converge_over(
      "udpin", [port](const fs::path&) { return "udpin://127.0.0.1:" + std::to_string(port); },
      {"--udp-send", "127.0.0.1:" + std::to_string(port)}, -1, [] {});
}

TEST(FlightLinkAutopilot, OverAPseudoTerminalPx4ConvergesAndOdometryIsUnchanged) {
  int master = -1, slave = -1;
  char slave_path[256] = {};
  ASSERT_EQ(::openpty(&master, &slave, slave_path, nullptr, nullptr), 0) << std::strerror(errno);
  termios raw{};
  ::tcgetattr(master, &raw);
  ::cfmakeraw(&raw);
  ::tcsetattr(master, TCSANOW, &raw);
  const std::string path = slave_path;
  converge_over(
      "pty", [path](const fs::path&) { return "serial://" + path + ":921600"; }, {"--fd", "3"}, master,
      [&] { ::close(master); }, [&] { ::close(slave); });  // the program is done: the simulator reads the end
}

// A peer that appears late, goes away and comes back: the listening link has nobody to send to
// until the first valid frame, then answers it; the autopilot's departure and return are news.
// GIVEN an ArduPilot-like autopilot (HEARTBEAT autopilot 3) and link.ekf_origin, WHEN the
// program runs, THEN the autopilot receives SET_GPS_GLOBAL_ORIGIN and SET_HOME_POSITION with
// exactly that origin, addressed to it, a bounded number of times, and ODOMETRY only (EKF3
// needs an origin to use an external position without GPS: AP_NavEKF3, the non-GPS wiki).
TEST(FlightLinkAutopilot, ArduPilotGetsTheEkfOriginAndOneMessageSet) {
  ASSERT_TRUE(fs::exists(kCheckDir + "/node_modules/node-mavlink"));
  const ScratchDir scratch_dir = scratch("ardupilot");
  const fs::path& dir = scratch_dir.path();
  const pid_t sim = start_node(kCheckDir, "autopilot_sim.mjs",
                               {"--udp-listen", "0", "--ardupilot", "--ready-file", (dir / "ready").string(), "--result",
                                (dir / "result.json").string(), "--idle-exit-ms", "2000", "--max-ms", "120000"},
                               -1);
  ASSERT_TRUE(wait_for_file(dir / "ready", 30)) << "simulator not ready";
  const std::string ready = read_text(dir / "ready");
  const std::string port = ready.substr(ready.rfind(':') + 1, ready.find_last_not_of("\n") - ready.rfind(':'));
  // Until the recording ends and the sensor is gone: the origin goes out 5 times a second apart.
  const auto start = std::chrono::steady_clock::now();
  const ProgramRun run = run_program(
      "udp://127.0.0.1:" + port, dir / "odometry.csv", "ardupilot",
      [&] { return std::chrono::steady_clock::now() - start > std::chrono::seconds(12); }, 60,
      {"link.ekf_origin=47.397742, 8.545594, 488.0"},
      "&stall=0:1500");  // the first frame 1.5 s late: the autopilot's ATTITUDE is in hand by then
  ASSERT_EQ(run.rc, 0) << run.output;
  // The local frame levelled with the autopilot's attitude at the first pair (the simulator
  // streams roll 0.0312 rad, pitch -0.0187 rad at 10 Hz).
  std::smatch level;
  ASSERT_TRUE(std::regex_search(run.output, level,
                                std::regex("levelled with the autopilot's attitude[^(]*\\(([-0-9.e]+) rad, ([-0-9.e]+) rad\\)")))
      << run.output;
  EXPECT_NEAR(std::stod(level[1]), 0.0312, 1e-7);
  EXPECT_NEAR(std::stod(level[2]), -0.0187, 1e-7);
  EXPECT_NE(run.output.find("link: EKF origin 47.3977420, 8.5455940, 488.000 m sent to system 1"), std::string::npos)
      << run.output;
  EXPECT_EQ(wait_exit(sim, 60), 0);
  const std::string result = read_text(dir / "result.json");
  const std::regex origin_re(
      "\\{\\s*\"latitude\": (-?[0-9]+),\\s*\"longitude\": (-?[0-9]+),\\s*\"altitude\": (-?[0-9]+),\\s*\"targetSystem\": ([0-9]+)");
  int origins = 0;
  for (auto it = std::sregex_iterator(result.begin(), result.end(), origin_re); it != std::sregex_iterator(); ++it) {
    EXPECT_EQ((*it)[1], "473977420") << result;
    EXPECT_EQ((*it)[2], "85455940") << result;
    EXPECT_EQ((*it)[3], "488000") << result;
    EXPECT_EQ((*it)[4], "1") << result;
    ++origins;
  }
  // SET_GPS_GLOBAL_ORIGIN and SET_HOME_POSITION each 5 times when the autopilot is heard, and
  // again only if it went quiet and came back (a loaded machine can make it seem so).
  const std::regex burst_re("link: EKF origin [^\n]* sent to system 1");
  const auto bursts = std::distance(std::sregex_iterator(run.output.begin(), run.output.end(), burst_re),
                                    std::sregex_iterator());
  EXPECT_GE(bursts, 1) << run.output;
  EXPECT_EQ(origins, 10 * bursts) << result;
  EXPECT_GT(json_number(result, "odometry"), 0) << result;
  EXPECT_EQ(json_number(result, "visionPositionDelta"), 0) << "never both message sets: " << result;
}

TEST(FlightLinkAutopilot, ALatePeerIsFoundAndAVanishedAutopilotIsReported) {
  ASSERT_TRUE(fs::exists(kCheckDir + "/node_modules/node-mavlink"));
  const ScratchDir scratch_dir = scratch("late");
  const fs::path& dir = scratch_dir.path();
  const int port = free_udp_port();
  // The simulator speaks after 3 s, goes quiet after 20 used answers for as long as the
  // program sends 4 heartbeats (>= 3 s of silence, the timeout is 1.5 s), speaks again and
  // leaves after 3 more.
  const pid_t sim = start_node(kCheckDir, "autopilot_sim.mjs",
                               {"--udp-send", "127.0.0.1:" + std::to_string(port), "--start-after-ms", "3000",
                                "--ready-file", (dir / "ready").string(), "--result", (dir / "result.json").string(),
                                "--capture", (dir / "capture.bin").string(), "--silent-after-answers", "20",
                                "--silent-for-heartbeats", "4", "--exit-after-heartbeats", "3", "--garbage", "0.2",
                                "--idle-exit-ms", "5000", "--max-ms", "120000"},
                               -1);
  ASSERT_TRUE(wait_for_file(dir / "ready", 30));
  std::atomic<bool> sim_done{false};
  int sim_rc = -1;
  std::thread waiter([&] {
    sim_rc = wait_exit(sim, 150);
    sim_done = true;
  });
  const ProgramRun run = run_program("udpin://127.0.0.1:" + std::to_string(port), dir / "odometry.csv", "late",
                                     [&] { return sim_done.load(); }, 150);
  waiter.join();
  ASSERT_EQ(run.rc, 0) << run.output;
  const std::string result = read_text(dir / "result.json");
  EXPECT_EQ(sim_rc, 0) << result;
  EXPECT_EQ(json_number(result, "silentPeriods"), 1) << result;

  // The news, in order: a peer, the autopilot, its departure, its return.
  const std::string& out = run.output;
  const auto peer = out.find("link: replying to 127.0.0.1:");
  const auto heard = out.find("link: autopilot PX4 (system 1, component 1) heard");
  const auto gone = out.find("link: autopilot PX4 (system 1, component 1) gone: nothing heard from it for ");
  const auto back = gone == std::string::npos ? gone : out.find("link: autopilot PX4 (system 1, component 1) up", gone);
  ASSERT_NE(peer, std::string::npos) << out;
  ASSERT_NE(heard, std::string::npos) << out;
  ASSERT_NE(gone, std::string::npos) << out;
  ASSERT_NE(back, std::string::npos) << out;
  EXPECT_LT(peer, heard) << out;
  EXPECT_LT(heard, gone) << out;
  // What the peer got decodes cleanly (the frames sent before it was known were dropped).
  const std::string decode = "node " + kCheckDir + "/decode.mjs --file " + (dir / "capture.bin").string() + " --out " +
                             (dir / "decoded.jsonl").string() + " > " + (dir / "decode.txt").string() + " 2>&1";
  const int decode_rc = std::system(decode.c_str());
  EXPECT_EQ(WIFEXITED(decode_rc) ? WEXITSTATUS(decode_rc) : 128, 0) << read_text(dir / "decode.txt");
  std::cout << run.output;
}

}  // namespace
}  // namespace rgbdo

namespace rgbdo {
namespace {

// One live run against an autopilot streaming ATTITUDE rates made from the recording's ground
// truth (autopilot_sim.mjs --gyro-groundtruth), mapped to the virtual sensor's clock; the
// capture latency the program's summary reports, and the simulator's result.
struct GyroRun {
  double latency_ms = std::nan(""), latency_sigma_ms = std::nan(""), applied_ms = std::nan("");
  std::string output, result;
  // The log's restamped t_curr less the frame's nominal capture instant on the program's clock
  // (the virtual sensor's timeline less the recording's own latency), ms, median over the
  // second half of the good pairs.
  double capture_error_ms = std::nan("");
};

// The recording's own capture latency behind its stamps, as a replay of the bundled frames
// with their gyro measures it (test/gyro_replay.cmake: 16.7 ms).
constexpr double kRecordingLatencyMs = 16.7;

double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// What the log's times say against the virtual sensor's timeline (its clock file): each good
// row's t_curr against the nominal capture instant of the frame nearest to t_curr + expected.
double capture_error_ms(const fs::path& log, const fs::path& clock_file, double expected_ms) {
  std::ifstream clock(clock_file);
  long long start_ns = 0, t0_ns = 0, pass_ns = 0;
  if (!(clock >> start_ns >> t0_ns >> pass_ns)) return std::nan("");
  std::vector<double> nominal_s;  // the frames' nominal capture instants, our clock, 3 passes
  std::ifstream rgb(std::string(RGBDO_TEST_DATA_DIR) + "/rgb.txt");
  for (std::string line; std::getline(rgb, line);) {
    if (line.empty() || line[0] == '#') continue;
    const double t = std::stod(line.substr(0, line.find(' ')));
    for (int pass = 0; pass < 3; ++pass)
      nominal_s.push_back((start_ns + pass * pass_ns) * 1e-9 + t - t0_ns * 1e-9 - kRecordingLatencyMs * 1e-3);
  }
  std::vector<double> errors;
  std::ifstream in(log);
  std::string line;
  std::getline(in, line);  // header
  for (; std::getline(in, line);) {
    std::stringstream row(line);
    std::string t_prev, t_curr, status;
    std::getline(row, t_prev, ',');
    std::getline(row, t_curr, ',');
    std::getline(row, status, ',');
    if (status != "ok") continue;
    const double t = std::stod(t_curr);
    double best = 1e9;
    for (double n : nominal_s)
      if (std::abs(t - expected_ms * 1e-3 - n) < std::abs(best)) best = t - expected_ms * 1e-3 - n;
    errors.push_back(best * 1e3 + expected_ms);
  }
  return median(std::vector<double>(errors.begin() + static_cast<long>(errors.size() / 2), errors.end()));
}

GyroRun live_with_gyro(const std::string& name, const std::vector<std::string>& autopilot_args, double expected_ms) {
  GyroRun g;
  const ScratchDir scratch_dir = scratch(name);
  const fs::path& dir = scratch_dir.path();
  // Set once for the process and never changed: the virtual sensor's player threads read it,
  // and setenv while another thread calls getenv is undefined (ThreadSanitizer crashed on it).
  static const fs::path clock_file = [] {
    const fs::path p = fs::temp_directory_path() / ("rgbdo_virtual_clock_" + std::to_string(::getpid()));
    ::setenv("RGBDO_VIRTUAL_SENSOR_CLOCK_FILE", p.string().c_str(), 1);
    return p;
  }();
  fs::remove(clock_file);  // the sensor writes it anew when it starts playing
  std::vector<std::string> args{"--udp-listen", "0", "--ready-file", (dir / "ready").string(), "--result",
                                (dir / "result.json").string(), "--idle-exit-ms", "2000", "--max-ms", "120000",
                                "--gyro-groundtruth", std::string(RGBDO_TEST_DATA_DIR) + "/groundtruth.txt",
                                "--gyro-clock-file", clock_file.string()};
  args.insert(args.end(), autopilot_args.begin(), autopilot_args.end());
  const pid_t sim = start_node(kCheckDir, "autopilot_sim.mjs", args, -1);
  EXPECT_TRUE(wait_for_file(dir / "ready", 30)) << "simulator not ready";
  const std::string ready = read_text(dir / "ready");
  const std::string port = ready.substr(ready.rfind(':') + 1, ready.find_last_not_of("\n") - ready.rfind(':'));
  // The autopilot's clock offset measured at 20 Hz (its rates are mapped through it: those of
  // the first frames, before the first answer, are lost); the recording played three times
  // (120 frames, ground truth and all).
  const auto start = std::chrono::steady_clock::now();
  const ProgramRun run = run_program("udp://127.0.0.1:" + port, dir / "odometry.csv", name,
                                     [&] { return std::chrono::steady_clock::now() - start > std::chrono::seconds(8); }, 60,
                                     {"link.timesync_rate_hz=20"}, "&loop=3");
  EXPECT_EQ(run.rc, 0) << run.output;
  EXPECT_EQ(wait_exit(sim, 60), 0);
  g.output = run.output;
  g.result = read_text(dir / "result.json");
  std::smatch m;
  if (std::regex_search(g.output, m,
                        std::regex("capture latency (-?[0-9.]+) \\+- ([0-9.]+) ms against the gyro.*\\(applied (-?[0-9.]+) ms"))) {
    g.latency_ms = std::stod(m[1]);
    g.latency_sigma_ms = std::stod(m[2]);
    g.applied_ms = std::stod(m[3]);
  }
  g.capture_error_ms = capture_error_ms(dir / "odometry.csv", clock_file, expected_ms);
  return g;
}

// What every live run with an autopilot's gyro must show: ATTITUDE asked for at 50 Hz and
// granted, its rates received, a latency measured.
void expect_gyro_flow(const GyroRun& g) {
  EXPECT_NE(g.output.find("link: ATTITUDE at 50 Hz accepted by the autopilot"), std::string::npos) << g.output;
  EXPECT_NE(g.result.find("\"messageId\": 30"), std::string::npos) << g.result;
  EXPECT_NE(g.result.find("\"intervalUs\": 20000"), std::string::npos) << g.result;
  EXPECT_GT(json_number(g.result, "gyroSamples"), 100) << g.result;
  EXPECT_NE(g.output.find("  capture latency "), std::string::npos) << g.output;
}

// The log's times against the virtual sensor's nominal capture instants, `expected_ms` being
// where the autopilot's stamps put them; printed with the latency behind them.
void expect_capture_error(const GyroRun& g, const char* name, double expected_ms) {
  ASSERT_FALSE(std::isnan(g.latency_ms)) << g.output;
  std::cout << "[ live ] capture latency against " << name << " " << g.latency_ms << " +- " << g.latency_sigma_ms
            << " ms (applied " << g.applied_ms << "), the log " << g.capture_error_ms
            << " ms from the capture instants\n";
  EXPECT_NEAR(g.capture_error_ms, expected_ms, 12);
}

// GIVEN a PX4-like autopilot whose ATTITUDE rates are the recording's ground truth's (with a
// bias and noise) and an ArduPilot-like one stamping the same rates 25 ms late (ArduPilot stamps
// ATTITUDE when it sends it), WHEN the program runs the virtual sensor live against each, THEN
// it asks each for ATTITUDE at 50 Hz (MAV_CMD_SET_MESSAGE_INTERVAL), maps the rates onto its
// clock through TIMESYNC, measures its frames' capture latency against them, and the late
// stamps move that latency by their 25 ms.
// Each autopilot in a process of its own: a second device opened in one process after the first
// was closed hung in OpenNI2's oniStreamStart now and then (AddressSanitizer build: 1 run in 5,
// stuck for the test's whole timeout; src/README.md).
// Each motion stamped when its frames were taken: the log's times against the virtual
// sensor's nominal capture instants, whatever the machine's load made of the frames' delivery
// (the latency itself measured 22-53 ms here, idle and loaded). Against rates stamped 25 ms
// late the frames seem taken 25 ms later, as an autopilot fusing them by those stamps needs.
// Measured: -1.3 and -2.7 ms idle and with both cores hogged, 7.6 inside the whole suite's
// parallel run, whose load changes during the run (the estimate averages the frames' delivery
// delay over it, the median here is its second half's); +21.3, +21.2 and +22.3 against the late
// stamps. Once -10.2 in CI's AddressSanitizer stage, its first seconds' frames delivered late
// (latency 24.9 +- 2.6 ms against 16-18 in six reruns there, which gave -0.2 … +2.4 and +18.1 …
// +21.1). The bounds (+-12 ms) part what is asserted from the stamps unchanged (+22 … +53) and
// from the gyro's delay ignored or taken the wrong way (25 ms off).
// Under ThreadSanitizer the pipeline keeps up with a few frames a second of the 30 it is
// given: too few pairs to measure a latency to a few milliseconds. The flow is checked there.
TEST(FlightLinkAutopilot, TheAutopilotsGyroTimesTheFramesLivePx4) {
  ASSERT_TRUE(fs::exists(kCheckDir + "/node_modules/node-mavlink"));
  const GyroRun px4 = live_with_gyro("gyro_px4", {}, 0);
  expect_gyro_flow(px4);
  if (RGBDO_THREAD_SANITIZER) GTEST_SKIP() << "latency figures not checked under ThreadSanitizer";
  expect_capture_error(px4, "PX4's rates", 0);
}

TEST(FlightLinkAutopilot, TheAutopilotsGyroTimesTheFramesLiveArduPilot) {
  ASSERT_TRUE(fs::exists(kCheckDir + "/node_modules/node-mavlink"));
  const GyroRun ardupilot = live_with_gyro("gyro_ardupilot", {"--ardupilot", "--gyro-delay-ms", "25", "--seed", "3"}, 25);
  expect_gyro_flow(ardupilot);
  if (RGBDO_THREAD_SANITIZER) GTEST_SKIP() << "latency figures not checked under ThreadSanitizer";
  expect_capture_error(ardupilot, "ArduPilot's stamped 25 ms late", 25);
}

}  // namespace
}  // namespace rgbdo
