#include "rgbd_odometry/sensor/sensor_openni.hpp"

#include <OpenNI.h>

#include <array>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include "rgbd_odometry/core/clock.hpp"
#include "rgbd_odometry/pipeline/frame_convert.hpp"
#include "rgbd_odometry/sensor/device_clock.hpp"
#include "rgbd_odometry/io/tum_sequence.hpp"  // SourceError

namespace rgbdo {
namespace {

constexpr std::int64_t kMaxColourDepthOffsetNs = 20'000'000;
constexpr int kDepthHistory = 4;  // depth frames kept for pairing (~130 ms at 30 Hz)
// Waits are cut into slices this long so that interrupt() and an unplug are noticed promptly
// (the program must stop within a second of SIGINT whatever the sensor does).
constexpr int kWaitSliceMs = 50;

void initialise_openni() {
  if (openni::OpenNI::initialize() != openni::STATUS_OK)
    throw SourceError(std::string("OpenNI2 could not be initialised: ") + openni::OpenNI::getExtendedError());
}

std::string mode_text(const openni::VideoMode& m) {
  std::ostringstream s;
  s << m.getResolutionX() << "x" << m.getResolutionY() << "@" << m.getFps() << " format " << m.getPixelFormat();
  return s.str();
}

// The device's mode with the requested size and rate, in the first acceptable pixel format.
openni::VideoMode choose_mode(const openni::SensorInfo& info, int w, int h, int fps,
                              std::initializer_list<openni::PixelFormat> formats, const char* what) {
  const auto& modes = info.getSupportedVideoModes();
  for (const auto format : formats)
    for (int i = 0; i < modes.getSize(); ++i)
      if (modes[i].getResolutionX() == w && modes[i].getResolutionY() == h && modes[i].getFps() == fps &&
          modes[i].getPixelFormat() == format)
        return modes[i];
  std::ostringstream s;
  s << "the device offers no " << what << " mode " << w << "x" << h << "@" << fps << "; it offers:";
  for (int i = 0; i < modes.getSize(); ++i) s << " " << mode_text(modes[i]);
  throw SourceError(s.str());
}

// Colour frames a just-started live stream numbered before `first_index`, the first one read.
// OpenNI2's drivers number a created stream's frames from 1 (its PS1080 driver for the Xtion
// and Carmine does, as do its test driver and the virtual sensor), and a stream keeps only its
// newest frame: those the device sent before the reader first looked (a device that dropped
// its first frames, a reader stalled right after the start) were replaced unread, and are
// counted as the sensor's drops are. An index
// beyond ten seconds of frames is a device that numbers otherwise (a counter that does not
// restart with the stream): nothing is known of what it skipped, and nothing is counted.
int frames_numbered_before(int first_index, int fps) {
  return first_index > 1 && first_index <= 1 + 10 * fps ? first_index - 1 : 0;
}

}  // namespace

struct OpenNiSource::Impl : openni::OpenNI::DeviceDisconnectedListener {
  OpenNiOptions options;
  std::string uri;  // of the open device, as the runtime names it
  std::atomic<bool> interrupted{false}, unplugged{false};
  openni::Device device;
  openni::VideoStream colour, depth;
  openni::Recorder recorder;
  double depth_m_per_unit = 0.001;
  // Device microseconds -> host nanoseconds: anchored at the first frame's arrival, then
  // following the crystal's rate against the host's (src/sensor/device_clock.cpp). Intervals stay the
  // device's to parts per million (odometry divides by them), host times do not walk away, and
  // the lead that start-up put into the anchor is taken off (RgbdFrame::host_lead_ns).
  DeviceClock clock;
  struct DepthSlot {
    std::int64_t t_ns = 0;
    cv::Mat depth_m;
  };
  std::array<DepthSlot, kDepthHistory> depth_history;
  int depth_count = 0;
  int last_colour_index = -1;
  // Read by other threads (the status line) while the capture thread counts: atomic.
  std::atomic<int> dropped{0};   // colour frame indices the sensor skipped, or numbered before the first read
  std::atomic<int> without_depth{0};  // colour frames given up: no depth frame within 20 ms before newer ones came
  // A colour frame that arrived while the one before it waited for its depth: the next call's
  // frame (converted already).
  cv::Mat pending_gray;
  std::int64_t pending_t_ns = 0;
  bool has_pending = false;
  // A recording played by OniFile at "manual" speed: it reads the next frame of the file each
  // time a wait finds no frame ready ("pokes" the device). Its frames must be waited for in one
  // wait each: a second poke while the player is still decoding makes it deliver two frames,
  // and the first is overwritten before it is read (the likely cause of frames lost from a
  // playback under load).
  bool playback = false;
  bool started = false;  // the streams (start_streams)
  int colour_frames_in_file = 0, colour_frames_read = 0, depth_frames_in_file = 0;

  // Called on an OpenNI2 thread when any device goes away.
  void onDeviceDisconnected(const openni::DeviceInfo* info) override {
    if (info && uri == info->getUri()) unplugged = true;
  }

  std::int64_t to_host(std::uint64_t device_us) {
    return clock.to_host(static_cast<std::int64_t>(device_us) * 1000, steady_now_ns());
  }

  // The colour frame next() is pairing: its image is in the caller's frame.
  struct InHand {
    bool have_colour = false;
    std::int64_t t_ns = 0;
  };

  // --- the pairing policy: next() pairs each colour frame with the depth frame nearest in
  // time within 20 ms, before or after it ---
  int kept() const { return std::min(depth_count, kDepthHistory); }
  bool depth_at_or_after(std::int64_t t) const;
  DepthSlot* nearest_depth(std::int64_t t);
  bool earlier_depth_is_nearest(std::int64_t t);
  int wait_for_stream(openni::VideoStream** streams, int budget_ms);  // both streams
  void start_streams();
  bool collect(cv::Mat& gray, InHand& hand, std::string& problem);
  void store_depth(const openni::VideoFrameRef& frame, std::int64_t t);
  bool take_colour(const openni::VideoFrameRef& frame, std::int64_t t, cv::Mat& gray, InHand& hand);
  void take_pending(cv::Mat& gray, InHand& hand);
  void deliver(RgbdFrame& out, std::int64_t colour_t);
};

bool OpenNiSource::Impl::depth_at_or_after(std::int64_t t) const {
  for (int k = 0; k < kept(); ++k)
    if (depth_history[static_cast<size_t>(k)].t_ns >= t) return true;
  return false;
}

OpenNiSource::Impl::DepthSlot* OpenNiSource::Impl::nearest_depth(std::int64_t t) {
  DepthSlot* best = nullptr;
  for (int k = 0; k < kept(); ++k) {
    auto& slot = depth_history[static_cast<size_t>(k)];
    if (!best || std::llabs(slot.t_ns - t) < std::llabs(best->t_ns - t)) best = &slot;
  }
  return best && std::llabs(best->t_ns - t) <= kMaxColourDepthOffsetNs ? best : nullptr;
}

// The depth frame in hand before colour time t is the nearest for good when the stream's next
// one, due a depth interval after the newest, would be farther: no need to wait for it (at
// 30 Hz that wait is most of a frame's latency when depth leads colour).
bool OpenNiSource::Impl::earlier_depth_is_nearest(std::int64_t t) {
  if (kept() < 2) return false;
  // The stream's period: the shortest interval between kept frames (one the sensor skipped
  // makes a double one, which must not push the next frame's estimate out). Four frames at
  // most: every pair is compared.
  std::int64_t period = std::numeric_limits<std::int64_t>::max(), newest = 0;
  for (int i = 0; i < kept(); ++i) {
    const std::int64_t ti = depth_history[static_cast<size_t>(i)].t_ns;
    newest = i == 0 ? ti : std::max(newest, ti);
    for (int j = i + 1; j < kept(); ++j) {
      const std::int64_t gap = std::llabs(ti - depth_history[static_cast<size_t>(j)].t_ns);
      if (gap > 0) period = std::min(period, gap);
    }
  }
  if (period > 4 * kMaxColourDepthOffsetNs) return false;  // no estimate
  const std::int64_t next_due = newest + period;
  const DepthSlot* best = nearest_depth(t);
  return best && best->t_ns <= t && t - best->t_ns <= next_due - t;
}

// One wait for any stream, in slices (one wait for a recording, see `playback`): the ready
// stream's index; -1: the budget ran out, -2: interrupted or unplugged. Frames that arrived
// before an unplug are still read: they are as good as any other (the virtual sensor unplugs
// itself right after the last frame of its recording).
int OpenNiSource::Impl::wait_for_stream(openni::VideoStream** streams, int budget_ms) {
  if (playback) {
    if (interrupted) return -2;
    int ready = -1;
    return openni::OpenNI::waitForAnyStream(streams, 2, &ready, budget_ms) == openni::STATUS_OK ? ready : -1;
  }
  for (int waited = 0; waited < budget_ms; waited += kWaitSliceMs) {
    if (interrupted) return -2;
    int ready = -1;
    if (unplugged) return openni::OpenNI::waitForAnyStream(streams, 2, &ready, 0) == openni::STATUS_OK ? ready : -2;
    if (openni::OpenNI::waitForAnyStream(streams, 2, &ready, std::min(kWaitSliceMs, budget_ms - waited)) ==
        openni::STATUS_OK)
      return ready;
  }
  return -1;
}

// Collects frames until a colour frame is in hand and a depth frame at or after it has arrived
// (the nearest depth can come up to 17 ms after its colour frame), the next colour frame
// arrives with the nearest depth already in hand, or the wait runs out. false: next() has
// nothing to deliver (`problem` says why).
bool OpenNiSource::Impl::collect(cv::Mat& gray, InHand& hand, std::string& problem) {
  openni::VideoStream* streams[2] = {&colour, &depth};
  openni::VideoFrameRef frame;
  while (!(hand.have_colour && (depth_at_or_after(hand.t_ns) || earlier_depth_is_nearest(hand.t_ns)))) {
    // A recording holds its next depth frame unless all were read: wait for it as for any frame,
    // so that pairing never depends on how fast the player decodes.
    if (hand.have_colour && playback && depth_count >= depth_frames_in_file) break;
    const int ready =
        wait_for_stream(streams, hand.have_colour && !playback ? options.pairing_wait_ms : options.frame_timeout_ms);
    if (ready == -2) {
      if (hand.have_colour && !interrupted) break;  // unplugged: the frame in hand goes out first
      problem = unplugged ? "the sensor was disconnected" : "interrupted";
      return false;
    }
    if (ready < 0) {
      if (hand.have_colour) break;  // no later depth: pair with what there is
      problem = "no frame from the sensor for " + std::to_string(options.frame_timeout_ms) + " ms (unplugged?)";
      return false;
    }
    if (streams[ready]->readFrame(&frame) != openni::STATUS_OK) continue;
    const std::int64_t t = to_host(frame.getTimestamp());
    if (ready == 1) {
      store_depth(frame, t);
      continue;
    }
    if (take_colour(frame, t, gray, hand)) break;
  }
  return true;
}

// Started at the first read, not when the device opens: a stream keeps only its newest frame,
// so whatever the program does between the two (its link, its pipeline's buffers and threads:
// tens of ms) would replace the first frames unread.
void OpenNiSource::Impl::start_streams() {
  if (colour.start() != openni::STATUS_OK || depth.start() != openni::STATUS_OK)
    throw SourceError(std::string("cannot start the OpenNI2 streams: ") + openni::OpenNI::getExtendedError());
  started = true;
}

void OpenNiSource::Impl::store_depth(const openni::VideoFrameRef& frame, std::int64_t t) {
  auto& slot = depth_history[static_cast<size_t>(depth_count++ % kDepthHistory)];
  slot.t_ns = t;
  const cv::Mat raw(frame.getHeight(), frame.getWidth(), CV_16UC1, const_cast<void*>(frame.getData()),
                    static_cast<size_t>(frame.getStrideInBytes()));
  depth_to_metres(raw, depth_m_per_unit, slot.depth_m);
}

// A colour frame read: the one in hand if there was none, else kept behind it. true: the
// collecting is over (the depth nearest the frame in hand is there).
bool OpenNiSource::Impl::take_colour(const openni::VideoFrameRef& frame, std::int64_t t, cv::Mat& gray,
                                     InHand& hand) {
  const int index = frame.getFrameIndex();
  if (last_colour_index >= 0 && index > last_colour_index + 1) dropped += index - last_colour_index - 1;
  if (last_colour_index < 0 && !playback) dropped += frames_numbered_before(index, options.fps);
  last_colour_index = index;
  const cv::Mat rgb(frame.getHeight(), frame.getWidth(), CV_8UC3, const_cast<void*>(frame.getData()),
                    static_cast<size_t>(frame.getStrideInBytes()));
  ++colour_frames_read;
  if (!hand.have_colour) {
    colour_to_gray(rgb, true, gray);
    hand = {true, t};
    return false;
  }
  // A newer colour frame while the one in hand waits for a depth at or after it. It is kept
  // for the next call, never replaces the one in hand: the depth nearest in time may be the
  // one before (the sensor's streams lead and lag each other by up to half a frame).
  if (has_pending) {
    // Already one waiting behind it: the frame in hand had two frame times to get a depth
    // and did not. Given up and counted, so that no frame goes unseen.
    ++without_depth;
    cv::swap(gray, pending_gray);
    hand.t_ns = pending_t_ns;
  }
  colour_to_gray(rgb, true, pending_gray);
  pending_t_ns = t;
  has_pending = true;
  // A depth frame within 20 ms is in hand: one still to come would be later than this
  // newer colour frame's arrival, and no nearer.
  return nearest_depth(hand.t_ns) != nullptr;
}

// The frame kept behind the one in hand becomes the one in hand.
void OpenNiSource::Impl::take_pending(cv::Mat& gray, InHand& hand) {
  cv::swap(gray, pending_gray);
  hand = {true, pending_t_ns};
  has_pending = false;
}

void OpenNiSource::Impl::deliver(RgbdFrame& out, std::int64_t colour_t) {
  out.t_colour_ns = colour_t;
  out.host_lead_ns = clock.lead_ns();  // as proved by every frame read so far, this one's depth too
  out.status = Status::Ok;
  out.problem.clear();
  const DepthSlot* best = nearest_depth(colour_t);
  if (!best) {
    out.t_depth_ns = colour_t;
    out.status = Status::NoDepth;
    out.problem = "no depth frame within 20 ms of the colour frame";
    // The status says there is none; the buffer is kept for the next frame (releasing a 1.2-MB
    // image and allocating it again moves glibc's mmap threshold, and the heap grows for it).
    return;
  }
  out.t_depth_ns = best->t_ns;
  best->depth_m.copyTo(out.depth_m);
}

std::vector<DeviceDescription> list_openni_devices() {
  initialise_openni();
  openni::Array<openni::DeviceInfo> infos;
  openni::OpenNI::enumerateDevices(&infos);
  std::vector<DeviceDescription> out;
  for (int i = 0; i < infos.getSize(); ++i)
    out.push_back({infos[i].getUri(), infos[i].getVendor(), infos[i].getName(),
                   static_cast<std::uint16_t>(infos[i].getUsbVendorId()),
                   static_cast<std::uint16_t>(infos[i].getUsbProductId())});
  return out;
}

OpenNiSource::OpenNiSource(const OpenNiOptions& options) : impl_(std::make_unique<Impl>()) {
  auto& s = *impl_;
  s.options = options;
  initialise_openni();
  const char* uri = options.uri.empty() ? openni::ANY_DEVICE : options.uri.c_str();
  if (s.device.open(uri) != openni::STATUS_OK)
    throw SourceError("cannot open OpenNI2 device '" + (options.uri.empty() ? std::string("(first found)") : options.uri) +
                      "': " + openni::OpenNI::getExtendedError());
  const openni::SensorInfo* colour_info = s.device.getSensorInfo(openni::SENSOR_COLOR);
  const openni::SensorInfo* depth_info = s.device.getSensorInfo(openni::SENSOR_DEPTH);
  if (!colour_info || !depth_info) throw SourceError("the OpenNI2 device has no colour or no depth sensor");
  const auto colour_mode =
      choose_mode(*colour_info, options.width, options.height, options.fps, {openni::PIXEL_FORMAT_RGB888}, "colour");
  const auto depth_mode = choose_mode(*depth_info, options.width, options.height, options.fps,
                                      {openni::PIXEL_FORMAT_DEPTH_100_UM, openni::PIXEL_FORMAT_DEPTH_1_MM}, "depth");
  s.depth_m_per_unit = depth_mode.getPixelFormat() == openni::PIXEL_FORMAT_DEPTH_100_UM ? 1e-4 : 1e-3;

  if (s.colour.create(s.device, openni::SENSOR_COLOR) != openni::STATUS_OK ||
      s.depth.create(s.device, openni::SENSOR_DEPTH) != openni::STATUS_OK)
    throw SourceError(std::string("cannot create the OpenNI2 streams: ") + openni::OpenNI::getExtendedError());
  const bool playback = s.playback = s.device.isFile();
  s.clock = DeviceClock(/*follow_rate=*/!playback);
  // A recording plays in the modes it was recorded in (choose_mode checked them above).
  if (!playback &&
      (s.colour.setVideoMode(colour_mode) != openni::STATUS_OK || s.depth.setVideoMode(depth_mode) != openni::STATUS_OK))
    throw SourceError(std::string("the device refused the video modes: ") + openni::OpenNI::getExtendedError());
  if (playback) {
    // Play once, each frame when it is read ("manual" speed): a recording is replayed
    // losslessly, at the pace of the pipeline, as a TUM sequence is.
    s.device.getPlaybackControl()->setRepeatEnabled(false);
    s.device.getPlaybackControl()->setSpeed(-1.0f);
    s.colour_frames_in_file = s.device.getPlaybackControl()->getNumberOfFrames(s.colour);
    s.depth_frames_in_file = s.device.getPlaybackControl()->getNumberOfFrames(s.depth);
  }
  if (options.registration && !playback) {  // a recording is registered, or not, already
    if (!s.device.isImageRegistrationModeSupported(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) ||
        s.device.setImageRegistrationMode(openni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) != openni::STATUS_OK)
      throw SourceError("the device cannot register depth to colour in hardware");
  }
  // Frame sync where the driver offers it; pairing by timestamp below works either way.
  (void)s.device.setDepthColorSyncEnabled(true);
  (void)s.colour.setMirroringEnabled(false);
  (void)s.depth.setMirroringEnabled(false);
  s.uri = s.device.getDeviceInfo().getUri();
  // The recorder starts before the streams do, so that their first frames are in the file.
  if (!options.record_path.empty() &&
      (s.recorder.create(options.record_path.c_str()) != openni::STATUS_OK ||
       s.recorder.attach(s.colour) != openni::STATUS_OK || s.recorder.attach(s.depth) != openni::STATUS_OK ||
       s.recorder.start() != openni::STATUS_OK))
    throw SourceError("cannot record to '" + options.record_path + "': " + openni::OpenNI::getExtendedError());
  if (openni::OpenNI::addDeviceDisconnectedListener(impl_.get()) != openni::STATUS_OK)
    throw SourceError("cannot watch the OpenNI2 device for disconnection");
  for (auto& slot : s.depth_history) slot.depth_m.create(options.height, options.width, CV_32FC1);
  s.pending_gray.create(options.height, options.width, CV_8UC1);  // no allocation when one first waits
}

OpenNiSource::~OpenNiSource() {
  openni::OpenNI::removeDeviceDisconnectedListener(impl_.get());
  if (impl_->recorder.isValid()) {
    impl_->recorder.stop();
    impl_->recorder.destroy();
  }
  impl_->colour.stop();
  impl_->depth.stop();
  impl_->colour.destroy();
  impl_->depth.destroy();
  impl_->device.close();
}

int OpenNiSource::dropped_colour_frames() const { return impl_->dropped; }

int OpenNiSource::colour_frames_without_depth() const { return impl_->without_depth; }

void OpenNiSource::interrupt() { impl_->interrupted = true; }

std::string OpenNiSource::description() const {
  const auto& s = *impl_;
  std::ostringstream d;
  d << s.device.getDeviceInfo().getVendor() << " " << s.device.getDeviceInfo().getName() << " ("
    << s.device.getDeviceInfo().getUri() << "), colour " << mode_text(s.colour.getVideoMode()) << ", depth "
    << mode_text(s.depth.getVideoMode());
  return d.str();
}

bool OpenNiSource::next(RgbdFrame& out, std::string& problem) {
  auto& s = *impl_;
  if (!s.started) s.start_streams();
  Impl::InHand hand;
  if (s.has_pending) s.take_pending(out.gray, hand);  // the frame that came while the last one waited
  if (!hand.have_colour && s.playback && s.colour_frames_read >= s.colour_frames_in_file) {
    problem = "all " + std::to_string(s.colour_frames_in_file) + " colour frames of the file read";
    return false;
  }
  for (;;) {
    if (!s.collect(out.gray, hand, problem)) return false;
    // No depth within 20 ms for the frame in hand, and a newer frame waits behind it: give the
    // older one up (counted) rather than send a frame without depth, which fails two pairs.
    if (s.nearest_depth(hand.t_ns) || !s.has_pending) break;
    ++s.without_depth;
    s.take_pending(out.gray, hand);
  }
  s.deliver(out, hand.t_ns);
  return true;
}

}  // namespace rgbdo
