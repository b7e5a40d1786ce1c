// send() allocates nothing after the link is open, on any thread, including when things go
// wrong: a UDP peer refusing every other datagram (problem reports on the send path) and a
// serial peer that reads nothing (a full queue, drops, problem reports, a writer thread waiting
// for room). Global operator new is replaced by a counting forward to malloc; everything the
// links own is C++ (the system calls they make do not allocate).
//
// Like test_allocations.cpp, not for sanitizer builds: AddressSanitizer owns the allocator.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <pty.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <new>
#include <thread>

#include <gtest/gtest.h>

#include "loopback_udp.hpp"
#include "rgbd_odometry/app/config.hpp"
#include "rgbd_odometry/link/flight_link.hpp"
#include "rgbd_odometry/link/transport.hpp"
#include "pty_test_env.hpp"

namespace {
std::atomic<long> g_allocations{0};
}  // namespace

// GCC 12 (at -O1, the test programs' level) takes these replacements' own free() for a
// mismatch with operator new: they are the pair, by definition.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif
void* operator new(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

namespace rgbdo {
namespace {

std::array<std::uint8_t, kMaxLinkFrameBytes> g_frame{};

// Allocations made anywhere in the process while `run` runs.
template <typename Run>
long allocations_during(Run run) {
  const long before = g_allocations.load();
  run();
  return g_allocations.load() - before;
}

TEST(LinkAllocations, UdpSendToARefusingPeerAllocatesNothing) {
  // Nothing listens on that port now.
  const auto link = open_link("udp://127.0.0.1:" + std::to_string(unused_loopback_udp_port()));
  const long n = allocations_during([&] {
    for (int i = 0; i < 1000; ++i) link->send(g_frame);
  });
  EXPECT_EQ(n, 0);
  EXPECT_GT(link->stats().errors, 0u);  // the failure path was exercised
}

TEST(LinkAllocations, SerialSendToAPeerThatDoesNotReadAllocatesNothing) {
  int master = -1, slave = -1;
  char name[256] = {};
  ASSERT_EQ(::openpty(&master, &slave, name, nullptr, nullptr), 0) << "openpty: " << std::strerror(errno);
  ::close(slave);
  SerialLinkOptions o;
  o.device_path = name;
  o.baud = link_test::fastest_test_baud();
  o.queue_frames = 16;
  const auto link = open_serial_link(o);
  const long n = allocations_during([&] {
    for (int i = 0; i < 2000; ++i) link->send(g_frame);
    std::this_thread::sleep_for(std::chrono::milliseconds(250));  // the writer waits for room meanwhile
  });
  EXPECT_EQ(n, 0);
  EXPECT_GT(link->stats().frames_dropped_queue_full, 0u);
  ::close(master);
}

// The receiver: a flood of TIMESYNC requests (each answered at once, from the receiver
// thread), heartbeats and noise costs no allocation once the link is up.
TEST(LinkAllocations, ReceiverAnsweringAFloodAllocatesNothing) {
  const LoopbackUdpSocket autopilot = bind_loopback_udp();
  const int peer = autopilot.fd;
  Config config;
  config.link.uri = "udp://127.0.0.1:" + std::to_string(autopilot.port);
  FlightLink flight(config.link, config.body);
  flight.tick(0);  // the heartbeat tells us the link's source address
  sockaddr_in from{};
  socklen_t from_length = sizeof from;
  std::uint8_t buffer[512];
  ASSERT_GT(::recvfrom(peer, buffer, sizeof buffer, 0, reinterpret_cast<sockaddr*>(&from), &from_length), 0);
  ::connect(peer, reinterpret_cast<sockaddr*>(&from), from_length);
  // A TIMESYNC request from system 1 component 1 (CRC_EXTRA 34), ts1 = 1, trimmed to 9 bytes.
  mavlink::Framer framer(1, 1);
  mavlink::FrameBuffer request{};
  mavlink::Timesync ask;
  ask.ts1 = 1;
  const std::size_t n = framer.encode(ask, request);
  std::uint8_t noise[200];
  for (std::size_t i = 0; i < sizeof noise; ++i) noise[i] = static_cast<std::uint8_t>(i * 37 + 0xFD * (i % 7 == 0));
  // Warm-up: the first answer (the receiver's first frame) and the peer settled.
  ::send(peer, request.data(), n, 0);
  ASSERT_GT(::recv(peer, buffer, sizeof buffer, 0), 0);
  const long allocations = allocations_during([&] {
    for (int i = 0; i < 2000; ++i) {
      ::send(peer, request.data(), n, 0);
      ::send(peer, noise, sizeof noise, 0);
      if (i % 50 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));  // let the receiver keep up
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
  });
  EXPECT_EQ(allocations, 0);
  EXPECT_GT(flight.receive_stats().timesync_requests_answered, 100u);
  ::close(peer);
}

}  // namespace
}  // namespace rgbdo
