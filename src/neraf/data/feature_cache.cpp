#include "neraf/data/feature_cache.h"

#include <c10/util/Half.h>
#include <fcntl.h>
#include <omp.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <exception>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <vector>

#include "neraf/io/atomic_file.h"
#include "neraf/io/sealed_file.h"
#include "neraf/util/error.h"
#include "neraf/util/progress.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace neraf::data {
namespace {

constexpr char kMagic[8] = {'N', 'R', 'F', 'F', 'E', 'A', 'T', '1'};
// 2: SoundSpaces features resampled with libsoxr HQ (librosa's soxr_hq), was libsamplerate.
constexpr int kVersion = 2;

int64_t round_up(int64_t v, int64_t m) { return (v + m - 1) / m * m; }

struct Layout {
  std::string header;  // JSON text
  int64_t lengths_offset = 0, data_offset = 0, total = 0;
};

Layout make_layout(const FeatureCacheSpec& s) {
  // Offsets depend on the header length, which contains the offsets: fix them with a generous
  // header size bound computed from the header written with placeholder offsets.
  json h = {{"format", "neraf-features"},
            {"version", kVersion},
            {"key", s.key},
            {"layout", s.layout},
            {"n_rirs", s.n_rirs},
            {"channels", s.channels},
            {"n_freq", s.n_freq},
            {"max_len", s.max_len},
            {"dtype", s.half ? "float16" : "float32"},
            {"lengths_offset", int64_t(0)},
            {"data_offset", int64_t(0)},
            {"description", s.description},
            {"sources_fnv1a", s.sources_fnv1a}};
  const int64_t bound = 16 + static_cast<int64_t>(h.dump().size()) + 64;  // offsets grow ≤ 40 chars
  Layout l;
  l.lengths_offset = round_up(bound, 64);
  l.data_offset = round_up(l.lengths_offset + 4 * s.n_rirs, 4096);
  h["lengths_offset"] = l.lengths_offset;
  h["data_offset"] = l.data_offset;
  l.header = h.dump();
  require(16 + static_cast<int64_t>(l.header.size()) <= l.lengths_offset,
          "feature cache: header layout overflow (internal error)");
  const int64_t esize = s.half ? 2 : 4;
  l.total = l.data_offset + s.n_rirs * s.max_len * s.channels * s.n_freq * esize;
  return l;
}

// pread until n bytes are in; false (errno set, or 0 at the end of the file) when they cannot be.
bool read_exactly(int fd, void* data, size_t n, int64_t offset) {
  char* p = static_cast<char*>(data);
  errno = 0;
  while (n > 0) {
    const ssize_t r = ::pread(fd, p, n, offset);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) return false;
    p += r;
    n -= static_cast<size_t>(r);
    offset += r;
  }
  return true;
}

void pwrite_all(int fd, const void* data, size_t n, int64_t offset, const std::string& path) {
  const char* p = static_cast<const char*>(data);
  while (n > 0) {
    const ssize_t w = ::pwrite(fd, p, n, offset);
    if (w < 0 && errno == EINTR) continue;
    require(w > 0, path + ": write failed (" + std::string(std::strerror(errno)) +
                       "); free disk space or choose another --cache-dir");
    p += w;
    n -= static_cast<size_t>(w);
    offset += w;
  }
}

}  // namespace

std::string hash_hex(const std::string& text) {
  uint64_t h = 1469598103934665603ull;
  for (const unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

std::shared_ptr<FeatureCache> FeatureCache::open(const std::string& path,
                                                 const FeatureCacheSpec& spec) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return nullptr;
  std::shared_ptr<FeatureCache> c(new FeatureCache());
  c->fd_ = fd;  // closed by the destructor, also when the file is refused below
  c->path_ = path;
  struct stat st {};
  if (::fstat(fd, &st) != 0 || st.st_size < 16) return nullptr;
  const auto size = static_cast<int64_t>(st.st_size);
  char head[16];
  if (!read_exactly(fd, head, 16, 0) || std::memcmp(head, kMagic, 8) != 0) return nullptr;
  uint64_t n = 0;
  std::memcpy(&n, head + 8, 8);
  if (n == 0 || 16 + n > static_cast<uint64_t>(size)) return nullptr;
  std::string text(n, '\0');
  if (!read_exactly(fd, text.data(), n, 16)) return nullptr;
  try {
    const json h = json::parse(text);
    if (h.at("format") != "neraf-features" || h.at("version") != kVersion) return nullptr;
    FeatureCacheSpec s;
    s.key = h.at("key");
    s.layout = h.at("layout");
    s.description = h.value("description", "");
    s.sources_fnv1a = h.value("sources_fnv1a", "");
    s.n_rirs = h.at("n_rirs");
    s.channels = h.at("channels");
    s.n_freq = h.at("n_freq");
    s.max_len = h.at("max_len");
    s.half = h.at("dtype") == "float16";
    c->data_offset_ = h.at("data_offset");
    const int64_t lengths_offset = h.at("lengths_offset");
    if (s.key != spec.key || s.layout != spec.layout || s.half != spec.half) return nullptr;
    for (auto [mine, want] : {std::pair<int64_t, int64_t>{s.n_rirs, spec.n_rirs},
                              {s.channels, spec.channels},
                              {s.n_freq, spec.n_freq},
                              {s.max_len, spec.max_len}})
      if (want != 0 && mine != want) return nullptr;
    const int64_t esize = s.half ? 2 : 4;
    const int64_t need = c->data_offset_ + s.n_rirs * s.max_len * s.channels * s.n_freq * esize;
    if (lengths_offset + 4 * s.n_rirs > c->data_offset_ || size != need) return nullptr;
    c->lengths_.resize(static_cast<size_t>(s.n_rirs));
    if (!read_exactly(fd, c->lengths_.data(), c->lengths_.size() * 4, lengths_offset))
      return nullptr;
    c->spec_ = s;
  } catch (const std::exception&) {
    return nullptr;
  }
  // Training reads scattered frames: no read-ahead of neighbouring pages.
  ::posix_fadvise(fd, 0, 0, POSIX_FADV_RANDOM);
  return c;
}

std::shared_ptr<FeatureCache> FeatureCache::build(
    const std::string& path, const FeatureCacheSpec& spec,
    const std::function<int64_t(int64_t, float*)>& compute, bool progress,
    const std::function<std::string(int64_t)>& source_file) {
  // The sources' hash is known at the end: lay the header out with a placeholder of its length.
  FeatureCacheSpec final_spec = spec;
  final_spec.sources_fnv1a = source_file ? std::string(16, '0') : "";
  const Layout layout = make_layout(final_spec);
  const int64_t per_rir = spec.max_len * spec.channels * spec.n_freq;
  const int64_t esize = spec.half ? 2 : 4;

  // Refuse early when the disk cannot hold the cache (a 120k-RIR scene needs tens of GB).
  std::error_code ec;
  fs::create_directories(fs::path(path).parent_path(), ec);
  struct statvfs vfs {};
  if (::statvfs(fs::path(path).parent_path().c_str(), &vfs) == 0) {
    const double free_bytes = double(vfs.f_bavail) * double(vfs.f_frsize);
    if (free_bytes < double(layout.total) * 1.02) {
      char buf[200];
      std::snprintf(buf, sizeof buf, "the feature cache needs %.1f GB but only %.1f GB are free",
                    layout.total / 1e9, free_bytes / 1e9);
      throw Error(
          path + ": " + buf +
          "; free space, pass --cache-dir on a larger disk, or --cache-precision fp16 (half the "
          "size)");
    }
  }

  io::write_atomically(path, [&](const std::string& tmp) {
    const int fd = ::open(tmp.c_str(), O_CREAT | O_TRUNC | O_WRONLY | O_CLOEXEC, 0644);
    require(fd >= 0, tmp + ": cannot create (" + std::string(std::strerror(errno)) +
                         "); choose a writable --cache-dir");
    struct FdCloser {
      int fd;
      ~FdCloser() { ::close(fd); }
    } closer{fd};
    require(::ftruncate(fd, layout.total) == 0,
            tmp + ": cannot size the cache file (" + std::string(std::strerror(errno)) +
                "); free disk space or choose another --cache-dir");

    std::vector<int32_t> lengths(static_cast<size_t>(spec.n_rirs), 0);
    std::vector<uint64_t> source_hashes(source_file ? static_cast<size_t>(spec.n_rirs) : 0);
    std::atomic<int64_t> done{0};
    std::atomic<bool> failed{false};
    std::exception_ptr first_error;
    std::mutex error_mutex;
    ProgressOptions popt;
    popt.unit = "RIR";
    popt.enabled = progress;
    Progress bar("computing audio features", spec.n_rirs, popt);
#pragma omp parallel
    {
      std::vector<float> buf(static_cast<size_t>(per_rir));
      std::vector<c10::Half> half_buf(spec.half ? static_cast<size_t>(per_rir) : 0);
#pragma omp for schedule(dynamic, 4)
      for (int64_t i = 0; i < spec.n_rirs; ++i) {
        if (failed.load(std::memory_order_relaxed)) continue;
        try {
          const int64_t own = compute(i, buf.data());
          lengths[i] = static_cast<int32_t>(own);
          if (source_file) source_hashes[i] = io::fnv1a64(io::read_text_file(source_file(i)));
          const int64_t offset = layout.data_offset + i * per_rir * esize;
          if (spec.half) {
            for (int64_t k = 0; k < per_rir; ++k) half_buf[k] = c10::Half(buf[k]);
            pwrite_all(fd, half_buf.data(), per_rir * 2, offset, tmp);
          } else {
            pwrite_all(fd, buf.data(), per_rir * 4, offset, tmp);
          }
        } catch (...) {
          std::lock_guard<std::mutex> lock(error_mutex);
          if (!first_error) first_error = std::current_exception();
          failed = true;
        }
        const int64_t d = ++done;
        if (omp_get_thread_num() == 0) bar.update(d);  // Progress is not thread-safe
      }
    }
    if (first_error) std::rethrow_exception(first_error);
    bar.finish();

    // Header and lengths last: an interrupted build never leaves a file that looks complete (and
    // the temporary name is only renamed after this function returns).
    if (source_file) {
      std::string all;
      for (uint64_t h : source_hashes) all.append(reinterpret_cast<const char*>(&h), sizeof h);
      final_spec.sources_fnv1a = hash_hex(all);
    }
    const Layout final_layout = make_layout(final_spec);
    require(final_layout.lengths_offset == layout.lengths_offset &&
                final_layout.data_offset == layout.data_offset,
            tmp + ": internal error: the feature cache header changed size");
    std::vector<char> head(static_cast<size_t>(layout.lengths_offset), ' ');
    std::memcpy(head.data(), kMagic, 8);
    const uint64_t n = final_layout.header.size();
    std::memcpy(head.data() + 8, &n, 8);
    std::memcpy(head.data() + 16, final_layout.header.data(), final_layout.header.size());
    pwrite_all(fd, head.data(), head.size(), 0, tmp);
    pwrite_all(fd, lengths.data(), lengths.size() * 4, layout.lengths_offset, tmp);
    require(::fsync(fd) == 0, tmp + ": fsync failed (" + std::string(std::strerror(errno)) +
                                  "); free disk space or choose another --cache-dir");
  });
  auto c = open(path, spec);
  require(c != nullptr, path +
                            ": the feature cache just written cannot be read back; delete the "
                            "folder and retry");
  return c;
}

FeatureCache::~FeatureCache() {
  if (fd_ >= 0) ::close(fd_);
}

int32_t FeatureCache::own_length(int64_t rir) const { return lengths_[static_cast<size_t>(rir)]; }

void FeatureCache::read_frames(int64_t rir, int64_t frame, int64_t count, float* out) const {
  const int64_t values = count * slice_size();
  const int64_t first = (rir * spec_.max_len + frame) * slice_size();
  auto read = [&](void* to, int64_t esize) {
    if (!read_exactly(fd_, to, static_cast<size_t>(values * esize), data_offset_ + first * esize))
      throw Error(path_ + ": cannot read the feature cache (" +
                  (errno != 0 ? std::string(std::strerror(errno)) : "it was truncated") +
                  "); delete the file and run the command again to rebuild it");
  };
  if (!spec_.half) return read(out, 4);
  thread_local std::vector<c10::Half> halves;  // grows once; no allocation per training step
  halves.resize(static_cast<size_t>(values));
  read(halves.data(), 2);
  for (int64_t k = 0; k < values; ++k) out[k] = static_cast<float>(halves[k]);
}

}  // namespace neraf::data
