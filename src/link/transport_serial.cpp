// MAVLink frames over a serial line (a USB-serial adapter or a UART to the flight controller):
// raw 8N1, no flow control.
//
// A tty write can block or stall for as long as the line is slower than the frames, or the far
// end holds it, so send() only copies the frame into a bounded ring allocated at construction;
// a writer thread drains it. When the ring is full the oldest frame is dropped: the newest
// odometry is worth most. The writer finishes one frame before taking the next (a partial
// write resumes mid-frame), so frames are never interleaved, and it waits in poll() for at
// most 100 ms at a time, so the destructor stops it promptly.
//
// Hot plug: when the device goes away (POLLHUP/POLLERR, or EIO/ENXIO/ENODEV from write) the
// writer closes it, reports why, and re-opens the same path every 0.5 s until it is back;
// frames sent meanwhile wait in the ring (oldest dropped). The frame being written when the
// device went is dropped: it is the oldest, and newer ones are waiting.
//
// Receiving: the receiver thread reads the same device through a dup() of the writer's
// descriptor, handed over at every (re-)open, so the two threads never share an fd number the
// other may close and reuse. A device that goes away hangs up both copies; the reader drops
// its own and waits for the next hand-over.
//
// A device path that does not exist when the link is made is not an error either: a
// USB-serial adapter, or a flight controller powered separately from the companion computer,
// may enumerate seconds after the odometry service starts, and throwing would only make
// systemd restart the whole program (sensor and all) until it did. The link starts, reports
// "cannot open ... No such file or directory" (the program should log last_problem() at
// start when stats().link_up is false) and comes up when the device appears. What waiting
// cannot fix throws LinkError: a directory, a file that is not a terminal, no permission, a
// baud the driver refuses.
#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <optional>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

#include "transport_problem.hpp"
#include "rgbd_odometry/link/transport.hpp"

namespace rgbdo {
namespace {

using link_detail::LinkProblem;

constexpr int kPollTimeout_ms = 100;  // the longest the writer waits before looking again
constexpr std::int64_t kReopenInterval_ns = 500'000'000;
constexpr std::size_t kUrgentFrames = 8;  // answers in flight at once: a handful at most
constexpr std::int64_t kShutdownDrain_ns = 300'000'000;  // the most the destructor gives the queue

// The termios constant of each rate in kSupportedSerialBauds, in the same order (the rates
// themselves have one home, transport.hpp).
constexpr std::array<speed_t, kSupportedSerialBauds.size()> kTermiosSpeeds{
    B57600, B115200, B230400, B460800, B500000, B576000, B921600, B1000000, B1152000, B1500000, B2000000, B3000000};

// Both lists ascend (Linux numbers the B* constants in rate order): a rate paired with the
// wrong constant breaks the order.
constexpr bool ascending() {
  for (std::size_t i = 1; i < kTermiosSpeeds.size(); ++i)
    if (kTermiosSpeeds[i] <= kTermiosSpeeds[i - 1] || kSupportedSerialBauds[i] <= kSupportedSerialBauds[i - 1])
      return false;
  return true;
}
static_assert(ascending());

std::optional<speed_t> termios_speed(int baud) {
  for (std::size_t i = 0; i < kSupportedSerialBauds.size(); ++i)
    if (kSupportedSerialBauds[i] == baud) return kTermiosSpeeds[i];
  return std::nullopt;
}

struct FrameSlot {
  std::array<std::uint8_t, kMaxLinkFrameBytes> bytes{};
  std::size_t size = 0;
};

// Whole frames, oldest first, in slots allocated once. Not thread-safe: the link's mutex guards it.
class FrameRing {
 public:
  explicit FrameRing(std::size_t capacity) : slots_(capacity) {}
  bool empty() const { return count_ == 0; }
  bool full() const { return count_ == slots_.size(); }
  std::size_t size() const { return count_; }

  void push(std::span<const std::uint8_t> frame) {  // precondition: !full()
    FrameSlot& slot = slots_[(head_ + count_) % slots_.size()];
    std::copy(frame.begin(), frame.end(), slot.bytes.begin());
    slot.size = frame.size();
    ++count_;
  }
  void drop_oldest() {  // precondition: !empty()
    head_ = (head_ + 1) % slots_.size();
    --count_;
  }
  void pop_oldest_into(FrameSlot& out) {  // precondition: !empty()
    const FrameSlot& slot = slots_[head_];
    std::copy_n(slot.bytes.begin(), slot.size, out.bytes.begin());
    out.size = slot.size;
    drop_oldest();
  }

 private:
  std::vector<FrameSlot> slots_;
  std::size_t head_ = 0, count_ = 0;
};

struct OpenAttempt {
  int fd = -1;
  const char* what = nullptr;  // why it failed
  int err = 0;
  bool waiting_may_fix = true;  // false: a configuration error
};

OpenAttempt fail_open(int fd, const char* what, int err, bool waiting_may_fix) {
  if (fd >= 0) ::close(fd);
  return {-1, what, err, waiting_may_fix};
}

// Open and configure the device: raw 8N1 at `speed`, no flow control, non-blocking.
OpenAttempt open_device(const std::string& path, speed_t speed) {
  const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    // Absent (not enumerated yet, unplugged), present but not ready, or held exclusively by
    // another program for a moment (ModemManager probing a new adapter): all may pass.
    const bool may_pass = err == ENOENT || err == ENODEV || err == ENXIO || err == EIO || err == EBUSY;
    return may_pass ? fail_open(-1, "cannot open the device (retrying every 0.5 s)", err, true)
                    : fail_open(-1, "cannot open the device", err, false);
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0) return fail_open(fd, "cannot stat the device", errno, true);
  if (!S_ISCHR(st.st_mode)) return fail_open(fd, "is not a serial device (not a character device)", 0, false);
  termios tio{};
  if (::tcgetattr(fd, &tio) != 0) {
    const int err = errno;
    return fail_open(fd, "is not a serial device (not a terminal)", err, err != ENOTTY);
  }
  ::cfmakeraw(&tio);
  tio.c_cflag &= ~(CSIZE | PARENB | CSTOPB | CRTSCTS);
  tio.c_cflag |= CS8 | CLOCAL | CREAD;  // CLOCAL: no modem control lines on a flight controller link
  tio.c_iflag &= ~(IXON | IXOFF | IXANY);
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  ::cfsetispeed(&tio, speed);
  ::cfsetospeed(&tio, speed);
  if (::tcsetattr(fd, TCSANOW, &tio) != 0) {
    const int err = errno;
    return fail_open(fd, "the driver refused the line settings", err, err != EINVAL);
  }
  // tcsetattr succeeds if any of the settings took: check that the baud did.
  termios applied{};
  if (::tcgetattr(fd, &applied) != 0) return fail_open(fd, "cannot read back the line settings", errno, true);
  if (::cfgetospeed(&applied) != speed) return fail_open(fd, "the driver does not support this baud", 0, false);
  // Keep other programs (ModemManager, a second instance) from opening it and writing into
  // our frames; best effort, root is exempt.
  ::ioctl(fd, TIOCEXCL);
  ::tcflush(fd, TCIOFLUSH);  // whatever a previous user left unsent or unread
  return {fd, nullptr, 0, true};
}

// Close without waiting for unsent output: a tty close waits (up to 30 s) for its buffer to
// drain, which a vanished device or a stalled line would turn into a hung shutdown.
void close_device(int fd) {
  ::tcflush(fd, TCOFLUSH);
  ::close(fd);
}

class SerialLink final : public OutputLink {
 public:
  explicit SerialLink(const SerialLinkOptions& o)
      : name_("serial " + o.device_path), problem_(name_), path_(o.device_path), ring_(o.queue_frames) {
    if (o.device_path.empty()) throw LinkError("serial: missing device path");
    if (o.queue_frames == 0) throw LinkError(name_ + ": queue_frames must be at least 1");
    try {
      check_serial_baud(o.baud);
    } catch (const LinkError& e) {
      throw LinkError(name_ + ": " + e.what());
    }
    const std::optional<speed_t> speed = termios_speed(o.baud);
    if (!speed) throw LinkError(name_ + ": baud " + std::to_string(o.baud) + " has no termios constant here");
    speed_ = *speed;
    description_ = name_ + " at " + std::to_string(o.baud) + " baud 8N1, queue " + std::to_string(o.queue_frames) +
                   " frames";

    const OpenAttempt first = open_device(path_, speed_);
    if (first.fd < 0 && !first.waiting_may_fix) {
      std::string message = name_ + ": " + first.what;
      if (first.err != 0) message += ": " + link_detail::errno_text(first.err);
      if (first.err == EACCES || first.err == EPERM) message += " (is the user in the dialout group?)";
      throw LinkError(message);
    }
    if (first.fd >= 0) {
      fd_ = first.fd;
      up_ = true;
      hand_to_reader(fd_);
    } else {
      ++errors_;
      problem_.report(first.what, first.err);
      next_open_ns_ = steady_now_ns() + kReopenInterval_ns;
    }
    try {
      writer_ = std::thread([this] { writer_loop(); });
    } catch (const std::system_error& e) {
      if (fd_ >= 0) close_device(fd_);
      throw LinkError(name_ + ": cannot start the writer thread: " + e.what());
    }
  }

  ~SerialLink() override {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
      // What is queued at shutdown (the last odometry) still goes out if the line takes it
      // within a bounded time; a dead line cannot hold the exit up for longer.
      stop_deadline_ns_ = steady_now_ns() + kShutdownDrain_ns;
    }
    wake_writer_.notify_all();
    writer_.join();
    if (reader_fd_ >= 0) ::close(reader_fd_);
    if (reader_handoff_fd_ >= 0) ::close(reader_handoff_fd_);
  }

  SendResult send(std::span<const std::uint8_t> frame) noexcept override { return enqueue(ring_, frame); }
  // Ahead of every queued frame: an answer's round trip is what the autopilot measures its
  // clock offset with (PX4 drops round trips of 10 ms or more), and a queue of odometry at
  // 921600 baud is ~3 ms a frame.
  SendResult send_urgent(std::span<const std::uint8_t> frame) noexcept override { return enqueue(urgent_, frame); }

  void set_restamp(std::function<void(std::span<std::uint8_t>)> restamp) override {
    std::lock_guard lock(mutex_);
    restamp_ = std::move(restamp);
  }

  SendResult enqueue(FrameRing& ring, std::span<const std::uint8_t> frame) noexcept {
    if (frame.empty() || frame.size() > kMaxLinkFrameBytes) {
      {
        std::lock_guard lock(mutex_);
        ++rejected_;
      }
      problem_.report("frame rejected: empty or longer than 280 bytes", 0, false);
      return SendResult::Rejected;
    }
    bool dropped_oldest = false;
    bool up = false;
    {
      // The writer holds this lock only to copy one frame out (a few hundred bytes), never
      // across I/O, so this wait is microseconds at worst.
      std::lock_guard lock(mutex_);
      if (ring.full()) {
        ring.drop_oldest();
        ++dropped_queue_full_;
        dropped_oldest = true;
      }
      ring.push(frame);
      up = up_;
    }
    wake_writer_.notify_one();
    if (!dropped_oldest) return SendResult::Queued;
    // While the device is away its own problem (why it went) is the one worth reading.
    if (up) problem_.report("queue full, oldest frame dropped (the line is slower than the frames)", 0, false);
    return SendResult::QueuedDroppedOldest;
  }

  LinkStats stats() const override {
    LinkStats s;
    {
      std::lock_guard lock(mutex_);
      s.frames_sent = sent_;
      s.bytes_sent = bytes_;
      s.frames_dropped_queue_full = dropped_queue_full_;
      s.frames_dropped_link_down = dropped_link_down_;
      s.frames_rejected = rejected_;
      s.frames_pending = ring_.size() + urgent_.size() + (in_flight_ ? 1 : 0);
      s.errors = errors_;
      s.reconnects = reconnects_;
      s.link_up = up_;
    }
    s.bytes_received = bytes_received_.load(std::memory_order_relaxed);
    s.problem_reports = problem_.reports();
    return s;
  }

  std::string last_problem() const override { return problem_.text(); }
  std::string description() const override { return description_; }

  ReceiveResult receive(std::span<std::uint8_t> into, int timeout_ms) noexcept override {
    {
      std::unique_lock lock(mutex_);
      if (reader_handoff_fd_ >= 0) {  // the device was (re-)opened: read the new one
        if (reader_fd_ >= 0) ::close(reader_fd_);
        reader_fd_ = std::exchange(reader_handoff_fd_, -1);
      } else if (reader_fd_ < 0) {  // no device now: wait for one, a bounded time
        wake_reader_.wait_for(lock, std::chrono::milliseconds(timeout_ms), [this] { return reader_handoff_fd_ >= 0; });
        return {};
      }
    }
    pollfd p{reader_fd_, POLLIN, 0};
    if (::poll(&p, 1, timeout_ms) <= 0) return {};
    if ((p.revents & POLLIN) == 0) {  // hung up: the writer notices too, and re-opens
      drop_reader_fd();
      return {};
    }
    const ssize_t n = ::read(reader_fd_, into.data(), into.size());
    if (n <= 0) {
      if (n == 0 || (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) drop_reader_fd();
      return {};
    }
    bytes_received_.fetch_add(static_cast<std::uint64_t>(n), std::memory_order_relaxed);
    return {static_cast<std::size_t>(n), false};
  }

 private:
  void hand_to_reader(int fd) {
    const int copy = ::fcntl(fd, F_DUPFD_CLOEXEC, 0);
    if (copy < 0) return;  // out of descriptors: sending goes on, receiving waits for the next open
    {
      std::lock_guard lock(mutex_);
      if (reader_handoff_fd_ >= 0) ::close(reader_handoff_fd_);
      reader_handoff_fd_ = copy;
    }
    wake_reader_.notify_all();
  }

  void drop_reader_fd() {
    ::close(reader_fd_);
    reader_fd_ = -1;
  }

  void writer_loop() {
    pthread_setname_np(pthread_self(), "rgbdo-serial");  // for top -H on the vehicle
    while (!stopping()) {
      if (fd_ < 0)
        reopen_when_due();
      else if (!in_flight_ && !take_next_frame())
        check_idle_device();
      else
        write_some();
    }
    if (fd_ >= 0) {
      // Let the kernel hand the last bytes over before the close flushes them.
      int unsent = 0;
      while (steady_now_ns() < stop_deadline_ns_ && ::ioctl(fd_, TIOCOUTQ, &unsent) == 0 && unsent > 0)
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
      close_device(fd_);
    }
  }

  bool stopping() {
    std::lock_guard lock(mutex_);
    if (!stop_) return false;
    const bool drained = ring_.empty() && urgent_.empty() && !in_flight_;
    return drained || fd_ < 0 || steady_now_ns() >= stop_deadline_ns_;
  }

  void reopen_when_due() {
    const std::int64_t now_ns = steady_now_ns();
    if (now_ns >= next_open_ns_) {
      const OpenAttempt attempt = open_device(path_, speed_);
      if (attempt.fd >= 0) {
        fd_ = attempt.fd;
        {
          std::lock_guard lock(mutex_);
          up_ = true;
          ++reconnects_;
        }
        hand_to_reader(fd_);
        return;
      }
      {
        std::lock_guard lock(mutex_);
        ++errors_;
      }
      problem_.report(attempt.what, attempt.err);
      next_open_ns_ = now_ns + kReopenInterval_ns;
    }
    const std::int64_t wait_ns = std::min<std::int64_t>(next_open_ns_ - steady_now_ns(), kPollTimeout_ms * 1'000'000LL);
    std::unique_lock lock(mutex_);
    if (wait_ns > 0) wake_writer_.wait_for(lock, std::chrono::nanoseconds(wait_ns), [this] { return stop_; });
  }

  // The oldest waiting frame into in_flight_, waiting up to one poll period for one.
  bool take_next_frame() {
    std::unique_lock lock(mutex_);
    wake_writer_.wait_for(lock, std::chrono::milliseconds(kPollTimeout_ms),
                          [this] { return stop_ || !ring_.empty() || !urgent_.empty(); });
    if (ring_.empty() && urgent_.empty()) return false;  // stopping or not: what is queued is still written
    (urgent_.empty() ? ring_ : urgent_).pop_oldest_into(in_flight_frame_);
    if (restamp_) restamp_(std::span<std::uint8_t>(in_flight_frame_.bytes.data(), in_flight_frame_.size));
    in_flight_ = true;
    written_ = 0;
    return true;
  }

  // With nothing to send, still notice an unplugged device, so link_up and the problem text
  // tell the truth while the odometry is not producing frames.
  void check_idle_device() {
    pollfd p{fd_, 0, 0};
    if (::poll(&p, 1, 0) > 0 && (p.revents & (POLLHUP | POLLERR | POLLNVAL))) lose_device("device hung up", 0);
  }

  void write_some() {
    pollfd p{fd_, POLLOUT, 0};
    const int ready = ::poll(&p, 1, kPollTimeout_ms);
    if (ready < 0) {
      if (errno != EINTR) lose_device("poll failed", errno);
      return;
    }
    if (ready == 0) return;  // the line is still busy: check for stop, then wait again
    if (p.revents & (POLLHUP | POLLERR | POLLNVAL)) {
      lose_device("device hung up", 0);
      return;
    }
    const std::size_t size = in_flight_frame_.size;
    const ssize_t n = ::write(fd_, in_flight_frame_.bytes.data() + written_, size - written_);
    if (n < 0) {
      if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) lose_device("write failed", errno);
      return;
    }
    written_ += static_cast<std::size_t>(n);
    if (written_ < size) return;  // the rest of this frame, before any other
    std::lock_guard lock(mutex_);
    in_flight_ = false;
    ++sent_;
    bytes_ += size;
  }

  void lose_device(const char* what, int err) {
    close_device(fd_);
    fd_ = -1;
    {
      std::lock_guard lock(mutex_);
      if (in_flight_) ++dropped_link_down_;
      in_flight_ = false;
      up_ = false;
      ++errors_;
    }
    problem_.report(what, err);
    next_open_ns_ = steady_now_ns() + kReopenInterval_ns;
  }

  const std::string name_;
  std::string description_;
  LinkProblem problem_;
  const std::string path_;
  speed_t speed_ = B921600;

  // The writer thread's own (set before it starts).
  int fd_ = -1;
  std::int64_t next_open_ns_ = 0;
  FrameSlot in_flight_frame_;
  std::size_t written_ = 0;  // bytes of in_flight_frame_ already written

  // Shared with send() and stats(), under mutex_.
  mutable std::mutex mutex_;
  std::condition_variable wake_writer_;
  FrameRing ring_;
  FrameRing urgent_{kUrgentFrames};  // TIMESYNC answers: written before ring_
  std::function<void(std::span<std::uint8_t>)> restamp_;  // on each frame as it leaves (under mutex_)
  bool in_flight_ = false;  // in_flight_frame_ holds a frame not yet fully written
  bool up_ = false;
  bool stop_ = false;
  std::int64_t stop_deadline_ns_ = 0;
  std::uint64_t sent_ = 0, bytes_ = 0, dropped_queue_full_ = 0, dropped_link_down_ = 0, rejected_ = 0, errors_ = 0,
                reconnects_ = 0;

  // The receiver thread's own descriptor, and the one the writer hands over at an open (under mutex_).
  int reader_fd_ = -1;
  int reader_handoff_fd_ = -1;
  std::condition_variable wake_reader_;
  std::atomic<std::uint64_t> bytes_received_{0};

  std::thread writer_;
};

}  // namespace

std::unique_ptr<OutputLink> open_serial_link(const SerialLinkOptions& options) {
  return std::make_unique<SerialLink>(options);
}

}  // namespace rgbdo
