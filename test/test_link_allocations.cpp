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

#include "rgbd_odometry/link/transport.hpp"
#include "pty_test_env.hpp"

namespace {
std::atomic<long> g_allocations{0};
}  // namespace

void* operator new(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

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
  int probe = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof a;
  ::bind(probe, reinterpret_cast<sockaddr*>(&a), sizeof a);
  ::getsockname(probe, reinterpret_cast<sockaddr*>(&a), &length);
  ::close(probe);  // nothing listens on that port now

  const auto link = open_link("udp://127.0.0.1:" + std::to_string(ntohs(a.sin_port)));
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

}  // namespace
}  // namespace rgbdo
