#pragma once
// The calibration stage: after training (run_training) or on demand (`neraf calibrate RUN`), the
// energy calibration and early/late balance of a run's acoustic field (acoustic/calibration.h)
// are fitted on its training RIRs and saved beside the checkpoint they belong to
// (checkpoint.h, calibration_path: step-XXXXXXXXX.calibration.pt, a sealed archive holding
// "step" and "gains"). Saving a checkpoint therefore stays fast and has no side effects.
#include <torch/types.h>

#include <atomic>
#include <optional>
#include <string>
#include <vector>

#include "neraf/data/rir_set.h"
#include "neraf/infer/audio_run.h"

namespace neraf::infer {

// [C, F, T] gains fitted for `run` (loaded uncalibrated) on the run's training RIRs of `rirs` (as
// training loaded them; a multi-scene run's scene is fitted on its own run.info().max_len frames)
// (its few-shot subset; at most 512 evenly strided for the energies, 64 of those rendered
// through Griffin-Lim for the balance); all ones when the run has calibration off. `stop` (set
// asynchronously by Ctrl-C / SIGTERM) makes it throw neraf::Interrupted between two RIRs.
torch::Tensor fit_calibration(const AudioRun& run, const data::RirSet& rirs,
                              const std::atomic<bool>* stop = nullptr);

// One file per checkpoint; a multi-scene run's holds every scene's gains ("gains", "gains_1", ...).
void save_calibration(const std::string& checkpoint, int64_t step, const torch::Tensor& gains);
void save_calibration(const std::string& checkpoint, int64_t step,
                      const std::vector<torch::Tensor>& scene_gains);
// The gains saved for `checkpoint` (of `scene`; nullopt when there are none); neraf::Error naming
// the file when it is damaged or was fitted for another step.
std::optional<torch::Tensor> load_calibration(const std::string& checkpoint, int64_t step,
                                              int64_t scene = 0);

// Fits and saves the calibration of RUN's latest checkpoint (or `checkpoint`) on `rirs` (the
// run's dataset); returns the calibration file written. A multi-scene run: one RirSet per scene,
// in the run's order. Stopped by `stop`: neraf::Interrupted, nothing written.
std::string calibrate_run(const std::string& run_dir, const data::RirSet& rirs,
                          const std::string& checkpoint = "",
                          const std::atomic<bool>* stop = nullptr);
std::string calibrate_run(const std::string& run_dir,
                          const std::vector<const data::RirSet*>& scenes,
                          const std::string& checkpoint = "",
                          const std::atomic<bool>* stop = nullptr);

}  // namespace neraf::infer
