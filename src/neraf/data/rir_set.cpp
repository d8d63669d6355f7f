#include "neraf/data/rir_set.h"

#include <ATen/Parallel.h>
#include <omp.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <limits>
#include <mutex>
#include <sstream>

#include "neraf/data/feature_cache.h"
#include "neraf/data/layout.h"
#include "neraf/data/rir_check.h"
#include "neraf/data/rir_layouts.h"
#include "neraf/io/atomic_file.h"
#include "neraf/util/error.h"
#include "neraf/util/log.h"

namespace fs = std::filesystem;

namespace neraf::data {

const char* to_string(AudioLayout layout) {
  return layout == AudioLayout::soundspaces ? "soundspaces" : "raf";
}

geometry::Vec3 normalize_position(const geometry::Vec3& p, const Aabb& box) {
  geometry::Vec3 q;
  for (int k = 0; k < 3; ++k) {
    q[k] = (p[k] - box.min[k]) / (box.max[k] - box.min[k]);
    if (!(q[k] > 0.0 && q[k] < 1.0)) return {0, 0, 0};
  }
  return q;
}

torch::Tensor normalize_position(const torch::Tensor& p, const Aabb& box) {
  TORCH_CHECK(p.dim() == 2 && p.size(1) == 3, "normalize_position: positions must be [N, 3]");
  const auto opts = torch::TensorOptions().dtype(p.scalar_type());
  const torch::Tensor lo =
      torch::tensor({box.min.x, box.min.y, box.min.z}, torch::kFloat64).to(opts);
  const torch::Tensor hi =
      torch::tensor({box.max.x, box.max.y, box.max.z}, torch::kFloat64).to(opts);
  torch::Tensor q = (p - lo) / (hi - lo);
  const torch::Tensor inside = ((q > 0) & (q < 1)).all(1, /*keepdim=*/true);
  return q * inside.to(q.scalar_type());
}

std::array<double, 3> encode_heading(int heading_deg) {
  const double a = heading_deg * 3.14159265358979323846 / 180.0;
  return {(std::cos(a) + 1.0) / 2.0, 0.5, (std::sin(a) + 1.0) / 2.0};
}

// ---------------------------------------------------------------------------------------------
namespace detail {

FileStamp stamp(const std::string& path) {
  struct stat st {};
  FileStamp s;
  if (::stat(path.c_str(), &st) != 0) return s;
  if (!S_ISREG(st.st_mode)) {
    s.not_regular = true;
    return s;
  }
  s.exists = true;
  s.size = static_cast<int64_t>(st.st_size);
  s.mtime_ns = static_cast<int64_t>(st.st_mtim.tv_sec) * 1000000000LL + st.st_mtim.tv_nsec;
  return s;
}

void write_padded_log(const std::vector<const float*>& mags, int64_t n_freq, int64_t n_frames,
                      int64_t max_len, float* out) {
  const int64_t C = static_cast<int64_t>(mags.size());
  float mn = std::numeric_limits<float>::infinity();
  for (const float* m : mags)
    for (int64_t k = 0; k < n_freq * n_frames; ++k) mn = std::min(mn, m[k]);
  const float pad = std::log(mn + kLogEps);
  const int64_t keep = std::min(n_frames, max_len);
  for (int64_t t = 0; t < max_len; ++t)
    for (int64_t c = 0; c < C; ++c) {
      float* o = out + (t * C + c) * n_freq;
      if (t < keep) {
        const float* m = mags[c];
        for (int64_t f = 0; f < n_freq; ++f) o[f] = std::log(m[f * n_frames + t] + kLogEps);
      } else {
        std::fill(o, o + n_freq, pad);
      }
    }
}

void parallel_for_each(int64_t n, const std::function<void(int64_t)>& fn) {
  std::exception_ptr first;
  std::mutex m;
  std::atomic<bool> failed{false};
#pragma omp parallel for schedule(dynamic, 16)
  for (int64_t i = 0; i < n; ++i) {
    if (failed.load(std::memory_order_relaxed)) continue;
    try {
      fn(i);
    } catch (...) {
      std::lock_guard<std::mutex> lock(m);
      if (!first) first = std::current_exception();
      failed = true;
    }
  }
  if (first) std::rethrow_exception(first);
}

}  // namespace detail

// ---------------------------------------------------------------------------------------------
namespace {

using detail::RirIndex;

void finish_index(RirSet& set) {
  const int64_t n = set.size();
  set.mic_positions = torch::empty({n, 3}, torch::kFloat64);
  set.source_positions = torch::empty({n, 3}, torch::kFloat64);
  set.rots = torch::empty({n, 3}, torch::kFloat64);
  auto m = set.mic_positions.accessor<double, 2>();
  auto s = set.source_positions.accessor<double, 2>();
  auto r = set.rots.accessor<double, 2>();
  for (int64_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      m[i][k] = set.rirs[i].mic[k];
      s[i][k] = set.rirs[i].source[k];
      r[i][k] = set.rirs[i].rot[k];
    }
  // The model's audio scene box: train microphone positions ± 1 m (sources not included).
  if (!set.train.empty()) {
    geometry::Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    for (const int64_t i : set.train)
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], set.rirs[i].mic[k]);
        hi[k] = std::max(hi[k], set.rirs[i].mic[k]);
      }
    set.audio_aabb = {lo - geometry::Vec3{1, 1, 1}, hi + geometry::Vec3{1, 1, 1}};
  }
}

RirIndex make_index(const std::string& dir, AudioLayout layout, bool use_npy,
                    ProblemList& problems) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    problems.error(dir, "is not a folder", "pass the dataset's scene/room folder");
    RirIndex idx;
    idx.set.layout = layout;
    idx.set.root = dir;
    return idx;
  }
  RirIndex idx = layout == AudioLayout::soundspaces
                     ? detail::index_soundspaces(dir, use_npy, problems)
                     : detail::index_raf(dir, problems);
  finish_index(idx.set);
  return idx;
}

bool writable_dir(const std::string& d) {
  std::error_code ec;
  fs::create_directories(d, ec);
  return !ec && fs::is_directory(d, ec) && ::access(d.c_str(), W_OK) == 0;
}

std::string sanitize(std::string s) {
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
  return s.empty() ? "dataset" : s;
}

// The dataset folder's own name ("office_4" for "data/office_4/" and for "." inside it).
std::string folder_name(const std::string& root) {
  const fs::path p = fs::absolute(root).lexically_normal();
  return p.has_filename() ? p.filename().string() : p.parent_path().filename().string();
}

void attach_features(RirSet& set, const RirIndex& idx, const RirLoadOptions& options) {
  const bool ss = set.layout == AudioLayout::soundspaces;
  const bool npy = ss && idx.use_npy;
  const int64_t n = set.size();

  // Frames per RIR: the option, RAF's fixed 0.32 s, a published scene's value, else (0 here) the
  // longest training RIR, read from the headers when the cache is built.
  const std::string scene = folder_name(set.root);
  const int64_t published = ss ? published_max_len(scene).value_or(0) : 0;  // 0: not published
  int64_t max_len = 0;
  if (options.max_len > 0) {
    max_len = options.max_len;
    set.max_len_source = "--max-len";
  } else if (!ss) {
    max_len = detail::kRafMaxLen;
    set.max_len_source = "RAF 0.32 s";
  } else if (published > 0) {
    max_len = published;
    set.max_len_source = "published (" + scene + ")";
  } else {
    set.max_len_source = "longest training RIR";
  }

  // What the features depend on: recipe, parameters, and each source file's identity.
  std::ostringstream params;
  params << "neraf-features v1\nlayout " << to_string(set.layout) << "\nsource "
         << (npy ? "npy-magnitudes" : "wav") << "\nmax_len "
         << (max_len > 0 ? std::to_string(max_len) : "longest-train") << "\nstft " << set.stft.n_fft
         << " " << set.stft.win_length << " " << set.stft.hop_length
         << (set.stft.center ? " center" : "") << "\nsample_rate " << set.sample_rate
         << "\nlog_eps 1e-3\ndtype " << (options.half_precision ? "float16" : "float32")
         << "\nn_rirs " << n << "\n";
  std::ostringstream files;
  for (int64_t i = 0; i < n; ++i) {
    const Rir& r = set.rirs[i];
    const std::string& path = npy ? r.magnitude_path : r.wav_path;
    const detail::FileStamp& st = npy ? idx.npy[i] : idx.wav[i];
    files << r.id << '\t' << fs::path(path).lexically_relative(set.root).string() << '\t' << st.size
          << '\t' << st.mtime_ns << '\n';
  }
  FeatureCacheSpec spec;
  spec.key = hash_hex(params.str() + files.str());
  spec.layout = to_string(set.layout);
  spec.description = params.str() + "files: hashed (path, size, mtime of each)";
  spec.n_rirs = n;
  spec.channels = set.channels;
  spec.n_freq = set.n_freq;
  spec.max_len = max_len;
  spec.half = options.half_precision;

  // Where: the user's folder, else <root>/.neraf_cache, else the user cache folder.
  std::string dir = options.cache_dir;
  if (dir.empty()) {
    dir = (fs::path(set.root) / ".neraf_cache").string();
    if (!writable_dir(dir)) {
      const char* xdg = std::getenv("XDG_CACHE_HOME");
      const char* home = std::getenv("HOME");
      const std::string fallback = xdg && *xdg
                                       ? std::string(xdg) + "/neraf"
                                       : std::string(home ? home : "/tmp") + "/.cache/neraf";
      warn(set.root + ": the dataset folder is not writable; caching audio features in " +
           fallback + " (pass --cache-dir to choose)");
      dir = fallback;
    }
  }
  require(writable_dir(dir), dir +
                                 ": cannot create or write the feature cache folder; pass a "
                                 "writable --cache-dir");
  const std::string prefix = sanitize(scene) + "_" + spec.layout + "_";
  const std::string path = (fs::path(dir) / (prefix + spec.key + ".bin")).string();

  std::shared_ptr<FeatureCache> cache = FeatureCache::open(path, spec);
  if (!cache) {
    // Every file is checked as `neraf info` checks it before anything is computed (a valid cache
    // was made from these very files, checked then: the key hashes their size and time).
    std::vector<detail::RirHeader> headers;
    ProblemList problems = detail::check_rir_headers(set, headers);
    // SoundSpaces automatic max_len: the longest STFT among the training RIRs (0 for the others),
    // from the headers only, bounded before a byte of the cache is written.
    std::vector<int64_t> train_frames(static_cast<size_t>(n), 0);
    for (int64_t i : set.train) train_frames[size_t(i)] = headers[size_t(i)].stft_frames;
    if (spec.max_len == 0) detail::check_padded_cache_size(set, train_frames, spec.half, problems);
    problems.throw_if_errors(set.root);
    const int64_t longest = *std::max_element(train_frames.begin(), train_frames.end());
    if (options.max_len > 0 && longest > 0 && options.max_len > 4 * longest) {
      // Only silence is added, but every RIR costs max_len frames in the cache, in each training
      // step and in the calibration: a typo (100000 for 100) costs hours.
      char msg[320];
      std::snprintf(msg, sizeof msg,
                    "--max-len %lld: %.0fx the longest training RIR here (%lld STFT frames); it "
                    "would pad every RIR with silence (a %.2f GB feature cache, training and "
                    "calibration as much slower); use at most %lld or leave --max-len out",
                    static_cast<long long>(options.max_len),
                    double(options.max_len) / double(longest), static_cast<long long>(longest),
                    detail::cache_bytes(set, options.max_len, spec.half) / 1e9,
                    static_cast<long long>(4 * longest));
      throw Error(set.root + ": " + msg);
    }
    if (options.progress) problems.print_warnings();
    if (spec.max_len == 0)
      spec.max_len =
          std::max<int64_t>(1, *std::max_element(train_frames.begin(), train_frames.end()));
    max_len = spec.max_len;
    const double gb = detail::cache_bytes(set, max_len, spec.half) / 1e9;
    char msg[160];
    std::snprintf(msg, sizeof msg,
                  "%s: building the audio feature cache (%lld RIRs x %lld frames, %.2f GB)",
                  set.root.c_str(), static_cast<long long>(n), static_cast<long long>(max_len), gb);
    if (options.progress) info(msg);
    // Temporary files of builds that were killed (SIGKILL cannot be caught) can be huge.
    io::remove_stale_temporaries(dir);
    std::function<int64_t(int64_t, float*, ProblemList&)> recipe;
    if (!ss)
      recipe = [&](int64_t i, float* out, ProblemList& p) {
        return detail::raf_features(set.rirs[i].wav_path, max_len, out, p);
      };
    else if (npy)
      recipe = [&](int64_t i, float* out, ProblemList& p) {
        return detail::soundspaces_features_from_npy(set.rirs[i].magnitude_path, max_len, out, p);
      };
    else
      recipe = [&](int64_t i, float* out, ProblemList& p) {
        return detail::soundspaces_features_from_wav(set.rirs[i].wav_path, max_len, out, p);
      };
    std::vector<ProblemList> warnings(static_cast<size_t>(n));
    const std::function<int64_t(int64_t, float*)> compute = [&](int64_t i, float* out) {
      // Checked per RIR, so a stop is honoured within one RIR's work; the throw makes the build
      // remove its temporary file.
      if (options.stop && options.stop->load(std::memory_order_relaxed))
        throw Error(set.root +
                    ": interrupted while building the audio feature cache; nothing was kept, "
                    "run the command again to build it");
      return recipe(i, out, warnings[i]);
    };
    cache = FeatureCache::build(path, spec, compute, options.progress, [&](int64_t i) {
      return npy ? set.rirs[i].magnitude_path : set.rirs[i].wav_path;
    });
    if (options.progress) {
      ProblemList found;
      for (const ProblemList& w : warnings) found.append(w.items());
      found.print_warnings();
    }
    // Drop caches of this dataset made for older files or other parameters (they can be huge).
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec)) {
      const std::string name = e.path().filename().string();
      if (e.path().string() != path && name.rfind(prefix, 0) == 0 &&
          e.path().extension() == ".bin") {
        fs::remove(e.path(), ec);
        if (!ec && options.progress) info("removed the stale feature cache " + e.path().string());
      }
    }
  }
  set.max_len = cache->spec().max_len;
  if (published > 0 && options.max_len <= 0) {
    int64_t longest = 0;
    for (int64_t i : set.train) longest = std::max<int64_t>(longest, cache->own_length(i));
    if (longest != published) {
      set.max_len_note = "max_len " + std::to_string(published) + " is the published value for " +
                         scene + "; the longest training RIR here has " + std::to_string(longest) +
                         " frames (pass --max-len " + std::to_string(longest) + " to use it)";
      if (options.progress) info(set.root + ": " + set.max_len_note);
    }
  }
  set.cache_path = path;
  set.waveform_length = ss ? set.max_len * set.stft.hop_length : detail::kRafSamples;
  for (int64_t i = 0; i < n; ++i) set.rirs[i].num_frames = cache->own_length(i);
  set.cache_ = cache;
}

RirSet load(const std::string& dir, AudioLayout layout, const RirLoadOptions& options) {
  ProblemList problems;
  RirIndex idx = make_index(dir, layout, options.use_magnitude_files, problems);
  problems.throw_if_errors(dir);
  if (options.progress) problems.print_warnings();
  RirSet set = std::move(idx.set);
  if (set.layout == AudioLayout::raf) {
    require(options.max_len <= 0 || options.max_len == detail::kRafMaxLen,
            dir + ": a RAF-layout dataset has " + std::to_string(detail::kRafMaxLen) +
                " frames per RIR (0.32 s, as published); --max-len applies to SoundSpaces-layout "
                "data only");
    set.max_len = detail::kRafMaxLen;
    set.waveform_length = detail::kRafSamples;
  } else if (options.max_len > 0) {
    set.max_len = options.max_len;
    set.waveform_length = set.max_len * set.stft.hop_length;
  }
  if (options.load_features) {
    // A refused or interrupted build leaves no cache folder it created behind (fs::remove only
    // removes an empty folder; one holding other caches stays).
    std::error_code ec;
    std::vector<std::string> created;
    for (const std::string& d : {(fs::path(set.root) / ".neraf_cache").string(), options.cache_dir})
      if (!d.empty() && !fs::exists(d, ec)) created.push_back(d);
    try {
      attach_features(set, idx, options);
    } catch (...) {
      for (const std::string& d : created) fs::remove(d, ec);
      throw;
    }
  }
  return set;
}

}  // namespace

RirSet index_rir_set(const std::string& dir, AudioLayout layout, ProblemList& problems) {
  return make_index(dir, layout, /*use_npy=*/true, problems).set;
}

RirSet load_soundspaces(const std::string& dir, const RirLoadOptions& options) {
  return load(dir, AudioLayout::soundspaces, options);
}

RirSet load_raf(const std::string& dir, const RirLoadOptions& options) {
  return load(dir, AudioLayout::raf, options);
}

RirSet first_frames(const RirSet& rirs, int64_t frames) {
  require(frames >= 2 && frames <= rirs.max_len,
          rirs.root + ": cannot cut " + std::to_string(rirs.max_len) + "-frame RIRs to " +
              std::to_string(frames) + " frames");
  RirSet out = rirs;
  out.max_len = frames;
  if (out.layout == AudioLayout::soundspaces) out.waveform_length = frames * out.stft.hop_length;
  return out;
}

std::optional<int64_t> published_max_len(const std::string& scene_name) {
  static const std::pair<const char*, int64_t> kPublished[] = {
      {"office_4", 78},    {"room_2", 84},           {"apartment_1", 101},
      {"apartment_2", 86}, {"frl_apartment_2", 107}, {"frl_apartment_4", 103}};
  for (const auto& [name, frames] : kPublished)
    if (scene_name == name) return frames;
  return std::nullopt;
}

bool parse_cache_precision(const std::string& text, const std::string& flag) {
  if (text == "fp32") return false;
  if (text == "fp16") return true;
  throw Error(flag + ": unknown cache precision \"" + text + "\"; use fp32 or fp16");
}

RirSet load_rir_set(const std::string& dir, const RirLoadOptions& options) {
  const DatasetLayout d = detect_layout(dir);
  if (d.soundspaces) return load_soundspaces(dir, options);
  if (d.raf) return load_raf(dir, options);
  throw Error(dir +
              ": no impulse responses found (neither SoundSpaces binaural_rirs/ + "
              "metadata/points.txt nor RAF data/ + metadata/data-split.json); check the path");
}

// ---------------------------------------------------------------------------------------------

std::string RirSet::sources_hash() const { return cache_ ? cache_->spec().sources_fnv1a : ""; }

torch::Tensor RirSet::features(int64_t i) const {
  require(cache_ != nullptr, "RirSet: features were not loaded (RirLoadOptions::load_features)");
  TORCH_CHECK(i >= 0 && i < size(), "RirSet::features: index ", i, " out of range [0, ", size(),
              ")");
  torch::Tensor tcf = torch::empty({max_len, channels, n_freq}, torch::kFloat32);
  cache_->read_frames(i, 0, max_len, tcf.data_ptr<float>());
  return tcf.permute({1, 2, 0}).contiguous();  // [C, F, T]
}

void RirSet::gather_into(const torch::Tensor& rir, const torch::Tensor& frame,
                         torch::Tensor& out) const {
  require(cache_ != nullptr, "RirSet: features were not loaded (RirLoadOptions::load_features)");
  TORCH_CHECK(rir.dim() == 1 && frame.dim() == 1 && rir.size(0) == frame.size(0),
              "RirSet::gather: rir and frame must be [B] tensors of the same length");
  const int64_t b = rir.size(0);
  TORCH_CHECK(out.scalar_type() == torch::kFloat32 && out.is_contiguous() && out.dim() == 3 &&
                  out.size(0) == b && out.size(1) == channels && out.size(2) == n_freq,
              "RirSet::gather_into: out must be a contiguous float32 [B, C, F] tensor");
  const torch::Tensor r = rir.to(torch::kInt64).contiguous();
  const torch::Tensor f = frame.to(torch::kInt64).contiguous();
  const int64_t* rp = r.data_ptr<int64_t>();
  const int64_t* fp = f.data_ptr<int64_t>();
  const int64_t n = size(), t = max_len;
  for (int64_t k = 0; k < b; ++k)
    TORCH_CHECK(rp[k] >= 0 && rp[k] < n && fp[k] >= 0 && fp[k] < t, "RirSet::gather: slice ", k,
                " (rir ", rp[k], ", frame ", fp[k], ") out of range [", n, ", ", t, ")");
  float* o = out.data_ptr<float>();
  const int64_t slice = channels * n_freq;
  const FeatureCache* c = cache_.get();
  at::parallel_for(0, b, 256, [&](int64_t b0, int64_t b1) {
    for (int64_t k = b0; k < b1; ++k) c->read_frames(rp[k], fp[k], 1, o + k * slice);
  });
}

torch::Tensor RirSet::gather(const torch::Tensor& rir, const torch::Tensor& frame) const {
  torch::Tensor out = torch::empty({rir.size(0), channels, n_freq}, torch::kFloat32);
  gather_into(rir, frame, out);
  return out;
}

torch::Tensor RirSet::waveform(int64_t i) const {
  TORCH_CHECK(i >= 0 && i < size(), "RirSet::waveform: index ", i, " out of range");
  require(waveform_length > 0,
          "RirSet: max_len is unknown until features are loaded (or "
          "RirLoadOptions::max_len is given)");
  const auto chans = layout == AudioLayout::soundspaces
                         ? detail::soundspaces_waveform(rirs[i].wav_path, waveform_length)
                         : detail::raf_waveform(rirs[i].wav_path, waveform_length);
  torch::Tensor w =
      torch::empty({static_cast<int64_t>(chans.size()), waveform_length}, torch::kFloat32);
  for (size_t c = 0; c < chans.size(); ++c)
    std::copy(chans[c].begin(), chans[c].end(), w[c].data_ptr<float>());
  return w;
}

}  // namespace neraf::data
