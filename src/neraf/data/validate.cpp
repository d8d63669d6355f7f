#include "neraf/data/validate.h"

#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "neraf/data/audio_probe.h"
#include "neraf/data/image_set.h"
#include "neraf/data/rir_check.h"
#include "neraf/data/rir_layouts.h"
#include "neraf/io/npy.h"
#include "neraf/util/error.h"
#include "neraf/util/progress.h"

namespace fs = std::filesystem;

namespace neraf::data {

Stats compute_stats(std::vector<double> v) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return std::isnan(x); }), v.end());
  Stats s;
  s.count = static_cast<int64_t>(v.size());
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  s.min = v.front();
  s.max = v.back();
  double sum = 0;
  for (const double x : v) sum += x;
  s.mean = sum / v.size();
  const size_t m = v.size() / 2;
  s.median = v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
  return s;
}

int64_t DatasetReport::num_errors() const {
  return std::count_if(problems.begin(), problems.end(),
                       [](const Problem& p) { return p.is_error(); });
}
int64_t DatasetReport::num_warnings() const {
  return static_cast<int64_t>(problems.size()) - num_errors();
}

namespace {

Aabb box_of(const std::vector<geometry::Vec3>& pts) {
  Aabb b;
  if (pts.empty()) return b;
  b.min = b.max = pts[0];
  for (const auto& p : pts)
    for (int k = 0; k < 3; ++k) {
      b.min[k] = std::min(b.min[k], p[k]);
      b.max[k] = std::max(b.max[k], p[k]);
    }
  return b;
}

bool zeroed(const geometry::Vec3& p, const Aabb& box) {
  const geometry::Vec3 q = normalize_position(p, box);
  return q.x == 0 && q.y == 0 && q.z == 0;
}

// What one RIR's check found (filled in parallel, reported in order).
struct AudioCheck {
  detail::RirHeader header;
  ProblemList problems;
  std::vector<double> t60;  // per channel, when this RIR was picked for the T60 summary
  bool t60_measured = false;
};

void inspect_audio(DatasetReport& r, AudioLayout layout, const InspectOptions& options,
                   ProblemList& problems) {
  r.audio_layout = layout;
  ProblemList index_problems;
  const RirSet set = index_rir_set(r.dir, layout, index_problems);
  problems.append(index_problems.items());
  r.rirs_train = static_cast<int64_t>(set.train.size());
  r.rirs_test = static_cast<int64_t>(set.test.size());
  const bool ss = layout == AudioLayout::soundspaces;
  r.expected_sample_rate = ss ? detail::kSoundSpacesWavRate : detail::kRafRate;
  r.expected_channels = ss ? 2 : 1;
  const int64_t n = set.size();
  if (n == 0) return;

  // T60 on at most max_sample_reads RIRs, evenly spaced (deterministic).
  const int64_t m = std::min<int64_t>(n, std::max<int64_t>(options.max_sample_reads, 1));
  std::vector<char> picked(static_cast<size_t>(n), 0);
  for (int64_t k = 0; k < m; ++k) picked[k * n / m] = 1;
  r.t60_subsampled = m < n;

  // Every file is read in full, with the very checks the loaders and feature recipes run
  // (rir_check.h): "0 errors" here means training accepts the data.
  std::vector<AudioCheck> checks(static_cast<size_t>(n));
  {
    ProgressOptions popt;
    popt.unit = "file";
    popt.enabled = options.progress && n >= 500;
    Progress bar("checking audio files", n, popt);
    std::atomic<int64_t> done{0};
    detail::parallel_for_each(n, [&](int64_t i) {
      const Rir& rir = set.rirs[i];
      AudioCheck& c = checks[i];
      c.header = detail::check_rir_header(set, i, c.problems);
      const AudioProbe& p = c.header.probe;
      const bool readable = p.ok && p.frames > 0 && p.sample_rate == set.wav_sample_rate &&
                            p.channels == set.channels && p.duration_s() <= detail::kMaxRirSeconds;
      if (readable) {
        try {
          const io::AudioBuffer audio = io::read_audio(rir.wav_path);
          detail::check_rir_samples(rir.wav_path, audio.channels, c.problems);
          if (options.t60 && picked[i]) {
            c.t60 = options.t60(audio, layout);
            c.t60_measured = true;
          }
        } catch (const Error& e) {
          c.problems.error_from_message(rir.wav_path, e.what());
        }
      }
      if (!rir.magnitude_path.empty() && c.header.stft_frames > 0) {
        try {
          detail::check_magnitudes(rir.magnitude_path, io::read_npy(rir.magnitude_path), set.n_freq,
                                   c.problems);
        } catch (const Error& e) {
          c.problems.error_from_message(rir.magnitude_path, e.what());
        }
      }
      const int64_t d = ++done;
      if (omp_get_thread_num() == 0) bar.update(d);
    });
    bar.finish();
  }

  std::vector<double> durations;
  std::vector<int64_t> frames(static_cast<size_t>(n), 0);
  for (int64_t i = 0; i < n; ++i) {
    const AudioCheck& c = checks[i];
    problems.append(c.problems.items());
    if (!set.rirs[i].magnitude_path.empty()) ++r.magnitude_files;
    if (c.header.probe.ok) durations.push_back(c.header.probe.duration_s());
    frames[i] = c.header.stft_frames;
  }
  // The bound training applies before it builds the cache (with the automatic max_len).
  if (ss) detail::check_padded_cache_size(set, frames, /*half=*/false, problems);
  r.duration_s = compute_stats(durations);

  std::vector<geometry::Vec3> mics, sources;
  for (const Rir& rir : set.rirs) {
    mics.push_back(rir.mic);
    sources.push_back(rir.source);
  }
  r.mic_box = box_of(mics);
  r.source_box = box_of(sources);
  r.audio_aabb = set.audio_aabb;
  if (!set.train.empty()) {
    for (const int64_t i : set.test) r.test_mics_outside += zeroed(set.rirs[i].mic, set.audio_aabb);
    for (const Rir& rir : set.rirs) r.sources_outside += zeroed(rir.source, set.audio_aabb);
  }

  if (!options.t60) return;
  std::vector<double> all;
  for (const AudioCheck& c : checks) {
    if (!c.t60_measured) continue;
    ++r.t60_rirs;
    for (const double x : c.t60) {
      if (std::isnan(x))
        ++r.t60_invalid;
      else
        all.push_back(x);
    }
  }
  r.t60_s = compute_stats(all);
}

std::string fmt_stats(const Stats& s, const char* unit, int prec = 3) {
  if (s.count == 0) return "n/a";
  char buf[200];
  std::snprintf(buf, sizeof buf, "min %.*f  mean %.*f  median %.*f  max %.*f %s", prec, s.min, prec,
                s.mean, prec, s.median, prec, s.max, unit);
  return buf;
}

std::string fmt_box(const Aabb& b) {
  char buf[200];
  std::snprintf(buf, sizeof buf, "[%.3f, %.3f, %.3f] .. [%.3f, %.3f, %.3f] m", b.min.x, b.min.y,
                b.min.z, b.max.x, b.max.y, b.max.z);
  return buf;
}

}  // namespace

DatasetReport inspect_dataset(const std::string& dir, const InspectOptions& options) {
  DatasetReport r;
  r.dir = dir;
  ProblemList problems;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    problems.error(dir, "is not a folder", "pass the dataset's scene/room folder");
    r.problems = problems.items();
    return r;
  }
  r.layout = detect_layout(dir);
  if (r.layout.empty())
    problems.error(dir, "holds no known dataset layout",
                   "expected SoundSpaces (binaural_rirs/, metadata/points.txt), RAF (data/, "
                   "metadata/data-split.json) and/or nerfstudio images (transforms.json)");
  if (r.layout.soundspaces && r.layout.raf)
    problems.warning(dir, "looks like both a SoundSpaces and a RAF scene; SoundSpaces is used",
                     "keep one layout per folder");
  if (r.layout.has_audio())
    inspect_audio(r, r.layout.soundspaces ? AudioLayout::soundspaces : AudioLayout::raf, options,
                  problems);
  if (r.layout.nerfstudio && options.check_images) {
    ImageLoadOptions iopt;
    iopt.progress = false;
    const ImageSet images = check_transforms_json(dir, iopt, problems);
    r.images_train = images.train.size();
    r.images_eval = images.eval.size();
    r.image_eval_mode = images.eval_mode;
    const ImageSplit& s = images.train.size() ? images.train : images.eval;
    if (s.size()) {
      r.image_width = s.intrinsics[0].width;
      r.image_height = s.intrinsics[0].height;
    }
  }
  r.problems = problems.items();
  return r;
}

std::vector<Problem> validate_dataset(const std::string& dir) {
  InspectOptions o;
  o.progress = false;
  return inspect_dataset(dir, o).problems;
}

std::string format_report(const DatasetReport& r) {
  std::ostringstream o;
  o << "dataset      " << r.dir << "\n";
  o << "layout       " << r.layout.describe() << "\n";
  if (r.layout.has_audio()) {
    const bool ss = r.audio_layout == AudioLayout::soundspaces;
    o << "RIRs         " << r.rirs_train << " train, " << r.rirs_test << " test ("
      << (ss ? "binaural, 44.1 kHz files; features at 22.05 kHz" : "mono, 48 kHz") << ")\n";
    if (ss)
      o << "magnitudes   " << r.magnitude_files << " published .npy files"
        << (r.magnitude_files == r.rirs_train + r.rirs_test && r.magnitude_files > 0
                ? " (used for features)"
                : " (features computed from the wavs)")
        << "\n";
    o << "duration     " << fmt_stats(r.duration_s, "s") << "\n";
    o << "mic box      " << fmt_box(r.mic_box) << "\n";
    o << "source box   " << fmt_box(r.source_box) << "\n";
    o << "audio aabb   " << fmt_box(r.audio_aabb) << " (train mics ± 1 m)\n";
    if (r.test_mics_outside || r.sources_outside)
      o << "             outside it (position encoded as 0, as the reference does; the "
           "relative geometry of preset cpu still uses their metres): "
        << r.test_mics_outside << " test mics, " << r.sources_outside << " sources\n";
    if (r.t60_rirs > 0) {
      o << "T60          " << fmt_stats(r.t60_s, "s")
        << (ss ? "  (full band, 30 dB decay)" : "  (200 Hz high-pass, 10 dB decay)") << "\n";
      o << "             over " << r.t60_rirs << " RIRs"
        << (r.t60_subsampled ? " (an evenly spaced subset)" : "") << ", " << r.t60_invalid
        << " channel(s) without a value\n";
    }
  }
  if (r.layout.nerfstudio) {
    o << "images       " << r.images_train << " train, " << r.images_eval << " eval";
    if (r.image_width > 0) o << ", " << r.image_width << "x" << r.image_height;
    if (!r.image_eval_mode.empty()) o << " (split: " << r.image_eval_mode << ")";
    o << "\n";
  }
  o << "problems     " << r.num_errors() << " error(s), " << r.num_warnings() << " warning(s)\n";
  return o.str();
}

}  // namespace neraf::data
