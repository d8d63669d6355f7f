// RirSet loaders on tiny datasets written in the real SoundSpaces and RAF layouts: poses, headings,
// splits, features against a direct dsp computation of the reference recipe, padding, max_len,
// the feature cache (reuse, invalidation) and the training-batch gather.
#include "neraf/data/rir_set.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "fixtures.h"
#include "neraf/data/rir_layouts.h"
#include "neraf/dsp/resample.h"
#include "neraf/dsp/stft.h"
#include "neraf/util/error.h"

namespace fs = std::filesystem;

namespace neraf::data {
namespace {

using testing::RafRoom;
using testing::SoundSpacesScene;
using testing::TempDir;

RirLoadOptions quiet_rirs() {
  RirLoadOptions o;
  o.progress = false;
  return o;
}

std::vector<float> clip(std::vector<float> x) {
  for (float& v : x) v = std::min(1.0f, std::max(-1.0f, v));
  return x;
}

// The process_audio.ipynb recipe written out with dsp calls: [C, F, T] log-magnitudes (unpadded)
// and the minimum magnitude.
torch::Tensor soundspaces_reference(const std::vector<std::vector<float>>& channels,
                                    float* min_mag) {
  std::vector<torch::Tensor> out;
  *min_mag = 1e30f;
  for (const auto& ch : channels) {
    std::vector<float> x = clip(ch);
    if (x.size() < 4410) x.resize(4410, 0.0f);
    std::vector<float> y = clip(dsp::resample(x, 44100, 22050));
    y.resize(std::max<size_t>(y.size() + 256, 4410), 0.0f);
    const dsp::Spectrogram s = dsp::stft(y, dsp::StftParams::soundspaces());
    const dsp::Matrix lm = dsp::log_magnitude(s, 1e-3f);
    const dsp::Matrix m = dsp::magnitude(s);
    *min_mag = std::min(*min_mag, *std::min_element(m.data.begin(), m.data.end()));
    out.push_back(torch::from_blob(const_cast<float*>(lm.data.data()), {lm.rows, lm.cols}).clone());
  }
  return torch::stack(out);
}

// Pads/cuts [C, F, T] to max_len with log(min + 1e-3).
torch::Tensor pad_to(const torch::Tensor& x, int64_t max_len, float min_mag) {
  const int64_t t = x.size(2);
  if (t >= max_len) return x.narrow(2, 0, max_len);
  torch::Tensor pad = torch::full({x.size(0), x.size(1), max_len - t}, std::log(min_mag + 1e-3f));
  return torch::cat({x, pad}, 2);
}

void expect_close(const torch::Tensor& a, const torch::Tensor& b, double atol = 1e-5) {
  ASSERT_EQ(a.sizes(), b.sizes());
  const double diff = (a - b).abs().max().item<double>();
  EXPECT_LE(diff, atol);
}

// ---------------------------------------------------------------------------------------------

TEST(SoundSpaces, PosesHeadingsSplitsAndAabb) {
  TempDir dir;
  SoundSpacesScene scene;
  scene.write(dir.path());
  RirLoadOptions o = quiet_rirs();
  o.load_features = false;
  const RirSet set = load_rir_set(dir.path(), o);
  EXPECT_EQ(set.layout, AudioLayout::soundspaces);
  ASSERT_EQ(set.size(), 7);
  EXPECT_EQ(set.train, (std::vector<int64_t>{0, 1, 2, 3, 4}));
  EXPECT_EQ(set.test, (std::vector<int64_t>{5, 6}));
  EXPECT_EQ(set.channels, 2);
  EXPECT_EQ(set.n_freq, 257);
  EXPECT_EQ(set.sample_rate, 22050);
  for (int64_t i = 0; i < set.size(); ++i) {
    const auto& e = scene.entries[i];
    const Rir& r = set.rirs[i];
    EXPECT_EQ(r.id, SoundSpacesScene::key(e));
    EXPECT_EQ(r.wav_path, scene.wav(dir.path(), e));
    // points.txt [x, y, z] -> [x, z, -y], no height offset.
    const auto& pm = scene.points[e.r];
    const auto& ps = scene.points[e.s];
    EXPECT_DOUBLE_EQ(r.mic.x, pm[0]);
    EXPECT_DOUBLE_EQ(r.mic.y, pm[2]);
    EXPECT_DOUBLE_EQ(r.mic.z, -pm[1]);
    EXPECT_DOUBLE_EQ(r.source.x, ps[0]);
    EXPECT_DOUBLE_EQ(r.source.y, ps[2]);
    EXPECT_DOUBLE_EQ(r.source.z, -ps[1]);
    EXPECT_EQ(r.heading_deg, e.rot);
    const double a = e.rot * M_PI / 180;
    EXPECT_NEAR(r.rot[0], (std::cos(a) + 1) / 2, 1e-15);
    EXPECT_EQ(r.rot[1], 0.5);
    EXPECT_NEAR(r.rot[2], (std::sin(a) + 1) / 2, 1e-15);
    EXPECT_EQ(set.mic_positions[i][2].item<double>(), r.mic.z);
    EXPECT_EQ(set.rots[i][0].item<double>(), r.rot[0]);
  }
  // Train mics use points 0, 1, 2, 3, 2 -> all four; mapped x: 1, -0.5, 2.5, 0; y(=z): 2, 0.25,
  // -1, 3; z(=-y): -1.5, -1.5, -1.2, -1.8.
  EXPECT_NEAR(set.audio_aabb.min.x, -1.5, 1e-12);
  EXPECT_NEAR(set.audio_aabb.max.x, 3.5, 1e-12);
  EXPECT_NEAR(set.audio_aabb.min.y, -2.0, 1e-12);
  EXPECT_NEAR(set.audio_aabb.max.y, 4.0, 1e-12);
  EXPECT_NEAR(set.audio_aabb.min.z, -2.8, 1e-12);
  EXPECT_NEAR(set.audio_aabb.max.z, -0.2, 1e-12);
}

TEST(SoundSpaces, FeaturesEqualTheDirectRecipeWithPaddingAndAutoMaxLen) {
  TempDir dir;
  SoundSpacesScene scene;
  scene.write(dir.path());
  const RirSet set = load_soundspaces(dir.path(), quiet_rirs());
  // max_len = longest STFT: the 20001-sample RIR -> 10001 @ 22.05k (round half up) + 256 -> 81.
  int64_t longest = 0;
  for (const auto& e : scene.entries) longest = std::max(longest, e.samples);
  EXPECT_EQ(set.max_len, detail::soundspaces_num_frames(longest));
  EXPECT_EQ(set.max_len, 1 + (10001 + 256) / 128);
  EXPECT_EQ(set.waveform_length, set.max_len * 128);
  for (int64_t i = 0; i < set.size(); ++i) {
    float mn = 0;
    const torch::Tensor ref = soundspaces_reference(scene.audio(i), &mn);
    EXPECT_EQ(set.rirs[i].num_frames, ref.size(2));
    EXPECT_EQ(ref.size(2), detail::soundspaces_num_frames(scene.entries[i].samples));
    const torch::Tensor got = set.features(i);
    ASSERT_EQ(got.sizes(), (std::vector<int64_t>{2, 257, set.max_len}));
    expect_close(got, pad_to(ref, set.max_len, mn));
    // Frames past the RIR's end hold log(min|STFT| + 1e-3) exactly.
    if (ref.size(2) < set.max_len) {
      const torch::Tensor tail = got.narrow(2, ref.size(2), set.max_len - ref.size(2));
      EXPECT_TRUE(torch::all(tail == std::log(mn + 1e-3f)).item<bool>());
    }
  }
  // The short RIR (3000 samples) is first padded to 4410: 2205 + 256 -> padded to 4410 -> 35.
  EXPECT_EQ(set.rirs[1].num_frames, 35);
}

TEST(SoundSpaces, EvalWaveformIsClippedResampledAndCut) {
  TempDir dir;
  SoundSpacesScene scene;
  scene.write(dir.path());
  const RirSet set = load_soundspaces(dir.path(), quiet_rirs());
  for (const int64_t i : {int64_t(0), int64_t(1)}) {
    const torch::Tensor w = set.waveform(i);
    ASSERT_EQ(w.sizes(), (std::vector<int64_t>{2, set.max_len * 128}));
    const auto audio = scene.audio(i);
    for (int c = 0; c < 2; ++c) {
      std::vector<float> y = dsp::resample(clip(audio[c]), 44100, 22050);
      y.resize(set.max_len * 128, 0.0f);
      const torch::Tensor want = torch::from_blob(y.data(), {int64_t(y.size())}).clone();
      expect_close(w[c], want, 0);
    }
  }
}

TEST(SoundSpaces, ExplicitMaxLenCutsAndHalfPrecisionIsClose) {
  TempDir dir;
  SoundSpacesScene scene;
  scene.write(dir.path());
  RirLoadOptions o = quiet_rirs();
  o.max_len = 40;
  const RirSet set = load_soundspaces(dir.path(), o);
  EXPECT_EQ(set.max_len, 40);
  float mn = 0;
  const torch::Tensor ref = soundspaces_reference(scene.audio(0), &mn);
  ASSERT_GT(ref.size(2), 40);
  expect_close(set.features(0), ref.narrow(2, 0, 40));
  EXPECT_EQ(set.rirs[0].num_frames, ref.size(2));  // own length is reported uncut

  o.half_precision = true;
  const RirSet half = load_soundspaces(dir.path(), o);
  EXPECT_NE(half.cache_path, set.cache_path);
  for (int64_t i = 0; i < set.size(); ++i) {
    const torch::Tensor a = set.features(i), b = half.features(i);
    // float16 keeps ~11 bits: relative error <= 2^-11 of |value| (values are within ±10).
    EXPECT_LE((a - b).abs().max().item<float>(), 10.0f / 2048) << i;
  }
}

TEST(SoundSpaces, PublishedMagnitudeFilesAreUsedWhenPresent) {
  TempDir dir;
  SoundSpacesScene scene;
  scene.write(dir.path());
  // Magnitudes with distinctive values and lengths (not derivable from the wavs).
  std::vector<torch::Tensor> mags;
  torch::manual_seed(3);
  for (size_t i = 0; i < scene.entries.size(); ++i) {
    const int64_t t = 20 + 7 * static_cast<int64_t>(i);
    torch::Tensor m = torch::rand({2, 257, t}) * 3 + 1e-4;
    mags.push_back(m);
    std::vector<float> v(m.data_ptr<float>(), m.data_ptr<float>() + m.numel());
    testing::write_npy(
        dir / ("binaural_magnitudes_sr22050/" + SoundSpacesScene::key(scene.entries[i]) + ".npy"),
        {2, 257, t}, v);
  }
  const RirSet set = load_soundspaces(dir.path(), quiet_rirs());
  // The longest training magnitude file (entries 5 and 6, 55 and 62 frames, are test RIRs: cut).
  EXPECT_EQ(set.max_len, 20 + 7 * 4);
  for (size_t i = 0; i < mags.size(); ++i) {
    EXPECT_FALSE(set.rirs[i].magnitude_path.empty());
    const float mn = mags[i].min().item<float>();
    expect_close(set.features(i), pad_to(torch::log(mags[i] + 1e-3f), set.max_len, mn), 1e-6);
  }
  // Opting out computes from the wavs instead.
  RirLoadOptions o = quiet_rirs();
  o.use_magnitude_files = false;
  const RirSet from_wav = load_soundspaces(dir.path(), o);
  EXPECT_TRUE(from_wav.rirs[0].magnitude_path.empty());
  EXPECT_EQ(from_wav.max_len, 81);
}

TEST(SoundSpaces, AutomaticMaxLenIsTheLongestTrainingRir) {
  TempDir dir;
  SoundSpacesScene scene;
  scene.entries[5].samples = 30001;  // a test RIR longer than every training RIR
  scene.write(dir.path());
  const RirSet set = load_soundspaces(dir.path(), quiet_rirs());
  EXPECT_EQ(set.max_len, 81);  // the 20001-sample training RIR, as before
  EXPECT_EQ(set.max_len_source, "longest training RIR");
  EXPECT_TRUE(set.max_len_note.empty());
  EXPECT_GT(set.rirs[5].num_frames, 81);  // its own length is kept; its features are cut
  EXPECT_EQ(set.features(5).size(2), 81);
}

TEST(SoundSpaces, PublishedSceneUsesThePublishedMaxLenWithANote) {
  EXPECT_EQ(published_max_len("office_4"), 78);
  EXPECT_EQ(published_max_len("frl_apartment_2"), 107);
  EXPECT_FALSE(published_max_len("office_5").has_value());
  TempDir dir;
  const std::string root = dir.path() + "/office_4";
  SoundSpacesScene scene;
  scene.write(root);
  for (const std::string& path : {root, root + "/"}) {
    const RirSet set = load_soundspaces(path, quiet_rirs());
    EXPECT_EQ(set.max_len, 78);
    EXPECT_EQ(set.waveform_length, 78 * 128);
    EXPECT_EQ(set.max_len_source, "published (office_4)");
    // The data's own value (81) differs: said, with the flag that selects it.
    EXPECT_NE(set.max_len_note.find("81 frames"), std::string::npos) << set.max_len_note;
    EXPECT_NE(set.max_len_note.find("--max-len 81"), std::string::npos) << set.max_len_note;
  }
  RirLoadOptions o = quiet_rirs();
  o.max_len = 81;
  const RirSet explicit_len = load_soundspaces(root, o);
  EXPECT_EQ(explicit_len.max_len, 81);
  EXPECT_EQ(explicit_len.max_len_source, "--max-len");
  EXPECT_TRUE(explicit_len.max_len_note.empty());
}

TEST(SoundSpaces, EmptyWavIsSilence) {
  TempDir dir;
  SoundSpacesScene scene;
  scene.write(dir.path());
  testing::write_empty_wav(scene.wav(dir.path(), scene.entries[6]), 44100, 2);
  const RirSet set = load_soundspaces(dir.path(), quiet_rirs());
  const torch::Tensor f = set.features(6);
  EXPECT_EQ(set.rirs[6].num_frames, 35);
  EXPECT_TRUE(torch::all(f == std::log(1e-3f)).item<bool>());
  EXPECT_EQ(set.waveform(6).abs().max().item<float>(), 0.0f);
}

TEST(SoundSpaces, SplitAtSceneRootIsAcceptedAndMissingSplitIsAnError) {
  TempDir dir;
  SoundSpacesScene scene;
  scene.write(dir.path(), /*split_in_metadata=*/false);
  RirLoadOptions o = quiet_rirs();
  o.load_features = false;
  EXPECT_EQ(load_soundspaces(dir.path(), o).size(), 7);
  fs::remove(dir / "split.json");
  try {
    load_soundspaces(dir.path(), o);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("metadata_AudioNeRF/split.json"), std::string::npos)
        << e.what();
  }
}

TEST(SoundSpaces, NumFramesPredictionMatchesTheRecipe) {
  // The automatic max_len comes from headers; it must equal what the recipe produces.
  for (const int64_t n : {int64_t(1), int64_t(4409), int64_t(4411), int64_t(8821), int64_t(9999),
                          int64_t(16385), int64_t(30001)}) {
    std::vector<std::vector<float>> ch{testing::decaying_noise(n, 44100, 0.2, 9),
                                       testing::decaying_noise(n, 44100, 0.2, 10)};
    float mn = 0;
    EXPECT_EQ(soundspaces_reference(ch, &mn).size(2), detail::soundspaces_num_frames(n)) << n;
  }
}

TEST(FeatureCache, ReusedWhenValidRebuiltWhenAFileChanges) {
  TempDir dir;
  SoundSpacesScene scene;
  scene.write(dir.path());
  const RirSet a = load_soundspaces(dir.path(), quiet_rirs());
  ASSERT_TRUE(fs::exists(a.cache_path));
  EXPECT_EQ(fs::path(a.cache_path).parent_path(), fs::path(dir / ".neraf_cache"));
  const auto stamp = fs::last_write_time(a.cache_path);
  const torch::Tensor f0 = a.features(0);

  const RirSet b = load_soundspaces(dir.path(), quiet_rirs());
  EXPECT_EQ(b.cache_path, a.cache_path);
  EXPECT_EQ(fs::last_write_time(b.cache_path), stamp);  // not rewritten
  EXPECT_TRUE(torch::equal(b.features(0), f0));

  // Change RIR 0's audio: the key changes, a new cache is built and the stale one removed.
  const std::string wav = scene.wav(dir.path(), scene.entries[0]);
  std::vector<std::vector<float>> other{testing::decaying_noise(20001, 44100, 0.1, 77),
                                        testing::decaying_noise(20001, 44100, 0.1, 78)};
  testing::write_wav(wav, 44100, other);
  fs::last_write_time(wav, fs::last_write_time(wav) + std::chrono::seconds(5));
  const RirSet c = load_soundspaces(dir.path(), quiet_rirs());
  EXPECT_NE(c.cache_path, a.cache_path);
  EXPECT_FALSE(fs::exists(a.cache_path));
  float mn = 0;
  expect_close(c.features(0), pad_to(soundspaces_reference(other, &mn), c.max_len, mn));
  EXPECT_FALSE(torch::equal(c.features(0), f0));
  // a still reads its (now deleted) file through the mapping.
  EXPECT_TRUE(torch::equal(a.features(0), f0));

  // A truncated cache file is detected and rebuilt.
  fs::resize_file(c.cache_path, fs::file_size(c.cache_path) - 100);
  const RirSet d = load_soundspaces(dir.path(), quiet_rirs());
  EXPECT_EQ(d.cache_path, c.cache_path);
  EXPECT_TRUE(torch::equal(d.features(3), c.features(3)));

  // A user cache folder.
  RirLoadOptions o = quiet_rirs();
  TempDir cache_dir;
  o.cache_dir = cache_dir.path();
  const RirSet e = load_soundspaces(dir.path(), o);
  EXPECT_EQ(fs::path(e.cache_path).parent_path(), fs::path(cache_dir.path()));
  EXPECT_TRUE(torch::equal(e.features(5), c.features(5)));
}

TEST(FeatureCache, GatherReturnsTheRequestedSlices) {
  TempDir dir;
  SoundSpacesScene scene;
  scene.write(dir.path());
  const RirSet set = load_soundspaces(dir.path(), quiet_rirs());
  torch::manual_seed(1);
  const int64_t b = 700;
  const torch::Tensor rir = torch::randint(0, set.size(), {b}, torch::kInt64);
  const torch::Tensor frame = torch::randint(0, set.max_len, {b}, torch::kInt64);
  const torch::Tensor g = set.gather(rir, frame);
  ASSERT_EQ(g.sizes(), (std::vector<int64_t>{b, 2, 257}));
  std::vector<torch::Tensor> feats;
  for (int64_t i = 0; i < set.size(); ++i) feats.push_back(set.features(i));
  for (int64_t k = 0; k < b; ++k) {
    const torch::Tensor want = feats[rir[k].item<int64_t>()].select(2, frame[k].item<int64_t>());
    ASSERT_TRUE(torch::equal(g[k], want)) << k;
  }
  torch::Tensor out = torch::empty({b, 2, 257});
  set.gather_into(rir.to(torch::kInt32), frame, out);
  EXPECT_TRUE(torch::equal(out, g));
  EXPECT_THROW(set.gather(torch::tensor({int64_t(set.size())}), torch::tensor({int64_t(0)})),
               c10::Error);
  EXPECT_THROW(set.gather(torch::tensor({int64_t(0)}), torch::tensor({set.max_len})), c10::Error);
}

// The cache is read, not mapped: a file cut short under a running trainer is one clear error
// (a mapping would kill the process with SIGBUS), and resident memory does not hold the cache.
TEST(FeatureCache, ACacheTruncatedWhileInUseIsAClearError) {
  TempDir dir;
  SoundSpacesScene scene;
  scene.write(dir.path());
  const RirSet set = load_soundspaces(dir.path(), quiet_rirs());
  const torch::Tensor last = set.features(set.size() - 1);
  ASSERT_EQ(::truncate(set.cache_path.c_str(), fs::file_size(set.cache_path) / 2), 0);
  EXPECT_TRUE(torch::equal(set.features(0), set.features(0)));  // the first half is still there
  try {
    set.features(set.size() - 1);
    FAIL() << "a read past the truncated end succeeded";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(set.cache_path), std::string::npos) << what;
    EXPECT_NE(what.find("delete the file"), std::string::npos) << what;
  }
  // The next load sees a broken file and rebuilds it.
  const RirSet again = load_soundspaces(dir.path(), quiet_rirs());
  EXPECT_TRUE(torch::equal(again.features(again.size() - 1), last));
}

// ---------------------------------------------------------------------------------------------

TEST(Raf, PosesYawSplitsFeaturesAndWaveforms) {
  TempDir dir;
  RafRoom room;
  room.write(dir.path());
  const RirSet set = load_rir_set(dir.path(), quiet_rirs());
  EXPECT_EQ(set.layout, AudioLayout::raf);
  ASSERT_EQ(set.size(), 6);
  EXPECT_EQ(set.train.size(), 4u);  // ['train'][0]
  EXPECT_EQ(set.test.size(), 2u);   // ['test'][0]
  EXPECT_EQ(set.channels, 1);
  EXPECT_EQ(set.n_freq, 513);
  EXPECT_EQ(set.max_len, 60);
  EXPECT_EQ(set.waveform_length, 15360);
  const int want_heading[6] = {30, 90, -120, 30, 179, -45};
  for (size_t i = 0; i < 6; ++i) {
    const Rir& r = set.rirs[i];
    const auto& e = room.entries[i];
    EXPECT_EQ(r.id, RafRoom::id(i));
    EXPECT_EQ(r.mic.x, e.rx[0]);
    EXPECT_EQ(r.mic.y, e.rx[1]);
    EXPECT_EQ(r.mic.z, e.rx[2]);
    EXPECT_EQ(r.source.x, e.tx[0]);
    EXPECT_EQ(r.source.z, e.tx[2]);
    EXPECT_NEAR(r.raw_yaw_deg, e.expected_yaw, 1e-9);
    EXPECT_EQ(r.heading_deg, want_heading[i]);
    const auto rot = encode_heading(want_heading[i]);
    EXPECT_EQ(r.rot, rot);
    EXPECT_EQ(r.num_frames, 61);

    // Features: first 15360 samples, STFT 1024/512/256, log(|.| + 1e-3), 60 of 61 frames.
    std::vector<float> x = room.audio(i);
    x.resize(15360);
    const dsp::Matrix lm = dsp::log_magnitude(dsp::stft(x, dsp::StftParams::raf()), 1e-3f);
    ASSERT_EQ(lm.cols, 61);
    const torch::Tensor want =
        torch::from_blob(const_cast<float*>(lm.data.data()), {1, 513, 61}).narrow(2, 0, 60);
    expect_close(set.features(i), want);

    const torch::Tensor w = set.waveform(i);
    ASSERT_EQ(w.sizes(), (std::vector<int64_t>{1, 15360}));
    EXPECT_TRUE(torch::equal(w[0], torch::from_blob(x.data(), {15360})));
  }
  // Audio aabb from the train mics only (ids 0-3).
  EXPECT_NEAR(set.audio_aabb.min.x, -0.5, 1e-12);
  EXPECT_NEAR(set.audio_aabb.max.x, 3.0, 1e-12);
  EXPECT_NEAR(set.audio_aabb.max.z, 3.5, 1e-12);
}

TEST(Raf, MaxLenOtherThanThePublished60IsRefused) {
  TempDir dir;
  RafRoom room;
  room.write(dir.path());
  RirLoadOptions o = quiet_rirs();
  o.max_len = 60;
  EXPECT_EQ(load_raf(dir.path(), o).max_len, 60);
  o.max_len = 80;
  try {
    load_raf(dir.path(), o);
    FAIL() << "a RAF max_len of 80 was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("SoundSpaces-layout data only"), std::string::npos);
  }
}

TEST(Raf, StringIdsAndWrongSampleRate) {
  TempDir dir;
  RafRoom room;
  room.write(dir.path());
  testing::write_text(dir / "metadata/data-split.json",
                      R"({"train": [["000000", "1", "000002"]], "test": [["000005"]]})");
  const RirSet set = load_raf(dir.path(), quiet_rirs());
  ASSERT_EQ(set.size(), 4);
  EXPECT_EQ(set.rirs[1].id, "000001");

  testing::write_wav(dir / "data/000002/rir.wav", 16000, {room.audio(2)});
  try {
    load_raf(dir.path(), quiet_rirs());
    FAIL() << "expected a sample-rate error";
  } catch (const Error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("data/000002/rir.wav"), std::string::npos) << msg;
    EXPECT_NE(msg.find("16000 Hz"), std::string::npos) << msg;
  }
}

}  // namespace
}  // namespace neraf::data
