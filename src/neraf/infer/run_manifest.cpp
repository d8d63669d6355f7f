#include "neraf/infer/run_manifest.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "neraf/util/error.h"
#include "neraf/util/json_text.h"

namespace neraf::infer {

bool is_multiscene(const nlohmann::json& m) {
  return m.is_object() && m.contains("scenes") && m["scenes"].is_array();
}

std::vector<std::string> scene_names(const nlohmann::json& m) {
  std::vector<std::string> out;
  if (!is_multiscene(m)) return out;
  for (const auto& s : m["scenes"])
    out.push_back(s.is_object() && s.contains("name") && s["name"].is_string()
                      ? s["name"].get<std::string>()
                      : "?");
  return out;
}

int64_t find_scene(const nlohmann::json& m, const std::string& selector, const std::string& run_dir,
                   const std::string& flag) {
  const std::vector<std::string> names = scene_names(m);
  std::string list;
  for (size_t i = 0; i < names.size(); ++i)
    list += (i ? ", " : "") + std::to_string(i) + " " + names[i];
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == selector) return static_cast<int64_t>(i);
  const bool digits = !selector.empty() && selector.size() < 10 &&
                      selector.find_first_not_of("0123456789") == std::string::npos;
  if (digits && std::stoll(selector) < static_cast<long long>(names.size()))
    return std::stoll(selector);
  throw Error(flag + " " + selector + ": " + run_dir + " has no such scene; its scenes are " +
              (list.empty() ? std::string("none (it is a one-scene run: drop ") + flag + ")"
                            : list + " (give a name or an index)"));
}

void check_data_paths(const nlohmann::json& m, const std::string& where) {
  auto check = [&](const nlohmann::json& one, const std::string& key) {
    if (!one.is_object() || !one.contains("data") || !one["data"].is_string()) return;
    const std::string& path = one["data"].get_ref<const std::string&>();
    const bool control = std::any_of(path.begin(), path.end(), [](char c) {
      return static_cast<unsigned char>(c) < 0x20 || c == 0x7f;
    });
    require(!control, where + ": is damaged (" + key + " " + json_quoted(path) +
                          " holds a control character); restore it or re-run neraf train");
  };
  check(m, "data");
  if (is_multiscene(m))
    for (size_t s = 0; s < m["scenes"].size(); ++s)
      check(m["scenes"][s], "scenes[" + std::to_string(s) + "].data");
}

namespace {

geometry::Vec3 vec_from(const nlohmann::json& j) {
  return {j.at(0).get<double>(), j.at(1).get<double>(), j.at(2).get<double>()};
}

}  // namespace

AudioRunInfo audio_info_from_manifest(const nlohmann::json& a, const std::string& where) {
  const std::string incomplete = where + ": the audio manifest is incomplete; re-run neraf train";
  try {
    AudioRunInfo info;
    const std::string layout = a.at("layout").get<std::string>();
    require(layout == "soundspaces" || layout == "raf", where + ": unknown audio layout");
    info.layout = layout == "raf" ? data::AudioLayout::raf : data::AudioLayout::soundspaces;
    // Integers are range-checked before they are narrowed: a number that is not a whole number
    // within int64 (1e300, 22050.5, 2^64 − 1) reads as INT64_MIN, which every check refuses, and
    // 2^32 + 22050 must not wrap to 22050.
    auto integer = [&](const char* key) {
      const nlohmann::json& v = a.at(key);
      require(v.is_number(), incomplete);
      const bool fits = v.is_number_integer() &&
                        !(v.is_number_unsigned() && v.get<uint64_t>() > uint64_t{INT64_MAX});
      return fits ? v.get<int64_t>() : INT64_MIN;
    };
    const int64_t sample_rate = integer("sample_rate");
    const int64_t channels = integer("channels");
    const int64_t n_fft = integer("n_fft");
    const int64_t win_length = integer("win_length");
    const int64_t hop_length = integer("hop_length");
    info.n_freq = integer("n_freq");
    info.max_len = integer("max_len");
    info.waveform_length = integer("waveform_length");
    info.aabb.min = vec_from(a.at("aabb_min"));
    info.aabb.max = vec_from(a.at("aabb_max"));
    // Every later failure (STFT sizes, a WAV at 0 Hz, a box inside out) would otherwise blame a
    // flag or an output file.
    auto check = [&](bool ok, const std::string& key, const nlohmann::json& value,
                     const std::string& rule) {
      require(ok, where + ": is damaged (audio." + key + " is " + value.dump() + "; " + rule +
                      "); restore it or re-run neraf train");
    };
    check(sample_rate >= 1 && sample_rate <= 768000, "sample_rate", a["sample_rate"],
          "expected 1..768000 Hz");
    check(channels >= 1 && channels <= 64, "channels", a["channels"], "expected 1..64");
    check(info.layout != data::AudioLayout::raf || channels == 1, "channels", a["channels"],
          "the raf layout is mono");
    check(n_fft >= 2 && n_fft <= (1 << 20), "n_fft", a["n_fft"], "expected 2..1048576");
    check(win_length >= 1 && win_length <= n_fft, "win_length", a["win_length"],
          "expected 1..n_fft");
    check(hop_length >= 1 && hop_length <= win_length, "hop_length", a["hop_length"],
          "expected 1..win_length");
    check(info.n_freq == n_fft / 2 + 1, "n_freq", a["n_freq"], "expected n_fft / 2 + 1");
    check(info.max_len >= 2 && info.max_len <= 100000, "max_len", a["max_len"],
          "expected 2..100000 frames");
    check(info.waveform_length >= 1, "waveform_length", a["waveform_length"],
          "expected a positive sample count");
    if (a.contains("scene_frames")) {
      // A scene of a multi-scene run: its own frames of the run's (max_len) time range.
      const int64_t own = integer("scene_frames");
      check(own >= 2 && own <= info.max_len, "scene_frames", a["scene_frames"],
            "expected 2..max_len frames");
      if (own < info.max_len) {
        info.time_frames = info.max_len;
        info.max_len = own;
        if (layout == "soundspaces") info.waveform_length = own * hop_length;
      }
    }
    const geometry::Vec3 &lo = info.aabb.min, &hi = info.aabb.max;
    for (double v : {lo.x, lo.y, lo.z, hi.x, hi.y, hi.z})
      check(std::isfinite(v), "aabb_min/aabb_max", a["aabb_min"], "expected finite metres");
    // The box is the train microphones +- 1 m: at least 2 m wide; a flat one is a damaged file.
    check(hi.x - lo.x >= 1e-3 && hi.y - lo.y >= 1e-3 && hi.z - lo.z >= 1e-3, "aabb_min",
          a["aabb_min"],
          "expected at least 1 mm below aabb_max " + a["aabb_max"].dump() + " on every axis");
    info.sample_rate = static_cast<int>(sample_rate);
    info.channels = static_cast<int>(channels);
    info.stft.n_fft = static_cast<int>(n_fft);
    info.stft.win_length = static_cast<int>(win_length);
    info.stft.hop_length = static_cast<int>(hop_length);
    info.stft.center = true;
    return info;
  } catch (const nlohmann::json::exception&) {
    throw Error(incomplete);
  }
}

nlohmann::json intrinsics_json(const data::Intrinsics& k) {
  return {{"fx", k.fx},       {"fy", k.fy},         {"cx", k.cx}, {"cy", k.cy},
          {"width", k.width}, {"height", k.height}, {"k1", k.k1}, {"k2", k.k2},
          {"k3", k.k3},       {"p1", k.p1},         {"p2", k.p2}};
}

data::Intrinsics intrinsics_from_json(const nlohmann::json& j, const std::string& where) {
  require(j.is_object(), where + ": expected an object with fx, fy, cx, cy, width, height");
  data::Intrinsics k;
  auto num = [&](const char* key, double fallback, bool required) {
    if (!j.contains(key)) {
      require(!required, where + "." + key + ": missing");
      return fallback;
    }
    require(j[key].is_number(), where + "." + key + ": expected a number");
    return j[key].get<double>();
  };
  k.fx = num("fx", 0, true);
  k.fy = num("fy", 0, true);
  k.cx = num("cx", 0, true);
  k.cy = num("cy", 0, true);
  // Whole pixels, checked before the conversion (16.5 or 1e30 pixels is no image size).
  auto pixels = [&](const char* key) {
    const double v = num(key, 0, true);
    require(v == std::floor(v) && v >= 1 && v <= 16384,
            where + ": width and height must be whole numbers in 1..16384 (" + key + " is " +
                j[key].dump() + ")");
    return static_cast<int>(v);
  };
  k.width = pixels("width");
  k.height = pixels("height");
  k.k1 = num("k1", 0, false);
  k.k2 = num("k2", 0, false);
  k.k3 = num("k3", 0, false);
  k.p1 = num("p1", 0, false);
  k.p2 = num("p2", 0, false);
  // The bounds transforms.json gets (data::intrinsics_problem): a camera file's focal length of
  // 1e-320 rendered a flat picture without a word.
  const std::string problem = data::intrinsics_problem(k);
  require(problem.empty(), where + ": " + problem +
                               "; give the camera's focal lengths (pixels) and distortion as "
                               "calibrated");
  require(k.width > 0 && k.height > 0 && k.width <= 16384 && k.height <= 16384,
          where + ": width and height must be in 1..16384");
  return k;
}

}  // namespace neraf::infer
