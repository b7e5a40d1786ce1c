#!/usr/bin/env bash
# Builds the Debian bookworm armhf sysroot the cross build links against and qemu runs the
# armhf tests in (toolchains/armhf-cortex-a15.cmake). Idempotent: when the sysroot already
# holds this recipe's package list it returns at once.
#
#   deploy/armhf-sysroot.sh [DIR]      (default: build/sysroot-armhf)
#
# Packages come from the host's own Debian mirror, minus the security suite (its armhf index
# can lag the main one, which breaks dependency resolution). Nothing is added to the host's
# dpkg architectures: mmdebstrap's extract variant unpacks into DIR only.
set -euo pipefail

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
dest=${1:-$repo/build/sysroot-armhf}
triplet=arm-linux-gnueabihf

# Every -dev package the project links, with the C/C++ runtime the cross compiler expects.
packages=(
  libc6-dev libstdc++-12-dev
  libopencv-dev libeigen3-dev libcli11-dev libopenni2-dev libusb-1.0-0-dev
  libgtest-dev libgmock-dev libbenchmark-dev
)
recipe_version=4
want="v$recipe_version $(printf '%s ' "${packages[@]}")"
stamp="$dest/.rgbdo-sysroot"
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
  echo "armhf sysroot: $dest is current"
  exit 0
fi

mapfile -t sources < <(apt-get indextargets --format '$(REPO_URI) $(RELEASE) $(COMPONENT)' 'Identifier: Packages' |
  sort -u | awk '$2 !~ /-security$/ && $1 ~ /debian/ { print "deb " $1 " " $2 " " $3 }')
if [ ${#sources[@]} -eq 0 ]; then
  echo "armhf-sysroot.sh: no Debian apt source configured on this host (run apt-get update?)" >&2
  exit 1
fi
echo "armhf sysroot: extracting ${packages[*]} into $dest"
printf '  from: %s\n' "${sources[@]}"

tmp="$dest.partial"
rm -rf "$tmp"
mkdir -p "$(dirname "$dest")"
include=$(IFS=,; echo "${packages[*]}")
mmdebstrap --quiet --variant=extract --arch=armhf --include="$include" bookworm "$tmp" "${sources[@]}"

# Absolute symlinks point into the host once the tree is used as a sysroot: make them relative.
while IFS= read -r -d '' link; do
  target=$(readlink "$link")
  case "$target" in
    /*) ln -sfn "$(realpath -m --relative-to="$(dirname "$link")" "$tmp$target")" "$link" ;;
  esac
done < <(find "$tmp" -type l -print0)

# libblas.so.3 / liblapack.so.3 are update-alternatives links made by maintainer scripts,
# which the extract variant does not run; OpenCV's libraries need them at link and run time.
libdir="$tmp/usr/lib/$triplet"
for lib in blas lapack; do
  if [ ! -e "$libdir/lib$lib.so.3" ]; then
    provider=$(cd "$libdir" && ls -d */lib$lib.so.3 2>/dev/null | sort | head -n 1 || true)
    [ -n "$provider" ] || { echo "armhf-sysroot.sh: no provider for lib$lib.so.3 in the sysroot" >&2; exit 1; }
    ln -sfn "$provider" "$libdir/lib$lib.so.3"
  fi
done

# mmdebstrap leaves device nodes in dev/. qemu-arm-static -L looks every path up in the sysroot
# first, so the armhf tests would open the sysroot's dev/ptmx, dev/null... and on a filesystem
# mounted nodev (as build trees often are) that fails with ENODEV. Without them qemu falls
# through to the host's /dev. Nothing is compiled or linked against dev/.
rm -rf "${tmp:?}/dev"

echo "$want" > "$tmp/.rgbdo-sysroot"
rm -rf "$dest"
mv "$tmp" "$dest"
echo "armhf sysroot: ready ($(du -sh "$dest" | cut -f1))"
