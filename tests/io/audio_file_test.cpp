#include "neraf/io/audio_file.h"

#include <gtest/gtest.h>
#include <sndfile.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "neraf/util/error.h"

namespace fs = std::filesystem;
using neraf::io::AudioBuffer;
using neraf::io::AudioFormat;

namespace {

// A fresh folder per test, removed afterwards.
class AudioFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("neraf_audio_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
};

AudioBuffer random_audio(int channels, int frames, int rate, uint32_t seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<float> u(-0.95f, 0.95f);
  AudioBuffer a;
  a.sample_rate = rate;
  a.channels.assign(channels, std::vector<float>(frames));
  for (auto& ch : a.channels) {
    for (float& v : ch) v = u(gen);
  }
  return a;
}

// Expects `fn` to throw neraf::Error whose message contains every string in `parts`.
template <typename Fn>
void expect_error(Fn fn, std::initializer_list<std::string> parts) {
  try {
    fn();
    ADD_FAILURE() << "expected neraf::Error";
  } catch (const neraf::Error& e) {
    const std::string msg = e.what();
    for (const auto& p : parts) EXPECT_NE(msg.find(p), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "one line: " << msg;
  }
}

void expect_close(const AudioBuffer& a, const AudioBuffer& b, float tol) {
  ASSERT_EQ(a.sample_rate, b.sample_rate);
  ASSERT_EQ(a.num_channels(), b.num_channels());
  ASSERT_EQ(a.num_frames(), b.num_frames());
  for (int c = 0; c < a.num_channels(); ++c) {
    for (int64_t i = 0; i < a.num_frames(); ++i) {
      ASSERT_NEAR(a.channels[c][i], b.channels[c][i], tol) << "channel " << c << " frame " << i;
    }
  }
}

int sndfile_format(const std::string& path) {
  SF_INFO info{};
  SNDFILE* f = sf_open(path.c_str(), SFM_READ, &info);
  if (!f) return 0;
  sf_close(f);
  return info.format;
}

bool has_temp_files(const fs::path& dir) {
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().filename().string().find(".tmp-") != std::string::npos) return true;
  }
  return false;
}

}  // namespace

TEST_F(AudioFileTest, WavFloatRoundTripIsExact) {
  for (int channels : {1, 2, 5}) {
    const AudioBuffer a = random_audio(channels, 1234, 48000, 10 + channels);
    const std::string p = path("float_" + std::to_string(channels) + ".wav");
    neraf::io::write_audio(p, a);
    EXPECT_EQ(sndfile_format(p), SF_FORMAT_WAV | SF_FORMAT_FLOAT) << "from extension: float WAV";
    expect_close(neraf::io::read_audio(p), a, 0.0f);
  }
}

TEST_F(AudioFileTest, SameSamplesGiveTheSameBytes) {
  // libsndfile's PEAK chunk carries a time stamp; it is switched off so datasets are reproducible.
  const AudioBuffer a = random_audio(2, 300, 44100, 3);
  neraf::io::write_audio(path("a.wav"), a);
  neraf::io::write_audio(path("b.wav"), a);
  auto bytes = [](const std::string& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const std::string x = bytes(path("a.wav"));
  EXPECT_EQ(x, bytes(path("b.wav")));
  EXPECT_EQ(x.find("PEAK"), std::string::npos);
}

TEST_F(AudioFileTest, WavPcm16RoundTripWithinOneStep) {
  for (int channels : {1, 2, 5}) {
    const AudioBuffer a = random_audio(channels, 777, 22050, 20 + channels);
    const std::string p = path("pcm16_" + std::to_string(channels) + ".wav");
    neraf::io::write_audio(p, a, AudioFormat::wav_pcm16);
    EXPECT_EQ(sndfile_format(p), SF_FORMAT_WAV | SF_FORMAT_PCM_16);
    expect_close(neraf::io::read_audio(p), a, 1.0f / 32768.0f);
  }
}

TEST_F(AudioFileTest, Flac24RoundTripWithinOneStep) {
  for (int channels : {1, 2, 5}) {
    const AudioBuffer a = random_audio(channels, 999, 44100, 30 + channels);
    const std::string p = path("x_" + std::to_string(channels) + ".flac");
    neraf::io::write_audio(p, a);  // .flac -> FLAC 24-bit
    EXPECT_EQ(sndfile_format(p), SF_FORMAT_FLAC | SF_FORMAT_PCM_24);
    expect_close(neraf::io::read_audio(p), a, 1.0f / 8388608.0f);
  }
}

TEST_F(AudioFileTest, IntegerFormatsClipInsteadOfWrapping) {
  AudioBuffer a;
  a.sample_rate = 16000;
  a.channels = {{1.5f, -2.0f, 0.25f}};
  const std::string p = path("clip.wav");
  neraf::io::write_audio(p, a, AudioFormat::wav_pcm16);
  const AudioBuffer b = neraf::io::read_audio(p);
  EXPECT_NEAR(b.channels[0][0], 1.0f, 1e-4f);
  EXPECT_NEAR(b.channels[0][1], -1.0f, 1e-4f);
  EXPECT_NEAR(b.channels[0][2], 0.25f, 1e-4f);
}

TEST_F(AudioFileTest, ReadsTheRealRecording) {
  const AudioBuffer a = neraf::io::read_audio(std::string(NERAF_ASSETS_DIR) + "/real/rir_clap.wav");
  EXPECT_EQ(a.sample_rate, 44100);
  EXPECT_EQ(a.num_channels(), 1);
  EXPECT_NEAR(a.duration_s(), 1.0, 0.01);
  float peak = 0.0f;
  for (float v : a.channels[0]) peak = std::max(peak, std::abs(v));
  EXPECT_GT(peak, 0.01f);
  EXPECT_LE(peak, 1.0f);
}

TEST_F(AudioFileTest, MissingFileIsNamed) {
  const std::string p = path("nope.wav");
  expect_error([&] { neraf::io::read_audio(p); }, {p, "no such file"});
}

TEST_F(AudioFileTest, ZeroByteFileIsNamed) {
  const std::string p = path("empty.wav");
  std::ofstream(p).close();
  expect_error([&] { neraf::io::read_audio(p); }, {p, "empty"});
}

TEST_F(AudioFileTest, ValidHeaderWithZeroFramesIsEmpty) {
  const std::string p = path("zero_frames.wav");
  SF_INFO info{};
  info.samplerate = 48000;
  info.channels = 1;
  info.format = SF_FORMAT_WAV | SF_FORMAT_PCM_16;
  SNDFILE* f = sf_open(p.c_str(), SFM_WRITE, &info);
  ASSERT_NE(f, nullptr);
  sf_close(f);
  ASSERT_GT(fs::file_size(p), 0u);
  expect_error([&] { neraf::io::read_audio(p); }, {p, "0 frames"});
}

TEST_F(AudioFileTest, TruncatedHeaderIsNotAudio) {
  const std::string good = path("good.wav");
  neraf::io::write_audio(good, random_audio(2, 1000, 48000, 1), AudioFormat::wav_pcm16);
  std::ifstream in(good, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  const std::string p = path("truncated.wav");
  std::ofstream(p, std::ios::binary) << bytes.substr(0, 20);  // inside the fmt chunk
  expect_error([&] { neraf::io::read_audio(p); }, {p, "not an audio file libsndfile can read"});
}

TEST_F(AudioFileTest, TruncatedSampleDataIsRejected) {
  // A copy interrupted halfway: valid header, half of the samples.
  for (const char* name : {"cut.wav", "cut.flac"}) {
    const std::string good = path(std::string("good_") + name);
    neraf::io::write_audio(good, random_audio(2, 4000, 48000, 9),
                           std::string(name).find(".wav") != std::string::npos
                               ? AudioFormat::wav_pcm16
                               : AudioFormat::from_extension);
    std::ifstream in(good, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    const std::string p = path(name);
    std::ofstream(p, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    expect_error([&] { neraf::io::read_audio(p); }, {p});
  }
}

namespace {

// `flac` (a file as write_audio writes it: STREAMINFO first) announcing `total` samples: the low 36
// bits of bytes 18..25 (sample rate, channels, bits per sample, total samples; big-endian).
std::string with_flac_total_samples(std::string flac, uint64_t total) {
  uint64_t v = 0;
  for (int i = 18; i < 26; ++i) v = (v << 8) | static_cast<unsigned char>(flac[i]);
  v = (v & ~((uint64_t(1) << 36) - 1)) | total;
  for (int i = 25; i >= 18; --i, v >>= 8) flac[i] = static_cast<char>(v & 0xFF);
  return flac;
}

}  // namespace

// Found by fuzz/fuzz_audio_file: libsndfile reports SF_COUNT_MAX frames for a stream of unknown
// length (a FLAC written through a pipe has total_samples 0; an Ogg file without its last page),
// and read_audio allocated that many samples (std::length_error escaped).
TEST_F(AudioFileTest, FlacOfUnknownLengthIsReadToTheEnd) {
  const std::string good = path("good.flac");
  const AudioBuffer a = random_audio(2, 3000, 22050, 4);
  neraf::io::write_audio(good, a);
  std::ifstream in(good, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), {});
  ASSERT_EQ(bytes.substr(0, 4), "fLaC");
  const std::string p = path("streamed.flac");
  std::ofstream(p, std::ios::binary) << with_flac_total_samples(bytes, 0);
  expect_close(neraf::io::read_audio(p), a, 1.0f / (1 << 22));
}

// Found by fuzz/fuzz_audio_file: a damaged header announcing 2^35 frames made read_audio allocate
// them all (128 GiB per channel) before reading; now it reads what is there and reports truncation.
TEST_F(AudioFileTest, ImplausibleFrameCountIsTruncationNotAnAllocation) {
  const std::string good = path("good.flac");
  neraf::io::write_audio(good, random_audio(2, 3000, 22050, 5));
  std::ifstream in(good, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), {});
  const std::string p = path("claims_2pow35.flac");
  std::ofstream(p, std::ios::binary) << with_flac_total_samples(bytes, uint64_t(1) << 35);
  expect_error([&] { neraf::io::read_audio(p); }, {p, "truncated"});
}

TEST_F(AudioFileTest, TextFileRenamedWavIsNotAudio) {
  const std::string p = path("notes.wav");
  std::ofstream(p) << "these are meeting notes, not a recording\n";
  expect_error([&] { neraf::io::read_audio(p); }, {p, "not an audio file libsndfile can read"});
}

TEST_F(AudioFileTest, FolderIsNotAFile) {
  expect_error([&] { neraf::io::read_audio(dir_.string()); }, {dir_.string(), "folder"});
}

TEST_F(AudioFileTest, AtomicWriteLeavesNoTemporaryFile) {
  const std::string p = path("sub/dir/out.wav");  // parent folders are created
  neraf::io::write_audio(p, random_audio(2, 100, 48000, 2));
  EXPECT_TRUE(fs::exists(p));
  EXPECT_FALSE(has_temp_files(fs::path(p).parent_path()));
  // Overwriting replaces the file whole.
  neraf::io::write_audio(p, random_audio(1, 50, 16000, 3));
  const AudioBuffer b = neraf::io::read_audio(p);
  EXPECT_EQ(b.num_channels(), 1);
  EXPECT_EQ(b.num_frames(), 50);
  EXPECT_FALSE(has_temp_files(fs::path(p).parent_path()));
}

TEST_F(AudioFileTest, RejectedWriteLeavesNothingBehind) {
  AudioBuffer a = random_audio(2, 100, 48000, 4);
  a.channels[1][7] = std::nanf("");
  const std::string p = path("nan.wav");
  expect_error([&] { neraf::io::write_audio(p, a); }, {p, "NaN"});
  EXPECT_FALSE(fs::exists(p));
  EXPECT_FALSE(has_temp_files(dir_));

  AudioBuffer ragged = random_audio(2, 100, 48000, 5);
  ragged.channels[1].resize(99);
  expect_error([&] { neraf::io::write_audio(p, ragged); }, {p, "same length"});
  AudioBuffer no_rate = random_audio(1, 10, 48000, 6);
  no_rate.sample_rate = 0;
  expect_error([&] { neraf::io::write_audio(p, no_rate); }, {p, "sample rate"});
  EXPECT_FALSE(fs::exists(p));
  EXPECT_FALSE(has_temp_files(dir_));
}

TEST_F(AudioFileTest, UnwritablePathIsNamed) {
  // A regular file where a folder is needed: nothing can be created below it.
  const std::string blocker = path("blocker");
  std::ofstream(blocker) << "x";
  const std::string p = blocker + "/out.wav";
  expect_error([&] { neraf::io::write_audio(p, random_audio(1, 10, 48000, 7)); }, {p});
  EXPECT_FALSE(has_temp_files(dir_));
}

TEST_F(AudioFileTest, FlacRejectsTooManyChannels) {
  const std::string p = path("many.flac");
  expect_error([&] { neraf::io::write_audio(p, random_audio(9, 10, 48000, 8)); }, {p, "FLAC"});
  // WAV takes them.
  neraf::io::write_audio(path("many.wav"), random_audio(9, 10, 48000, 8));
  EXPECT_EQ(neraf::io::read_audio(path("many.wav")).num_channels(), 9);
}

namespace {

// A float WAV holding exactly `samples` (mono), written through libsndfile directly: write_audio
// refuses non-finite samples.
void write_raw_float_wav(const std::string& p, const std::vector<float>& samples) {
  SF_INFO info{};
  info.samplerate = 48000;
  info.channels = 1;
  info.format = SF_FORMAT_WAV | SF_FORMAT_FLOAT;
  SNDFILE* f = sf_open(p.c_str(), SFM_WRITE, &info);
  ASSERT_NE(f, nullptr);
  sf_command(f, SFC_SET_ADD_PEAK_CHUNK, nullptr, SF_FALSE);
  ASSERT_EQ(sf_writef_float(f, samples.data(), sf_count_t(samples.size())),
            sf_count_t(samples.size()));
  sf_close(f);
}

}  // namespace

TEST_F(AudioFileTest, NonFiniteAndHugeSamplesAreRejected) {
  for (const float bad : {std::nanf(""), INFINITY, -1e30f, 1001.0f}) {
    std::vector<float> x(500, 0.1f);
    x[321] = bad;
    const std::string p = path("bad.wav");
    write_raw_float_wav(p, x);
    expect_error([&] { neraf::io::read_audio(p); }, {p, "sample 321 of channel 0", "re-export"});
  }
  // Loud but plausible (float files may exceed full scale): read as stored.
  std::vector<float> loud(500, 0.1f);
  loud[7] = 999.0f;
  write_raw_float_wav(path("loud.wav"), loud);
  EXPECT_EQ(neraf::io::read_audio(path("loud.wav")).channels[0][7], 999.0f);
}

// The example: a header promising 48,000 samples with 5 present (a copy cut short).
TEST_F(AudioFileTest, HeaderPromisingMoreSamplesThanPresentIsTruncated) {
  const std::string good = path("good.wav");
  neraf::io::write_audio(good, random_audio(1, 48000, 48000, 3));
  std::ifstream in(good, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), {});
  const size_t data = bytes.find("data");
  ASSERT_NE(data, std::string::npos);
  const std::string p = path("cut.wav");
  std::ofstream(p, std::ios::binary) << bytes.substr(0, data + 8 + 5 * 4);
  expect_error([&] { neraf::io::read_audio(p); }, {p, "truncated"});
  expect_error([&] { neraf::io::read_audio_info(p); }, {p, "truncated"});
}

// A WAV written to a pipe (`espeak-ng --stdout`, SoX) cannot seek back to fill in its sizes and
// declares 0x7FFFF000 or 0xFFFFFFFF bytes: streamed audio, read as what is there.
TEST_F(AudioFileTest, StreamedWavSizePlaceholdersAreNotTruncation) {
  const std::string good = path("good.wav");
  neraf::io::write_audio(good, random_audio(1, 300, 22050, 4));
  std::ifstream in(good, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  const size_t data = bytes.find("data");
  ASSERT_NE(data, std::string::npos);
  for (const uint32_t placeholder : {0x7FFFF000u, 0x7FFFFFFFu, 0xFFFFFFFFu}) {
    for (int b = 0; b < 4; ++b) bytes[data + 4 + b] = static_cast<char>(placeholder >> (8 * b));
    const std::string p = path("streamed.wav");
    std::ofstream(p, std::ios::binary) << bytes;
    EXPECT_EQ(neraf::io::read_audio(p).channels[0].size(), 300u) << std::hex << placeholder;
  }
}

TEST_F(AudioFileTest, InfoReadsTheHeaderOnly) {
  const std::string p = path("a.flac");
  neraf::io::write_audio(p, random_audio(2, 1234, 22050, 6));
  const neraf::io::AudioFileInfo i = neraf::io::read_audio_info(p);
  EXPECT_EQ(i.sample_rate, 22050);
  EXPECT_EQ(i.channels, 2);
  EXPECT_EQ(i.frames, 1234);
  expect_error([&] { neraf::io::read_audio_info(path("none.wav")); }, {"none.wav", "no such"});
  expect_error([&] { neraf::io::read_audio_info(dir_.string()); }, {"folder"});
}
