// The diagnostic used on 2026-12-04 (not part of the build): the share of a run's predicted
// log-STFT values at ±10 (the acoustic field's output_scale), at a few checkpoints. Built by
// copying it into tests/infer/ (the test glob picks it up) and running
//   PROBE_RUN=/tmp/col/s3 build/neraf_test_infer --gtest_filter='ZzProbe*'
// on the killed old-schedule run of seed 3 (train --data ss_demo --seed 3 --save-every 100).
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "neraf/infer/audio_run.h"

TEST(ZzProbe, Saturation) {
  const char* run = std::getenv("PROBE_RUN");
  if (!run) GTEST_SKIP();
  for (const char* ck : {"step-000001100.pt", "step-000001200.pt", "step-000003000.pt"}) {
    const std::string path = std::string(run) + "/checkpoints/" + ck;
    if (!std::filesystem::exists(path)) continue;
    auto r = neraf::infer::load_audio_run(run, torch::kCPU, path, neraf::nerf::Precision::fp32,
                                          false);
    const auto x = r.predict_log_stft({2.0, 1.5, 2.0}, {1.0, 1.2, 1.0}, 90.0);
    const double sat = (x.abs() >= 9.99).to(torch::kFloat).mean().item<double>();
    std::printf("%s: saturated %.4f  min %.3f max %.3f mean %.3f\n", ck, sat,
                x.min().item<double>(), x.max().item<double>(), x.mean().item<double>());
  }
}
