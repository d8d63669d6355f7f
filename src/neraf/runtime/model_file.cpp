#include "neraf/runtime/model_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>

#include "neraf/runtime/stft_window.h"

namespace neraf::rt {

// Arrays are copied with memcpy: the file is little-endian, so is every supported host.
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "neraf model files are little-endian");

namespace {

using nlohmann::json;

constexpr char kMagic[8] = {'N', 'E', 'R', 'A', 'F', 'M', 'D', 'L'};
constexpr size_t kPrefixSize = 24;                 // magic, version, flags, payload size
constexpr size_t kFileOverhead = kPrefixSize + 8;  // + checksum
// Bounds that no real model reaches (preset paper: ~61 MB, widths ≤ 5096) but that keep a
// corrupt or hostile header from asking for absurd work or memory.
constexpr uint64_t kMaxFileSize = uint64_t(1) << 34;  // 16 GiB
constexpr uint64_t kMaxHeaderSize = uint64_t(1) << 24;
constexpr int kMaxJsonDepth = 16;
constexpr int64_t kMaxWidth = int64_t(1) << 20;
constexpr size_t kMaxLayers = 64;
constexpr size_t kMaxVersionLength = sizeof(neraf_model_info{}.neraf_version) - 1;  // 31
// Plausible values of what export writes (exported_model.cpp): an edited header with a valid
// checksum must not give RIRs at +71 dBFS or a WAV at 1 Hz. Sample rates as the data loaders take
// them; NAcF's output_scale is 10 and its leaky_slope 0.1 in every neraf model (NacfOptions, not
// flags), output_scale ≤ 30 keeps exp(out) and its square finite in float32; positions within
// 10 km (every pose file's bound) in a box and extent at least 1 mm wide.
constexpr int kMinSampleRate = 8000, kMaxSampleRate = 384000;
constexpr double kMaxOutputScale = 30;
constexpr double kMaxAbsCoordinate = 1e4;
constexpr double kMinSideM = 1e-3;

[[noreturn]] void format_error(const std::string& name, const std::string& what) {
  throw ModelFileError(NERAF_ERR_FORMAT, name + ": " + what);
}

void put_u32(std::vector<uint8_t>& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(uint8_t(v >> (8 * i)));
}
void put_u64(std::vector<uint8_t>& out, uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(uint8_t(v >> (8 * i)));
}
uint32_t get_u32(const uint8_t* p) {
  uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}
uint64_t get_u64(const uint8_t* p) {
  uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

// ---- header JSON ----------------------------------------------------------------------------

json vec3(const std::array<double, 3>& v) { return json::array({v[0], v[1], v[2]}); }

json shapes(const std::vector<DenseLayer>& layers) {
  json a = json::array();
  for (const DenseLayer& l : layers) a.push_back(json::array({l.out, l.in}));
  return a;
}

json header_json(const ModelData& m) {
  json h;
  h["neraf_version"] = m.neraf_version;
  h["layout"] = m.layout;
  h["sample_rate"] = m.sample_rate;
  h["channels"] = m.channels;
  h["n_fft"] = m.n_fft;
  h["win_length"] = m.win_length;
  h["hop_length"] = m.hop_length;
  h["n_freq"] = m.n_freq;
  h["max_len"] = m.max_len;
  if (m.time_frames > 0 && m.time_frames != m.max_len) h["time_frames"] = m.time_frames;
  h["waveform_length"] = m.waveform_length;
  h["box_min"] = vec3(m.box_min);
  h["box_max"] = vec3(m.box_max);
  h["relative_geometry"] = m.relative_geometry;
  h["position_max_freq_exp"] = m.position_max_freq_exp;
  h["extent_m"] = vec3(m.extent_m);
  h["leaky_slope"] = m.leaky_slope;
  h["output_scale"] = m.output_scale;
  h["trunk"] = shapes(m.trunk);
  h["heads"] = shapes(m.heads);
  h["calibration"] =
      m.calibration.empty() ? json::array() : json::array({m.channels, m.n_freq, m.max_len});
  h["weight_dtype"] = m.bf16_storage ? "bfloat16" : "float32";
  h["metadata"] = m.metadata_json;
  return h;
}

// nlohmann's parser recurses per nesting level: bound the depth before handing it the text.
bool json_depth_ok(const char* s, size_t n, int max_depth) {
  int depth = 0;
  bool in_string = false, escaped = false;
  for (size_t i = 0; i < n; ++i) {
    const char c = s[i];
    if (in_string) {
      if (escaped)
        escaped = false;
      else if (c == '\\')
        escaped = true;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > max_depth) return false;
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return true;
}

// Typed access to header fields; every failure names the file and the field.
class Header {
 public:
  Header(const json& j, const std::string& name) : j_(j), name_(name) {}

  const json& at(const char* key) const {
    const auto it = j_.find(key);
    if (it == j_.end()) format_error(name_, std::string("header: field '") + key + "' is missing");
    return *it;
  }
  int64_t integer(const char* key, int64_t lo, int64_t hi) const {
    const json& v = at(key);
    if (!v.is_number_integer()) bad(key, "is not an integer");
    if (v.is_number_unsigned() && v.get<uint64_t>() > uint64_t(hi)) bad(key, "is out of range");
    const int64_t x = v.get<int64_t>();
    if (x < lo || x > hi)
      bad(key, "is " + std::to_string(x) + ", outside [" + std::to_string(lo) + ", " +
                   std::to_string(hi) + "]");
    return x;
  }
  double number(const char* key) const {
    const json& v = at(key);
    if (!v.is_number()) bad(key, "is not a number");
    return v.get<double>();
  }
  bool boolean(const char* key) const {
    const json& v = at(key);
    if (!v.is_boolean()) bad(key, "is not true/false");
    return v.get<bool>();
  }
  std::string string(const char* key) const {
    const json& v = at(key);
    if (!v.is_string()) bad(key, "is not a string");
    return v.get<std::string>();
  }
  std::array<double, 3> vec3(const char* key) const {
    const json& v = at(key);
    if (!v.is_array() || v.size() != 3) bad(key, "is not an array of 3 numbers");
    std::array<double, 3> out{};
    for (int i = 0; i < 3; ++i) {
      if (!v[i].is_number()) bad(key, "is not an array of 3 numbers");
      out[i] = v[i].get<double>();
    }
    return out;
  }
  // [[out, in], ...] → layers with their sizes set (arrays not allocated yet).
  std::vector<DenseLayer> layers(const char* key) const {
    const json& v = at(key);
    if (!v.is_array() || v.empty() || v.size() > kMaxLayers)
      bad(key, "is not a list of 1 to " + std::to_string(kMaxLayers) + " [out, in] shapes");
    std::vector<DenseLayer> out(v.size());
    for (size_t i = 0; i < v.size(); ++i) {
      const json& s = v[i];
      if (!s.is_array() || s.size() != 2 || !s[0].is_number_integer() || !s[1].is_number_integer())
        bad(key, "entry " + std::to_string(i) + " is not an [out, in] pair of integers");
      out[i].out = dim(s[0], key);
      out[i].in = dim(s[1], key);
    }
    return out;
  }
  std::vector<int64_t> int_list(const char* key, size_t max_size) const {
    const json& v = at(key);
    if (!v.is_array() || v.size() > max_size) bad(key, "is not a short list of integers");
    std::vector<int64_t> out;
    for (const json& x : v) out.push_back(dim(x, key));
    return out;
  }

 private:
  [[noreturn]] void bad(const char* key, const std::string& what) const {
    format_error(name_, std::string("header: field '") + key + "' " + what);
  }
  int64_t dim(const json& x, const char* key) const {
    if (!x.is_number_integer()) bad(key, "holds a size that is not an integer");
    if (x.is_number_unsigned() ? x.get<uint64_t>() > uint64_t(kMaxWidth)
                               : (x.get<int64_t>() < 1 || x.get<int64_t>() > kMaxWidth))
      bad(key, "holds a size outside [1, " + std::to_string(kMaxWidth) + "]");
    return x.get<int64_t>();
  }

  const json& j_;
  const std::string& name_;
};

// ---- arrays ---------------------------------------------------------------------------------

void put_floats(std::vector<uint8_t>& out, const std::vector<float>& v) {
  if (v.empty()) return;  // (memcpy from an empty vector's null data is undefined)
  const size_t at = out.size();
  out.resize(at + v.size() * sizeof(float));
  std::memcpy(out.data() + at, v.data(), v.size() * sizeof(float));
}

void put_bf16(std::vector<uint8_t>& out, const std::vector<float>& v, const std::string& name,
              const std::string& what) {
  const size_t at = out.size();
  out.resize(at + v.size() * sizeof(uint16_t));
  for (size_t i = 0; i < v.size(); ++i) {
    const uint16_t h = float_to_bf16(v[i]);
    if (!std::isfinite(bf16_to_float(h)))
      format_error(name, what + " holds " + std::to_string(v[i]) + ", beyond bfloat16's range");
    std::memcpy(out.data() + at + 2 * i, &h, 2);
  }
}

// Reads the payload's arrays in order, checking each length against what is left BEFORE
// allocating it.
class ArrayReader {
 public:
  ArrayReader(const uint8_t* p, size_t size, const std::string& name)
      : p_(p), left_(size), name_(name) {}

  std::vector<float> floats(uint64_t count, bool bf16, const std::string& what) {
    const uint64_t elem = bf16 ? 2 : 4;
    if (count > left_ / elem)
      format_error(name_, "the payload ends inside " + what + " (" + std::to_string(count) +
                              " values declared, " + std::to_string(left_ / elem) + " left)");
    std::vector<float> out(count);
    if (bf16) {
      for (uint64_t i = 0; i < count; ++i) {
        uint16_t h;
        std::memcpy(&h, p_ + 2 * i, 2);
        out[i] = bf16_to_float(h);
      }
    } else if (count > 0) {
      std::memcpy(out.data(), p_, count * 4);
    }
    p_ += count * elem;
    left_ -= count * elem;
    return out;
  }
  size_t left() const { return left_; }

 private:
  const uint8_t* p_;
  size_t left_;
  const std::string& name_;
};

std::string layer_name(const char* group, size_t i) {
  return std::string(group) + "[" + std::to_string(i) + "]";
}

void check_finite(const std::vector<float>& v, const std::string& name, const std::string& what) {
  for (size_t i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i]))
      format_error(name, what + " holds a NaN or infinite value (index " + std::to_string(i) + ")");
}

void check_shapes(const std::vector<DenseLayer>& layers, const char* group,
                  const std::string& name) {
  for (size_t i = 0; i < layers.size(); ++i) {
    const DenseLayer& l = layers[i];
    if (l.in < 1 || l.in > kMaxWidth || l.out < 1 || l.out > kMaxWidth)
      format_error(name, layer_name(group, i) + " is [" + std::to_string(l.out) + ", " +
                             std::to_string(l.in) + "]: sizes must lie in [1, " +
                             std::to_string(kMaxWidth) + "]");
  }
}

void check_arrays(const std::vector<DenseLayer>& layers, const char* group,
                  const std::string& name) {
  for (size_t i = 0; i < layers.size(); ++i) {
    const DenseLayer& l = layers[i];
    const std::string what = layer_name(group, i);
    if (l.weight.size() != uint64_t(l.in) * uint64_t(l.out))
      format_error(name, what + ".weight has " + std::to_string(l.weight.size()) +
                             " values, its shape [" + std::to_string(l.out) + ", " +
                             std::to_string(l.in) + "] needs " + std::to_string(l.in * l.out));
    if (l.bias.size() != uint64_t(l.out))
      format_error(name, what + ".bias has " + std::to_string(l.bias.size()) + " values, needs " +
                             std::to_string(l.out));
    check_finite(l.weight, name, what + ".weight");
    check_finite(l.bias, name, what + ".bias");
  }
}

bool finite3(const std::array<double, 3>& v) {
  return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
}

void check_range(int64_t v, int64_t lo, int64_t hi, const char* what, const std::string& name) {
  if (v < lo || v > hi)
    format_error(name, std::string(what) + " is " + std::to_string(v) + ", outside [" +
                           std::to_string(lo) + ", " + std::to_string(hi) + "]");
}

void write_all(int fd, const uint8_t* p, size_t n) {
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) throw std::system_error(errno ? errno : EIO, std::generic_category());
    p += w;
    n -= size_t(w);
  }
}

std::string number_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string vec3_text(const std::array<double, 3>& v) {
  return "[" + number_text(v[0]) + ", " + number_text(v[1]) + ", " + number_text(v[2]) + "]";
}

// A short, one-line rendering of JSON from the file for a message (escapes, at most ~80 bytes).
std::string json_text_for_message(const json& v) {
  const std::string s = v.dump(-1, ' ', false, json::error_handler_t::replace);
  return s.size() <= 80 ? s : s.substr(0, 80) + "...";
}

// JSON text parsed as neraf's other readers parse it (util/json_text.h, which the runtime may not
// link): a key given twice in one object is refused, not silently the last one. Returns a
// discarded value for text that is not JSON; `duplicate` gets the first key given twice.
json parse_strict(const char* text, size_t size, std::string& duplicate) {
  std::vector<std::set<std::string>> keys;  // of each open object
  const json::parser_callback_t note_keys = [&](int, json::parse_event_t event, json& parsed) {
    using Event = json::parse_event_t;
    if (event == Event::object_start) keys.emplace_back();
    if (event == Event::object_end && !keys.empty()) keys.pop_back();
    if (event == Event::key && !keys.empty() &&
        !keys.back().insert(parsed.get<std::string>()).second && duplicate.empty())
      duplicate = parsed.get<std::string>();
    return true;
  };
  return json::parse(text, text + size, note_keys, /*allow_exceptions=*/false);
}

// The free-form metadata must be JSON (export writes an object; eval reads its "data" entry).
// Where it holds the run's audio manifest (export's "data"."audio"), it must agree with the
// header: eval reads the metadata and render the header, so an edit of one alone would make the
// two commands disagree about the same file without a word.
void check_metadata(const ModelData& m, const std::string& name) {
  if (m.metadata_json.empty()) return;
  const std::string& text = m.metadata_json;
  if (!json_depth_ok(text.data(), text.size(), kMaxJsonDepth))
    format_error(name, "header: field 'metadata' is JSON nested too deeply");
  std::string duplicate;
  const json meta = parse_strict(text.data(), text.size(), duplicate);
  if (meta.is_discarded()) format_error(name, "header: field 'metadata' is not valid JSON text");
  if (!duplicate.empty())
    format_error(name, "header: field 'metadata' gives the key " +
                           json_text_for_message(json(duplicate)) + " twice in one object");
  const auto data = meta.is_object() ? meta.find("data") : meta.end();
  if (data == meta.end() || !data->is_object()) return;
  const auto audio = data->find("audio");
  if (audio == data->end() || !audio->is_object()) return;
  const auto agree = [&](const char* key, const json& header_value) {
    const auto it = audio->find(key);
    if (it != audio->end() && *it != header_value)
      format_error(name, std::string("metadata data.audio.") + key + " " +
                             json_text_for_message(*it) + " disagrees with the header's " +
                             json_text_for_message(header_value) +
                             "; the file was edited: export it again from its run");
  };
  agree("layout", m.layout == 1 ? "raf" : "soundspaces");
  agree("sample_rate", m.sample_rate);
  agree("channels", m.channels);
  agree("n_fft", m.n_fft);
  agree("win_length", m.win_length);
  agree("hop_length", m.hop_length);
  agree("n_freq", m.n_freq);
  const auto own = audio->find("scene_frames");
  if (own != audio->end() && audio->value("max_len", json()) != *own) {
    // A scene of a multi-scene run at its own length: the manifest holds the run's frames.
    agree("scene_frames", m.max_len);
    agree("max_len", m.time_frames);
  } else {
    agree("max_len", m.max_len);
    agree("waveform_length", m.waveform_length);
  }
  agree("aabb_min", vec3(m.box_min));
  agree("aabb_max", vec3(m.box_max));
}

// Everything but the arrays' contents: sizes, STFT parameters, shapes and their chaining (what
// the reader can check before reading, and allocating, any array).
void check_config(const ModelData& m, const std::string& name) {
  if (m.neraf_version.size() > kMaxVersionLength || m.neraf_version.find('\0') != std::string::npos)
    format_error(name, "neraf_version '" + m.neraf_version.substr(0, 40) +
                           "' is longer than 31 bytes or holds a NUL");
  check_range(m.layout, 0, 1, "layout (0 soundspaces, 1 raf)", name);
  check_range(m.sample_rate, kMinSampleRate, kMaxSampleRate, "sample_rate", name);
  check_range(m.channels, 1, 16, "channels", name);
  if (m.layout == 1 && m.channels != 1)
    format_error(name, "channels is " + std::to_string(m.channels) +
                           ", but the raf layout (layout 1) is mono");
  check_range(m.n_fft, 2, 1 << 16, "n_fft", name);
  check_range(m.win_length, 1, m.n_fft, "win_length", name);
  check_range(m.hop_length, 1, m.n_fft, "hop_length", name);
  if (m.n_freq != m.n_fft / 2 + 1)
    format_error(name, "n_freq " + std::to_string(m.n_freq) +
                           " is not n_fft/2 + 1 = " + std::to_string(m.n_fft / 2 + 1));
  check_range(m.max_len, 2, 1 << 16, "max_len (frames)", name);
  if (m.time_frames != 0) check_range(m.time_frames, m.max_len, 1 << 16, "time_frames", name);
  check_range(m.waveform_length, 0, int64_t(1) << 26, "waveform_length", name);
  // The implicit length hop·(T − 1) gets the same bound: the RIR length sizes Griffin-Lim's
  // buffers at load, and neraf_model_info holds it in an int.
  check_range(m.rir_length(), 1, int64_t(1) << 26,
              "the RIR length (waveform_length, or hop_length·(max_len − 1))", name);
  if (!satisfies_nola(padded_hann_window(m.n_fft, m.win_length), m.hop_length))
    format_error(name, "hop_length " + std::to_string(m.hop_length) +
                           " leaves gaps between the Hann windows of " +
                           std::to_string(m.win_length) + " (no inverse STFT)");
  for (int a = 0; a < 3; ++a) {
    if (!(std::fabs(m.box_min[a]) <= kMaxAbsCoordinate) ||
        !(std::fabs(m.box_max[a]) <= kMaxAbsCoordinate) ||
        !(m.box_max[a] - m.box_min[a] >= kMinSideM))
      format_error(name, "box_min " + vec3_text(m.box_min) + " / box_max " + vec3_text(m.box_max) +
                             ": the box must lie within ±10000 m with box_max at least 1 mm "
                             "above box_min on every axis");
    if (!(m.extent_m[a] >= kMinSideM && m.extent_m[a] <= 2 * kMaxAbsCoordinate))
      format_error(name, "extent_m " + vec3_text(m.extent_m) +
                             " must be within [0.001, 20000] m on every axis");
  }
  if (!(std::fabs(m.position_max_freq_exp) <= 30.0))
    format_error(name, "position_max_freq_exp must be finite, within [-30, 30]");
  if (!(m.leaky_slope >= 0 && m.leaky_slope <= 1))
    format_error(name, "leaky_slope is " + number_text(m.leaky_slope) +
                           ", outside [0, 1] (neraf models use 0.1)");
  if (!(m.output_scale > 0 && m.output_scale <= kMaxOutputScale))
    format_error(name, "output_scale is " + number_text(m.output_scale) +
                           ", outside (0, 30] (neraf models use 10)");
  check_metadata(m, name);

  if (m.trunk.empty() || m.trunk.size() > kMaxLayers)
    format_error(name, "the trunk must have 1 to " + std::to_string(kMaxLayers) + " layers");
  check_shapes(m.trunk, "trunk", name);
  if (m.trunk[0].in != m.input_dim())
    format_error(name, "trunk[0] takes " + std::to_string(m.trunk[0].in) +
                           " inputs, the canonical input has " + std::to_string(m.input_dim()) +
                           (m.relative_geometry ? " (with relative geometry)" : ""));
  for (size_t i = 0; i + 1 < m.trunk.size(); ++i)
    if (m.trunk[i].out != m.trunk[i + 1].in)
      format_error(name, layer_name("trunk", i) + " gives " + std::to_string(m.trunk[i].out) +
                             " values, " + layer_name("trunk", i + 1) + " takes " +
                             std::to_string(m.trunk[i + 1].in));
  if (m.heads.size() != size_t(m.channels))
    format_error(name, std::to_string(m.heads.size()) + " heads for " + std::to_string(m.channels) +
                           " channels");
  check_shapes(m.heads, "heads", name);
  for (size_t c = 0; c < m.heads.size(); ++c)
    if (m.heads[c].in != m.trunk.back().out || m.heads[c].out != m.n_freq)
      format_error(name, layer_name("heads", c) + " is [" + std::to_string(m.heads[c].out) + ", " +
                             std::to_string(m.heads[c].in) + "], expected [" +
                             std::to_string(m.n_freq) + ", " + std::to_string(m.trunk.back().out) +
                             "]");
}

}  // namespace

// ---- public ---------------------------------------------------------------------------------

uint64_t fnv1a64(const uint8_t* data, size_t size) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (size_t i = 0; i < size; ++i) {
    h ^= data[i];
    h *= 0x100000001b3ull;
  }
  return h;
}

void check_model_data(const ModelData& m, const std::string& name) {
  check_config(m, name);
  check_arrays(m.trunk, "trunk", name);
  check_arrays(m.heads, "heads", name);
  const size_t cft = size_t(m.channels) * m.n_freq * m.max_len;
  if (!m.calibration.empty()) {
    if (m.calibration.size() != cft)
      format_error(name, "the calibration has " + std::to_string(m.calibration.size()) +
                             " gains, [C, F, T] needs " + std::to_string(cft));
    for (float g : m.calibration)
      if (!(g >= 0.0f && std::isfinite(g)))
        format_error(name, "the calibration holds a negative, NaN or infinite gain");
  }
}

std::vector<uint8_t> serialize_model(const ModelData& m, const std::string& name) {
  check_model_data(m, name);  // (the metadata's JSON too)
  std::string header;
  try {
    header = header_json(m).dump(-1, ' ', false, json::error_handler_t::strict);
  } catch (const json::exception&) {
    format_error(name, "neraf_version or metadata_json is not valid UTF-8");
  }

  std::vector<uint8_t> payload;
  put_u64(payload, header.size());
  payload.insert(payload.end(), header.begin(), header.end());
  auto put_layers = [&](const std::vector<DenseLayer>& layers, const char* group) {
    for (size_t i = 0; i < layers.size(); ++i) {
      if (m.bf16_storage)
        put_bf16(payload, layers[i].weight, name, layer_name(group, i) + ".weight");
      else
        put_floats(payload, layers[i].weight);
      put_floats(payload, layers[i].bias);
    }
  };
  put_layers(m.trunk, "trunk");
  put_layers(m.heads, "heads");
  put_floats(payload, m.calibration);

  std::vector<uint8_t> out(kMagic, kMagic + 8);
  out.reserve(payload.size() + kFileOverhead);
  put_u32(out, format_version_of(m));
  put_u32(out, m.bf16_storage ? kModelFlagBf16 : 0u);
  put_u64(out, payload.size());
  out.insert(out.end(), payload.begin(), payload.end());
  put_u64(out, fnv1a64(payload.data(), payload.size()));
  return out;
}

void write_model_file(const std::string& path, const ModelData& m) {
  const std::vector<uint8_t> bytes = serialize_model(m, path);
  std::string tmp = path + ".tmp-XXXXXX";
  const int fd = ::mkstemp(tmp.data());
  if (fd < 0)
    throw std::runtime_error(path + ": cannot create a temporary file next to it (" +
                             std::strerror(errno) + ")");
  try {
    write_all(fd, bytes.data(), bytes.size());
    if (::fchmod(fd, 0644) != 0 || ::fsync(fd) != 0)
      throw std::system_error(errno, std::generic_category());
    if (::close(fd) != 0) {
      ::unlink(tmp.c_str());
      throw std::runtime_error(path + ": cannot write (" + std::strerror(errno) + ")");
    }
  } catch (const std::system_error& e) {
    ::close(fd);
    ::unlink(tmp.c_str());
    throw std::runtime_error(path + ": cannot write (" + std::strerror(e.code().value()) + ")");
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    throw std::runtime_error(path + ": cannot write (" + std::strerror(err) + ")");
  }
  // The rename is durable only once the folder's entry is on disk.
  const size_t slash = path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "." : path.substr(0, slash + 1);
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    ::fsync(dfd);  // best effort: some file systems refuse fsync on folders
    ::close(dfd);
  }
}

ModelData parse_model(const uint8_t* data, size_t size, const std::string& name) {
  if (size == 0) format_error(name, "empty file, not a neraf model");
  if (std::memcmp(data, kMagic, std::min<size_t>(size, 8)) != 0)
    format_error(name, "not a neraf model (no NERAFMDL signature)");
  if (size < kPrefixSize)
    format_error(name, "truncated (" + std::to_string(size) + " bytes, less than the " +
                           std::to_string(kPrefixSize) + "-byte prefix)");
  const uint32_t version = get_u32(data + 8);
  const uint32_t flags = get_u32(data + 12);
  const uint64_t payload_size = get_u64(data + 16);
  if (version == 0) format_error(name, "invalid format version 0");
  if (version > kModelFormatVersion)
    throw ModelFileError(NERAF_ERR_VERSION, name + ": written by a newer neraf (format " +
                                                std::to_string(version) + ", this reads up to " +
                                                std::to_string(kModelFormatVersion) +
                                                "); update neraf");
  if (flags & ~kModelFlagBf16) format_error(name, "unknown flags " + std::to_string(flags));
  if (size < kFileOverhead || payload_size > size - kFileOverhead)
    format_error(name,
                 "truncated (" + std::to_string(size) + " bytes, the header declares " +
                     (payload_size > kMaxFileSize ? std::string("more than 16 GiB")
                                                  : std::to_string(payload_size + kFileOverhead)) +
                     ")");
  if (payload_size < size - kFileOverhead)
    format_error(name, std::to_string(size - kFileOverhead - payload_size) +
                           " unexpected bytes after the model");
  const uint8_t* payload = data + kPrefixSize;
  if (fnv1a64(payload, payload_size) != get_u64(payload + payload_size))
    format_error(name, "checksum mismatch: the file is corrupt");

  // Past the checksum the bytes are what a writer wrote; the checks below still trust nothing.
  if (payload_size < 8) format_error(name, "payload too short for its header size");
  const uint64_t header_size = get_u64(payload);
  if (header_size > payload_size - 8 || header_size > kMaxHeaderSize)
    format_error(name, "header size " + std::to_string(header_size) + " exceeds the payload");
  const char* text = reinterpret_cast<const char*>(payload + 8);
  if (!json_depth_ok(text, header_size, kMaxJsonDepth))
    format_error(name, "header: JSON nested too deeply");
  std::string duplicate;
  const json j = parse_strict(text, header_size, duplicate);
  if (j.is_discarded() || !j.is_object()) format_error(name, "header is not a JSON object");
  if (!duplicate.empty())
    format_error(name,
                 "header: the key " + json_text_for_message(json(duplicate)) + " is given twice");
  const Header h(j, name);

  ModelData m;
  m.neraf_version = h.string("neraf_version");
  m.layout = int(h.integer("layout", 0, 1));
  m.sample_rate = int(h.integer("sample_rate", kMinSampleRate, kMaxSampleRate));
  m.channels = int(h.integer("channels", 1, 16));
  m.n_fft = int(h.integer("n_fft", 2, 1 << 16));
  m.win_length = int(h.integer("win_length", 1, 1 << 16));
  m.hop_length = int(h.integer("hop_length", 1, 1 << 16));
  m.n_freq = int(h.integer("n_freq", 2, (1 << 15) + 1));
  m.max_len = int(h.integer("max_len", 2, 1 << 16));
  if (version >= 2 && j.contains("time_frames"))
    m.time_frames = int(h.integer("time_frames", 2, 1 << 16));
  m.waveform_length = h.integer("waveform_length", 0, int64_t(1) << 26);
  m.box_min = h.vec3("box_min");
  m.box_max = h.vec3("box_max");
  m.relative_geometry = h.boolean("relative_geometry");
  m.position_max_freq_exp = h.number("position_max_freq_exp");
  m.extent_m = h.vec3("extent_m");
  m.leaky_slope = h.number("leaky_slope");
  m.output_scale = h.number("output_scale");
  m.trunk = h.layers("trunk");
  m.heads = h.layers("heads");
  const std::vector<int64_t> cal = h.int_list("calibration", 3);
  const std::string dtype = h.string("weight_dtype");
  m.metadata_json = h.string("metadata");
  if (dtype != "float32" && dtype != "bfloat16")
    format_error(name, "header: weight_dtype '" + dtype.substr(0, 40) + "' is unknown");
  m.bf16_storage = dtype == "bfloat16";
  if (m.bf16_storage != bool(flags & kModelFlagBf16))
    format_error(name, "header: weight_dtype disagrees with the file's flags");
  if (!cal.empty() &&
      (cal.size() != 3 || cal[0] != m.channels || cal[1] != m.n_freq || cal[2] != m.max_len))
    format_error(name, "header: the calibration shape is not [channels, n_freq, max_len]");

  check_config(m, name);  // shapes first: no array is read (or allocated) for a bad header
  ArrayReader r(payload + 8 + header_size, payload_size - 8 - header_size, name);
  auto read_layers = [&](std::vector<DenseLayer>& layers, const char* group) {
    for (size_t i = 0; i < layers.size(); ++i) {
      DenseLayer& l = layers[i];
      const std::string what = layer_name(group, i);
      l.weight = r.floats(uint64_t(l.out) * uint64_t(l.in), m.bf16_storage, what + ".weight");
      l.bias = r.floats(uint64_t(l.out), false, what + ".bias");
    }
  };
  read_layers(m.trunk, "trunk");
  read_layers(m.heads, "heads");
  if (!cal.empty())
    m.calibration = r.floats(uint64_t(m.channels) * m.n_freq * m.max_len, false, "calibration");
  if (r.left() != 0)
    format_error(name, std::to_string(r.left()) + " unexpected bytes after the arrays");
  check_model_data(m, name);
  return m;
}

ModelData read_model_file(const std::string& path) {
  // O_NONBLOCK: opening a FIFO would otherwise wait for a writer for ever (fstat refuses it next).
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0)
    throw ModelFileError(NERAF_ERR_IO, path + ": cannot open (" + std::strerror(errno) + ")");
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0)
    throw ModelFileError(NERAF_ERR_IO, path + ": cannot read (" + std::strerror(errno) + ")");
  if (S_ISDIR(st.st_mode))
    throw ModelFileError(NERAF_ERR_IO, path + ": is a folder, not a model file");
  if (!S_ISREG(st.st_mode)) throw ModelFileError(NERAF_ERR_IO, path + ": not a regular file");
  if (uint64_t(st.st_size) > kMaxFileSize)
    format_error(path, "too large to be a neraf model (" + std::to_string(st.st_size) + " bytes)");
  std::vector<uint8_t> bytes(size_t(st.st_size));
  size_t got = 0;
  while (got < bytes.size()) {
    const ssize_t n = ::read(fd, bytes.data() + got, bytes.size() - got);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0)
      throw ModelFileError(NERAF_ERR_IO, path + ": cannot read (" + std::strerror(errno) + ")");
    if (n == 0) break;  // the file shrank meanwhile: parse what is there (reports "truncated")
    got += size_t(n);
  }
  return parse_model(bytes.data(), got, path);
}

}  // namespace neraf::rt
