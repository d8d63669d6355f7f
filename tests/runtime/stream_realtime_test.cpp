// neraf_stream_process allocates nothing, crossfade blocks included. Counted by interposing
// malloc/calloc/realloc for the whole test program (the executable's definitions take precedence
// over the C library's; they forward to glibc's own entry points, so every allocation still comes
// from, and returns to, the one allocator). operator new reaches malloc too. They count only on
// the thread that armed them. Not under sanitizers, which bring their own allocator.
#include <gtest/gtest.h>

#include <cstddef>
#include <random>
#include <vector>

#include "neraf/neraf_rt.h"

#if !defined(__SANITIZE_THREAD__) && !defined(__SANITIZE_ADDRESS__)
#define NERAF_COUNT_MALLOC 1

namespace {
thread_local bool armed = false;  // constant-initialised: no allocation to reach it
thread_local long allocations = 0;
}  // namespace

extern "C" {
void* __libc_malloc(size_t);
void* __libc_calloc(size_t, size_t);
void* __libc_realloc(void*, size_t);

void* malloc(size_t n) {
  if (armed) ++allocations;
  return __libc_malloc(n);
}
void* calloc(size_t n, size_t size) {
  if (armed) ++allocations;
  return __libc_calloc(n, size);
}
void* realloc(void* p, size_t n) {
  if (armed) ++allocations;
  return __libc_realloc(p, n);
}
}
#endif

TEST(StreamRealtime, ProcessAllocatesNothing) {
#ifndef NERAF_COUNT_MALLOC
  GTEST_SKIP() << "allocation counting is off under sanitizers";
#else
  const int channels = 2, block = 128;
  const size_t len = 5000;
  neraf_stream* s = nullptr;
  ASSERT_EQ(neraf_stream_create(nullptr, channels, block, len, &s), NERAF_OK);
  std::mt19937 gen(1);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<float> h(channels * len), x(block), out(channels * block);
  for (float& v : x) v = u(gen);
  long counted = 0;
  for (int change = 0; change < 5; ++change) {
    for (float& v : h) v = 0.01f * u(gen);
    ASSERT_EQ(neraf_stream_set_rir(s, h.data(), channels, len - 100 * change), NERAF_OK);
    ASSERT_EQ(neraf_stream_wait(s, 10000), NERAF_OK);
    // Armed around the audio calls only: set_rir and wait (the control side) may allocate.
    armed = true;
    allocations = 0;
    for (int k = 0; k < 20; ++k) neraf_stream_process(s, x.data(), out.data());  // 1st: crossfade
    armed = false;
    counted += allocations;
  }
  // The counter works: an allocation while armed is seen.
  armed = true;
  allocations = 0;
  std::vector<float>* probe = new std::vector<float>(10);
  armed = false;
  EXPECT_GT(allocations, 0);
  delete probe;
  EXPECT_EQ(counted, 0);
  neraf_stream_free(s);
#endif
}
