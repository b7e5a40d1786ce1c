# Cross toolchain for the Odroid-XU3 (Exynos 5422: Cortex-A15 + A7, ARMv7-A, NEON/VFPv4,
# hard float, Debian armhf). Point RGBDO_SYSROOT (cache or environment) at an armhf sysroot.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR armv7l)

if(NOT RGBDO_SYSROOT)
  set(RGBDO_SYSROOT "$ENV{RGBDO_SYSROOT}")
endif()
# try_compile re-reads this file in a fresh project: hand the sysroot on to it.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES RGBDO_SYSROOT)
if(NOT RGBDO_SYSROOT)
  message(FATAL_ERROR "armhf toolchain: set RGBDO_SYSROOT to an armhf sysroot")
endif()

set(CMAKE_C_COMPILER arm-linux-gnueabihf-gcc)
set(CMAKE_CXX_COMPILER arm-linux-gnueabihf-g++)
set(CMAKE_SYSROOT "${RGBDO_SYSROOT}")

# Tuned for the A15 cores the service is pinned to; runs on the A7s too.
set(CMAKE_C_FLAGS_INIT "-mcpu=cortex-a15 -mfpu=neon-vfpv4 -mfloat-abi=hard")
set(CMAKE_CXX_FLAGS_INIT "-mcpu=cortex-a15 -mfpu=neon-vfpv4 -mfloat-abi=hard")

set(CMAKE_FIND_ROOT_PATH "${RGBDO_SYSROOT}")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# ctest runs the armhf test binaries under user-mode emulation.
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-arm-static -L "${RGBDO_SYSROOT}")
