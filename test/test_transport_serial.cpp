// The serial link (src/link/transport_serial.cpp) on real pseudo-terminals: the link opens the slave
// side as it would /dev/ttyUSB0, the test reads the master side as the flight controller.
// Bytes arrive byte-exact; a peer that does not read fills the queue and the oldest frames are
// dropped while send() keeps returning; a vanished device is noticed, and a device that comes
// back under the same name (a symlink, as /dev/serial/by-id/ names are) is re-opened.
#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "rgbd_odometry/link/transport.hpp"
#include "link_test_frames.hpp"
#include "pty_test_env.hpp"

namespace rgbdo {
namespace {

using link_test::Bytes;
using link_test::frame_seq;
using link_test::fastest_test_baud;
using link_test::make_frame;
using link_test::pty_carries_speed;
using Clock = std::chrono::steady_clock;

// A pseudo-terminal whose master end the test holds; the link opens slave_path().
class Pty {
 public:
  Pty() {
    int slave = -1;
    char name[256] = {};
    if (::openpty(&master_, &slave, name, nullptr, nullptr) != 0) {
      std::string why = "openpty failed: ";
      why += std::strerror(errno);
      throw std::runtime_error(why);
    }
    slave_path_ = name;
    ::close(slave);  // only the link holds the slave; the pty lives on while the master is open
    termios tio{};
    ::tcgetattr(master_, &tio);
    ::cfmakeraw(&tio);  // no translation on the way back either
    ::tcsetattr(master_, TCSANOW, &tio);
  }
  ~Pty() { close_master(); }
  Pty(const Pty&) = delete;
  Pty& operator=(const Pty&) = delete;

  const std::string& slave_path() const { return slave_path_; }
  void close_master() {
    if (master_ >= 0) ::close(master_);
    master_ = -1;
  }

  // Reads until `count` bytes have arrived or nothing arrives for `quiet_ms`.
  Bytes read(std::size_t count, int quiet_ms = 2000) {
    Bytes out;
    std::uint8_t buffer[4096];
    auto deadline = Clock::now() + std::chrono::milliseconds(quiet_ms);
    while (out.size() < count && Clock::now() < deadline) {
      pollfd p{master_, POLLIN, 0};
      if (::poll(&p, 1, 10) <= 0) continue;
      if (!(p.revents & POLLIN)) {
        // POLLHUP: nobody has the slave open (yet); the link may be about to open it.
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
        continue;
      }
      const ssize_t n = ::read(master_, buffer, std::min(sizeof buffer, count - out.size()));
      if (n <= 0) continue;
      out.insert(out.end(), buffer, buffer + n);
      deadline = Clock::now() + std::chrono::milliseconds(quiet_ms);
    }
    return out;
  }

 private:
  int master_ = -1;
  std::string slave_path_;
};

// A private directory for the symlink that stands for the device's stable name.
class TempDir {
 public:
  TempDir() {
    char pattern[] = "/tmp/link_serial_test_XXXXXX";
    path_ = ::mkdtemp(pattern);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  std::string operator/(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

// Points `link_path` at `target`, replacing any previous target in one step (as udev does).
void point_symlink(const std::string& link_path, const std::string& target) {
  const std::string fresh = link_path + ".new";
  std::filesystem::remove(fresh);
  std::filesystem::create_symlink(target, fresh);
  std::filesystem::rename(fresh, link_path);
}

SerialLinkOptions options_for(const std::string& path, std::size_t queue_frames = 64) {
  SerialLinkOptions o;
  o.device_path = path;
  o.baud = fastest_test_baud();
  o.queue_frames = queue_frames;
  return o;
}

// Waits (bounded) until the link's statistics satisfy `done`.
template <typename Done>
bool wait_for_stats(const OutputLink& link, Done done, std::chrono::milliseconds limit = std::chrono::seconds(5)) {
  const auto deadline = Clock::now() + limit;
  while (Clock::now() < deadline) {
    if (done(link.stats())) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return done(link.stats());
}

TEST(SerialLink, BytesArriveByteExactAtTheOtherEnd) {
  Pty pty;
  const auto link =
      open_link("serial://" + pty.slave_path() + ":" + std::to_string(fastest_test_baud()) + "?queue_frames=1024");
  EXPECT_TRUE(link->stats().link_up);
  EXPECT_EQ(link->last_problem(), "");

  Bytes expected;
  for (std::uint32_t seq = 0; seq < 500; ++seq) {
    const Bytes f = make_frame(seq, 1 + (seq * 37) % kMaxLinkFrameBytes);  // every size from 1 to 280
    expected.insert(expected.end(), f.begin(), f.end());
    EXPECT_EQ(link->send(f), SendResult::Queued);
  }
  // 70 kB: more than the pty holds, so the writer meets a full line and resumes mid-frame.
  const Bytes got = pty.read(expected.size());
  ASSERT_EQ(got.size(), expected.size());
  EXPECT_TRUE(got == expected) << "the bytes differ";

  ASSERT_TRUE(wait_for_stats(*link, [](const LinkStats& s) { return s.frames_pending == 0; }));
  const LinkStats s = link->stats();
  EXPECT_EQ(s.frames_sent, 500u);
  EXPECT_EQ(s.bytes_sent, expected.size());
  EXPECT_EQ(s.frames_dropped_queue_full + s.frames_dropped_link_down + s.errors, 0u);
  EXPECT_EQ(pty.read(1, 50).size(), 0u);  // nothing more
}

TEST(SerialLink, EverySupportedBaudIsAcceptedWhereThePtyCarriesIt) {
  // Natively every baud must be accepted. Under qemu-user (see pty_test_env.hpp) the ones
  // above 460800 cannot be represented: the link must then refuse them, naming the reason,
  // rather than run at a speed nobody asked for.
  Pty pty;
  const bool all_carried = fastest_test_baud() == 921600 && pty_carries_speed(B3000000);
  for (const int baud : kSupportedSerialBauds) {
    SerialLinkOptions o = options_for(pty.slave_path());
    o.baud = baud;
    std::string error;
    try {
      const auto link = open_serial_link(o);
      EXPECT_TRUE(link->stats().link_up) << baud << ": " << link->last_problem();
    } catch (const LinkError& e) {
      error = e.what();
    }
    if (all_carried || baud <= 460800) {
      EXPECT_EQ(error, "") << baud;
    } else {
      EXPECT_NE(error.find("the driver does not support this baud"), std::string::npos) << baud << ": " << error;
    }
  }
}

TEST(SerialLink, APeerThatDoesNotReadCostsTheOldestFramesNotABlockedSender) {
  // GIVEN a flight controller that reads nothing, and a 16-frame queue
  Pty pty;
  constexpr std::size_t kQueue = 16;
  const auto link = open_serial_link(options_for(pty.slave_path(), kQueue));

  // WHEN 1000 full-size frames are sent, far more than the pty and the queue hold
  constexpr std::uint32_t kFrames = 1000;
  std::uint32_t queued = 0, replaced = 0;
  for (std::uint32_t seq = 0; seq < kFrames; ++seq) {
    const SendResult r = link->send(make_frame(seq, kMaxLinkFrameBytes));
    queued += r == SendResult::Queued;
    replaced += r == SendResult::QueuedDroppedOldest;
  }
  // THEN every send returned, and every frame is accounted for
  EXPECT_EQ(queued + replaced, kFrames);
  LinkStats s = link->stats();
  EXPECT_EQ(s.frames_dropped_queue_full, replaced);
  EXPECT_GT(s.frames_dropped_queue_full, 0u);
  EXPECT_EQ(s.frames_sent + s.frames_dropped_queue_full + s.frames_dropped_link_down + s.frames_pending, kFrames);
  EXPECT_LE(s.frames_pending, kQueue + 1);  // the queue and the frame being written
  EXPECT_NE(link->last_problem().find("queue full"), std::string::npos) << link->last_problem();

  // WHEN the peer starts reading
  Bytes got;
  for (;;) {
    const Bytes more = pty.read(1 << 20, 300);
    if (more.empty()) break;
    got.insert(got.end(), more.begin(), more.end());
  }
  // THEN it gets whole frames, in order, ending with the newest: the dropped ones were the oldest waiting
  s = link->stats();
  EXPECT_EQ(s.frames_pending, 0u);
  EXPECT_EQ(s.frames_sent + s.frames_dropped_queue_full, kFrames);
  ASSERT_EQ(got.size(), s.frames_sent * kMaxLinkFrameBytes);
  std::vector<std::uint32_t> seqs;
  for (std::size_t at = 0; at < got.size(); at += kMaxLinkFrameBytes) {
    const std::uint32_t seq = frame_seq(&got[at]);
    ASSERT_LT(seq, kFrames);
    ASSERT_TRUE(std::equal(got.begin() + at, got.begin() + at + kMaxLinkFrameBytes, make_frame(seq, kMaxLinkFrameBytes).begin()))
        << "frame at byte " << at << " is not whole";
    if (!seqs.empty()) {
      ASSERT_GT(seq, seqs.back());
    }
    seqs.push_back(seq);
  }
  ASSERT_GE(seqs.size(), kQueue);
  for (std::size_t i = 0; i < kQueue; ++i) EXPECT_EQ(seqs[seqs.size() - kQueue + i], kFrames - kQueue + i);
}

TEST(SerialLink, AVanishedDeviceIsNoticedAndReported) {
  Pty pty;
  const auto link = open_serial_link(options_for(pty.slave_path()));
  link->send(make_frame(1, 50));
  ASSERT_EQ(pty.read(50).size(), 50u);

  pty.close_master();  // the adapter is unplugged
  // Noticed even without traffic (the idle writer watches for a hang-up); keep sending anyway.
  const auto deadline = Clock::now() + std::chrono::seconds(5);
  std::uint32_t seq = 2;
  while (link->stats().link_up && Clock::now() < deadline) {
    link->send(make_frame(seq++, 50));
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  const LinkStats s = link->stats();
  EXPECT_FALSE(s.link_up);
  EXPECT_GE(s.errors, 1u);
  const std::string problem = link->last_problem();
  EXPECT_NE(problem.find("serial " + pty.slave_path()), std::string::npos) << problem;
  EXPECT_TRUE(problem.find("hung up") != std::string::npos || problem.find("write failed") != std::string::npos ||
              problem.find("cannot open") != std::string::npos)
      << problem;
  for (int i = 0; i < 100; ++i) link->send(make_frame(seq++, 50));  // still returns while down
  EXPECT_EQ(link->stats().frames_pending, 64u);                      // the queue kept the newest
}

TEST(SerialLink, ReopensTheDeviceWhenItComesBackUnderTheSameName) {
  // GIVEN a link opened through a stable name (a symlink, like /dev/serial/by-id/...)
  TempDir dir;
  const std::string stable = dir / "ttyLINK";
  auto first = std::make_unique<Pty>();
  point_symlink(stable, first->slave_path());
  const auto link = open_serial_link(options_for(stable));
  link->send(make_frame(1, 100));
  ASSERT_EQ(first->read(100), make_frame(1, 100));

  // WHEN the device goes away, the link notices, and it comes back as another pty
  first->close_master();
  ASSERT_TRUE(wait_for_stats(*link, [](const LinkStats& s) { return !s.link_up; }));
  first.reset();
  Pty second;
  point_symlink(stable, second.slave_path());

  // THEN frames reach the new device within a bounded wait, and the reconnect is counted
  constexpr std::size_t kSize = 100;
  Bytes got;
  std::uint32_t seq = 2;
  const auto deadline = Clock::now() + std::chrono::seconds(5);
  while (got.size() < kSize && Clock::now() < deadline) {
    link->send(make_frame(seq++, kSize));
    const Bytes more = second.read(kSize - got.size(), 50);
    got.insert(got.end(), more.begin(), more.end());
  }
  ASSERT_EQ(got.size(), kSize) << link->last_problem();
  EXPECT_EQ(got, make_frame(frame_seq(got.data()), kSize));  // a whole frame from the start
  const LinkStats s = link->stats();
  EXPECT_TRUE(s.link_up);
  EXPECT_GE(s.reconnects, 1u);
}

TEST(SerialLink, AMissingDeviceIsWaitedForNotAnError) {
  // GIVEN a path where no device exists yet (an adapter that enumerates after the service starts)
  TempDir dir;
  const std::string stable = dir / "ttyLATE";
  const auto link = open_serial_link(options_for(stable));
  LinkStats s = link->stats();
  EXPECT_FALSE(s.link_up);
  EXPECT_NE(link->last_problem().find(stable), std::string::npos) << link->last_problem();
  EXPECT_NE(link->last_problem().find("No such file"), std::string::npos) << link->last_problem();
  EXPECT_EQ(link->send(make_frame(0, 60)), SendResult::Queued);  // kept for when it appears

  // WHEN it appears
  Pty pty;
  point_symlink(stable, pty.slave_path());
  // THEN the waiting frame and the next ones arrive
  link->send(make_frame(1, 60));
  Bytes got = pty.read(120, 5000);
  ASSERT_EQ(got.size(), 120u) << link->last_problem();
  EXPECT_TRUE(std::equal(got.begin(), got.begin() + 60, make_frame(0, 60).begin()));
  EXPECT_TRUE(std::equal(got.begin() + 60, got.end(), make_frame(1, 60).begin()));
  s = link->stats();
  EXPECT_TRUE(s.link_up);
  EXPECT_EQ(s.reconnects, 1u);
}

std::string construction_error(const SerialLinkOptions& o) {
  try {
    open_serial_link(o);
  } catch (const LinkError& e) {
    return e.what();
  }
  return "";
}

TEST(SerialLink, PathsThatCannotBeASerialDeviceAreLinkErrors) {
  TempDir dir;
  const std::string directory = dir / "a_directory";
  std::filesystem::create_directory(directory);
  EXPECT_NE(construction_error(options_for(directory)).find("Is a directory"), std::string::npos)
      << construction_error(options_for(directory));

  const std::string file = dir / "a_file";
  std::FILE* f = std::fopen(file.c_str(), "w");
  std::fclose(f);
  EXPECT_NE(construction_error(options_for(file)).find("not a character device"), std::string::npos)
      << construction_error(options_for(file));

  EXPECT_NE(construction_error(options_for("/dev/null")).find("not a terminal"), std::string::npos)
      << construction_error(options_for("/dev/null"));

  const std::string below_a_file = file + "/ttyUSB0";
  EXPECT_NE(construction_error(options_for(below_a_file)).find("Not a directory"), std::string::npos)
      << construction_error(options_for(below_a_file));
}

TEST(SerialLink, BadOptionsAreLinkErrors) {
  Pty pty;
  SerialLinkOptions o = options_for(pty.slave_path());
  o.baud = 9600;
  EXPECT_NE(construction_error(o).find("unsupported baud 9600"), std::string::npos) << construction_error(o);
  o = options_for(pty.slave_path(), 0);
  EXPECT_NE(construction_error(o).find("queue_frames"), std::string::npos) << construction_error(o);
  EXPECT_NE(construction_error(options_for("")).find("missing device path"), std::string::npos);
}

TEST(SerialLink, EmptyAndOversizedFramesAreRejectedAndCounted) {
  Pty pty;
  const auto link = open_serial_link(options_for(pty.slave_path()));
  EXPECT_EQ(link->send({}), SendResult::Rejected);
  EXPECT_EQ(link->send(make_frame(0, kMaxLinkFrameBytes + 1)), SendResult::Rejected);
  EXPECT_EQ(link->stats().frames_rejected, 2u);
  EXPECT_EQ(link->stats().frames_pending, 0u);
}

TEST(SerialLink, DestructionIsPromptWithAStalledLine) {
  Pty pty;  // never read: the writer sits in poll() waiting for room
  auto link = open_serial_link(options_for(pty.slave_path()));
  for (std::uint32_t seq = 0; seq < 500; ++seq) link->send(make_frame(seq, kMaxLinkFrameBytes));
  ASSERT_TRUE(wait_for_stats(*link, [](const LinkStats& s) { return s.frames_pending > 0; }));
  const auto start = Clock::now();
  link.reset();
  // The writer waits at most 100 ms at a time; a generous bound so a loaded machine passes.
  EXPECT_LT(Clock::now() - start, std::chrono::seconds(1));
}

}  // namespace
}  // namespace rgbdo
