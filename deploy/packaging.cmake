# Debian packages (CPack): `cpack -G DEB` in a build directory, native or armhf, makes two:
#  - rgbd-odometry: the program and what the vehicle runs it with (component `main`);
#  - rgbd-odometry-virtual-sensor: the OpenNI2 driver that replays a recording as a device, a
#    test and replay tool (component `virtualsensor`). Kept out of the vehicle's package, so
#    that `--list-devices` on the drone shows only real sensors.
include(GNUInstallDirs)
install(TARGETS rgbd-odometry RUNTIME DESTINATION bin COMPONENT main)
install(FILES deploy/config/xtion.yaml DESTINATION /etc/rgbd-odometry RENAME rgbd-odometry.yaml COMPONENT main)
install(FILES deploy/default.env DESTINATION /etc/default RENAME rgbd-odometry COMPONENT main)
install(FILES deploy/systemd/rgbd-odometry.service DESTINATION /lib/systemd/system COMPONENT main)
install(FILES deploy/udev/60-rgbd-odometry.rules DESTINATION /lib/udev/rules.d COMPONENT main)
install(FILES deploy/sysusers.conf DESTINATION /usr/lib/sysusers.d RENAME rgbd-odometry.conf COMPONENT main)
install(FILES deploy/config/tum-fr1.yaml deploy/config/xtion.yaml DESTINATION ${CMAKE_INSTALL_DATADIR}/rgbd-odometry/config
        COMPONENT main)
install(FILES README.md DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/rgbd-odometry COMPONENT main)
# The autopilot set-up (PX4, ArduPilot) and the deploy notes, beside the user's guide.
install(FILES deploy/README.md DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/rgbd-odometry RENAME DEPLOY.md COMPONENT main)
# The odometry log's format, which every consumer of --log reads.
install(FILES src/io/LOG_FORMAT.md DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/rgbd-odometry COMPONENT main)
# The virtual sensor, where OpenNI2 looks for drivers: `--source openni://rgbdo-virtual:DIR`.
install(TARGETS RgbdoVirtualSensor LIBRARY DESTINATION lib/${CMAKE_LIBRARY_ARCHITECTURE}/OpenNI2/Drivers
        COMPONENT virtualsensor)

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME rgbd-odometry)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL main virtualsensor)
set(CPACK_DEBIAN_MAIN_PACKAGE_NAME rgbd-odometry)
set(CPACK_DEBIAN_VIRTUALSENSOR_PACKAGE_NAME rgbd-odometry-virtual-sensor)
set(CPACK_COMPONENT_VIRTUALSENSOR_DESCRIPTION
    "OpenNI2 driver replaying a TUM RGB-D recording as a live sensor, for tests and replays (not for the vehicle)")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_CONTACT "rgbd-odometry maintainers <rgbd-odometry@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "RGB-D visual odometry with covariance for flight controllers")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_STRIP_FILES TRUE)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
if(CMAKE_CROSSCOMPILING AND CMAKE_SYSTEM_PROCESSOR MATCHES "^arm")
  set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE armhf)
endif()
# Bookworm's runtime packages of what the binary links (dpkg-shlibdeps cannot run on a
# cross build without the target's dpkg database).
set(CPACK_DEBIAN_MAIN_PACKAGE_DEPENDS
  "libc6 (>= 2.36), libstdc++6 (>= 12), libopencv-core406, libopencv-imgproc406, libopencv-imgcodecs406, libopencv-features2d406, libopencv-calib3d406, libopenni2-0, libusb-1.0-0, systemd")
set(CPACK_DEBIAN_VIRTUALSENSOR_PACKAGE_DEPENDS
  "libc6 (>= 2.36), libstdc++6 (>= 12), libopencv-core406, libopencv-imgproc406, libopencv-imgcodecs406, libopenni2-0")
set(CPACK_DEBIAN_MAIN_PACKAGE_CONTROL_EXTRA
  "${CMAKE_CURRENT_SOURCE_DIR}/deploy/debian/conffiles;${CMAKE_CURRENT_SOURCE_DIR}/deploy/debian/postinst;${CMAKE_CURRENT_SOURCE_DIR}/deploy/debian/prerm;${CMAKE_CURRENT_SOURCE_DIR}/deploy/debian/postrm")
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION TRUE)
include(CPack)
