// The runtime's two hand-overs, deterministically (no timing): FrameMailbox (newest wins when
// live, nothing lost when recorded, replaced frames counted and folded into the next, close)
// and BoundedQueue (FIFO order, full and empty, close ending both waits, draining after
// close). Where a thread must block, the test proves it blocked by what it could not yet
// have done, and releases it by the one call that may.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "rgbd_odometry/runtime/bounded_queue.hpp"
#include "rgbd_odometry/runtime/frame_mailbox.hpp"

namespace rgbdo {
namespace {

void publish_frame(FrameMailbox& box, std::int64_t t, bool after_gap = false) {
  CapturedFrame& slot = box.fill_slot();
  slot.frame.t_colour_ns = t;
  slot.skipped_before = 0;
  slot.after_gap = after_gap;
  ASSERT_TRUE(box.publish());
}

TEST(FrameMailbox, LiveNewestWinsAndTheReplacedAreCountedIntoTheNext) {
  FrameMailbox box(false);
  publish_frame(box, 1);
  publish_frame(box, 2, true);  // replaces 1; carries a gap flag forward
  publish_frame(box, 3);        // replaces 2
  EXPECT_EQ(box.skipped(), 2u);
  CapturedFrame* f = box.take();
  ASSERT_NE(f, nullptr);
  EXPECT_EQ(f->frame.t_colour_ns, 3);
  EXPECT_EQ(f->skipped_before, 2);
  EXPECT_TRUE(f->after_gap);  // a replaced frame's gap is not forgotten
  // The taken frame stays intact while newer ones come and go.
  publish_frame(box, 4);
  publish_frame(box, 5);
  EXPECT_EQ(f->frame.t_colour_ns, 3);
  CapturedFrame* g = box.take();
  EXPECT_EQ(g->frame.t_colour_ns, 5);
  EXPECT_EQ(g->skipped_before, 1);
  EXPECT_FALSE(g->after_gap);
  EXPECT_EQ(box.skipped(), 3u);
}

TEST(FrameMailbox, RecordedWaitsForTheReaderAndLosesNothing) {
  FrameMailbox box(true);
  std::vector<std::int64_t> taken;
  std::thread reader([&] {
    while (CapturedFrame* f = box.take()) taken.push_back(f->frame.t_colour_ns);
  });
  for (std::int64_t t = 1; t <= 500; ++t) publish_frame(box, t);
  box.close();
  reader.join();
  ASSERT_EQ(taken.size(), 500u);
  for (std::int64_t t = 1; t <= 500; ++t) EXPECT_EQ(taken[static_cast<size_t>(t - 1)], t);
  EXPECT_EQ(box.skipped(), 0u);
}

TEST(FrameMailbox, CloseReleasesAWaitingReaderAndRefusesNewFrames) {
  FrameMailbox box(true);
  std::atomic<bool> returned{false};
  CapturedFrame* got = reinterpret_cast<CapturedFrame*>(1);
  std::thread reader([&] {
    got = box.take();  // nothing published: waits
    returned = true;
  });
  EXPECT_FALSE(returned.load());
  box.close();
  reader.join();
  EXPECT_EQ(got, nullptr);
  EXPECT_FALSE(box.publish());
  // A frame published before the close is still taken after it.
  FrameMailbox other(false);
  publish_frame(other, 7);
  other.close();
  ASSERT_NE(other.take(), nullptr);
  EXPECT_EQ(other.take(), nullptr);
}

TEST(BoundedQueue, KeepsOrderAndCapacity) {
  BoundedQueue<int, 4> q;
  for (int i = 0; i < 4; ++i) ASSERT_TRUE(q.push(i));
  EXPECT_FALSE(q.pop_for(std::chrono::milliseconds(0)) == std::nullopt);  // 0
  ASSERT_TRUE(q.push(4));                                                   // room again
  for (int i = 1; i <= 4; ++i) EXPECT_EQ(q.pop(), i);
  EXPECT_EQ(q.pop_for(std::chrono::milliseconds(1)), std::nullopt);  // empty, not closed
  EXPECT_FALSE(q.closed_and_empty());
}

TEST(BoundedQueue, AFullQueueBlocksThePusherUntilAPop) {
  BoundedQueue<int, 2> q;
  ASSERT_TRUE(q.push(1));
  ASSERT_TRUE(q.push(2));
  std::atomic<int> pushed{0};
  std::thread pusher([&] {
    if (q.push(3)) pushed = 1;
  });
  // Whatever the scheduling, 3 cannot be in before a pop: the first pop is 1 either way.
  EXPECT_EQ(q.pop(), 1);
  pusher.join();
  EXPECT_EQ(pushed.load(), 1);
  EXPECT_EQ(q.pop(), 2);
  EXPECT_EQ(q.pop(), 3);
}

TEST(BoundedQueue, CloseEndsBothWaitsAndTheRestIsDrained) {
  BoundedQueue<int, 1> full;
  ASSERT_TRUE(full.push(1));
  std::atomic<int> push_result{-1};
  std::thread pusher([&] { push_result = full.push(2) ? 1 : 0; });  // waits: full
  BoundedQueue<int, 1> empty;
  std::optional<int> popped = 99;
  std::thread popper([&] { popped = empty.pop(); });  // waits: empty
  full.close();
  empty.close();
  pusher.join();
  popper.join();
  EXPECT_EQ(push_result.load(), 0);  // refused, not queued
  EXPECT_EQ(popped, std::nullopt);
  EXPECT_FALSE(full.closed_and_empty());
  EXPECT_EQ(full.pop(), 1);  // what was queued before the close is still delivered
  EXPECT_TRUE(full.closed_and_empty());
  EXPECT_EQ(full.pop(), std::nullopt);
}

TEST(BoundedQueue, ManyItemsBetweenTwoThreadsArriveOnceInOrder) {
  BoundedQueue<int, 4> q;
  std::thread producer([&] {
    for (int i = 0; i < 20000; ++i) ASSERT_TRUE(q.push(i));
    q.close();
  });
  int expected = 0;
  while (auto v = q.pop()) ASSERT_EQ(*v, expected++);
  producer.join();
  EXPECT_EQ(expected, 20000);
}

}  // namespace
}  // namespace rgbdo
