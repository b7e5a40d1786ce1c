#!/usr/bin/env bash
# Builds the .deb of a build directory, unpacks it into a temporary root and checks what a
# deployment relies on: files and permissions, conffiles, maintainer scripts, the systemd
# unit (contents and systemd-analyze verify), the udev rule, and that the packaged binary
# replays the bundled frames (armhf: under qemu with the sysroot).
#
#   package_test.sh BUILD_DIR DEB_ARCH DATA_DIR [SYSROOT]
set -euo pipefail
build=$1 arch=$2 data=$3 sysroot=${4:-}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

(cd "$build" && cpack -G DEB -B "$work/out" >/dev/null) || fail "cpack could not build the package"
deb=$(ls "$work"/out/rgbd-odometry_*_"$arch".deb 2>/dev/null | head -n 1)
[ -n "$deb" ] || fail "no rgbd-odometry_*_$arch.deb produced"
root=$work/root
dpkg-deb -x "$deb" "$root"
dpkg-deb -e "$deb" "$root/DEBIAN"

[ "$(dpkg-deb -f "$deb" Architecture)" = "$arch" ] || fail "Architecture is not $arch"
dpkg-deb -f "$deb" Depends | grep -q libopencv-features2d406 || fail "Depends lacks the OpenCV runtime"

expect_file() {  # path mode
  [ -f "$root/$1" ] || fail "missing /$1"
  [ "$(stat -c %a "$root/$1")" = "$2" ] || fail "/$1 has mode $(stat -c %a "$root/$1"), expected $2"
}
expect_file usr/bin/rgbd-odometry 755
expect_file etc/rgbd-odometry/rgbd-odometry.yaml 644
expect_file etc/default/rgbd-odometry 644
expect_file lib/systemd/system/rgbd-odometry.service 644
expect_file lib/udev/rules.d/60-rgbd-odometry.rules 644
expect_file usr/lib/sysusers.d/rgbd-odometry.conf 644
expect_file usr/share/rgbd-odometry/config/tum-fr1.yaml 644
expect_file usr/share/doc/rgbd-odometry/README.md 644
expect_file usr/share/doc/rgbd-odometry/DEPLOY.md 644
expect_file usr/share/doc/rgbd-odometry/LOG_FORMAT.md 644
# The virtual sensor is a test tool: its own package, not the vehicle's.
[ -z "$(find "$root" -name 'libRgbdoVirtualSensor*')" ] || fail "the vehicle's package carries the virtual sensor"
dpkg-deb -f "$deb" Depends | grep -q libopenni2-0 || fail "Depends lacks the OpenNI2 runtime"
vdeb=$(ls "$work"/out/rgbd-odometry-virtual-sensor_*_"$arch".deb 2>/dev/null | head -n 1)
[ -n "$vdeb" ] || fail "no rgbd-odometry-virtual-sensor_*_$arch.deb produced"
vroot=$work/vroot
dpkg-deb -x "$vdeb" "$vroot"
driver=$(find "$vroot/usr/lib" -path '*/OpenNI2/Drivers/libRgbdoVirtualSensor.so.0' | head -n 1)
[ -n "$driver" ] || fail "the virtual sensor driver is not in an OpenNI2/Drivers directory of its package"
dpkg-deb -f "$vdeb" Depends | grep -q libopenni2-0 || fail "the virtual sensor's Depends lacks the OpenNI2 runtime"
[ -z "$(find "$vroot" -name rgbd-odometry -type f)" ] || fail "the virtual sensor's package carries the program"
for s in postinst prerm postrm; do expect_file "DEBIAN/$s" 755; done
grep -qx /etc/rgbd-odometry/rgbd-odometry.yaml "$root/DEBIAN/conffiles" || fail "config is not a conffile"
grep -qx /etc/default/rgbd-odometry "$root/DEBIAN/conffiles" || fail "/etc/default file is not a conffile"
grep -q "systemd-sysusers rgbd-odometry.conf" "$root/DEBIAN/postinst" || fail "postinst does not create the user"

# The binary is for the package's architecture (ELF e_machine: 0x3e x86-64, 0x28 ARM).
machine=$(od -An -tx1 -j18 -N1 "$root/usr/bin/rgbd-odometry" | tr -d ' ')
case "$arch" in amd64) want=3e ;; armhf) want=28 ;; *) want=unknown ;; esac
[ "$machine" = "$want" ] || fail "binary ELF machine 0x$machine does not match $arch"

unit=$root/lib/systemd/system/rgbd-odometry.service
for line in "User=rgbd-odometry" "Restart=on-failure" "CPUAffinity=4 5 6 7" "StandardOutput=journal" \
            "NoNewPrivileges=yes" "WantedBy=multi-user.target"; do
  grep -qx "$line" "$unit" || fail "unit lacks '$line'"
done
grep -q '^ExecStart=/usr/bin/rgbd-odometry --config /etc/rgbd-odometry/rgbd-odometry.yaml' "$unit" || fail "unit ExecStart"
if command -v systemd-analyze >/dev/null; then
  # verify resolves the unit's dependencies inside --root: give it the host's stock units.
  cp -an /lib/systemd/system/. "$root/lib/systemd/system/"
  out=$(systemd-analyze verify --root="$root" --man=no /lib/systemd/system/rgbd-odometry.service 2>&1) ||
    fail "systemd-analyze verify: $out"
  [ -z "$out" ] || fail "systemd-analyze verify complains: $out"
else
  fail "systemd-analyze not installed (deploy/setup.sh installs systemd)"
fi
rules=$root/lib/udev/rules.d/60-rgbd-odometry.rules
grep -q 'ATTR{idVendor}=="1d27", MODE="0660", GROUP="rgbd-odometry"' "$rules" || fail "udev rule for the sensor"
grep -q 'SUBSYSTEM=="tty"' "$rules" || fail "udev rule for the serial link"
grep -q '^u rgbd-odometry ' "$root/usr/lib/sysusers.d/rgbd-odometry.conf" || fail "sysusers entry"

# The packaged binary, with the packaged configuration, on the bundled real frames.
run=("$root/usr/bin/rgbd-odometry")
[ -z "$sysroot" ] || run=(qemu-arm-static -L "$sysroot" "${run[@]}")
out=$("${run[@]}" --source "tum:$data" --config "$root/usr/share/rgbd-odometry/config/tum-fr1.yaml" -q) ||
  fail "packaged binary exited non-zero"
echo "$out" | grep -q "39 pairs, 39 ok, 0 failed" || fail "packaged binary replay: $out"
echo "package $arch: $(basename "$deb") and $(basename "$vdeb") pass"
