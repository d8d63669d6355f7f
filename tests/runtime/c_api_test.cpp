// The C API's argument checks and statuses (neraf_rt.h): every failure returns its status and
// leaves a message in neraf_last_error().
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "neraf/neraf_rt.h"
#include "random_model.h"

namespace fs = std::filesystem;

namespace {

class CApi : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string t = (fs::temp_directory_path() / "neraf_rt_capi_XXXXXX").string();
    dir_ = ::mkdtemp(t.data());
    path_ = (dir_ / "room.nrf").string();
    neraf::rt::write_model_file(path_, neraf::rt::testing::random_model());
    ASSERT_EQ(neraf_model_load(path_.c_str(), &model_), NERAF_OK) << neraf_last_error();
    ASSERT_EQ(neraf_model_get_info(model_, &info_), NERAF_OK);
    ASSERT_EQ(neraf_workspace_create(model_, &ws_), NERAF_OK);
    log_.resize(size_t(info_.channels) * info_.n_freq * info_.n_frames);
    rir_.resize(size_t(info_.channels) * info_.rir_length);
  }
  void TearDown() override {
    neraf_workspace_free(ws_);
    neraf_model_free(model_);
    fs::remove_all(dir_);
  }
  neraf_status log_query(const neraf_pose& p, unsigned flags = 0) {
    return neraf_query_log_stft(model_, ws_, &p, flags, log_.data(), log_.size());
  }
  neraf_status rir_query(const neraf_pose& p, unsigned flags = 0) {
    return neraf_query_rir(model_, ws_, &p, flags, rir_.data(), rir_.size());
  }
  std::string error() const { return neraf_last_error(); }

  fs::path dir_;
  std::string path_;
  neraf_model* model_ = nullptr;
  neraf_workspace* ws_ = nullptr;
  neraf_model_info info_{};
  std::vector<float> log_, rir_;
  const neraf_pose inside_ = {{0.5, 1.2, -0.5}, {2.0, 1.5, 1.0}, 90.0};
};

}  // namespace

TEST_F(CApi, InfoDescribesTheModel) {
  EXPECT_EQ(info_.format_version, 1u);
  EXPECT_EQ(info_.layout, 0);
  EXPECT_EQ(info_.sample_rate, 22050);
  EXPECT_EQ(info_.channels, 2);
  EXPECT_EQ(info_.n_freq, 33);
  EXPECT_EQ(info_.n_frames, 12);
  EXPECT_EQ(info_.n_fft, 64);
  EXPECT_EQ(info_.hop_length, 16);
  EXPECT_EQ(info_.rir_length, 16 * 11);
  EXPECT_EQ(info_.box_min[2], -2.0);
  EXPECT_EQ(info_.box_max[0], 3.0);
  EXPECT_STREQ(info_.neraf_version, "0.1.0-test");
}

TEST_F(CApi, QueriesSucceedInsideTheBox) {
  ASSERT_EQ(log_query(inside_), NERAF_OK) << error();
  ASSERT_EQ(rir_query(inside_), NERAF_OK) << error();
  double energy = 0;
  for (float v : rir_) {
    ASSERT_TRUE(std::isfinite(v));
    energy += double(v) * v;
  }
  EXPECT_GT(energy, 0);
}

TEST_F(CApi, NonFinitePoseIsRejected) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  neraf_pose p = inside_;
  p.mic[1] = nan;
  EXPECT_EQ(log_query(p), NERAF_ERR_NOT_FINITE);
  EXPECT_NE(error().find("NaN"), std::string::npos) << error();
  EXPECT_EQ(rir_query(p, NERAF_ALLOW_OUTSIDE), NERAF_ERR_NOT_FINITE);
  p = inside_;
  p.source[2] = -inf;
  EXPECT_EQ(log_query(p), NERAF_ERR_NOT_FINITE);
  p = inside_;
  p.yaw_deg = nan;
  EXPECT_EQ(rir_query(p), NERAF_ERR_NOT_FINITE);
}

TEST_F(CApi, OutsideTheBoxNeedsTheFlag) {
  neraf_pose p = inside_;
  p.source[0] = 3.5;  // box x: [-1, 3]
  EXPECT_EQ(log_query(p), NERAF_ERR_OUTSIDE);
  EXPECT_NE(error().find("source"), std::string::npos) << error();
  EXPECT_EQ(rir_query(p), NERAF_ERR_OUTSIDE);
  EXPECT_EQ(log_query(p, NERAF_ALLOW_OUTSIDE), NERAF_OK) << error();
  EXPECT_EQ(rir_query(p, NERAF_ALLOW_OUTSIDE), NERAF_OK) << error();
  EXPECT_EQ(log_query(inside_, 1u << 5), NERAF_ERR_INVALID_ARGUMENT);  // unknown flag
  // The box is open, as the input encoding (a position on a face is encoded as zeros), and as
  // the neraf command line checks it.
  p = inside_;
  p.mic[0] = 3.0;
  EXPECT_EQ(log_query(p), NERAF_ERR_OUTSIDE);
  p.mic[0] = -1.0;
  EXPECT_EQ(rir_query(p), NERAF_ERR_OUTSIDE);
}

TEST_F(CApi, SmallCapacityIsRejected) {
  EXPECT_EQ(neraf_query_log_stft(model_, ws_, &inside_, 0, log_.data(), log_.size() - 1),
            NERAF_ERR_BUFFER_TOO_SMALL);
  EXPECT_NE(error().find(std::to_string(log_.size())), std::string::npos) << error();
  EXPECT_EQ(neraf_query_rir(model_, ws_, &inside_, 0, rir_.data(), 0), NERAF_ERR_BUFFER_TOO_SMALL);
  // Larger is fine.
  std::vector<float> big(rir_.size() + 10, -1.0f);
  EXPECT_EQ(neraf_query_rir(model_, ws_, &inside_, 0, big.data(), big.size()), NERAF_OK);
  EXPECT_EQ(big.back(), -1.0f);  // nothing written past the RIR
}

TEST_F(CApi, NullArgumentsAreRejected) {
  neraf_model* m = reinterpret_cast<neraf_model*>(1);
  EXPECT_EQ(neraf_model_load(nullptr, &m), NERAF_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(m, nullptr);
  EXPECT_EQ(neraf_model_load(path_.c_str(), nullptr), NERAF_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(neraf_model_get_info(nullptr, &info_), NERAF_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(neraf_model_get_info(model_, nullptr), NERAF_ERR_INVALID_ARGUMENT);
  neraf_workspace* w = nullptr;
  EXPECT_EQ(neraf_workspace_create(nullptr, &w), NERAF_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(neraf_workspace_create(model_, nullptr), NERAF_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(neraf_workspace_set_griffin_lim(nullptr, 32, 0), NERAF_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(neraf_workspace_set_threads(nullptr, 1), NERAF_ERR_INVALID_ARGUMENT);
  float* out = log_.data();
  const size_t n = log_.size();
  EXPECT_EQ(neraf_query_log_stft(nullptr, ws_, &inside_, 0, out, n), NERAF_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(neraf_query_log_stft(model_, nullptr, &inside_, 0, out, n), NERAF_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(neraf_query_log_stft(model_, ws_, nullptr, 0, out, n), NERAF_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(neraf_query_log_stft(model_, ws_, &inside_, 0, nullptr, n), NERAF_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(neraf_query_rir(nullptr, ws_, &inside_, 0, out, n), NERAF_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(neraf_query_rir(model_, ws_, &inside_, 0, nullptr, n), NERAF_ERR_INVALID_ARGUMENT);
  EXPECT_FALSE(error().empty());
  neraf_model_free(nullptr);
  neraf_workspace_free(nullptr);
}

TEST_F(CApi, BadSettingsAreRejected) {
  EXPECT_EQ(neraf_workspace_set_griffin_lim(ws_, -1, 0), NERAF_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(neraf_workspace_set_threads(ws_, -3), NERAF_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(neraf_workspace_set_griffin_lim(ws_, 0, 5), NERAF_OK);
  EXPECT_EQ(rir_query(inside_), NERAF_OK);
}

TEST_F(CApi, WorkspaceOfAnotherModelIsRejected) {
  neraf_model* other = nullptr;
  ASSERT_EQ(neraf_model_load(path_.c_str(), &other), NERAF_OK);
  EXPECT_EQ(neraf_query_log_stft(other, ws_, &inside_, 0, log_.data(), log_.size()),
            NERAF_ERR_INVALID_ARGUMENT);
  EXPECT_NE(error().find("another model"), std::string::npos) << error();
  neraf_model_free(other);
}

TEST_F(CApi, LoadErrorsGiveTheirStatusAndNameTheFile) {
  neraf_model* m = nullptr;
  const std::string missing = (dir_ / "missing.nrf").string();
  EXPECT_EQ(neraf_model_load(missing.c_str(), &m), NERAF_ERR_IO);
  EXPECT_EQ(error().rfind(missing, 0), 0u) << error();
  const std::string wav = (dir_ / "x.wav").string();
  std::ofstream(wav) << "RIFF\x24\0\0\0WAVEfmt ";
  EXPECT_EQ(neraf_model_load(wav.c_str(), &m), NERAF_ERR_FORMAT);
  EXPECT_EQ(error(), wav + ": not a neraf model (no NERAFMDL signature)");
  EXPECT_EQ(m, nullptr);
  // Truncated.
  const std::string cut = (dir_ / "cut.nrf").string();
  fs::copy_file(path_, cut);
  fs::resize_file(cut, fs::file_size(path_) / 2);
  EXPECT_EQ(neraf_model_load(cut.c_str(), &m), NERAF_ERR_FORMAT);
  EXPECT_NE(error().find("truncated"), std::string::npos) << error();
  EXPECT_EQ(error().rfind(cut, 0), 0u) << error();
}

TEST_F(CApi, ErrorsArePerThread) {
  neraf_pose p = inside_;
  p.mic[0] = 100;
  ASSERT_EQ(log_query(p), NERAF_ERR_OUTSIDE);
  const std::string mine = error();
  std::string theirs = "unset";
  std::thread([&] { theirs = neraf_last_error(); }).join();
  EXPECT_EQ(theirs, "");
  EXPECT_EQ(error(), mine);
}

TEST(CApiStatus, EveryStatusHasAString) {
  for (int s = NERAF_OK; s <= NERAF_ERR_INTERNAL; ++s)
    EXPECT_STRNE(neraf_status_string(neraf_status(s)), "unknown status") << s;
  EXPECT_STREQ(neraf_status_string(neraf_status(77)), "unknown status");
}
