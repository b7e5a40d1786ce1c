// The UDP link (src/link/transport_udp.cpp) over real loopback sockets: frames arrive whole, byte-exact
// and in order; a peer that is not listening is reported without blocking or throwing, and
// receives the frames once it starts listening.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "loopback_udp.hpp"
#include "rgbd_odometry/link/transport.hpp"
#include "link_test_frames.hpp"

namespace rgbdo {
namespace {

using link_test::Bytes;
using link_test::make_frame;
using Clock = std::chrono::steady_clock;

// A UDP socket bound on the loopback address: the flight computer's end.
class Receiver {
 public:
  explicit Receiver(int family = AF_INET, std::uint16_t port = 0) {
    fd_ = ::socket(family, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (family == AF_INET6) {
      sockaddr_in6 a{};
      a.sin6_family = AF_INET6;
      a.sin6_addr = in6addr_loopback;
      a.sin6_port = htons(port);
      bound_ = ::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
    } else {
      sockaddr_in a{};
      a.sin_family = AF_INET;
      a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
      a.sin_port = htons(port);
      bound_ = ::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
    }
    sockaddr_storage a{};
    socklen_t length = sizeof a;
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &length);
    port_ = ntohs(family == AF_INET6 ? reinterpret_cast<sockaddr_in6&>(a).sin6_port
                                     : reinterpret_cast<sockaddr_in&>(a).sin_port);
  }
  ~Receiver() { ::close(fd_); }
  Receiver(const Receiver&) = delete;
  Receiver& operator=(const Receiver&) = delete;

  bool bound() const { return bound_; }
  std::uint16_t port() const { return port_; }

  // The next datagram, or nothing within the timeout. `from_port` gets the sender's port.
  std::optional<Bytes> receive(int timeout_ms, std::uint16_t* from_port = nullptr) {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, timeout_ms) <= 0) return std::nullopt;
    Bytes buffer(2048);
    sockaddr_storage from{};
    socklen_t length = sizeof from;
    const ssize_t n = ::recvfrom(fd_, buffer.data(), buffer.size(), 0, reinterpret_cast<sockaddr*>(&from), &length);
    if (n < 0) return std::nullopt;
    buffer.resize(static_cast<std::size_t>(n));
    if (from_port != nullptr) *from_port = ntohs(reinterpret_cast<sockaddr_in&>(from).sin_port);
    return buffer;
  }

 private:
  int fd_ = -1;
  bool bound_ = false;
  std::uint16_t port_ = 0;
};

// A loopback port with nothing bound to it (it was bound a moment ago, then released).
std::uint16_t closed_port() {
  Receiver r;
  return r.port();
}

std::string udp_uri(std::uint16_t port) { return "udp://127.0.0.1:" + std::to_string(port); }

TEST(UdpLink, FramesArriveByteExactAndInOrder) {
  Receiver receiver;
  ASSERT_TRUE(receiver.bound());
  const auto link = open_link(udp_uri(receiver.port()));
  EXPECT_TRUE(link->stats().link_up);

  std::vector<Bytes> sent;
  for (std::uint32_t seq = 0; seq < 200; ++seq) {
    sent.push_back(make_frame(seq, 1 + (seq * 37) % kMaxLinkFrameBytes));  // 1 to 280 bytes
    ASSERT_EQ(link->send(sent.back()), SendResult::Sent) << seq;
  }
  for (std::size_t i = 0; i < sent.size(); ++i) {
    const auto got = receiver.receive(2000);
    ASSERT_TRUE(got.has_value()) << "frame " << i << " did not arrive";
    ASSERT_EQ(*got, sent[i]) << "frame " << i;
  }
  EXPECT_FALSE(receiver.receive(50).has_value());  // nothing more

  const LinkStats s = link->stats();
  EXPECT_EQ(s.frames_sent, sent.size());
  std::uint64_t bytes = 0;
  for (const Bytes& f : sent) bytes += f.size();
  EXPECT_EQ(s.bytes_sent, bytes);
  EXPECT_EQ(s.frames_dropped_queue_full + s.frames_dropped_link_down + s.frames_rejected + s.errors, 0u);
  EXPECT_EQ(link->last_problem(), "");
}

TEST(UdpLink, ClosedPortIsReportedAndTheFramesFlowOnceAReceiverBinds) {
  // GIVEN a link to a port nobody listens on
  const std::uint16_t port = closed_port();
  const auto link = open_link(udp_uri(port));

  // WHEN frames are sent (spaced so the ICMP port-unreachable of one is back before the next)
  std::uint32_t seq = 0;
  for (; seq < 20; ++seq) {
    link->send(make_frame(seq, 100));
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  // THEN the refusal is counted and reported, and every send returned
  LinkStats s = link->stats();
  EXPECT_GE(s.errors, 1u);
  EXPECT_GE(s.frames_dropped_link_down, 1u);
  EXPECT_EQ(s.frames_sent + s.frames_dropped_link_down, 20u);
  EXPECT_GE(s.problem_reports, 1u);
  EXPECT_NE(link->last_problem().find("refused"), std::string::npos) << link->last_problem();
  EXPECT_NE(link->last_problem().find("127.0.0.1:" + std::to_string(port)), std::string::npos) << link->last_problem();

  // WHEN a receiver binds the port
  Receiver receiver(AF_INET, port);
  ASSERT_TRUE(receiver.bound()) << "port " << port << " was taken in the meantime";
  // THEN frames arrive (the first send may still collect the last refusal)
  std::optional<Bytes> first;
  const auto deadline = Clock::now() + std::chrono::seconds(5);
  while (!first && Clock::now() < deadline) {
    link->send(make_frame(seq++, 100));
    first = receiver.receive(20);
  }
  ASSERT_TRUE(first.has_value()) << "no frame reached the new receiver";
  while (receiver.receive(20)) {
  }
  // and from then on every frame, in order
  for (std::uint32_t i = 0; i < 10; ++i) EXPECT_EQ(link->send(make_frame(1000 + i, 100)), SendResult::Sent);
  for (std::uint32_t i = 0; i < 10; ++i) {
    const auto got = receiver.receive(2000);
    ASSERT_TRUE(got.has_value());
    EXPECT_EQ(*got, make_frame(1000 + i, 100));
  }
  EXPECT_TRUE(link->stats().link_up);
}

TEST(UdpLink, RepeatedRefusalsRaiseTheReportCountOncePerSecondAtMost) {
  const auto link = open_link(udp_uri(closed_port()));
  for (int i = 0; i < 40; ++i) {
    link->send(make_frame(i, 20));
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  const LinkStats s = link->stats();
  EXPECT_GE(s.errors, 10u);
  // 40 sends in well under 2 s: the same problem is reported once (or twice at a second's edge).
  EXPECT_LE(s.problem_reports, 2u);
  EXPECT_NE(link->last_problem().find("times)"), std::string::npos) << link->last_problem();
}

TEST(UdpLink, HostNameIsResolvedPreferringIpv4) {
  Receiver receiver;
  const auto link = open_link("udp://localhost:" + std::to_string(receiver.port()));
  EXPECT_NE(link->description().find("(127.0.0.1)"), std::string::npos) << link->description();
  link->send(make_frame(7, 64));
  const auto got = receiver.receive(2000);
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(*got, make_frame(7, 64));
}

TEST(UdpLink, Ipv6Loopback) {
  Receiver receiver(AF_INET6);
  if (!receiver.bound()) GTEST_SKIP() << "no IPv6 loopback here";
  const auto link = open_link("udp://[::1]:" + std::to_string(receiver.port()));
  EXPECT_EQ(link->send(make_frame(3, 280)), SendResult::Sent);
  const auto got = receiver.receive(2000);
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(*got, make_frame(3, 280));
}

TEST(UdpLink, OptionalLocalPortIsTheSourcePort) {
  Receiver receiver;
  const std::uint16_t local = closed_port();
  const auto link = open_link(udp_uri(receiver.port()) + "?local_port=" + std::to_string(local));
  link->send(make_frame(1, 10));
  std::uint16_t from = 0;
  ASSERT_TRUE(receiver.receive(2000, &from).has_value());
  EXPECT_EQ(from, local);
}

TEST(UdpLink, LocalPortInUseIsALinkError) {
  Receiver receiver, occupant;
  try {
    open_link(udp_uri(receiver.port()) + "?local_port=" + std::to_string(occupant.port()));
    FAIL() << "bound a port already in use";
  } catch (const LinkError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot bind local port " + std::to_string(occupant.port())),
              std::string::npos)
        << e.what();
  }
}

TEST(UdpLink, EmptyAndOversizedFramesAreRejectedAndCounted) {
  Receiver receiver;
  const auto link = open_link(udp_uri(receiver.port()));
  EXPECT_EQ(link->send({}), SendResult::Rejected);
  EXPECT_EQ(link->send(make_frame(0, kMaxLinkFrameBytes + 1)), SendResult::Rejected);
  EXPECT_EQ(link->send(make_frame(0, kMaxLinkFrameBytes)), SendResult::Sent);
  EXPECT_EQ(link->stats().frames_rejected, 2u);
  EXPECT_EQ(link->stats().frames_sent, 1u);
  const auto got = receiver.receive(2000);
  ASSERT_TRUE(got.has_value());
  EXPECT_EQ(got->size(), kMaxLinkFrameBytes);
}

// udpin: nobody to send to until a datagram arrives and is confirmed as MAVLink
// (reply_to_last_sender), then its sender gets the frames; a second sender takes over.
TEST(UdpInLink, SendsNothingUntilAPeerSpeaksThenAnswersTheLastOne) {
  sockaddr_in a{};  // where the link listens
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(unused_loopback_udp_port());
  const auto link = open_link("udpin://127.0.0.1:" + std::to_string(ntohs(a.sin_port)));
  const std::vector<std::uint8_t> frame(40, 0xAB);
  EXPECT_EQ(link->send(frame), SendResult::DroppedLinkDown);
  EXPECT_EQ(link->stats().frames_dropped_link_down, 1u);
  EXPECT_TRUE(link->peer().empty());

  auto peer_socket = [&] {
    const int s = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_in any{};
    any.sin_family = AF_INET;
    any.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::bind(s, reinterpret_cast<sockaddr*>(&any), sizeof any);
    ::connect(s, reinterpret_cast<sockaddr*>(&a), sizeof a);
    timeval tv{5, 0};
    ::setsockopt(s, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    return s;
  };
  std::vector<std::uint8_t> into(kMaxDatagramBytes);
  for (int round = 0; round < 2; ++round) {
    const int peer = peer_socket();
    const std::uint8_t hello[3] = {1, 2, static_cast<std::uint8_t>(round)};
    ASSERT_EQ(::send(peer, hello, sizeof hello, 0), 3);
    ReceiveResult got;
    for (int i = 0; i < 50 && got.bytes == 0; ++i) got = link->receive(into, 100);
    ASSERT_EQ(got.bytes, 3u);
    EXPECT_TRUE(got.datagram);
    EXPECT_EQ(into[2], round);
    link->reply_to_last_sender();
    EXPECT_FALSE(link->peer().empty());
    EXPECT_EQ(link->stats().peer_changes, static_cast<std::uint64_t>(round + 1));
    EXPECT_EQ(link->send(frame), SendResult::Sent);
    std::uint8_t back[64] = {};
    EXPECT_EQ(::recv(peer, back, sizeof back, 0), 40) << "the last sender gets the frame";
    ::close(peer);
  }
}

}  // namespace
}  // namespace rgbdo
