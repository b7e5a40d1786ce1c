// rgbd-odometry: RGB-D visual odometry with covariance (Willis & Brink, PLANS 2016).
#include <CLI/CLI.hpp>
#include <csignal>
#include <iostream>
#include <string>
#include <vector>

#include "rgbd_odometry/simd/kernels.hpp"
#include "rgbd_odometry/app/list_devices.hpp"
#include "rgbd_odometry/app/run.hpp"
#include "rgbd_odometry/core/version.hpp"
#include "rgbd_odometry/app/config_file.hpp"

namespace {

// The flags that print something about the build or the machine, then exit.
void add_exit_flags(CLI::App& app) {
  app.add_flag_callback(
      "--print-kernels",
      [] {
        std::cout << "build: " << rgbdo::simd::build_architecture() << "\ncompiled kernel sets:";
        for (const auto& s : rgbdo::simd::compiled_kernel_sets())
          std::cout << " " << s.name << (rgbdo::simd::cpu_supports(s) ? "" : " (unsupported by this CPU)");
        const std::string requested = rgbdo::simd::requested_kernels();
        std::cout << "\nactive: " << rgbdo::simd::active_kernels().name
                  << (requested.empty() ? "" : " (requested by the environment: " + requested + ")") << "\n";
        if (const std::string problem = rgbdo::simd::kernel_request_problem(); !problem.empty()) {
          std::cerr << "rgbd-odometry: " << problem << "\n";
          throw CLI::RuntimeError(2);
        }
        throw CLI::Success();
      },
      "list the SIMD kernel sets in this build and the one in use, then exit");
  app.add_flag_callback(
      "--list-devices", [] { throw CLI::RuntimeError(rgbdo::list_devices(std::cout)); },
      "list the OpenNI2 devices present, then exit");
  app.add_flag_callback(
      "--print-config-reference",
      [] {
        std::cout << rgbdo::config_reference_markdown();
        throw CLI::Success();
      },
      "print the configuration reference (every key, default, unit, range, help) as Markdown, then exit");
}

// Options that stand for --set KEY=VALUE.
struct Shorthands {
  std::string detector, seed, max_features, scale;

  void add_to(std::vector<std::string>& overrides) const {
    if (!detector.empty()) {
      overrides.push_back("features.detector=" + detector);
      overrides.push_back("features.descriptor=" + detector);
    }
    if (!max_features.empty()) overrides.push_back("features.max_features=" + max_features);
    if (!scale.empty()) overrides.push_back("covariance.scale=" + scale);
    if (!seed.empty()) overrides.push_back("seed=" + seed);
  }
};

// The options of a run.
void add_run_options(CLI::App& app, rgbdo::RunOptions& options, Shorthands& shorthands) {
  app.add_option("--source", options.source,
                 "frame source: tum:DIR (a TUM RGB-D sequence), openni://[DEVICE-URI] (a live sensor, the first "
                 "found when empty) or oni:FILE.oni (an OpenNI2 recording)");
  app.add_option("--config", options.config_path, "YAML configuration (e.g. deploy/config/tum-fr1.yaml)")
      ->check(CLI::ExistingFile);
  app.add_option("--set", options.overrides, "override a configuration key: --set ransac.max_iterations=300")
      ->type_name("KEY=VALUE");
  app.add_option("--detector", shorthands.detector, "shorthand for --set features.detector=NAME --set features.descriptor=NAME");
  app.add_option("--max-features", shorthands.max_features, "shorthand for --set features.max_features=N");
  app.add_option("--covariance-scale", shorthands.scale, "shorthand for --set covariance.scale=S");
  app.add_option("--seed", shorthands.seed, "shorthand for --set seed=N");
  app.add_option("--log", options.log_path, "write the odometry CSV log here");
  app.add_option("--link", options.link,
                 "send MAVLink 2 odometry to the flight computer: udp://HOST:PORT or serial:///dev/ttyX[:BAUD] "
                 "(overrides link.uri)");
  app.add_option("--trajectory", options.trajectory_path, "write the integrated trajectory (TUM format) here");
  app.add_option("--groundtruth-allowance", options.groundtruth_allowance,
                 "noise of the ground truth allowed for in the covariance checks: auto (estimated from the "
                 "ground-truth file), none, or T_M,R_RAD per axis (e.g. 0.0003,0.0015)")
      ->capture_default_str();
  app.add_option("--evaluation", options.evaluation_path,
                 "write the per-pair evaluation against ground truth (errors, sigmas, NEES) as CSV here, for plots");
  app.add_option("--calibrate", options.calibration_path,
                 "measure the sensor's constants against the recording's ground truth (latencies, depth noise) and "
                 "write them with the whole configuration to this YAML file, for --config");
  app.add_option("--imu", options.imu_path,
                 "a replay's gyro, 'timestamp wx wy wz' lines (rad/s, body FRD, the recording's clock), against which "
                 "the frames' capture latency is measured and applied (default: imu.txt in the tum: directory, if any)")
      ->check(CLI::ExistingFile);
  app.add_option("--max-frames", options.max_frames, "stop after this many frames (0: all)")->check(CLI::NonNegativeNumber);
  app.add_flag("--start-at-groundtruth", options.start_at_groundtruth,
               "start the trajectory at the first frame's ground-truth pose");
  app.add_flag("-q,--quiet", options.quiet, "no per-pair lines, only the summary");
  app.add_flag("-v,--verbose", options.verbose, "per-pair stage times and counts");
}

}  // namespace

int main(int argc, char** argv) {
  rgbdo::RunOptions options;
  CLI::App app{"rgbd-odometry: frame-to-frame RGB-D odometry with a 6x6 covariance per pair"};
  app.set_version_flag("--version", std::string("rgbd-odometry ") + rgbdo::kVersion);
  add_exit_flags(app);
  bool print_config = false;
  app.add_flag("--print-config", print_config,
               "print the whole effective configuration (--config, then --set) as a commented YAML file that "
               "--config reads back, then exit");
  Shorthands shorthands;
  add_run_options(app, options, shorthands);
  CLI11_PARSE(app, argc, argv);
  // A kernel set forced by the environment that cannot run here is a usage error, not a
  // silent fallback: the user asked to measure or test that set.
  if (const std::string problem = rgbdo::simd::kernel_request_problem(); !problem.empty()) {
    std::cerr << "rgbd-odometry: " << problem << "\n";
    return 2;
  }
  shorthands.add_to(options.overrides);
  if (print_config) return rgbdo::print_configuration(options, std::cout, std::cerr);
  if (options.source.empty()) {
    std::cerr << "rgbd-odometry: --source is required (or --print-config, --print-kernels, --list-devices)\n";
    return 2;
  }
  // SIGINT / SIGTERM: finish the frame in hand, flush every output, print the summary.
  std::signal(SIGINT, rgbdo::on_stop_signal);
  std::signal(SIGTERM, rgbdo::on_stop_signal);
  return rgbdo::run_odometry(options, std::cout, std::cerr);
}
