#pragma once
// Tiny datasets written in exactly the published on-disk layouts (SoundSpaces, RAF, nerfstudio),
// for the data tests. Everything is deterministic (fixed seeds).
#include <stb/stb_image_write.h>
#include <stdlib.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "neraf/geometry/quaternion.h"
#include "neraf/io/audio_file.h"

namespace neraf::data::testing {

namespace fs = std::filesystem;

class TempDir {
 public:
  TempDir() {
    std::string tmpl = (fs::temp_directory_path() / "neraf_data_test_XXXXXX").string();
    path_ = mkdtemp(tmpl.data());
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const std::string& path() const { return path_; }
  std::string operator/(const std::string& rel) const { return (fs::path(path_) / rel).string(); }

 private:
  std::string path_;
};

inline void write_text(const std::string& path, const std::string& text) {
  fs::create_directories(fs::path(path).parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

// An exponentially decaying noise burst: looks like an RIR, different per seed.
inline std::vector<float> decaying_noise(int64_t n, int fs, double t60_s, uint32_t seed,
                                         float peak = 0.5f) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> g(0.0f, 1.0f);
  std::vector<float> x(static_cast<size_t>(n));
  const double k = std::log(1000.0) / (t60_s * fs);  // −60 dB after t60
  for (int64_t i = 0; i < n; ++i) x[i] = peak * std::exp(-k * i) * g(rng) * 0.3f;
  if (n > 10) x[10] = peak;  // direct sound
  return x;
}

inline void write_wav(const std::string& path, int fs, const std::vector<std::vector<float>>& ch,
                      io::AudioFormat format = io::AudioFormat::wav_float) {
  fs::create_directories(fs::path(path).parent_path());
  io::AudioBuffer a;
  a.sample_rate = fs;
  a.channels = ch;
  io::write_audio(path, a, format);
}

// A RIFF/WAVE float32 file holding exactly `interleaved` ([frame][channel]) whose header announces
// `declared_frames` (0: as many as given). Unlike write_wav it writes what damaged files hold:
// NaN or huge samples, and headers promising more samples than are there.
inline void write_raw_float_wav(const std::string& path, int fs, int channels,
                                const std::vector<float>& interleaved,
                                uint32_t declared_frames = 0) {
  fs::create_directories(fs::path(path).parent_path());
  const uint32_t frames =
      declared_frames ? declared_frames : static_cast<uint32_t>(interleaved.size() / channels);
  const uint32_t data_bytes = frames * channels * 4;
  std::ofstream out(path, std::ios::binary);
  auto u32 = [&](uint32_t v) { out.write(reinterpret_cast<const char*>(&v), 4); };
  auto u16 = [&](uint16_t v) { out.write(reinterpret_cast<const char*>(&v), 2); };
  out.write("RIFF", 4);
  u32(36 + data_bytes);
  out.write("WAVEfmt ", 8);
  u32(16);
  u16(3);  // IEEE float
  u16(static_cast<uint16_t>(channels));
  u32(static_cast<uint32_t>(fs));
  u32(static_cast<uint32_t>(fs * channels * 4));
  u16(static_cast<uint16_t>(channels * 4));
  u16(32);
  out.write("data", 4);
  u32(data_bytes);
  out.write(reinterpret_cast<const char*>(interleaved.data()),
            static_cast<std::streamsize>(interleaved.size() * sizeof(float)));
}

// A RIFF/WAVE float32 file with a header and no samples (SoundSpaces ships some of these).
inline void write_empty_wav(const std::string& path, int fs, int channels) {
  write_raw_float_wav(path, fs, channels, {});
}

// numpy.save of a float32 C-order array (format 1.0).
inline void write_npy(const std::string& path, const std::vector<int64_t>& shape,
                      const std::vector<float>& data) {
  fs::create_directories(fs::path(path).parent_path());
  std::string shp = "(";
  for (size_t i = 0; i < shape.size(); ++i)
    shp += std::to_string(shape[i]) + (i + 1 < shape.size() ? ", " : "");
  if (shape.size() == 1) shp += ",";
  shp += ")";
  std::string dict = "{'descr': '<f4', 'fortran_order': False, 'shape': " + shp + ", }";
  size_t total = 10 + dict.size() + 1;
  const size_t pad = (64 - total % 64) % 64;
  dict += std::string(pad, ' ') + "\n";
  std::ofstream out(path, std::ios::binary);
  out.write("\x93NUMPY\x01\x00", 8);
  const uint16_t hl = static_cast<uint16_t>(dict.size());
  out.write(reinterpret_cast<const char*>(&hl), 2);
  out.write(dict.data(), static_cast<std::streamsize>(dict.size()));
  out.write(reinterpret_cast<const char*>(data.data()),
            static_cast<std::streamsize>(data.size() * sizeof(float)));
}

// ---------------------------------------------------------------------------------------------
// SoundSpaces scene: 4 points, 5 train + 2 test RIRs of various lengths (one shorter than the
// notebook's 4410-sample minimum, odd lengths to exercise the resampler's rounding).
struct SoundSpacesScene {
  struct Entry {
    int rot;
    int r, s;
    int64_t samples;
    bool train;
  };
  std::vector<std::array<double, 3>> points{
      {1.0, 1.5, 2.0}, {-0.5, 1.5, 0.25}, {2.5, 1.2, -1.0}, {0.0, 1.8, 3.0}};
  std::vector<Entry> entries{{0, 0, 1, 20001, true},   {90, 1, 2, 3000, true},
                             {180, 2, 3, 12345, true}, {270, 3, 0, 4410, true},
                             {0, 2, 1, 9001, true},    {90, 0, 3, 15000, false},
                             {180, 1, 0, 7777, false}};

  static std::string key(const Entry& e) {
    return std::to_string(e.rot) + "/" + std::to_string(e.r) + "_" + std::to_string(e.s);
  }
  std::string wav(const std::string& dir, const Entry& e) const {
    return dir + "/binaural_rirs/" + key(e) + ".wav";
  }
  std::vector<std::vector<float>> audio(size_t i) const {
    const auto& e = entries[i];
    return {decaying_noise(e.samples, 44100, 0.3, 100 + 2 * i),
            decaying_noise(e.samples, 44100, 0.3, 101 + 2 * i, 1.5f)};  // peaks > 1: clipped
  }

  void write(const std::string& dir, bool split_in_metadata = true) const {
    std::string pts;
    for (size_t i = 0; i < points.size(); ++i) {
      char buf[128];
      std::snprintf(buf, sizeof buf, "%zu\t%.6f\t%.6f\t%.6f\n", i, points[i][0], points[i][1],
                    points[i][2]);
      pts += buf;
    }
    write_text(dir + "/metadata/points.txt", pts);
    std::string train, test;
    for (size_t i = 0; i < entries.size(); ++i) {
      std::string& list = entries[i].train ? train : test;
      list += (list.empty() ? "\"" : ", \"") + key(entries[i]) + "\"";
      write_wav(wav(dir, entries[i]), 44100, audio(i));
    }
    write_text(dir + (split_in_metadata ? "/metadata_AudioNeRF/split.json" : "/split.json"),
               "{\"train\": [" + train + "], \"test\": [" + test + "]}");
  }
};

// ---------------------------------------------------------------------------------------------
// RAF room: ids 0..5, train [[0,1,2,3]], validation [[4]], test [[4,5]]; source yaw 30°, 90°,
// −120°, ... as quaternions about +y (real last), one composite rotation (a source leaning 5°,
// as a measured upright loudspeaker may: below the tilt that is warned about).
struct RafRoom {
  struct Entry {
    std::array<double, 3> rx, tx;
    geometry::Quaternion q;
    double expected_yaw;  // scipy as_euler('yxz')[0], degrees
  };
  std::vector<Entry> entries;

  RafRoom() {
    auto yaw = [](double deg) { return geometry::axis_angle(0, 1, 0, deg * M_PI / 180.0); };
    // Composite R = Rz(3°)·Rx(4°)·Ry(30°): extrinsic 'yxz' angles (30, 4, 3).
    const geometry::Quaternion comp =
        geometry::multiply(geometry::axis_angle(0, 0, 1, 3 * M_PI / 180),
                           geometry::multiply(geometry::axis_angle(1, 0, 0, 4 * M_PI / 180),
                                              geometry::axis_angle(0, 1, 0, 30 * M_PI / 180)));
    entries = {{{1.0, 1.2, 2.0}, {3.0, 1.5, 1.0}, yaw(30), 30},
               {{2.0, 1.0, 0.5}, {3.0, 1.5, 1.0}, yaw(90), 90},
               {{0.5, 1.6, 1.5}, {0.2, 1.4, 2.2}, yaw(-120), -120},
               {{1.5, 0.9, 2.5}, {0.2, 1.4, 2.2}, comp, 30},
               {{1.2, 1.1, 1.1}, {2.5, 1.3, 0.7}, yaw(179.4), 179.4},
               {{4.0, 1.3, 0.2}, {2.5, 1.3, 0.7}, yaw(-44.6), -44.6}};
  }
  static std::string id(size_t i) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%06zu", i);
    return buf;
  }
  std::vector<float> audio(size_t i) const {
    return decaying_noise(72000, 48000, 0.5, 500 + i, 0.01f);
  }

  void write(const std::string& dir) const {
    for (size_t i = 0; i < entries.size(); ++i) {
      const std::string f = dir + "/data/" + id(i);
      const auto& e = entries[i];
      char buf[256];
      std::snprintf(buf, sizeof buf, "%.17g,%.17g,%.17g\n", e.rx[0], e.rx[1], e.rx[2]);
      write_text(f + "/rx_pos.txt", buf);
      std::snprintf(buf, sizeof buf, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", e.q.x, e.q.y,
                    e.q.z, e.q.w, e.tx[0], e.tx[1], e.tx[2]);
      write_text(f + "/tx_pos.txt", buf);
      write_wav(f + "/rir.wav", 48000, {audio(i)});
    }
    write_text(dir + "/metadata/data-split.json",
               "{\"train\": [[0, 1, 2, 3]], \"validation\": [[4]], \"test\": [[4, 5]]}");
  }
};

// ---------------------------------------------------------------------------------------------
// nerfstudio transforms.json with PNG images. Cameras on a circle looking at the origin with +y up.
struct NerfstudioScene {
  int width = 12, height = 8;
  std::vector<std::string> names{"images/train_0000.png", "images/train_0001.png",
                                 "images/eval_0000.png", "images/train_0002.png"};
  std::string extra_top_level;  // e.g. "\"orientation_override\": \"none\","

  static uint8_t pixel(size_t frame, int x, int y, int c) {
    return static_cast<uint8_t>((frame * 40 + x * 7 + y * 13 + c * 50) % 256);
  }
  // Camera i: position on a circle of radius 2 at height 1, rotation about +y.
  static std::array<std::array<double, 4>, 3> pose(size_t i) {
    const double a = 0.7 * i;
    const double c = std::cos(a), s = std::sin(a);
    return {{{c, 0, s, 2 * s}, {0, 1, 0, 1.0}, {-s, 0, c, 2 * c}}};
  }
  void write_image(const std::string& dir, size_t i, int w, int h) const {
    std::vector<uint8_t> px(size_t(w) * h * 3);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c) px[(size_t(y) * w + x) * 3 + c] = pixel(i, x, y, c);
    const std::string path = dir + "/" + names[i];
    fs::create_directories(fs::path(path).parent_path());
    stbi_write_png(path.c_str(), w, h, 3, px.data(), w * 3);
  }
  std::string json_text() const {
    std::string frames;
    for (size_t i = 0; i < names.size(); ++i) {
      const auto p = pose(i);
      char m[512];
      std::snprintf(m, sizeof m,
                    "[[%.17g, %.17g, %.17g, %.17g], [%.17g, %.17g, %.17g, %.17g], "
                    "[%.17g, %.17g, %.17g, %.17g], [0, 0, 0, 1]]",
                    p[0][0], p[0][1], p[0][2], p[0][3], p[1][0], p[1][1], p[1][2], p[1][3], p[2][0],
                    p[2][1], p[2][2], p[2][3]);
      frames += std::string(i ? ", " : "") + "{\"file_path\": \"" + names[i] +
                "\", \"transform_matrix\": " + m + "}";
    }
    return "{\"camera_model\": \"OPENCV\", " + extra_top_level +
           " \"fl_x\": 10.0, \"fl_y\": 11.0, " +
           "\"cx\": 6.0, \"cy\": 4.0, \"w\": " + std::to_string(width) +
           ", \"h\": " + std::to_string(height) + ", \"k1\": 0.01, \"frames\": [" + frames + "]}";
  }
  void write(const std::string& dir) const {
    for (size_t i = 0; i < names.size(); ++i) write_image(dir, i, width, height);
    write_text(dir + "/transforms.json", json_text());
  }
};

}  // namespace neraf::data::testing
