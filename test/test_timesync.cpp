// The link's receive-side bookkeeping: the TIMESYNC offset estimator (timesync.hpp) and the
// autopilot's heartbeat (autopilot_watch.hpp), with synthetic clocks of known offset.
#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "rgbd_odometry/link/autopilot_watch.hpp"
#include "rgbd_odometry/link/timesync.hpp"

namespace rgbdo {
namespace {

constexpr std::int64_t kMs = 1'000'000;

TEST(TimesyncEstimator, SymmetricRoundTripGivesTheExactOffset) {
  TimesyncEstimator e(100 * kMs);
  const std::int64_t offset = 1'234'567'890'123LL;  // autopilot - ours
  e.note_request(1000 * kMs);
  // 2 ms out, answered at once, 2 ms back.
  EXPECT_EQ(e.add_answer(1002 * kMs + offset, 1000 * kMs, 1004 * kMs), TimesyncEstimator::Answer::Used);
  const TimesyncEstimate est = e.estimate();
  ASSERT_TRUE(est.valid);
  EXPECT_EQ(est.offset_ns, offset);
  EXPECT_EQ(est.rtt_ns, 4 * kMs);
  EXPECT_EQ(*e.to_autopilot_ns(5 * kMs), 5 * kMs + offset);
}

TEST(TimesyncEstimator, TheShortestRoundTripOfTheWindowWins) {
  // GIVEN answers delayed by queues on one side (asymmetric: the estimate of each is off by
  // half its extra delay), one of them quick
  TimesyncEstimator e(100 * kMs);
  const std::int64_t offset = -5'000 * kMs;
  std::mt19937 rng(3);
  for (int i = 0; i < 8; ++i) {
    const std::int64_t t0 = (1000 + 100 * i) * kMs;
    const std::int64_t out = (i == 5 ? 0 : 1 + static_cast<std::int64_t>(rng() % 30)) * kMs;  // queued outbound
    e.note_request(t0);
    e.add_answer(t0 + out + 100'000 + offset, t0, t0 + out + 200'000);
  }
  // THEN the estimate is the quick one's, good to 0.1 ms
  const TimesyncEstimate est = e.estimate();
  EXPECT_EQ(est.rtt_ns, 200'000);
  EXPECT_LE(std::llabs(est.offset_ns - offset), 100'000);
  EXPECT_EQ(est.samples, 8u);
}

TEST(TimesyncEstimator, AnswersToOtherRequestsDuplicatesAndSlowOnesAreNotUsed) {
  TimesyncEstimator e(10 * kMs);
  e.note_request(100 * kMs);
  EXPECT_EQ(e.add_answer(5, 99 * kMs, 101 * kMs), TimesyncEstimator::Answer::NotOurs);
  EXPECT_EQ(e.add_answer(5, 100 * kMs, 150 * kMs), TimesyncEstimator::Answer::TooSlow);
  EXPECT_EQ(e.add_answer(5, 100 * kMs, 101 * kMs), TimesyncEstimator::Answer::NotOurs) << "answered already";
  EXPECT_FALSE(e.estimate().valid);
  EXPECT_EQ(e.estimate().rejected, 3u);
  e.reset();
  EXPECT_EQ(e.estimate().rejected, 0u);
}

TEST(TimesyncEstimator, ClockReadingsAtTheEndsOf64BitsAreRefusedNotOverflowed) {
  // tc1 is whatever the wire carries: near -2^63 its offset from our clock does not fit 64
  // bits (UBSan flagged the subtraction); near +2^63 the offset fits but our later times
  // carried onto that clock do not.
  constexpr std::int64_t kMin = std::numeric_limits<std::int64_t>::min(), kMax = std::numeric_limits<std::int64_t>::max();
  TimesyncEstimator e(10 * kMs);
  e.note_request(100 * kMs);
  EXPECT_EQ(e.add_answer(kMin + 5, 100 * kMs, 101 * kMs), TimesyncEstimator::Answer::ClockOutOfRange);
  EXPECT_FALSE(e.estimate().valid);
  EXPECT_EQ(e.estimate().rejected, 1u);
  e.note_request(200 * kMs);
  EXPECT_EQ(e.add_answer(kMax - 5, 200 * kMs, 201 * kMs), TimesyncEstimator::Answer::Used);
  ASSERT_TRUE(e.to_autopilot_ns(200 * kMs));
  EXPECT_EQ(*e.to_autopilot_ns(200 * kMs), kMax - 5 - kMs / 2);
  EXPECT_FALSE(e.to_autopilot_ns(300 * kMs)) << "past 2^63 on the autopilot's clock";
}

mavlink::ReceivedFrame heartbeat(std::uint8_t sysid, std::uint8_t compid, std::uint8_t autopilot,
                                 std::array<std::uint8_t, mavlink::kMaxPayloadBytes>& payload) {
  payload.fill(0);
  payload[mavlink::Heartbeat::kAutopilotOffset] = autopilot;
  payload[mavlink::Heartbeat::kTypeOffset] = 2;
  mavlink::ReceivedFrame f;
  f.sysid = sysid;
  f.compid = compid;
  f.msgid = mavlink::Heartbeat::kId;
  f.payload = payload;
  return f;
}

TEST(AutopilotWatch, FollowsTheFirstAutopilotAndTellsWhenItGoes) {
  std::array<std::uint8_t, mavlink::kMaxPayloadBytes> p{};
  AutopilotWatch w(0, 1, 197, 1500 * kMs);
  EXPECT_FALSE(w.state(0).known);
  // A ground station's heartbeat (autopilot INVALID) is not an autopilot.
  EXPECT_TRUE(w.accept(heartbeat(255, 190, mavlink::kMavAutopilotInvalid, p), 1 * kMs));
  EXPECT_FALSE(w.state(1 * kMs).known);
  EXPECT_TRUE(w.accept(heartbeat(1, 1, mavlink::kMavAutopilotPx4, p), 10 * kMs));
  AutopilotState s = w.state(10 * kMs);
  ASSERT_TRUE(s.known);
  EXPECT_TRUE(s.up);
  EXPECT_EQ(s.identity.system_id, 1);
  EXPECT_EQ(s.identity.autopilot, mavlink::kMavAutopilotPx4);
  // Another system is ignored while the first is up; our own echo always is.
  EXPECT_FALSE(w.accept(heartbeat(2, 1, mavlink::kMavAutopilotArdupilotmega, p), 20 * kMs));
  EXPECT_FALSE(w.accept(heartbeat(1, 197, mavlink::kMavAutopilotInvalid, p), 20 * kMs));
  EXPECT_EQ(w.state(20 * kMs).identity.system_id, 1);
  EXPECT_EQ(w.state(20 * kMs).ignored_frames, 2u);
  EXPECT_TRUE(w.state(1510 * kMs).up);
  EXPECT_FALSE(w.state(1511 * kMs).up) << "1.5 s without a frame";
  // Once it is gone another autopilot may take over.
  EXPECT_TRUE(w.accept(heartbeat(2, 1, mavlink::kMavAutopilotArdupilotmega, p), 2000 * kMs));
  s = w.state(2000 * kMs);
  EXPECT_TRUE(s.up);
  EXPECT_EQ(s.identity.system_id, 2);
  EXPECT_STREQ(autopilot_name(s.identity.autopilot), "ArduPilot");
}

TEST(AutopilotWatch, AConfiguredSystemIdIsTheOnlyOneFollowed) {
  std::array<std::uint8_t, mavlink::kMaxPayloadBytes> p{};
  AutopilotWatch w(42, 1, 197, 1500 * kMs);
  EXPECT_FALSE(w.accept(heartbeat(1, 1, mavlink::kMavAutopilotPx4, p), 1 * kMs));
  EXPECT_FALSE(w.state(1 * kMs).known);
  EXPECT_TRUE(w.accept(heartbeat(42, 1, mavlink::kMavAutopilotPx4, p), 2 * kMs));
  EXPECT_EQ(w.state(2 * kMs).identity.system_id, 42);
}

}  // namespace
}  // namespace rgbdo
