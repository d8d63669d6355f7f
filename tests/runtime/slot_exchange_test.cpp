// The lock-free slot handoff on its own (header-only, so it is tested directly): a producer
// thread fills slots with one value each and publishes them as fast as it can while a consumer
// reads its current and previous slots; a slot written while read shows as mixed values.
#include "neraf/runtime/slot_exchange.h"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>
#include <vector>

using neraf::rt::SlotExchange;

TEST(SlotExchange, SingleThreadedSemantics) {
  SlotExchange x;
  EXPECT_FALSE(x.take_newest());  // nothing published yet
  const int first = x.writable();
  x.publish();
  EXPECT_NE(x.writable(), first);
  const int before = x.current();
  EXPECT_TRUE(x.take_newest());
  EXPECT_EQ(x.current(), first);
  EXPECT_EQ(x.previous(), before);
  EXPECT_FALSE(x.take_newest());  // taken once

  // Two publications before a pick-up: the consumer gets the newer one (latest wins).
  x.publish();
  const int newer = x.writable();
  x.publish();
  EXPECT_TRUE(x.take_newest());
  EXPECT_EQ(x.current(), newer);
  // The four indices stay a permutation of the four slots.
  std::vector<bool> seen(SlotExchange::kSlots, false);
  seen[x.current()] = seen[x.previous()] = seen[x.writable()] = true;
  int distinct = 0;
  for (bool b : seen) distinct += b;
  EXPECT_EQ(distinct, 3);
}

TEST(SlotExchange, ConsumerNeverSeesASlotBeingWritten) {
  constexpr size_t kWords = 2048;
  constexpr int kPublications = 200000;
  std::vector<std::vector<int>> slots(SlotExchange::kSlots, std::vector<int>(kWords, 0));
  SlotExchange x;
  std::atomic<bool> done{false};
  std::thread producer([&] {
    for (int v = 1; v <= kPublications; ++v) {
      // Plain (non-atomic) writes: ThreadSanitizer flags them if the consumer could be reading.
      for (int& w : slots[x.writable()]) w = v;
      x.publish();
    }
    done = true;
  });
  long mixed = 0, backwards = 0, taken = 0;
  int last = 0;
  while (!done.load(std::memory_order_relaxed) || taken == 0) {
    if (!x.take_newest()) continue;
    ++taken;
    // Read both slots the consumer holds (a crossfade block reads the two).
    for (int slot : {x.current(), x.previous()}) {
      const std::vector<int>& s = slots[slot];
      for (int w : s) mixed += w != s[0];
    }
    const int v = slots[x.current()][0];
    backwards += v <= last;
    last = v;
  }
  producer.join();
  EXPECT_EQ(mixed, 0);
  EXPECT_EQ(backwards, 0);  // each pick-up is newer than the one before
  EXPECT_GT(taken, 0);
  // The last publication is the one left to take, or taken.
  if (x.take_newest()) last = slots[x.current()][0];
  EXPECT_EQ(last, kPublications);
}
