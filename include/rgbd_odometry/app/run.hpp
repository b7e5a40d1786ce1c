#pragma once
// The executable's job, as a library call: read frames from a source, run the pipeline,
// write every output, report. main() only parses the command line into RunOptions.
#include <iosfwd>
#include <string>
#include <vector>

namespace rgbdo {

struct RunOptions {
  std::string source;       // "tum:DIR" or "openni://[DEVICE-URI]" (empty: the first device)
  std::string config_path;  // empty: built-in defaults
  std::vector<std::string> overrides;  // "section.key=value", applied after the file
  std::string log_path;         // odometry CSV, empty: none
  std::string trajectory_path;  // TUM trajectory, empty: none
  std::string link;             // MAVLink link URI (overrides link.uri), empty: the config's
  bool quiet = false;           // no per-pair lines
  bool verbose = false;         // per-pair stage times and counts
  bool start_at_groundtruth = false;  // trajectory origin: ground-truth pose of the first frame
  int max_frames = 0;           // 0: all
  // A replay's gyro (io/imu_file.hpp); empty: the tum: directory's imu.txt if there is one,
  // live the link's autopilot.
  std::string imu_path;
  // Evaluation against ground truth (when the source has it): the allowance for its own noise
  // ("auto": estimated from it; "none"; "T_M,R_RAD") and a per-pair CSV for plots (empty: none).
  std::string groundtruth_allowance = "auto";
  std::string evaluation_path;
  // --calibrate: the sensor's constants measured against the ground truth, written here as a
  // configuration file (app/calibration.hpp); empty: none. A source without ground truth is refused.
  std::string calibration_path;
};

// Returns the process exit code: 0 ok, 1 input/output failure, 2 bad configuration.
// A live source runs until it stops delivering or request_stop() is called.
int run_odometry(const RunOptions& options, std::ostream& out, std::ostream& err);

// --print-config: the configuration run_odometry would run with (file, overrides, --link),
// checked, as a commented YAML file on out. 0, or 2 with the problem on err.
int print_configuration(const RunOptions& options, std::ostream& out, std::ostream& err);

// Asks a running run_odometry to finish the current frame, flush and return (signal-safe).
void request_stop();

// The SIGINT / SIGTERM handler: request_stop() while frames are processed; before that (the
// configuration read, the source opened) the process ends at once with status 128 + signal.
void on_stop_signal(int signal_number);

}  // namespace rgbdo
