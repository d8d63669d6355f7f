#pragma once
// The on-disk feature cache of a RirSet: every RIR's padded log-magnitude STFT, written once
// (atomically, in parallel) and read slice by slice with pread for training. It is not
// memory-mapped: pages of a mapping count in the process's resident memory, so a 25 GB cache
// would grow the trainer to 25 GB; read, the data stays in the kernel's reclaimable page cache
// and the process holds only the lengths and one batch.
//
// File layout (little-endian):
//   [0, 8)               magic "NRFFEAT1"
//   [8, 16)              uint64 n = byte length of the JSON header
//   [16, 16 + n)         JSON header: {"format": "neraf-features", "version": 2, "key": "<hex>",
//                        "layout", "n_rirs", "channels", "n_freq", "max_len",
//                        "dtype": "float32" | "float16", "lengths_offset", "data_offset",
//                        "description": the text the key hashes (parameters + file list summary),
//                        "sources_fnv1a": FNV-1a of the source files' bytes ("" if not hashed)}
//   [lengths_offset, …)  int32 own STFT length of each RIR [n_rirs] (before padding/cutting)
//   [data_offset, …)     features [n_rirs][max_len][channels][n_freq] (data_offset is a multiple
//                        of 4096). Frame-major per RIR so that the (rir, frame) slice a training
//                        step needs is one contiguous run of channels·n_freq values.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace neraf::data {

struct FeatureCacheSpec {
  std::string key;     // 16 hex digits identifying parameters + source files
  std::string layout;  // "soundspaces" / "raf"
  std::string description;
  int64_t n_rirs = 0, channels = 0, n_freq = 0, max_len = 0;
  bool half = false;  // float16 values instead of float32
  // What the RIR files hold, unlike `key` (their names, sizes and times): a copied dataset has the
  // same value, a file replaced by another of the same size does not. Filled by build.
  std::string sources_fnv1a;
};

// 64-bit FNV-1a of `text` as 16 lowercase hex digits (stable across runs and machines).
std::string hash_hex(const std::string& text);

class FeatureCache {
 public:
  // Maps `path` when it is a complete cache whose key equals `spec.key` (and whose sizes agree
  // with the spec where the spec gives them, i.e. are nonzero); nullptr otherwise (missing,
  // stale, truncated or foreign files are not errors: the caller rebuilds).
  static std::shared_ptr<FeatureCache> open(const std::string& path, const FeatureCacheSpec& spec);

  // Computes every RIR's features with `compute(i, out)` in parallel (OpenMP), where `out` holds
  // max_len·channels·n_freq floats [max_len][channels][n_freq] and the return value is the RIR's
  // own STFT length; writes them to `path` atomically (temporary file + rename) and maps the
  // result. The first exception thrown by `compute` is rethrown after the workers stop. With
  // `source_file` (RIR i's source file), the files' bytes are hashed into spec().sources_fnv1a.
  static std::shared_ptr<FeatureCache> build(
      const std::string& path, const FeatureCacheSpec& spec,
      const std::function<int64_t(int64_t, float*)>& compute, bool progress,
      const std::function<std::string(int64_t)>& source_file = nullptr);

  ~FeatureCache();
  FeatureCache(const FeatureCache&) = delete;
  FeatureCache& operator=(const FeatureCache&) = delete;

  const FeatureCacheSpec& spec() const { return spec_; }
  const std::string& path() const { return path_; }
  int64_t slice_size() const { return spec_.channels * spec_.n_freq; }  // values per frame
  int32_t own_length(int64_t rir) const;

  // Copies `count` consecutive frames of RIR `rir` starting at `frame` into out (float32),
  // [count][channels][n_freq]. Thread-safe; throws neraf::Error when the file cannot be read.
  void read_frames(int64_t rir, int64_t frame, int64_t count, float* out) const;

 private:
  FeatureCache() = default;
  FeatureCacheSpec spec_;
  std::string path_;
  int fd_ = -1;
  std::vector<int32_t> lengths_;  // own STFT length of each RIR
  int64_t data_offset_ = 0;
};

}  // namespace neraf::data
