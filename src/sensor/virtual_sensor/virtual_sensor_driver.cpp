// An OpenNI2 driver plugin that presents a recorded TUM RGB-D sequence as a live device:
// a colour stream (RGB888) and a depth stream (DEPTH_100_UM, registered to colour, which is
// how TUM recorded it), each frame delivered at its recorded time (scaled by `rate`) from when
// the first stream starts, with device timestamps in microseconds from the first frame and
// per-stream frame indices (from 1).
// OpenNI2 loads it like any vendor driver, so code under test reads it exactly as it reads a
// PrimeSense sensor.
//
// URI: rgbdo-virtual:<TUM directory>[?rate=R&drop=i,j&stall=i:ms&disconnect=i&reconnect=ms&loop=N]
//   rate        playback speed (1 = recorded rate)
//   drop        colour frames (0-based, of the recording) never delivered (their index is
//               skipped, as a USB drop)
//   stall       before colour frame i (0-based, of the recording), both streams stop for
//               `ms` milliseconds
//   disconnect  at colour frame i the device reports itself disconnected and stops
//   reconnect   `ms` after the disconnect the device is plugged back in: it can be opened
//               again and plays on from the frames recorded by then (the scene went on
//               while it was away), as a sensor on a loose cable does
//   loop        play the recording this many times, one pass after the other on one clock
//               and one frame numbering (soak runs)
// Other parameters (say id=3, to tell otherwise equal URIs apart) are ignored.
// When the recording has been played to its end the device unplugs itself for good: a
// program reading it sees what it would see of a sensor pulled out for ever.
// The device is also announced at start-up when RGBDO_VIRTUAL_SENSOR holds such a URI.
// When RGBDO_VIRTUAL_SENSOR_CLOCK_FILE names a file, the player writes it a line
// "START_NS RECORDED_NS PASS_NS" when it starts: the steady clock (CLOCK_MONOTONIC) at which the
// recording's first instant RECORDED_NS is due (its device time 0; later frames are due and
// stamped (t - RECORDED_NS) / rate after it) and the time between passes of a looped recording:
// a test's simulated autopilot maps the recording's ground truth onto the program's clock with it.
#include <Driver/OniDriverAPI.h>

#include <algorithm>
#include <atomic>
#include <charconv>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "rgbd_odometry/io/tum_sequence.hpp"
#include "virtual_sensor_uri.hpp"

namespace {

using rgbdo::virtual_sensor::Options;
using rgbdo::virtual_sensor::parse_uri;

constexpr int kWidth = 640, kHeight = 480, kFps = 30;

struct Event {
  std::int64_t t_ns;
  bool colour;
  std::string path;
};

// What outlives one open of a device: the recording's clock (it runs on while the device is
// unplugged) and whether the one disconnect has happened. Shared by every open of a URI.
struct Timeline {
  std::mutex mutex;
  std::chrono::steady_clock::time_point start;
  bool disconnected = false;
  bool exhausted = false;  // played to the end: gone for good
  std::chrono::steady_clock::time_point back_at;
  bool unplugged_now() {
    std::lock_guard<std::mutex> lock(mutex);
    return exhausted || (disconnected && std::chrono::steady_clock::now() < back_at);
  }
};

// A recording's frames as the device delivers them (RGB888, depth in 100 um), decoded from
// their PNG files. A looped recording is decoded before it starts playing (when the device
// is opened) and kept when it fits in kKeptBytes (the bundled 40 frames: 61 MB): a soak's
// passes then cost what the program under test does, not the player's decoding, and every
// pass reaches the reader as soon after its due time as the others. A frame of another size
// than the device's is none (an empty image: the reader sees the gap in the indices), a huge
// one refused from its PNG header before it is decoded.
class RecordedImages {
 public:
  RecordedImages(const std::vector<Event>& events, int loops) : events_(events) {
    if (loops > 1 && events.size() * kFrameBytes <= kKeptBytes)
      for (const Event& e : events) kept_.push_back(decode(e));
  }

  cv::Mat at(std::size_t i) const { return i < kept_.size() ? kept_[i] : decode(events_[i]); }

 private:
  static constexpr std::size_t kFrameBytes = std::size_t{kWidth} * kHeight * 3;  // the larger stream's
  static constexpr std::size_t kKeptBytes = std::size_t{256} << 20;

  static cv::Mat decode(const Event& e) {
    const auto declared = rgbdo::png_declared_size(e.path);
    if (declared && (declared->first != std::uint32_t{kWidth} || declared->second != std::uint32_t{kHeight})) return {};
    cv::Mat image = cv::imread(e.path, e.colour ? cv::IMREAD_COLOR : cv::IMREAD_ANYDEPTH);
    if (image.empty() || image.cols != kWidth || image.rows != kHeight) return {};
    if (e.colour) {
      cv::cvtColor(image, image, cv::COLOR_BGR2RGB);
    } else {
      image.convertTo(image, CV_16U, 2.0);  // TUM: 5000 per metre = 0.2 mm; 100 um units: x2, exact
    }
    return image;
  }

  const std::vector<Event>& events_;
  std::vector<cv::Mat> kept_;
};

// Colour and depth images of the recording in time order, read by the program's own TUM
// reader (io/tum_sequence.hpp); empty when the recording cannot be read.
std::vector<Event> read_events(const std::string& dir) {
  std::vector<Event> events;
  try {
    for (const bool colour : {true, false})
      for (auto& image : rgbdo::read_tum_images(dir, colour ? "rgb.txt" : "depth.txt"))
        events.push_back({image.t_ns, colour, std::move(image.path)});
  } catch (const rgbdo::SourceError&) {
    return {};
  }
  std::stable_sort(events.begin(), events.end(), [](const Event& a, const Event& b) { return a.t_ns < b.t_ns; });
  return events;
}

class VirtualStream : public oni::driver::StreamBase {
 public:
  VirtualStream(OniSensorType type, std::function<void()> on_start) : type_(type), on_start_(std::move(on_start)) {}
  OniStatus start() override {
    running_ = true;
    on_start_();
    return ONI_STATUS_OK;
  }
  void stop() override { running_ = false; }
  bool running() const { return running_; }
  OniSensorType type() const { return type_; }

  OniVideoMode mode() const {
    return OniVideoMode{type_ == ONI_SENSOR_COLOR ? ONI_PIXEL_FORMAT_RGB888 : ONI_PIXEL_FORMAT_DEPTH_100_UM, kWidth,
                        kHeight, kFps};
  }
  int bytes_per_pixel() const { return type_ == ONI_SENSOR_COLOR ? 3 : 2; }

  OniStatus getProperty(int id, void* data, int* size) override {
    switch (id) {
      case ONI_STREAM_PROPERTY_VIDEO_MODE:
        if (*size != sizeof(OniVideoMode)) return ONI_STATUS_BAD_PARAMETER;
        *static_cast<OniVideoMode*>(data) = mode();
        return ONI_STATUS_OK;
      case ONI_STREAM_PROPERTY_STRIDE:
        return put<int>(data, size, kWidth * bytes_per_pixel());
      case ONI_STREAM_PROPERTY_MIRRORING:
        return put<OniBool>(data, size, FALSE);
      case ONI_STREAM_PROPERTY_CROPPING: {
        if (*size != sizeof(OniCropping)) return ONI_STATUS_BAD_PARAMETER;
        *static_cast<OniCropping*>(data) = OniCropping{FALSE, 0, 0, kWidth, kHeight};
        return ONI_STATUS_OK;
      }
      case ONI_STREAM_PROPERTY_HORIZONTAL_FOV:  // Kinect v1 colour camera, fr1 calibration
        return put<float>(data, size, 2.0f * std::atan(kWidth / (2.0f * 517.3f)));
      case ONI_STREAM_PROPERTY_VERTICAL_FOV:
        return put<float>(data, size, 2.0f * std::atan(kHeight / (2.0f * 516.5f)));
      case ONI_STREAM_PROPERTY_MAX_VALUE:
        return put<int>(data, size, type_ == ONI_SENSOR_DEPTH ? 65535 : 255);
      case ONI_STREAM_PROPERTY_MIN_VALUE:
        return put<int>(data, size, 0);
      default:
        return ONI_STATUS_NOT_SUPPORTED;
    }
  }
  OniStatus setProperty(int id, const void* data, int size) override {
    if (id == ONI_STREAM_PROPERTY_MIRRORING && size == sizeof(OniBool))
      return *static_cast<const OniBool*>(data) ? ONI_STATUS_NOT_SUPPORTED : ONI_STATUS_OK;
    if (id == ONI_STREAM_PROPERTY_VIDEO_MODE && size == sizeof(OniVideoMode)) {
      const auto& m = *static_cast<const OniVideoMode*>(data);
      const OniVideoMode own = mode();
      return m.pixelFormat == own.pixelFormat && m.resolutionX == own.resolutionX &&
                     m.resolutionY == own.resolutionY && m.fps == own.fps
                 ? ONI_STATUS_OK
                 : ONI_STATUS_NOT_SUPPORTED;
    }
    return ONI_STATUS_NOT_SUPPORTED;
  }
  OniBool isPropertySupported(int id) override {
    return id == ONI_STREAM_PROPERTY_VIDEO_MODE || id == ONI_STREAM_PROPERTY_STRIDE ||
           id == ONI_STREAM_PROPERTY_MIRRORING || id == ONI_STREAM_PROPERTY_CROPPING ||
           id == ONI_STREAM_PROPERTY_HORIZONTAL_FOV || id == ONI_STREAM_PROPERTY_VERTICAL_FOV ||
           id == ONI_STREAM_PROPERTY_MAX_VALUE || id == ONI_STREAM_PROPERTY_MIN_VALUE;
  }
  int getRequiredFrameSize() override { return kWidth * kHeight * bytes_per_pixel(); }

  // Delivers one decoded image (CV_8UC3 RGB or CV_16UC1 in 100 um units).
  void deliver(const cv::Mat& image, std::uint64_t timestamp_us, int index) {
    if (!running_) return;
    OniFrame* frame = getServices().acquireFrame();
    if (frame == nullptr) return;
    const int bytes = getRequiredFrameSize();
    std::memcpy(frame->data, image.data, static_cast<size_t>(bytes));
    frame->dataSize = bytes;
    frame->sensorType = type_;
    frame->timestamp = timestamp_us;
    frame->frameIndex = index;
    frame->width = kWidth;
    frame->height = kHeight;
    frame->videoMode = mode();
    frame->croppingEnabled = FALSE;
    frame->cropOriginX = frame->cropOriginY = 0;
    frame->stride = kWidth * bytes_per_pixel();
    raiseNewFrame(frame);
    getServices().releaseFrame(frame);
  }

 private:
  template <typename T>
  static OniStatus put(void* data, int* size, T value) {
    if (*size != static_cast<int>(sizeof(T))) return ONI_STATUS_BAD_PARAMETER;
    *static_cast<T*>(data) = value;
    return ONI_STATUS_OK;
  }
  OniSensorType type_;
  std::function<void()> on_start_;
  std::atomic<bool> running_{false};
};

class VirtualDevice : public oni::driver::DeviceBase {
 public:
  VirtualDevice(const OniDeviceInfo& info, Options options, std::shared_ptr<Timeline> timeline,
                std::function<void()> on_disconnect)
      : info_(info), options_(std::move(options)), timeline_(std::move(timeline)),
        on_disconnect_(std::move(on_disconnect)), events_(read_events(options_.directory)),
        images_(events_, options_.loops) {
    colour_modes_[0] = OniVideoMode{ONI_PIXEL_FORMAT_RGB888, kWidth, kHeight, kFps};
    depth_modes_[0] = OniVideoMode{ONI_PIXEL_FORMAT_DEPTH_100_UM, kWidth, kHeight, kFps};
    sensors_[0] = OniSensorInfo{ONI_SENSOR_COLOR, 1, colour_modes_};
    sensors_[1] = OniSensorInfo{ONI_SENSOR_DEPTH, 1, depth_modes_};
  }
  ~VirtualDevice() override {
    stop_ = true;
    if (player_.joinable()) player_.join();
    // The re-plugged device has been used up: a later open of the URI starts the story anew.
    if (resumed_) {
      std::lock_guard<std::mutex> lock(timeline_->mutex);
      timeline_->disconnected = false;
    }
  }

  OniStatus getSensorInfoList(OniSensorInfo** infos, int* count) override {
    *infos = sensors_;
    *count = 2;
    return ONI_STATUS_OK;
  }
  oni::driver::StreamBase* createStream(OniSensorType type) override {
    if (type != ONI_SENSOR_COLOR && type != ONI_SENSOR_DEPTH) return nullptr;
    std::lock_guard<std::mutex> lock(mutex_);
    // The recording starts playing when a stream first starts, as a sensor starts sending
    // then: a reader that starts its streams late loses nothing.
    auto* s = new VirtualStream(type, [this] {
      std::call_once(play_once_, [this] { player_ = std::thread([this] { play(); }); });
    });
    (type == ONI_SENSOR_COLOR ? colour_ : depth_) = s;
    return s;
  }
  void destroyStream(oni::driver::StreamBase* stream) override {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stream == colour_) colour_ = nullptr;
    if (stream == depth_) depth_ = nullptr;
    delete stream;
  }
  OniStatus getProperty(int id, void* data, int* size) override {
    if (id == ONI_DEVICE_PROPERTY_IMAGE_REGISTRATION && *size == sizeof(OniImageRegistrationMode)) {
      *static_cast<OniImageRegistrationMode*>(data) = ONI_IMAGE_REGISTRATION_DEPTH_TO_COLOR;
      return ONI_STATUS_OK;
    }
    if (id == ONI_DEVICE_PROPERTY_SERIAL_NUMBER && *size >= 16) {
      std::snprintf(static_cast<char*>(data), static_cast<size_t>(*size), "virtual-0001");
      return ONI_STATUS_OK;
    }
    return ONI_STATUS_NOT_SUPPORTED;
  }
  OniStatus setProperty(int id, const void* data, int size) override {
    // The recorded depth is registered to colour already: that is the only mode offered.
    if (id == ONI_DEVICE_PROPERTY_IMAGE_REGISTRATION && size == sizeof(OniImageRegistrationMode))
      return *static_cast<const OniImageRegistrationMode*>(data) == ONI_IMAGE_REGISTRATION_DEPTH_TO_COLOR
                 ? ONI_STATUS_OK
                 : ONI_STATUS_NOT_SUPPORTED;
    return ONI_STATUS_NOT_SUPPORTED;
  }
  OniBool isPropertySupported(int id) override {
    return id == ONI_DEVICE_PROPERTY_IMAGE_REGISTRATION || id == ONI_DEVICE_PROPERTY_SERIAL_NUMBER;
  }
  OniBool isImageRegistrationModeSupported(OniImageRegistrationMode mode) override {
    return mode == ONI_IMAGE_REGISTRATION_DEPTH_TO_COLOR;
  }
  const OniDeviceInfo& info() const { return info_; }

 private:
  static void write_clock_file(std::chrono::steady_clock::time_point start, std::int64_t recorded_ns,
                               std::int64_t pass_ns) {
    const char* path = std::getenv("RGBDO_VIRTUAL_SENSOR_CLOCK_FILE");
    if (path == nullptr) return;
    const auto start_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(start.time_since_epoch()).count();
    if (std::FILE* f = std::fopen(path, "w")) {
      std::fprintf(f, "%lld %lld %lld\n", static_cast<long long>(start_ns), static_cast<long long>(recorded_ns),
                   static_cast<long long>(pass_ns));
      std::fclose(f);
    }
  }

  // Plays the recording in real time (scaled by rate) to whichever streams are started.
  void play() {
    const std::vector<Event>& events = events_;
    if (events.empty()) return;
    const std::int64_t t0_ns = events.front().t_ns;
    std::chrono::steady_clock::time_point start;
    bool resumed = false;
    {
      std::lock_guard<std::mutex> lock(timeline_->mutex);
      resumed = timeline_->disconnected;
      if (!resumed) timeline_->start = std::chrono::steady_clock::now();
      start = timeline_->start;
      resumed_ = resumed;
    }
    const auto opened = std::chrono::steady_clock::now();
    const auto seconds_since = [](std::chrono::steady_clock::time_point t) {
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
    };
    double stalled_s = 0;
    int colour_index = 0, depth_index = 0;  // in the recording: what drop, stall and disconnect name
    // What the device numbers its frames, as OpenNI2's drivers do: from 1 for the first frame
    // after the streams are opened (a re-plugged device starts again), a dropped frame's number
    // left out.
    int colour_numbered = 0, depth_numbered = 0;
    // Each pass of a looped recording follows the last one a frame period later, on one clock,
    // shifted by whole microseconds (the timestamps' unit): every pass has the same intervals.
    const std::int64_t pass_ns = (events.back().t_ns - t0_ns + 1'000'000'000 / kFps) / 1000 * 1000;
    if (!resumed) write_clock_file(start, t0_ns, pass_ns);
    for (int pass = 0; pass < options_.loops; ++pass) {
      for (std::size_t i = 0; i < events.size(); ++i) {
        const Event& e = events[i];
        if (stop_) return;
        const std::int64_t t_ns = e.t_ns + pass * pass_ns;
        if (e.colour && colour_index == options_.disconnect_at && !resumed) {
          {
            std::lock_guard<std::mutex> lock(timeline_->mutex);
            timeline_->disconnected = true;
            timeline_->back_at = options_.reconnect_ms < 0
                                     ? std::chrono::steady_clock::time_point::max()
                                     : std::chrono::steady_clock::now() + std::chrono::milliseconds(options_.reconnect_ms);
          }
          on_disconnect_();
          return;
        }
        if (e.colour && colour_index == options_.stall_at) stalled_s += options_.stall_ms * 1e-3;
        const double due_s = static_cast<double>(t_ns - t0_ns) * 1e-9 / options_.rate + stalled_s;
        const auto timestamp_us = static_cast<std::uint64_t>((t_ns - t0_ns + 500) / 1000);
        const int index = e.colour ? colour_index++ : depth_index++;
        // Re-plugged: what was recorded while the device was away is gone.
        if (resumed && due_s < std::chrono::duration<double>(opened - start).count()) continue;
        while (!stop_ && seconds_since(start) < due_s) std::this_thread::sleep_for(std::chrono::milliseconds(1));
        const int frame_number = e.colour ? ++colour_numbered : ++depth_numbered;
        if (e.colour && options_.drop.count(index)) continue;
        const cv::Mat image = images_.at(i);
        if (image.empty()) continue;
        std::lock_guard<std::mutex> lock(mutex_);
        VirtualStream* s = e.colour ? colour_ : depth_;
        if (s) s->deliver(image, timestamp_us, frame_number);
      }
    }
    // The last frames are out; a frame period later the recording's device leaves.
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(static_cast<int>(100 / options_.rate));
    while (!stop_ && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    if (stop_) return;
    {
      std::lock_guard<std::mutex> lock(timeline_->mutex);
      timeline_->exhausted = true;
    }
    on_disconnect_();
  }

  OniDeviceInfo info_;
  Options options_;
  std::shared_ptr<Timeline> timeline_;
  std::function<void()> on_disconnect_;
  // Read when the device is opened: a looped recording is decoded then, before a stream asks
  // for frames (under qemu 80 frames take seconds, longer than a reader waits for its first).
  const std::vector<Event> events_;
  const RecordedImages images_;
  OniVideoMode colour_modes_[1], depth_modes_[1];
  OniSensorInfo sensors_[2];
  std::mutex mutex_;
  VirtualStream* colour_ = nullptr;
  VirtualStream* depth_ = nullptr;
  // Started once, by the first stream's start(): not under mutex_, which the player holds
  // while it hands OpenNI2 a frame, while OpenNI2 may hold its own lock around a start().
  std::once_flag play_once_;
  std::thread player_;
  std::atomic<bool> stop_{false};
  bool resumed_ = false;
};

class VirtualDriver : public oni::driver::DriverBase {
 public:
  explicit VirtualDriver(OniDriverServices* services) : DriverBase(services) {}
  ~VirtualDriver() override { shutdown(); }

  OniStatus initialize(oni::driver::DeviceConnectedCallback connected, oni::driver::DeviceDisconnectedCallback disconnected,
                       oni::driver::DeviceStateChangedCallback state_changed, void* cookie) override {
    DriverBase::initialize(connected, disconnected, state_changed, cookie);
    if (const char* uri = std::getenv("RGBDO_VIRTUAL_SENSOR")) tryDevice(uri);
    return ONI_STATUS_OK;
  }
  OniStatus tryDevice(const char* uri) override {
    Options o;
    if (!parse_uri(uri, o)) return ONI_STATUS_ERROR;
    const auto timeline = timeline_of(uri);
    if (timeline->unplugged_now()) return ONI_STATUS_NO_DEVICE;
    std::lock_guard<std::mutex> lock(mutex_);
    if (announced_.count(uri)) return ONI_STATUS_OK;
    const OniDeviceInfo info = info_for(uri);
    announced_.insert(uri);
    deviceConnected(&info);
    return ONI_STATUS_OK;
  }
  oni::driver::DeviceBase* deviceOpen(const char* uri, const char* /*mode*/) override {
    Options o;
    if (!parse_uri(uri, o)) return nullptr;
    const auto timeline = timeline_of(uri);
    if (timeline->unplugged_now()) return nullptr;
    const OniDeviceInfo info = info_for(uri);
    return new VirtualDevice(info, o, timeline, [this, info, timeline] {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        announced_.erase(info.uri);
        if (!timeline->exhausted) replugs_.push_back(info);
      }
      deviceDisconnected(&info);
    });
  }
  void deviceClose(oni::driver::DeviceBase* device) override { delete device; }
  void shutdown() override {
    stop_ = true;
    if (replugger_.joinable()) replugger_.join();
  }

 private:
  static OniDeviceInfo info_for(const char* uri) {
    OniDeviceInfo info{};
    std::snprintf(info.uri, ONI_MAX_STR, "%s", uri);
    std::snprintf(info.vendor, ONI_MAX_STR, "rgbd-odometry");
    std::snprintf(info.name, ONI_MAX_STR, "virtual sensor (TUM replay)");
    return info;
  }
  std::shared_ptr<Timeline> timeline_of(const std::string& uri) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto& t = timelines_[uri];
    if (!t) t = std::make_shared<Timeline>();
    return t;
  }
  // A real driver announces a device again when USB reports it back (OpenNI2 finds a
  // disconnected device only through such an announcement); this thread does that for a
  // virtual device whose reconnect time has come.
  void replug_when_due() {
    while (!stop_) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      std::vector<OniDeviceInfo> due;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        for (auto it = replugs_.begin(); it != replugs_.end();) {
          if (!timelines_[it->uri]->unplugged_now()) {
            due.push_back(*it);
            announced_.insert(it->uri);
            it = replugs_.erase(it);
          } else {
            ++it;
          }
        }
      }
      for (const auto& info : due) deviceConnected(&info);
    }
  }
  std::mutex mutex_;
  std::set<std::string> announced_;
  std::map<std::string, std::shared_ptr<Timeline>> timelines_;
  std::vector<OniDeviceInfo> replugs_;
  std::atomic<bool> stop_{false};
  std::thread replugger_{[this] { replug_when_due(); }};
};

}  // namespace

// ONI_EXPORT_DRIVER allocates with XN_NEW / XN_DELETE, which the public headers do not define.
#define XN_NEW(type, arg) new type(arg)
#define XN_DELETE(p) delete (p)
ONI_EXPORT_DRIVER(VirtualDriver)
