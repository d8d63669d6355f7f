#pragma once
// The lock-free handoff of RIR partition slots from one producer thread (the stream's worker,
// which prepares RIRs) to one consumer thread (the audio thread, in process()). Internal to
// neraf_rt; header-only so the tests can drive it directly.
//
// Why four slots and not a triple buffer: the consumer crossfades from the old RIR to the new
// one over the block in which it picks the new one up, so during that block it reads TWO slots.
// A triple buffer hands the old slot back at pick-up, and the producer could then overwrite it
// mid-crossfade. Here the consumer keeps the old slot as its "spare" until its next pick-up:
//
//   producer: back_   (being filled; only the producer touches it)
//   shared:   latest_ (the last published slot, or a free one; owned by whoever holds the index)
//   consumer: current_ (read every block), spare_ (the previous RIR during a crossfade block,
//             otherwise free; handed to latest_ at the next pick-up, when nobody reads it)
//
// Every index is owned by exactly one side at a time and ownership only moves through the one
// atomic exchange on latest_, so a slot is never written while the consumer reads it. The
// producer's writes to a slot happen before its release exchange; the consumer's acquire
// exchange then sees them. Symmetrically, the consumer's last reads of the slot it gives away
// happen before its release exchange, which the producer acquires before writing that slot.
#include <atomic>
#include <cstdint>

namespace neraf::rt {

class SlotExchange {
 public:
  static constexpr int kSlots = 4;

  // Producer: the slot to fill next (not read by the consumer until published).
  int writable() const { return back_; }
  // Producer: makes the writable slot the newest; a published slot the consumer has not picked
  // up yet comes back as the next writable one (latest wins).
  void publish() {
    back_ = static_cast<int>(latest_.exchange(uint32_t(back_) | kFresh, std::memory_order_acq_rel) &
                             kIndex);
  }

  // Consumer, at the start of a block: picks up the newest published slot if there is one.
  // Returns true when current() changed; previous() then stays readable until the next call.
  // Wait-free: one atomic load, plus one exchange when something new was published.
  bool take_newest() {
    if (!(latest_.load(std::memory_order_acquire) & kFresh)) return false;
    const int newest =
        static_cast<int>(latest_.exchange(uint32_t(spare_), std::memory_order_acq_rel) & kIndex);
    spare_ = current_;  // still read during this block (the crossfade's old RIR)
    current_ = newest;
    return true;
  }
  int current() const { return current_; }
  int previous() const { return spare_; }

 private:
  static constexpr uint32_t kIndex = 0x3;
  static constexpr uint32_t kFresh = 0x4;  // latest_ holds a slot the consumer has not taken

  // Slot 0 starts as the consumer's current: the stream's "no RIR yet" (silence) slot. Each
  // side's indices on their own cache line, so the audio thread's reads of its own never miss
  // because the producer wrote its own.
  alignas(64) int current_ = 0;
  int spare_ = 1;
  alignas(64) int back_ = 3;
  alignas(64) std::atomic<uint32_t> latest_{2};  // the only word both threads write
};

}  // namespace neraf::rt
