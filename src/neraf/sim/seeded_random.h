#pragma once
// A small deterministic random stream for the simulator's placements and splits. std::mt19937 is
// portable but the standard distributions are not (their algorithms are implementation-defined),
// so the uniform/integer draws are implemented here: same seed → same numbers on every platform.
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace neraf::sim {

inline uint64_t splitmix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Independent sub-seed for one use of the run seed ("cameras-train", "split", ...), so adding
// draws to one stream never changes another.
inline uint64_t derive_seed(uint64_t seed, const std::string& stream) {
  uint64_t h = 1469598103934665603ull;  // FNV-1a of the stream name
  for (unsigned char c : stream) h = (h ^ c) * 1099511628211ull;
  return splitmix64(seed ^ splitmix64(h));
}

class SeededRandom {  // xoshiro256** seeded through splitmix64
 public:
  explicit SeededRandom(uint64_t seed) {
    for (auto& s : s_) s = seed = splitmix64(seed);
  }
  uint64_t next() {
    const uint64_t result = rotl(s_[1] * 5, 7) * 9;
    const uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }
  double uniform() { return double(next() >> 11) * 0x1.0p-53; }  // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // Integer in [0, n), n > 0 (rejection sampling: no modulo bias).
  uint64_t below(uint64_t n) {
    const uint64_t limit = UINT64_MAX - UINT64_MAX % n;
    uint64_t x;
    do x = next();
    while (x >= limit);
    return x % n;
  }
  template <typename T>
  void shuffle(std::vector<T>& v) {  // Fisher-Yates
    for (size_t i = v.size(); i > 1; --i) std::swap(v[i - 1], v[below(i)]);
  }

 private:
  static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  uint64_t s_[4];
};

}  // namespace neraf::sim
