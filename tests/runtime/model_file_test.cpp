#include "neraf/runtime/model_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "random_model.h"

namespace fs = std::filesystem;
using neraf::rt::ModelData;
using neraf::rt::ModelFileError;
using neraf::rt::parse_model;
using neraf::rt::serialize_model;
using neraf::rt::testing::random_model;
using neraf::rt::testing::RandomModelOptions;

namespace {

// A fresh folder per test, removed afterwards.
class TempDir {
 public:
  TempDir() {
    std::string t = (fs::temp_directory_path() / "neraf_rt_test_XXXXXX").string();
    path_ = ::mkdtemp(t.data());
  }
  ~TempDir() { fs::remove_all(path_); }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  fs::path path_;
};

void expect_same_layers(const std::vector<neraf::rt::DenseLayer>& a,
                        const std::vector<neraf::rt::DenseLayer>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].in, b[i].in);
    EXPECT_EQ(a[i].out, b[i].out);
    EXPECT_EQ(a[i].weight, b[i].weight);
    EXPECT_EQ(a[i].bias, b[i].bias);
  }
}

void expect_same(const ModelData& a, const ModelData& b) {
  EXPECT_EQ(a.neraf_version, b.neraf_version);
  EXPECT_EQ(a.layout, b.layout);
  EXPECT_EQ(a.sample_rate, b.sample_rate);
  EXPECT_EQ(a.channels, b.channels);
  EXPECT_EQ(a.n_fft, b.n_fft);
  EXPECT_EQ(a.win_length, b.win_length);
  EXPECT_EQ(a.hop_length, b.hop_length);
  EXPECT_EQ(a.n_freq, b.n_freq);
  EXPECT_EQ(a.max_len, b.max_len);
  EXPECT_EQ(a.time_frames, b.time_frames);
  EXPECT_EQ(a.waveform_length, b.waveform_length);
  EXPECT_EQ(a.box_min, b.box_min);
  EXPECT_EQ(a.box_max, b.box_max);
  EXPECT_EQ(a.relative_geometry, b.relative_geometry);
  EXPECT_EQ(a.position_max_freq_exp, b.position_max_freq_exp);
  EXPECT_EQ(a.extent_m, b.extent_m);
  EXPECT_EQ(a.leaky_slope, b.leaky_slope);
  EXPECT_EQ(a.output_scale, b.output_scale);
  expect_same_layers(a.trunk, b.trunk);
  expect_same_layers(a.heads, b.heads);
  EXPECT_EQ(a.calibration, b.calibration);
  EXPECT_EQ(a.bf16_storage, b.bf16_storage);
  EXPECT_EQ(a.metadata_json, b.metadata_json);
}

// Runs parse_model and returns the error (status NERAF_OK when it parsed).
ModelFileError parse_error(const std::vector<uint8_t>& bytes, const std::string& name = "m.nrf") {
  try {
    parse_model(bytes.data(), bytes.size(), name);
  } catch (const ModelFileError& e) {
    return e;
  }
  return ModelFileError(NERAF_OK, "");
}

// The file's parts, to rebuild it with an edited header and a valid checksum.
struct Parts {
  std::string header;
  std::vector<uint8_t> arrays;
  uint32_t version, flags;
};

uint64_t le64(const uint8_t* p) {
  uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}
void put64(std::vector<uint8_t>& out, uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(uint8_t(v >> (8 * i)));
}
void put32(std::vector<uint8_t>& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(uint8_t(v >> (8 * i)));
}

Parts split(const std::vector<uint8_t>& file) {
  Parts p;
  std::memcpy(&p.version, file.data() + 8, 4);
  std::memcpy(&p.flags, file.data() + 12, 4);
  const uint64_t header = le64(file.data() + 24);
  p.header.assign(reinterpret_cast<const char*>(file.data()) + 32, header);
  p.arrays.assign(file.begin() + 32 + header, file.end() - 8);
  return p;
}

std::vector<uint8_t> join(const Parts& p) {
  std::vector<uint8_t> payload;
  put64(payload, p.header.size());
  payload.insert(payload.end(), p.header.begin(), p.header.end());
  payload.insert(payload.end(), p.arrays.begin(), p.arrays.end());
  std::vector<uint8_t> out = {'N', 'E', 'R', 'A', 'F', 'M', 'D', 'L'};
  put32(out, p.version);
  put32(out, p.flags);
  put64(out, payload.size());
  out.insert(out.end(), payload.begin(), payload.end());
  put64(out, neraf::rt::fnv1a64(payload.data(), payload.size()));
  return out;
}

std::string replaced(std::string s, const std::string& from, const std::string& to) {
  const size_t at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) s.replace(at, from.size(), to);
  return s;
}

RandomModelOptions tiny() {
  RandomModelOptions o;
  o.channels = 1;
  o.n_fft = 16;
  o.win_length = 16;
  o.hop_length = 4;
  o.max_len = 4;
  o.trunk = {8};
  return o;
}

}  // namespace

TEST(ModelFile, RoundTripFloat32) {
  TempDir dir;
  RandomModelOptions o;
  o.relative_geometry = true;
  o.waveform_length = 1234;
  const ModelData m = random_model(o);
  const std::string path = dir.file("room.nrf");
  neraf::rt::write_model_file(path, m);
  expect_same(neraf::rt::read_model_file(path), m);
  // Nothing else left in the folder (the temporary file was renamed).
  EXPECT_EQ(
      std::distance(fs::directory_iterator(fs::path(path).parent_path()), fs::directory_iterator{}),
      1);
}

TEST(ModelFile, RoundTripBfloat16StoresRoundedWeights) {
  TempDir dir;
  RandomModelOptions o;
  o.bf16 = true;
  const ModelData m = random_model(o);
  const std::string path = dir.file("room.nrf");
  neraf::rt::write_model_file(path, m);
  ModelData expected = m;
  for (auto* group : {&expected.trunk, &expected.heads})
    for (auto& l : *group)
      for (float& w : l.weight) w = neraf::rt::bf16_to_float(neraf::rt::float_to_bf16(w));
  const ModelData r = neraf::rt::read_model_file(path);
  expect_same(r, expected);
  EXPECT_TRUE(r.bf16_storage);
  // Weights take half the bytes (biases and calibration stay float32); the header's
  // "bfloat16" is one byte longer than "float32".
  o.bf16 = false;
  neraf::rt::write_model_file(dir.file("f32.nrf"), random_model(o));
  size_t weights = 0;
  for (const auto* group : {&m.trunk, &m.heads})
    for (const auto& l : *group) weights += l.weight.size();
  EXPECT_EQ(fs::file_size(dir.file("f32.nrf")) - fs::file_size(path), 2 * weights - 1);
}

TEST(ModelFile, Bfloat16RoundsToNearestEven) {
  using neraf::rt::bf16_to_float;
  using neraf::rt::float_to_bf16;
  EXPECT_EQ(bf16_to_float(float_to_bf16(1.0f)), 1.0f);
  // 1 + 2^-8 lies halfway between 1 and 1 + 2^-7: ties go to the even mantissa (1).
  EXPECT_EQ(bf16_to_float(float_to_bf16(1.0f + 0x1p-8f)), 1.0f);
  // 1 + 3·2^-8 is halfway between 1 + 2^-7 (odd) and 1 + 2^-6 (even).
  EXPECT_EQ(bf16_to_float(float_to_bf16(1.0f + 3 * 0x1p-8f)), 1.0f + 0x1p-6f);
  EXPECT_EQ(bf16_to_float(float_to_bf16(1.0f + 0x1p-8f + 0x1p-20f)), 1.0f + 0x1p-7f);
  EXPECT_EQ(bf16_to_float(float_to_bf16(-2.5f)), -2.5f);
}

TEST(ModelFile, WriteFailsWithAMessageNamingTheFile) {
  TempDir dir;
  const std::string path = dir.file("no/such/folder/room.nrf");
  try {
    neraf::rt::write_model_file(path, random_model());
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST(ModelFile, WriteReplacesAnExistingFile) {
  TempDir dir;
  const std::string path = dir.file("room.nrf");
  std::ofstream(path) << "old";
  RandomModelOptions o;
  o.seed = 7;
  neraf::rt::write_model_file(path, random_model(o));
  expect_same(neraf::rt::read_model_file(path), random_model(o));
}

TEST(ModelFile, WriterRejectsInvalidModels) {
  auto rejects = [](const ModelData& m, const char* needle) {
    try {
      serialize_model(m, "bad.nrf");
      ADD_FAILURE() << "accepted; expected: " << needle;
    } catch (const ModelFileError& e) {
      EXPECT_EQ(e.status(), NERAF_ERR_FORMAT);
      EXPECT_NE(std::string(e.what()).find("bad.nrf: "), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  ModelData m = random_model();
  m.trunk[0].in = 100;
  rejects(m, "trunk[0]");
  m = random_model();
  m.trunk[1].in = 23;
  rejects(m, "trunk[1]");
  m = random_model();
  m.heads.pop_back();
  rejects(m, "heads");
  m = random_model();
  m.calibration.pop_back();
  rejects(m, "calibration");
  m = random_model();
  m.trunk[0].weight[5] = std::nanf("");
  rejects(m, "NaN");
  m = random_model();
  m.n_freq = 30;
  rejects(m, "n_freq");
  m = random_model();
  m.hop_length = m.win_length;
  rejects(m, "gaps");
  m = random_model();
  m.box_max[1] = m.box_min[1];
  rejects(m, "box");
  m = random_model();
  m.metadata_json = "{not json";
  rejects(m, "'metadata' is not valid JSON");
  m = random_model();
  m.neraf_version = std::string(40, 'x');
  rejects(m, "neraf_version");
  m = random_model();
  m.bf16_storage = true;
  m.heads[0].weight[0] = 3.4e38f;  // rounds to infinity in bfloat16
  rejects(m, "bfloat16");
}

// Found while writing fuzz/fuzz_c_api: with waveform_length 0 the RIR length hop·(T − 1) had no
// bound of its own (up to 65535·65535), so a 263 KB file made neraf_model_load allocate ~31 GB of
// Griffin-Lim buffers, and neraf_model_info.rir_length (an int) would have overflowed.
TEST(ModelFile, ImplicitRirLengthIsBoundedLikeAnExplicitOne) {
  RandomModelOptions o;
  o.channels = 1;
  o.n_fft = o.win_length = 65536;
  o.hop_length = 60000;
  o.max_len = 65536;  // 60000 · 65535 ≈ 3.9e9 samples
  o.trunk = {1};
  o.calibration = false;
  const ModelData m = random_model(o);
  try {
    serialize_model(m, "long.nrf");
    ADD_FAILURE() << "accepted a RIR of " << m.rir_length() << " samples";
  } catch (const ModelFileError& e) {
    EXPECT_EQ(e.status(), NERAF_ERR_FORMAT);
    EXPECT_NE(std::string(e.what()).find("RIR length"), std::string::npos) << e.what();
  }
  o.max_len = (1 << 26) / 60000 + 1;  // the largest T within the bound is still a model
  EXPECT_NO_THROW(serialize_model(random_model(o), "long.nrf"));
}

TEST(ModelFile, ReadErrorsNameTheFile) {
  TempDir dir;
  auto status_of = [](const std::string& path, std::string* message) {
    try {
      neraf::rt::read_model_file(path);
    } catch (const ModelFileError& e) {
      *message = e.what();
      return e.status();
    }
    return NERAF_OK;
  };
  std::string msg;
  const std::string missing = dir.file("missing.nrf");
  EXPECT_EQ(status_of(missing, &msg), NERAF_ERR_IO);
  EXPECT_EQ(msg.rfind(missing + ": cannot open", 0), 0u) << msg;
  EXPECT_EQ(status_of(dir.file(""), &msg), NERAF_ERR_IO);
  EXPECT_NE(msg.find("folder"), std::string::npos) << msg;
  const std::string empty = dir.file("empty.nrf");
  std::ofstream(empty).close();
  EXPECT_EQ(status_of(empty, &msg), NERAF_ERR_FORMAT);
  EXPECT_EQ(msg.rfind(empty + ": ", 0), 0u) << msg;
  const std::string text = dir.file("notes.txt");
  std::ofstream(text) << "RIFF....WAVEfmt  hello, this is not a model at all";
  EXPECT_EQ(status_of(text, &msg), NERAF_ERR_FORMAT);
  EXPECT_EQ(msg, text + ": not a neraf model (no NERAFMDL signature)");
}

TEST(ModelFile, NewerVersionAsksForAnUpdate) {
  std::vector<uint8_t> bytes = serialize_model(random_model(tiny()));
  bytes[8] = 3;
  const ModelFileError e = parse_error(bytes, "future.nrf");
  EXPECT_EQ(e.status(), NERAF_ERR_VERSION);
  EXPECT_STREQ(e.what(),
               "future.nrf: written by a newer neraf (format 3, this reads up to 2); update neraf");
}

// Format 2 only where a reader of format 1 would go wrong: a time encoding spanning more frames
// than the file predicts (a multi-scene run's shorter scene).
TEST(ModelFile, TimeFramesNeedFormat2) {
  RandomModelOptions o = tiny();
  const std::vector<uint8_t> plain = serialize_model(random_model(o));
  EXPECT_EQ(plain[8], 1);
  o.time_frames = o.max_len;  // the same as none
  EXPECT_EQ(serialize_model(random_model(o))[8], 1);
  o.time_frames = o.max_len + 5;
  const ModelData m = random_model(o);
  const std::vector<uint8_t> bytes = serialize_model(m);
  EXPECT_EQ(bytes[8], 2);
  expect_same(parse_model(bytes.data(), bytes.size(), "scene.nrf"), m);
  o.time_frames = o.max_len - 1;  // fewer frames than predicted: refused by the writer
  EXPECT_THROW(serialize_model(random_model(o)), ModelFileError);
}

TEST(ModelFile, EveryTruncationIsRejected) {
  const std::vector<uint8_t> bytes = serialize_model(random_model(tiny()));
  for (size_t n = 0; n < bytes.size(); ++n) {
    const std::vector<uint8_t> cut(bytes.begin(), bytes.begin() + n);
    const ModelFileError e = parse_error(cut, "cut.nrf");
    ASSERT_EQ(e.status(), NERAF_ERR_FORMAT) << n << " bytes";
    const std::string msg = e.what();
    ASSERT_EQ(msg.rfind("cut.nrf: ", 0), 0u) << msg;
    ASSERT_TRUE(msg.find("truncated") != std::string::npos ||
                msg.find("empty") != std::string::npos)
        << n << " bytes: " << msg;
  }
  // One byte too many is not a model either.
  std::vector<uint8_t> longer = bytes;
  longer.push_back(0);
  EXPECT_EQ(parse_error(longer).status(), NERAF_ERR_FORMAT);
}

TEST(ModelFile, EveryFlippedByteIsRejected) {
  const std::vector<uint8_t> bytes = serialize_model(random_model(tiny()));
  for (size_t i = 0; i < bytes.size(); ++i) {
    std::vector<uint8_t> bad = bytes;
    bad[i] ^= 0x10;
    const ModelFileError e = parse_error(bad, "flip.nrf");
    ASSERT_TRUE(e.status() == NERAF_ERR_FORMAT || e.status() == NERAF_ERR_VERSION)
        << "byte " << i << ": " << e.what();
    ASSERT_EQ(std::string(e.what()).rfind("flip.nrf: ", 0), 0u) << e.what();
    if (i >= 24 && i < bytes.size()) {  // payload and checksum bytes
      ASSERT_NE(std::string(e.what()).find("checksum"), std::string::npos) << i << e.what();
    }
  }
}

TEST(ModelFile, BadShapesBehindAValidChecksumAreRejected) {
  const std::vector<uint8_t> bytes = serialize_model(random_model());
  const Parts p = split(bytes);
  ASSERT_EQ(join(p), bytes);  // the test's own writer agrees with write_model_file
  auto error_with_header = [&](const std::string& header) {
    Parts q = p;
    q.header = header;
    return parse_error(join(q), "edit.nrf");
  };
  auto expect = [&](const ModelFileError& e, const char* needle) {
    EXPECT_EQ(e.status(), NERAF_ERR_FORMAT);
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind("edit.nrf: ", 0), 0u) << e.what();
  };
  // A layer far larger than the payload: rejected before allocating it.
  expect(
      error_with_header(replaced(p.header, "[[24,163],[16,24]]", "[[1000000,163],[16,1000000]]")),
      "the payload ends inside trunk[0].weight");
  expect(error_with_header(replaced(p.header, "[24,163]", "[24,162]")), "trunk[0]");
  expect(error_with_header(replaced(p.header, "\"channels\":2", "\"channels\":3")), "calibration");
  expect(error_with_header(replaced(p.header, "\"channels\":2", "\"channels\":-2")), "channels");
  expect(error_with_header(replaced(p.header, "\"n_fft\":64", "\"n_fft\":64.5")), "n_fft");
  expect(error_with_header(replaced(p.header, "\"trunk\":", "\"trunkk\":")), "'trunk' is missing");
  expect(error_with_header(replaced(p.header, "\"float32\"", "\"float16\"")), "weight_dtype");
  expect(error_with_header(replaced(p.header, "\"float32\"", "\"bfloat16\"")), "flags");
  expect(error_with_header("[1,2,3]"), "not a JSON object");
  expect(error_with_header("{\"a\":" + std::string(100, '[') + std::string(100, ']') + "}"),
         "nested too deeply");
  expect(error_with_header(p.header.substr(0, p.header.size() - 1)), "not a JSON object");
  // Arrays: one float short, one float extra.
  Parts q = p;
  q.arrays.resize(q.arrays.size() - 4);
  expect(parse_error(join(q), "edit.nrf"), "the payload ends inside calibration");
  q = p;
  q.arrays.resize(q.arrays.size() + 4);
  expect(parse_error(join(q), "edit.nrf"), "unexpected bytes after the arrays");
  // A NaN weight.
  q = p;
  const float nan = std::nanf("");
  std::memcpy(q.arrays.data() + 8, &nan, 4);
  expect(parse_error(join(q), "edit.nrf"), "NaN");
  q = p;
  q.flags = 4;
  expect(parse_error(join(q), "edit.nrf"), "unknown flags");
}

// Probe round d, G08: a header edited behind a recomputed checksum was accepted with absurd values
// (RIRs at +71 dBFS, a WAV at 1 Hz, a two-channel raf field, a key given twice, metadata that is
// not JSON or disagrees with the header). Each is refused, naming the field.
TEST(ModelFile, ImplausibleHeaderValuesAreRejected) {
  ModelData m = random_model();
  m.metadata_json =
      R"({"step":2,"data":{"audio":{"layout":"soundspaces","sample_rate":22050,"channels":2,)"
      R"("n_fft":64,"win_length":64,"hop_length":16,"n_freq":33,"max_len":12,)"
      R"("waveform_length":0,"aabb_min":[-1.0,0.0,-2.0],"aabb_max":[3.0,2.5,1.5]}}})";
  const std::vector<uint8_t> bytes = serialize_model(m);
  ASSERT_NO_THROW(parse_model(bytes.data(), bytes.size(), "edit.nrf"));
  const Parts p = split(bytes);
  auto expect_refused = [&](const std::string& from, const std::string& to, const char* needle) {
    Parts q = p;
    q.header = replaced(p.header, from, to);
    const ModelFileError e = parse_error(join(q), "edit.nrf");
    EXPECT_EQ(e.status(), NERAF_ERR_FORMAT);
    EXPECT_EQ(std::string(e.what()).rfind("edit.nrf: ", 0), 0u) << e.what();
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << to << ": " << e.what();
  };
  expect_refused("\"output_scale\":10.0", "\"output_scale\":1e308",
                 "output_scale is 1e+308, outside (0, 30]");
  expect_refused("\"leaky_slope\":0.1", "\"leaky_slope\":1e308",
                 "leaky_slope is 1e+308, outside [0, 1]");
  expect_refused("\"leaky_slope\":0.1", "\"leaky_slope\":-0.5", "leaky_slope");
  expect_refused("\"extent_m\":[4.0,2.5,3.5]", "\"extent_m\":[4.0,1e-320,3.5]", "extent_m");
  expect_refused("\"box_max\":[3.0,2.5,1.5]", "\"box_max\":[3.0,1e308,1.5]", "box_max");
  expect_refused("\"box_min\":[-1.0,0.0,-2.0]", "\"box_min\":[-1.0,2.4999999,-2.0]",
                 "at least 1 mm");
  expect_refused("\"sample_rate\":22050", "\"sample_rate\":1",
                 "'sample_rate' is 1, outside [8000, 384000]");
  expect_refused("\"channels\":2", "\"channels\":2,\"channels\":2",
                 "the key \"channels\" is given twice");
  expect_refused("\"waveform_length\":0,", "\"waveform_length\":100,",
                 "metadata data.audio.waveform_length 0 disagrees with the header's 100");
  // The header and its metadata edited alike still make the old eval/render disagreement
  // impossible; one of them alone is refused.
  const std::string meta_rate = R"(\"sample_rate\":22050)";
  expect_refused(meta_rate, R"(\"sample_rate\":48000)",
                 "metadata data.audio.sample_rate 48000 disagrees with the header's 22050");
  expect_refused("\"metadata\":\"", "\"metadata\":\"{{{\",\"x\":\"",
                 "'metadata' is not valid JSON");

  // A raf (mono) layout with two channels.
  ModelData two = random_model();
  two.layout = 1;
  try {
    serialize_model(two, "raf.nrf");
    ADD_FAILURE() << "a two-channel raf model was written";
  } catch (const ModelFileError& e) {
    EXPECT_NE(std::string(e.what()).find("the raf layout (layout 1) is mono"), std::string::npos)
        << e.what();
  }
  // Metadata with a key given twice, or not JSON, is refused by the writer as well.
  ModelData meta = random_model();
  meta.metadata_json = R"({"step":1,"step":2})";
  EXPECT_THROW(serialize_model(meta, "meta.nrf"), ModelFileError);
  meta.metadata_json = "{{{";
  EXPECT_THROW(serialize_model(meta, "meta.nrf"), ModelFileError);
  meta.metadata_json = std::string(40, '[') + std::string(40, ']');
  EXPECT_THROW(serialize_model(meta, "meta.nrf"), ModelFileError);
  meta.metadata_json = "";  // no metadata at all is fine
  EXPECT_NO_THROW(serialize_model(meta, "meta.nrf"));
}

// Random edits of the header and arrays behind a valid checksum: every outcome is a parsed model
// or a ModelFileError, never a crash (a small in-test fuzzer; run under ASan/UBSan to see more).
TEST(ModelFile, RandomEditsNeverCrash) {
  const std::vector<uint8_t> bytes = serialize_model(random_model(tiny()));
  const Parts p = split(bytes);
  std::mt19937 gen(3);
  const std::string alphabet = "0123456789-.,:[]{}\"eE ntrufalsx\\";
  int parsed = 0;
  for (int iter = 0; iter < 3000; ++iter) {
    Parts q = p;
    const int edits = 1 + int(gen() % 4);
    for (int k = 0; k < edits; ++k) {
      if (gen() % 4 == 0 && !q.arrays.empty()) {
        q.arrays[gen() % q.arrays.size()] = uint8_t(gen());
      } else {
        const size_t at = gen() % q.header.size();
        switch (gen() % 3) {
          case 0:
            q.header[at] = alphabet[gen() % alphabet.size()];
            break;
          case 1:
            q.header.erase(at, 1 + gen() % 8);
            break;
          default:
            q.header.insert(at, 1, alphabet[gen() % alphabet.size()]);
        }
        if (q.header.empty()) q.header = "{";
      }
    }
    const ModelFileError e = parse_error(join(q));
    if (e.status() == NERAF_OK)
      ++parsed;
    else
      ASSERT_EQ(e.status(), NERAF_ERR_FORMAT) << e.what();
  }
  EXPECT_LT(parsed, 3000);
}
