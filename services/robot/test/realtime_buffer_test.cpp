#include "concert/hardware/realtime_buffer.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>
#include <vector>

namespace concert::hardware {
namespace {

struct Value {
  std::uint64_t a{0};
  std::uint64_t b{0};  // always a * 3: a torn read would break it
};

TEST(RealtimeBuffer, ReaderSeesOnlyWhatWasPublishedNewestFirst) {
  RealtimeBuffer<Value> buffer;
  EXPECT_FALSE(buffer.update());
  buffer.back() = {1, 3};
  buffer.publish();
  buffer.back() = {2, 6};
  buffer.publish();
  EXPECT_TRUE(buffer.update());
  EXPECT_EQ(buffer.front().a, 2u);
  EXPECT_FALSE(buffer.update());
  EXPECT_EQ(buffer.front().a, 2u);
}

TEST(RealtimeBuffer, ConcurrentWriterAndReaderNeverTearAValue) {
  RealtimeBuffer<Value> buffer;
  constexpr std::uint64_t kCount = 200000;
  std::thread writer([&] {
    for (std::uint64_t i = 1; i <= kCount; ++i) {
      buffer.back() = {i, 3 * i};
      buffer.publish();
    }
  });
  std::uint64_t last = 0;
  while (last < kCount) {
    if (buffer.update()) {
      const Value& v = buffer.front();
      ASSERT_EQ(v.b, 3 * v.a);
      ASSERT_GT(v.a, last);  // values only move forward
      last = v.a;
    }
  }
  writer.join();
}

TEST(Handover, LoopTakesTheNewestAndRetiredObjectsAreDeletedOffTheLoop) {
  static std::atomic<int> alive{0};
  struct Counted {
    Counted() { ++alive; }
    ~Counted() { --alive; }
  };
  {
    Handover<Counted> h;
    h.submit(std::make_unique<Counted>());
    h.submit(std::make_unique<Counted>());  // replaces the one not taken yet
    EXPECT_EQ(alive.load(), 1);
    Counted* taken = h.take();
    ASSERT_NE(taken, nullptr);
    EXPECT_EQ(h.take(), nullptr);
    EXPECT_TRUE(h.retire(taken));
    EXPECT_EQ(alive.load(), 1);  // the loop never deletes
    h.collect();
    EXPECT_EQ(alive.load(), 0);
    h.submit(std::make_unique<Counted>());
  }
  EXPECT_EQ(alive.load(), 0);
}

}  // namespace
}  // namespace concert::hardware
