// MAVLink frames as UDP datagrams to one peer (a flight computer on Ethernet, mavlink-router,
// a simulator). One datagram per frame, so frames can be lost but never split or merged.
// Two ways to find the peer: a fixed address (udp://HOST:PORT, UdpLink) or listening on a port
// and answering whoever sent the last valid MAVLink frame (udpin://[ADDR]:PORT, UdpListenLink),
// as PX4 and MAVSDK do. Both receive on the socket they send from (receive(), on the link's
// receiver thread): a datagram is read whole, and the sender never waits for the receiver.
//
// The socket is non-blocking and connect()ed to the peer: a send either goes to the kernel at
// once or fails at once, and the ICMP "port unreachable" that comes back while nothing listens
// on the peer's port is delivered to the socket and returned by the next send (ECONNREFUSED).
// That is counted and reported, never fatal: sending simply goes on, and the frames reach the
// peer as soon as it starts listening. A connect() that fails because the network is not up
// yet (an interface still coming up at boot) is retried from send() every 0.5 s; for UDP,
// connect() is a route lookup and never waits.
#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <mutex>

#include "transport_problem.hpp"
#include "rgbd_odometry/link/transport.hpp"

namespace rgbdo {
namespace {

using link_detail::LinkProblem;

constexpr std::int64_t kConnectRetryInterval_ns = 500'000'000;

struct PeerAddress {
  sockaddr_storage address{};
  socklen_t length = 0;
};

// A link's name in its messages: "udp host:port", an IPv6 host in brackets.
std::string link_name(const char* scheme, const UdpLinkOptions& o) {
  const bool ipv6 = o.host.find(':') != std::string::npos;
  return std::string(scheme) + " " + (ipv6 ? "[" + o.host + "]" : o.host) + ":" + std::to_string(o.port);
}

std::string numeric_address(const sockaddr_storage& a, socklen_t length) {
  char host[NI_MAXHOST] = {};
  if (getnameinfo(reinterpret_cast<const sockaddr*>(&a), length, host, sizeof host, nullptr, 0, NI_NUMERICHOST) != 0)
    return "?";
  std::string text(host);
  if (a.ss_family == AF_INET6) text.insert(0, 1, '[').push_back(']');  // (GCC 12 misreads the '+' form)
  return text;
}

// Once, at open: getaddrinfo may wait for DNS, which the output thread must never do. `what`
// names the address in the error ("host", "local address"); `flags` adds AI_PASSIVE for a
// local one. IPv4 first: MAVLink endpoints (mavlink-router, PX4 SITL, QGroundControl) listen
// on IPv4 by default, and "localhost" often resolves to ::1 first.
PeerAddress look_up(const UdpLinkOptions& o, const std::string& name, const char* what, int flags) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_DGRAM;
  hints.ai_flags = AI_NUMERICSERV | flags;
  addrinfo* list = nullptr;
  const int rc = getaddrinfo(o.host.c_str(), std::to_string(o.port).c_str(), &hints, &list);
  if (rc != 0) {
    const std::string why = rc == EAI_SYSTEM ? link_detail::errno_text(errno) : gai_strerror(rc);
    throw LinkError(name + ": cannot resolve " + what + " '" + o.host + "': " + why);
  }
  const addrinfo* chosen = list;
  for (const addrinfo* a = list; a != nullptr; a = a->ai_next)
    if (a->ai_family == AF_INET) {
      chosen = a;
      break;
    }
  PeerAddress address;
  std::memcpy(&address.address, chosen->ai_addr, chosen->ai_addrlen);
  address.length = chosen->ai_addrlen;
  freeaddrinfo(list);
  return address;
}

PeerAddress resolve(const UdpLinkOptions& o, const std::string& name) { return look_up(o, name, "host", 0); }

// connect() failures that mean "the network is not up yet" rather than "this cannot work".
bool network_not_ready(int err) {
  return err == ENETUNREACH || err == EHOSTUNREACH || err == ENETDOWN || err == EADDRNOTAVAIL;
}

// The counters both UDP links keep (read by stats() from any thread while the output thread
// and the receiver count).
struct UdpCounters {
  std::atomic<std::uint64_t> sent{0}, bytes{0}, dropped_queue_full{0}, dropped_link_down{0}, rejected{0}, errors{0},
      reconnects{0}, bytes_received{0}, peer_changes{0};
  std::atomic<bool> up{false};

  LinkStats snapshot(const LinkProblem& problem) const {
    LinkStats s;
    s.frames_sent = sent.load(std::memory_order_relaxed);
    s.bytes_sent = bytes.load(std::memory_order_relaxed);
    s.frames_dropped_queue_full = dropped_queue_full.load(std::memory_order_relaxed);
    s.frames_dropped_link_down = dropped_link_down.load(std::memory_order_relaxed);
    s.frames_rejected = rejected.load(std::memory_order_relaxed);
    s.errors = errors.load(std::memory_order_relaxed);
    s.reconnects = reconnects.load(std::memory_order_relaxed);
    s.problem_reports = problem.reports();
    s.link_up = up.load(std::memory_order_relaxed);
    s.bytes_received = bytes_received.load(std::memory_order_relaxed);
    s.peer_changes = peer_changes.load(std::memory_order_relaxed);
    return s;
  }

  // Whether a frame is one no link sends (empty, or longer than MAVLink's longest): counted and
  // reported if so.
  bool reject_malformed(std::span<const std::uint8_t> frame, LinkProblem& problem) {
    if (!frame.empty() && frame.size() <= kMaxLinkFrameBytes) return false;
    rejected.fetch_add(1, std::memory_order_relaxed);
    problem.report("frame rejected: empty or longer than 280 bytes", 0, false);
    return true;
  }

  // What one datagram's send() or sendto() (returning n) came to, counted and reported.
  SendResult count_send(ssize_t n, std::size_t size, LinkProblem& problem) {
    if (n == static_cast<ssize_t>(size)) {
      sent.fetch_add(1, std::memory_order_relaxed);
      bytes.fetch_add(size, std::memory_order_relaxed);
      up.store(true, std::memory_order_relaxed);
      return SendResult::Sent;
    }
    const int err = n < 0 ? errno : EMSGSIZE;  // a datagram goes whole or not at all
    if (err == EAGAIN || err == EWOULDBLOCK || err == ENOBUFS) {
      dropped_queue_full.fetch_add(1, std::memory_order_relaxed);
      problem.report("socket send buffer full, frame dropped", err, false);
      return SendResult::DroppedBufferFull;
    }
    errors.fetch_add(1, std::memory_order_relaxed);
    dropped_link_down.fetch_add(1, std::memory_order_relaxed);
    up.store(false, std::memory_order_relaxed);
    problem.report(err == ECONNREFUSED ? "peer refused a datagram (nothing listening on its port?)" : "send failed", err,
                   false);
    return SendResult::DroppedLinkDown;
  }
};

class UdpLink final : public OutputLink {
 public:
  explicit UdpLink(const UdpLinkOptions& o)
      : name_(link_name("udp", o)), problem_(name_) {
    const PeerAddress peer = resolve(o, name_);
    peer_ = peer.address;
    peer_length_ = peer.length;
    description_ = name_ + " (" + numeric_address(peer_, peer_length_) + ")";
    fd_ = ::socket(peer_.ss_family, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd_ < 0) throw LinkError(name_ + ": cannot create a socket: " + link_detail::errno_text(errno));
    try {
      // A broadcast peer (192.168.1.255) is a common MAVLink set-up; without this connect() says EACCES.
      const int on = 1;
      ::setsockopt(fd_, SOL_SOCKET, SO_BROADCAST, &on, sizeof on);
      if (o.local_port != 0) bind_local(o.local_port);
      connect_at_open();
    } catch (...) {
      ::close(fd_);
      throw;
    }
  }

  ~UdpLink() override { ::close(fd_); }

  SendResult send(std::span<const std::uint8_t> frame) noexcept override {
    if (counters_.reject_malformed(frame, problem_)) return SendResult::Rejected;
    if (!connected_ && !retry_connect()) {
      counters_.dropped_link_down.fetch_add(1, std::memory_order_relaxed);
      return SendResult::DroppedLinkDown;
    }
    const ssize_t n = ::send(fd_, frame.data(), frame.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
    return counters_.count_send(n, frame.size(), problem_);
  }

  LinkStats stats() const override { return counters_.snapshot(problem_); }

  std::string last_problem() const override { return problem_.text(); }
  std::string description() const override { return description_; }

  // The socket is connect()ed: the kernel delivers datagrams from the peer only.
  ReceiveResult receive(std::span<std::uint8_t> into, int timeout_ms) noexcept override {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, timeout_ms) <= 0) return {};
    const ssize_t n = ::recv(fd_, into.data(), into.size(), MSG_DONTWAIT);
    if (n < 0) {
      // The refusal the ICMP "port unreachable" reports goes to whichever call on the socket
      // comes first; when that is this one, it is reported here as send() would have.
      if (errno == ECONNREFUSED) {
        counters_.errors.fetch_add(1, std::memory_order_relaxed);
        counters_.up.store(false, std::memory_order_relaxed);
        problem_.report("peer refused a datagram (nothing listening on its port?)", ECONNREFUSED);
      }
      return {};
    }
    counters_.bytes_received.fetch_add(static_cast<std::uint64_t>(n), std::memory_order_relaxed);
    return {static_cast<std::size_t>(n), true};
  }

 private:
  void bind_local(std::uint16_t local_port) {
    sockaddr_storage local{};
    socklen_t length = 0;
    if (peer_.ss_family == AF_INET6) {
      auto& a = reinterpret_cast<sockaddr_in6&>(local);
      a.sin6_family = AF_INET6;
      a.sin6_addr = in6addr_any;
      a.sin6_port = htons(local_port);
      length = sizeof a;
    } else {
      auto& a = reinterpret_cast<sockaddr_in&>(local);
      a.sin_family = AF_INET;
      a.sin_addr.s_addr = htonl(INADDR_ANY);
      a.sin_port = htons(local_port);
      length = sizeof a;
    }
    if (::bind(fd_, reinterpret_cast<const sockaddr*>(&local), length) != 0)
      throw LinkError(name_ + ": cannot bind local port " + std::to_string(local_port) + ": " +
                      link_detail::errno_text(errno));
    description_ += " from local port " + std::to_string(local_port);
  }

  void connect_at_open() {
    if (::connect(fd_, reinterpret_cast<const sockaddr*>(&peer_), peer_length_) == 0) {
      connected_ = true;
      counters_.up.store(true, std::memory_order_relaxed);
      return;
    }
    const int err = errno;
    if (!network_not_ready(err)) throw LinkError(name_ + ": cannot connect: " + link_detail::errno_text(err));
    counters_.errors.fetch_add(1, std::memory_order_relaxed);
    problem_.report("no route to the peer yet; retrying every 0.5 s", err);
    next_connect_ns_ = steady_now_ns() + kConnectRetryInterval_ns;
  }

  bool retry_connect() noexcept {
    const std::int64_t now_ns = steady_now_ns();
    if (now_ns < next_connect_ns_) return false;
    next_connect_ns_ = now_ns + kConnectRetryInterval_ns;
    if (::connect(fd_, reinterpret_cast<const sockaddr*>(&peer_), peer_length_) == 0) {
      connected_ = true;
      counters_.reconnects.fetch_add(1, std::memory_order_relaxed);
      return true;
    }
    counters_.errors.fetch_add(1, std::memory_order_relaxed);
    problem_.report("no route to the peer yet; retrying every 0.5 s", errno, false);
    return false;
  }

  const std::string name_;
  std::string description_;
  int fd_ = -1;
  sockaddr_storage peer_{};
  socklen_t peer_length_ = 0;
  // Touched by send() only, hence by one thread.
  bool connected_ = false;
  std::int64_t next_connect_ns_ = 0;
  UdpCounters counters_;
  LinkProblem problem_;
};

bool same_address(const sockaddr_storage& a, socklen_t a_length, const sockaddr_storage& b, socklen_t b_length) {
  return a_length == b_length && std::memcmp(&a, &b, a_length) == 0;
}

// Once, at open: the local address to bind (empty host: any IPv4 address).
PeerAddress resolve_local(const UdpLinkOptions& o, const std::string& name) {
  PeerAddress local;
  if (o.host.empty()) {
    auto& a = reinterpret_cast<sockaddr_in&>(local.address);
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_ANY);
    a.sin_port = htons(o.port);
    local.length = sizeof a;
    return local;
  }
  return look_up(o, name, "local address", AI_PASSIVE);
}

class UdpListenLink final : public OutputLink {
 public:
  explicit UdpListenLink(const UdpLinkOptions& o)
      : name_(link_name("udpin", o)), problem_(name_) {
    const PeerAddress local = resolve_local(o, name_);
    fd_ = ::socket(local.address.ss_family, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (fd_ < 0) throw LinkError(name_ + ": cannot create a socket: " + link_detail::errno_text(errno));
    if (local.address.ss_family == AF_INET6) {
      // [::] takes IPv4 peers too (as IPv4-mapped addresses), whatever net.ipv6.bindv6only says.
      const int off = 0;
      ::setsockopt(fd_, IPPROTO_IPV6, IPV6_V6ONLY, &off, sizeof off);
    }
    if (::bind(fd_, reinterpret_cast<const sockaddr*>(&local.address), local.length) != 0) {
      const int err = errno;
      ::close(fd_);
      throw LinkError(name_ + ": cannot listen on port " + std::to_string(o.port) + ": " + link_detail::errno_text(err));
    }
    description_ = name_ + " (listening on " + numeric_address(local.address, local.length) + ":" +
                   std::to_string(o.port) + ", replying to the last sender of a valid MAVLink frame)";
    problem_.report("no peer yet: waiting for a MAVLink frame", 0);
  }

  ~UdpListenLink() override { ::close(fd_); }

  SendResult send(std::span<const std::uint8_t> frame) noexcept override {
    if (counters_.reject_malformed(frame, problem_)) return SendResult::Rejected;
    sockaddr_storage peer{};
    socklen_t peer_length = 0;
    {
      // The receiver holds this lock only to copy an address in: a wait of nanoseconds.
      std::lock_guard lock(peer_mutex_);
      peer = peer_;
      peer_length = peer_length_;
    }
    if (peer_length == 0) {  // until someone speaks MAVLink to us there is nobody to send to
      counters_.dropped_link_down.fetch_add(1, std::memory_order_relaxed);
      return SendResult::DroppedLinkDown;
    }
    const ssize_t n = ::sendto(fd_, frame.data(), frame.size(), MSG_DONTWAIT | MSG_NOSIGNAL,
                               reinterpret_cast<const sockaddr*>(&peer), peer_length);
    return counters_.count_send(n, frame.size(), problem_);
  }

  ReceiveResult receive(std::span<std::uint8_t> into, int timeout_ms) noexcept override {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, timeout_ms) <= 0) return {};
    sockaddr_storage from{};
    socklen_t from_length = sizeof from;
    const ssize_t n =
        ::recvfrom(fd_, into.data(), into.size(), MSG_DONTWAIT, reinterpret_cast<sockaddr*>(&from), &from_length);
    if (n < 0) return {};
    last_from_ = from;
    last_from_length_ = from_length;
    counters_.bytes_received.fetch_add(static_cast<std::uint64_t>(n), std::memory_order_relaxed);
    return {static_cast<std::size_t>(n), true};
  }

  void reply_to_last_sender() noexcept override {
    if (last_from_length_ == 0 || same_address(last_from_, last_from_length_, current_, current_length_)) return;
    current_ = last_from_;
    current_length_ = last_from_length_;
    std::string text;
    try {  // once per change of peer, not per frame
      text = numeric_address(current_, current_length_) + ":" + std::to_string(port_of(current_));
    } catch (...) {
      text = "?";
    }
    std::lock_guard lock(peer_mutex_);
    peer_ = current_;
    peer_length_ = current_length_;
    peer_text_.swap(text);
    counters_.peer_changes.fetch_add(1, std::memory_order_relaxed);
    counters_.up.store(true, std::memory_order_relaxed);
  }

  std::string peer() const override {
    std::lock_guard lock(peer_mutex_);
    return peer_text_;
  }

  LinkStats stats() const override { return counters_.snapshot(problem_); }

  std::string last_problem() const override { return problem_.text(); }
  std::string description() const override { return description_; }

 private:
  static std::uint16_t port_of(const sockaddr_storage& a) {
    return ntohs(a.ss_family == AF_INET6 ? reinterpret_cast<const sockaddr_in6&>(a).sin6_port
                                         : reinterpret_cast<const sockaddr_in&>(a).sin_port);
  }

  const std::string name_;
  std::string description_;
  int fd_ = -1;
  // The receiver thread's own: the sender of the last datagram, and the peer it last chose.
  sockaddr_storage last_from_{}, current_{};
  socklen_t last_from_length_ = 0, current_length_ = 0;
  // Shared with send() and peer().
  mutable std::mutex peer_mutex_;
  sockaddr_storage peer_{};
  socklen_t peer_length_ = 0;  // 0: no peer yet
  std::string peer_text_;
  UdpCounters counters_;
  LinkProblem problem_;
};

}  // namespace

std::unique_ptr<OutputLink> open_udp_link(const UdpLinkOptions& options) {
  if (options.listen) {
    if (options.port == 0) throw LinkError("udpin: port 0 is not a port to listen on (1-65535)");
    return std::make_unique<UdpListenLink>(options);
  }
  if (options.port == 0) throw LinkError("udp " + options.host + ": port 0 is not a peer port (1-65535)");
  return std::make_unique<UdpLink>(options);
}

}  // namespace rgbdo
