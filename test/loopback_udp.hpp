#pragma once
// Loopback UDP endpoints for the link tests: a socket on a port the kernel picks, and a port
// nothing listens on (bound once to learn it, then closed).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdint>

namespace rgbdo {

struct LoopbackUdpSocket {
  int fd = -1;
  std::uint16_t port = 0;
};

inline LoopbackUdpSocket bind_loopback_udp() {
  LoopbackUdpSocket s;
  s.fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof a;
  ::bind(s.fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  ::getsockname(s.fd, reinterpret_cast<sockaddr*>(&a), &length);
  s.port = ntohs(a.sin_port);
  return s;
}

inline std::uint16_t unused_loopback_udp_port() {
  const LoopbackUdpSocket s = bind_loopback_udp();
  ::close(s.fd);
  return s.port;
}

}  // namespace rgbdo
