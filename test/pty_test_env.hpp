#pragma once
// What the pseudo-terminals of the machine running the serial tests can carry.
//
// The armhf tests run under qemu-user, whose termios translation (qemu 7.2, bookworm) knows
// speeds only up to 460800 baud: a faster one set through it comes back changed, and the link
// then reports, rightly, that "the driver does not support this baud". A real ARM kernel's pty
// and USB-serial drivers carry them all. The probe below asks the pty directly, without the
// code under test, so the tests pick the fastest baud the environment can represent and hold
// the link to the error it must give for the others.
#include <pty.h>
#include <termios.h>
#include <unistd.h>

namespace rgbdo::link_test {

inline bool pty_carries_speed(speed_t speed) {
  int master = -1, slave = -1;
  if (::openpty(&master, &slave, nullptr, nullptr, nullptr) != 0) return false;
  termios tio{};
  ::tcgetattr(slave, &tio);
  ::cfmakeraw(&tio);
  ::cfsetispeed(&tio, speed);
  ::cfsetospeed(&tio, speed);
  termios applied{};
  const bool carried = ::tcsetattr(slave, TCSANOW, &tio) == 0 && ::tcgetattr(slave, &applied) == 0 &&
                       ::cfgetospeed(&applied) == speed;
  ::close(slave);
  ::close(master);
  return carried;
}

// 921600 (the flight-controller default this project documents) wherever the pty carries it.
inline int fastest_test_baud() {
  static const int baud = pty_carries_speed(B921600) ? 921600 : 460800;
  return baud;
}

}  // namespace rgbdo::link_test
