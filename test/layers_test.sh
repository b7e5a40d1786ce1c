#!/usr/bin/env bash
# The layers of src/ and include/rgbd_odometry/ include only what they may (src/README.md).
# The linker already refuses a library that calls into a layer it does not
# link; this also catches headers: a thread or socket header in the math layer, OpenCV in the
# wire layer, a layer reaching up into one above it.
#   layers_test.sh REPO
set -u
repo=$1
failures=0

# layer: the project layers it may include, then the system headers it must not
allowed() {
  case $1 in
    core)     echo "core" ;;
    simd)     echo "core simd" ;;
    pipeline) echo "core simd pipeline" ;;
    io)       echo "core simd pipeline io" ;;
    eval)     echo "core simd pipeline io eval" ;;
    link)     echo "core link" ;;
    sensor)   echo "core simd pipeline io sensor" ;;
    runtime)  echo "core simd pipeline io runtime" ;;
    app)      echo "core simd pipeline io eval link sensor runtime app" ;;
  esac
}
forbidden() {
  local devices='OpenNI|Driver/Oni|libusb'
  local threads_and_wires='<thread>|<mutex>|<condition_variable>|<sys/socket.h>|<termios.h>|<netdb.h>|<pthread.h>'
  case $1 in
    core)     echo "opencv2|$devices|$threads_and_wires" ;;
    simd)     echo "opencv2|Eigen|$devices|$threads_and_wires" ;;
    pipeline) echo "$devices|$threads_and_wires" ;;
    io)       echo "$devices|$threads_and_wires" ;;
    eval)     echo "$devices|$threads_and_wires" ;;
    link)     echo "opencv2|$devices" ;;
    runtime)  echo "$devices" ;;
    *)        echo '^$' ;;
  esac
}

checked=0
for layer in core simd pipeline io eval link sensor runtime app; do
  # Every file below the layer's folders, sub-folders too (src/sensor/virtual_sensor/).
  files=$(find "$repo/src/$layer" "$repo/include/rgbd_odometry/$layer" \( -name '*.cpp' -o -name '*.hpp' \) 2>/dev/null)
  [ "$layer" = simd ] && files="$files $(find "$repo/simd" -name '*.cpp' -o -name '*.hpp')"
  for f in $files; do
    checked=$((checked + 1))
    while IFS= read -r line; do
      inc=${line#*rgbd_odometry/}
      used=${inc%%/*}
      if ! [[ " $(allowed "$layer") " == *" $used "* ]]; then
        echo "FAIL: ${f#$repo/} ($layer) includes the $used layer: $line"
        failures=$((failures + 1))
      fi
    done < <(grep -E '^#include "rgbd_odometry/' "$f")
    if bad=$(grep -E '^#include' "$f" | grep -E "$(forbidden "$layer")"); then
      echo "FAIL: ${f#$repo/} ($layer) includes what its layer must not: $bad"
      failures=$((failures + 1))
    fi
  done
done
echo "$checked files checked, $failures layering violations"
[ "$checked" -gt 50 ] && [ "$failures" -eq 0 ]
