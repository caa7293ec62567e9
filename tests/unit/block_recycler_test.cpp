// The block recycler of the attractor recorder's event log (include/vibro/block_recycler.hpp):
// a deque that uses it holds what std::deque holds after any sequence of pushes and pops at both
// ends, its freed nodes come back on its next allocations, and a copy has a cache of its own.
#include "vibro/block_recycler.hpp"

#include <deque>
#include <random>

#include <gtest/gtest.h>

#include "vibro/observer.hpp"

namespace {

TEST(BlockRecycler, DequeHoldsWhatStdDequeHolds) {
  std::deque<vibro::Event> ref;
  std::deque<vibro::Event, vibro::BlockRecycler<vibro::Event>> rec;
  std::mt19937_64 rng(39);
  for (int step = 0; step < 200000; ++step) {
    const auto op = rng() % 8;
    if (op < 4 || ref.empty()) {  // grow more than shrink, as the recorder's window does at first
      vibro::Event e{};
      e.t = static_cast<double>(step);
      e.contact = static_cast<int>(rng() % 5);
      if (op % 2 == 0) {
        ref.push_back(e);
        rec.push_back(e);
      } else {
        ref.push_front(e);
        rec.push_front(e);
      }
    } else if (op < 7) {
      ref.pop_front();
      rec.pop_front();
    } else {
      ref.pop_back();
      rec.pop_back();
    }
    if (step % 997 == 0) {
      ASSERT_EQ(ref.size(), rec.size());
      for (size_t i = 0; i < ref.size(); ++i) {
        ASSERT_EQ(ref[i].t, rec[i].t);
        ASSERT_EQ(ref[i].contact, rec[i].contact);
      }
    }
  }
  const auto copy = rec;  // a cache of its own
  EXPECT_FALSE(copy.get_allocator() == rec.get_allocator());
  ASSERT_EQ(copy.size(), ref.size());
  for (size_t i = 0; i < ref.size(); ++i) EXPECT_EQ(copy[i].t, ref[i].t);
}

TEST(BlockRecycler, FreedBlocksComeBackBoundedAndOfOneSize) {
  vibro::detail::BlockCache cache;
  void* a = cache.Get(480);
  void* b = cache.Get(480);
  cache.Put(a, 480);
  cache.Put(b, 480);
  EXPECT_EQ(cache.Get(480), b);  // last freed, first reused
  EXPECT_EQ(cache.Get(480), a);
  void* other = cache.Get(64);  // another size: never from the list
  cache.Put(other, 64);         // nor kept in it
  void* c = cache.Get(480);
  EXPECT_NE(c, other);
  cache.Put(c, 480);
  // At most kMaxBlocks kept: the rest are freed (no leak under ASan/valgrind).
  std::vector<void*> many;
  for (size_t i = 0; i < 3 * vibro::detail::BlockCache::kMaxBlocks; ++i) many.push_back(cache.Get(480));
  for (void* p : many) cache.Put(p, 480);
  size_t reused = 0;
  std::vector<void*> again;
  for (size_t i = 0; i < 3 * vibro::detail::BlockCache::kMaxBlocks; ++i) {
    again.push_back(cache.Get(480));
    for (void* p : many) reused += again.back() == p;
  }
  EXPECT_GE(reused, vibro::detail::BlockCache::kMaxBlocks);
  for (void* p : again) cache.Put(p, 480);
  vibro::detail::BlockCache other_cache;  // destroyed with nothing kept
}

}  // namespace
