#!/usr/bin/env bash
# One command from a fresh Debian bookworm machine: installs every build dependency from
# Debian's packages (skipped when already installed), builds, and runs the chosen job.
#
#   deploy/setup.sh demo    build, then replay the bundled fr1_xyz frames (the main job)
#   deploy/setup.sh test    build for x86-64 and armhf (Odroid-XU3), run the whole test suite
#                           natively, on armhf under qemu, natively again under
#                           AddressSanitizer + UndefinedBehaviorSanitizer with a bounded fuzzing
#                           of every parser of outside input (libFuzzer), then ThreadSanitizer
#   deploy/setup.sh bench   build, then run the Google Benchmark programs and the ARM cost
#                           model (the armhf build's instructions per frame, per stage)
#   deploy/setup.sh plots [TUM_DIR]
#                           build, replay TUM_DIR (default: the bundled frames) and plot its
#                           evaluation against ground truth into build/plots/ (error with +-1/3
#                           sigma per axis, NEES per pair and per 1-s window, trajectories)
#   deploy/setup.sh peer [TUM_DIR]
#                           build, replay TUM_DIR and estimate its pairs again with OpenCV's
#                           RgbdICPOdometry: how much of the error against ground truth both
#                           share, and how much is ours (bench/peer_check.py)
#   deploy/setup.sh blur [TUM_DIR [EXPOSURE_S]]
#                           build, replay TUM_DIR as recorded and with its colour frames
#                           motion-blurred over EXPOSURE_S (default 0.1) along their ground-truth
#                           motion: does the covariance still cover the error (bench/blur_check.py)
#   deploy/setup.sh fuzz-sweep [FIRST [LAST]]
#                           the test command's bounded fuzz runs again with seeds FIRST..LAST
#                           (default 2..13): more of what CI's one seed may reach (~10 min)
#   deploy/setup.sh deps    only install the dependencies
#
# Idempotent: re-running it re-uses the build directories under build/.
set -euo pipefail

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$repo"
jobs=${JOBS:-$(nproc)}

packages=(
  build-essential cmake ninja-build pkg-config
  libopencv-dev libeigen3-dev libcli11-dev libopenni2-dev libusb-1.0-0-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  python3-matplotlib
)
# The armhf cross build, its sysroot and emulators (qemu-user-static runs the armhf tests;
# qemu-user's dynamic qemu-arm loads the ARM cost model's plugin), systemd-analyze for the
# package test, and clang with libFuzzer for the fuzz targets.
cross_packages=(g++-arm-linux-gnueabihf mmdebstrap qemu-user-static qemu-user systemd clang libclang-rt-14-dev)

log() { printf '\n== %s\n' "$*"; }

# stage NAME COMMAND...: runs one stage of a job and records how long it took; the job ends
# with the table (stage_report), so a slow stage is seen before it costs CI its 90 minutes.
stage_times=()
stage() {
  local name=$1 start=$SECONDS
  shift
  "$@"
  stage_times+=("$(awk -v s=$((SECONDS - start)) -v n="$name" 'BEGIN { printf "%6.1f min  %s", s / 60, n }')")
}
stage_report() {
  log "stage times"
  printf '%s\n' "${stage_times[@]}"
}

install_dependencies() {
  local missing=()
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if [ ${#missing[@]} -eq 0 ]; then
    log "dependencies: all $# Debian packages present"
    return
  fi
  log "installing from Debian: ${missing[*]}"
  local sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    command -v sudo >/dev/null || { echo "setup.sh: not root and no sudo: cannot install ${missing[*]}" >&2; exit 1; }
    sudo=sudo
  fi
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

# build DIR [cmake options...]: everything, or with targets="A B" set, only those (a job
# builds what it runs: the demo's replay needs none of the tests and benchmarks).
build() {
  local dir=$1
  shift
  log "building $dir${targets:+ ($targets)}"
  # Ninja for a new build directory; one made before keeps the generator it was made with.
  local generator=(-G Ninja)
  [ -f "$dir/CMakeCache.txt" ] && generator=()
  cmake -S . -B "$dir" "${generator[@]}" -DRGBDO_WERROR=ON "$@" >/dev/null
  # shellcheck disable=SC2086  # targets: a list of names
  cmake --build "$dir" -j "$jobs" ${targets:+--target $targets}
}

run_demo() {
  targets=rgbd-odometry build build/release -DCMAKE_BUILD_TYPE=Release
  mkdir -p build/demo
  log "replaying the bundled frames (test/data/fr1_xyz, TUM RGB-D fr1_xyz, CC BY 4.0) with an autopilot's gyro made from its ground truth"
  build/release/rgbd-odometry --source tum:test/data/fr1_xyz --config deploy/config/tum-fr1.yaml \
    --imu test/data/imu/fr1_xyz.txt --log build/demo/odometry.csv --trajectory build/demo/trajectory.txt
  log "odometry log: build/demo/odometry.csv   trajectory: build/demo/trajectory.txt"
}

# The independent MAVLink decoder of the link tests: node-mavlink from the npm registry, at the
# versions pinned in test/mavlink_check/package-lock.json. Node.js itself: the machine's, or
# Debian's when there is none.
install_mavlink_checker() {
  command -v node >/dev/null && command -v npm >/dev/null || install_dependencies nodejs npm
  log "node-mavlink (test/mavlink_check, npm ci)"
  npm ci --prefix test/mavlink_check --no-audit --no-fund --loglevel=error
}

# ctest_in DIR NAME [ctest options...]: the suite in DIR, with a JUnit report build/junit/NAME.xml.
ctest_in() {
  local dir=$1 name=$2
  shift 2
  mkdir -p "$repo/build/junit"
  (cd "$dir" && ctest --output-on-failure -j "$jobs" --output-junit "$repo/build/junit/$name.xml" "$@")
}

# in_background NAME COMMAND...: starts a stage that waits on the network and the disk more
# than on the CPU, its output kept in build/logs/NAME.log; wait_background waits for every
# one started, and stops the job with the log of the first that failed.
background_names=() background_pids=()
# at_lowest_priority COMMAND...: COMMAND (a shell function too) at nice 19.
at_lowest_priority() {
  renice -n 19 -p "$BASHPID" >/dev/null
  "$@"
}
in_background() {
  local name=$1
  shift
  mkdir -p "$repo/build/logs"
  "$@" >"$repo/build/logs/$name.log" 2>&1 &
  background_names+=("$name") background_pids+=($!)
}
wait_background() {
  local i
  for i in "${!background_pids[@]}"; do
    if ! wait "${background_pids[$i]}"; then
      cat "$repo/build/logs/${background_names[$i]}.log" >&2
      echo "setup.sh: ${background_names[$i]} failed" >&2
      exit 1
    fi
    cat "$repo/build/logs/${background_names[$i]}.log"
  done
  background_names=() background_pids=()
}

run_tests() {
  stage "node-mavlink" install_mavlink_checker
  # The armhf sysroot (downloads and unpacking) comes in while the native build compiles.
  in_background armhf-sysroot deploy/armhf-sysroot.sh "$repo/build/sysroot-armhf"
  # The native build also compares its replay with the armhf binary's (cross_arch_replay_matches).
  # It builds and runs only what no other stage runs (RGBDO_NATIVE_STAGE, test/CMakeLists.txt):
  # the studies, the allocation counts and the release program's own checks.
  stage "native build" build build/release -DCMAKE_BUILD_TYPE=Release -DRGBDO_ARMHF_BUILD_DIR="$repo/build/armhf" \
    -DRGBDO_SYSROOT="$repo/build/sysroot-armhf" -DRGBDO_NATIVE_STAGE=ON
  stage "armhf sysroot (the rest of)" wait_background
  # No benchmarks in the armhf build: no test runs them there (the ARM cost model measures
  # the armhf rgbd-odometry itself). The studies run natively only, and each test program
  # whole, as one process: under qemu a process's start is dear (test/CMakeLists.txt).
  stage "armhf build" build build/armhf -DCMAKE_BUILD_TYPE=Release -DCMAKE_TOOLCHAIN_FILE=toolchains/armhf-cortex-a15.cmake \
    -DRGBDO_SYSROOT="$repo/build/sysroot-armhf" -DRGBDO_BUILD_BENCHMARKS=OFF -DRGBDO_STUDIES=OFF -DRGBDO_TEST_WHOLE_PROGRAMS=ON
  # Sanitised build: memory errors and undefined behaviour must never land. One clang build
  # carries the suite and the libFuzzer targets (test/fuzz: every parser of outside input; its
  # suite replays their kept crash inputs, then fuzzes each from its seeds for a fixed number
  # of runs with a fixed seed). The tests that load the vendor OpenNI2 libraries, which have no
  # frame pointers, unwind their leak stacks in full (test/CMakeLists.txt, test/lsan.supp).
  # It compiles at the lowest priority while the native and armhf suites run: they wait on
  # their recordings' real time for a quarter to a half of it, and the compiler takes only
  # what they leave (their verdicts rest on counts and order, not on an idle machine).
  in_background asan-build at_lowest_priority build_sanitized
  log "test suite, native release build (x86-64)"
  stage "native suite" ctest_in build/release native
  log "test suite, armhf build under qemu-arm-static"
  stage "armhf suite (qemu)" ctest_in build/armhf armhf
  stage "ASan+UBSan+fuzz build (the rest of)" wait_background
  log "test suite and bounded fuzzing, AddressSanitizer + UndefinedBehaviorSanitizer"
  export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    LSAN_OPTIONS=suppressions="$repo/test/lsan.supp"
  # The live gyro test measures a latency that a load starting or stopping beside it moves
  # (test/CMakeLists.txt): it runs first, alone, before the TSan build starts beside the rest.
  stage "ASan+UBSan live gyro test (alone)" ctest_in build/sanitize sanitize-gyro -L alone
  # ThreadSanitizer: data races and lock-order inversions in the threaded pipeline, the
  # hand-overs, the worker pool, the links and the device clock must never land. Reports
  # inside the vendor libraries we do not build are suppressed by library name
  # (test/tsan.supp); the options also reach the test binaries run at build time (test
  # discovery). Every test that starts a thread runs here, the live ones too: they stop on
  # events and assert counts and order, so TSan's 5-15x slowdown (or a busy machine) changes
  # no verdict. The test programs that never start a thread are not built here
  # (test/CMakeLists.txt: rgbdo_single_threaded_tests), nor the studies (run natively).
  # clang's TSan: measured here, it builds in 1.7 min against GCC's 2.6 and runs the suite in
  # about half the time. It compiles at the lowest priority while the ASan suite runs, whose
  # live tests leave a fifth of the two cores idle.
  in_background tsan-build at_lowest_priority build_thread_sanitized
  stage "ASan+UBSan suite" ctest_in build/sanitize sanitize -LE alone
  unset ASAN_OPTIONS UBSAN_OPTIONS LSAN_OPTIONS
  stage "TSan build (the rest of)" wait_background
  log "test suite, ThreadSanitizer"
  TSAN_OPTIONS=$tsan_options stage "TSan suite" ctest_in build/tsan tsan
  stage_report
}

# build_sanitized [TARGET...]: the clang ASan + UBSan build with the fuzz targets (Debian's
# clang and its compiler-rt carry libFuzzer); with targets, only those.
build_sanitized() {
  CC=clang CXX=clang++ targets="$*" build build/sanitize -DRGBDO_FUZZ=ON -DRGBDO_BUILD_BENCHMARKS=OFF \
    -DRGBDO_STUDIES=OFF -DRGBDO_TEST_WHOLE_PROGRAMS=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo
}

# build_thread_sanitized: the clang ThreadSanitizer build of the threaded test programs (its
# options reach the programs run at build time: test discovery).
tsan_options="suppressions=$repo/test/tsan.supp halt_on_error=1 second_deadlock_stack=1"
build_thread_sanitized() {
  TSAN_OPTIONS=$tsan_options CC=clang CXX=clang++ build build/tsan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DRGBDO_SANITIZE_THREAD=ON \
    -DRGBDO_BUILD_BENCHMARKS=OFF -DRGBDO_STUDIES=OFF -DRGBDO_TEST_WHOLE_PROGRAMS=ON
}

# The test command's bounded runs again, with seeds FIRST..LAST: the fixed seed fixes the run
# count, not what libFuzzer explores, and CI once reached an input two runs here had not. It
# stops at the first finding, whose input stays in build/sanitize/test/fuzz/work/TARGET/artifacts/.
run_fuzz_sweep() {
  local first=${1:-2} last=${2:-13}
  if [[ ! $first =~ ^[0-9]+$ || ! $last =~ ^[0-9]+$ ]]; then
    echo "fuzz-sweep: seeds must be whole numbers (got '$first' '$last')" >&2
    exit 2
  fi
  build_sanitized fuzz_config_file fuzz_config_overrides fuzz_tum_sequence fuzz_imu_file fuzz_uris fuzz_images fuzz_mavlink
  local seed
  for ((seed = first; seed <= last; seed++)); do
    log "fuzzing every target with seed $seed"
    (cd build/sanitize && RGBDO_FUZZ_SEED=$seed UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
      ctest --output-on-failure -j "$jobs" -R _bounded_run)
  done
}

run_plots() {
  local dir=${1:-test/data/fr1_xyz}
  local name
  name=$(basename "$dir")
  targets=rgbd-odometry build build/release -DCMAKE_BUILD_TYPE=Release
  mkdir -p build/plots
  log "replaying $dir with the evaluation against its ground truth (allowance 0.3 mm, 0.0015 rad)"
  build/release/rgbd-odometry --source "tum:$dir" --config deploy/config/tum-fr1.yaml -q \
    --groundtruth-allowance 0.0003,0.0015 --evaluation "build/plots/$name.csv"
  bench/plot_evaluation.py "build/plots/$name.csv" "build/plots/$name" "$name"
  log "plots: build/plots/${name}_errors.png ${name}_nees.png ${name}_trajectory.png"
}

run_peer() {
  local dir=${1:-test/data/fr1_xyz}
  targets="rgbd-odometry peer_odometry" build build/release -DCMAKE_BUILD_TYPE=Release
  mkdir -p build/peer
  log "$dir: our odometry and OpenCV's RgbdICPOdometry, each against the ground truth and each other"
  bench/peer_check.sh "$dir" deploy/config/tum-fr1.yaml build/release/rgbd-odometry \
    build/release/bench/peer_odometry "build/peer/$(basename "$dir")"
}

run_blur() {
  local dir=${1:-test/data/fr1_xyz}
  local exposure=${2:-0.1}
  targets=rgbd-odometry build build/release -DCMAKE_BUILD_TYPE=Release
  log "$dir: as recorded and blurred over $exposure s, each against the ground truth"
  bench/blur_check.sh "$dir" deploy/config/tum-fr1.yaml build/release/rgbd-odometry "$exposure" \
    "build/blur/$(basename "$dir")"
}

run_benchmarks() {
  deploy/armhf-sysroot.sh "$repo/build/sysroot-armhf"
  build build/armhf -DCMAKE_BUILD_TYPE=Release -DCMAKE_TOOLCHAIN_FILE=toolchains/armhf-cortex-a15.cmake \
    -DRGBDO_SYSROOT="$repo/build/sysroot-armhf"
  build build/release -DCMAKE_BUILD_TYPE=Release -DRGBDO_ARMHF_BUILD_DIR="$repo/build/armhf" \
    -DRGBDO_SYSROOT="$repo/build/sysroot-armhf"
  log "benchmarks (one thread, PNG decoding excluded)"
  for b in build/release/bench/bench_*; do "$b" --benchmark_counters_tabular=true; done
  log "ARM cost model: the armhf build under qemu-arm, instructions per frame by stage"
  (cd build/release && ctest -R arm_cost_within_budget -V | sed -n 's/^[0-9]*: //p')
}

job=${1:-}
case "$job" in
  deps) install_dependencies "${packages[@]}" "${cross_packages[@]}" ;;
  demo) install_dependencies "${packages[@]}"; run_demo ;;
  test) install_dependencies "${packages[@]}" "${cross_packages[@]}"; run_tests ;;
  bench) install_dependencies "${packages[@]}" "${cross_packages[@]}"; run_benchmarks ;;
  plots) install_dependencies "${packages[@]}"; run_plots "${2:-}" ;;
  peer) install_dependencies "${packages[@]}"; run_peer "${2:-}" ;;
  blur) install_dependencies "${packages[@]}"; run_blur "${2:-}" "${3:-}" ;;
  fuzz-sweep) install_dependencies "${packages[@]}" "${cross_packages[@]}"; run_fuzz_sweep "${2:-}" "${3:-}" ;;
  *) echo "usage: deploy/setup.sh demo|test|bench|plots [TUM_DIR]|peer [TUM_DIR]|blur [TUM_DIR [EXPOSURE_S]]|fuzz-sweep [FIRST [LAST]]|deps" >&2; exit 2 ;;
esac
