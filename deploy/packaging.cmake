# Debian packages (CPack): `cpack -G DEB` in a build directory, native or armhf.
include(GNUInstallDirs)
install(FILES deploy/config/xtion.yaml DESTINATION /etc/rgbd-odometry RENAME rgbd-odometry.yaml)
install(FILES deploy/default.env DESTINATION /etc/default RENAME rgbd-odometry)
install(FILES deploy/systemd/rgbd-odometry.service DESTINATION /lib/systemd/system)
install(FILES deploy/udev/60-rgbd-odometry.rules DESTINATION /lib/udev/rules.d)
install(FILES deploy/sysusers.conf DESTINATION /usr/lib/sysusers.d RENAME rgbd-odometry.conf)
install(FILES deploy/config/tum-fr1.yaml deploy/config/xtion.yaml DESTINATION ${CMAKE_INSTALL_DATADIR}/rgbd-odometry/config)
# The virtual sensor, where OpenNI2 looks for drivers: `--source openni://rgbdo-virtual:DIR`.
install(TARGETS RgbdoVirtualSensor LIBRARY DESTINATION lib/${CMAKE_LIBRARY_ARCHITECTURE}/OpenNI2/Drivers)
install(FILES README.md DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/rgbd-odometry)
# The autopilot set-up (PX4, ArduPilot) and the deploy notes, beside the user's guide.
install(FILES deploy/README.md DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/rgbd-odometry RENAME DEPLOY.md)

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME rgbd-odometry)
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
set(CPACK_DEBIAN_PACKAGE_DEPENDS
  "libc6 (>= 2.36), libstdc++6 (>= 12), libopencv-core406, libopencv-imgproc406, libopencv-imgcodecs406, libopencv-features2d406, libopencv-calib3d406, libopenni2-0, libusb-1.0-0, systemd")
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
  "${CMAKE_CURRENT_SOURCE_DIR}/deploy/debian/conffiles;${CMAKE_CURRENT_SOURCE_DIR}/deploy/debian/postinst;${CMAKE_CURRENT_SOURCE_DIR}/deploy/debian/prerm;${CMAKE_CURRENT_SOURCE_DIR}/deploy/debian/postrm")
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION TRUE)
include(CPack)
