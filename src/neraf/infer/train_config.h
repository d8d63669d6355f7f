#pragma once
// Training configuration: presets `cpu` (default), `paper` and `reference`, resolved once and saved
// beside the run as RUN/config.json (JSON round trip through the same field tables as the model
// config).
// It lives in infer/ because loading a finished run reads it; `neraf train` resolves it from its
// flags with resolve_train_config (the one place the per-modality preset rules live).
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "neraf/nerf/config.h"

namespace neraf::infer {

// What a run trains. Only `vision` is implemented here; `audio` and `joint` are the acoustic
// branch's (see trainer.h, "Adding a branch").
enum class Modality { vision, audio, joint };
std::string to_string(Modality m);
Modality parse_enum(Modality, const std::string& s, const std::string& where);
Modality parse_modality(const std::string& s);

// nerfstudio ExponentialDecayScheduler: optional warm-up from lr_pre_warmup (linear, or a sine
// ramp when warmup_ramp = "sine") over [warmup_start, warmup_start + warmup_steps], then
// log-linear from lr to lr_final until max_steps, flat afterwards. Adam with this eps (betas
// 0.9/0.999, no decay). warmup_start lets a branch that starts late (the cpu preset's acoustic
// field, from step 1000) warm up when it starts: at full LR from its first step, Adam drove its
// tanh outputs into saturation, where they stop learning (one seed in three on the demo room).
struct ScheduleConfig {
  double lr = 1e-2;
  double lr_final = 1e-4;
  int64_t max_steps = 200000;
  int64_t warmup_steps = 0;
  double lr_pre_warmup = 1e-8;
  std::string warmup_ramp = "linear";  // "linear" | "sine"
  double eps = 1e-15;
  int64_t warmup_start = 0;  // lr_pre_warmup before it

  template <class V>
  void visit(V& v) {
    v("lr", lr);
    v("lr_final", lr_final);
    v("max_steps", max_steps);
    v("warmup_steps", warmup_steps);
    v("lr_pre_warmup", lr_pre_warmup);
    v("warmup_ramp", warmup_ramp);
    v("eps", eps);
    v("warmup_start", warmup_start);
  }
};

struct AudioConfig {
  std::string grid = "sampled";  // sampled | none | zeros (the paper's ablations, --grid)
  // How the encoded grid reaches NAcF (--grid-features; acoustic_model.h): "global" (the paper's
  // one pooled vector per room), "local" (features read along each query's mic–source segment)
  // or "both".
  std::string grid_features = "global";
  int64_t start_step = 2000;        // audio losses from the step AFTER this one (reference: 2000)
  int64_t batch_size = 2048;        // (RIR, frame) slices per audio step
  int64_t grid_resolution = 32;     // S (cpu 32, paper 128)
  int64_t cells_per_update = 4096;  // grid cells written per training step (round robin)
  int64_t nacf_width = 0;           // 0: the acoustic preset's NAcF trunk; else N layers of this
  int64_t nacf_layers = 5;          //    width (only used when nacf_width > 0)
  double fraction = 1.0;  // few-shot: seeded fraction of the train RIRs used (--audio-fraction)
  // Training criterion (--audio-loss; the paper's loss study): sc_slmse (the reference's),
  // sc_sll1 or mse (acoustic/losses.h).
  std::string loss = "sc_slmse";
  // Energy-decay loss (the paper's "++" variant, off in the reference): its weight (0 = off,
  // --decay-loss) and how many whole RIRs (all frames) per audio step it is computed on.
  double decay_weight = 0.0;
  int64_t decay_rirs = 4;
  // Share of each audio batch drawn from the first early_frames frames (0 = the reference's
  // uniform slices). The direct sound and early reflections, which carry the binaural level
  // differences, C50 and EDT, are a few frames of ~100: uniform slices rarely show them.
  double early_fraction = 0.0;
  int64_t early_frames = 12;
  // Per-frame energy gains fitted on the train RIRs, applied at inference (ours, off in the
  // paper preset; acoustic/calibration.h).
  bool energy_calibration = true;
  // NAcF also sees the source's direction and distance relative to the listener (ours, off in the
  // paper preset; acoustic/nacf.h, encode_relative_geometry).
  bool relative_geometry = true;
  // Highest frequency exponent of the mic/source position encoding (reference 8).
  double position_max_freq_exp = 8.0;
  // NAcF's decay heads: a slope per bin beside each level head, out = output_scale·tanh(level +
  // τ·slope) (ours, off in every preset; --decay-heads; acoustic/nacf.h).
  bool decay_heads = false;
  // Weight averaging (ours, off in every preset; --audio-average): the acoustic model that
  // inference loads is the uniform average of its weights after each of the last share
  // average_fraction of the audio steps (0 = off: the last step's weights). Training is unchanged.
  double average_fraction = 0.0;
  // The grid sampler's 18 viewing directions: "spread" (ours: unit vectors spread over the
  // sphere) or "reference" (the published code's degenerate vectors; acoustic/grid_sampler.h).
  std::string view_directions = "spread";
  // ResNet3D's BatchNorm: "grid" (ours: the grid's own statistics in train and eval mode) or
  // "running" (the reference: running statistics in eval mode; acoustic/resnet3d.h).
  std::string resnet_batch_norm = "grid";
  std::string vision_run;  // modality audio: the finished vision run whose field is frozen
  // Multi-scene (modality audio with 2+ --data): each scene's vision run, in --data order
  // (vision_run is the first). Empty for a one-scene run, which is the case N = 1 of the same code.
  std::vector<std::string> vision_runs;
  // The RIR feature cache (data::RirLoadOptions): its folder ("" = <dataset>/.neraf_cache,
  // --cache-dir) and precision ("fp32", or "fp16": half the disk, features rounded to ~1e-3
  // relative; --cache-precision). Recorded so resume, calibration and eval reuse the same cache.
  std::string cache_dir;
  std::string cache_precision = "fp32";
  // SoundSpaces frames per RIR (--max-len); 0 = automatic (data::RirLoadOptions::max_len: the
  // published value of a known scene, else the longest training RIR).
  int64_t max_len = 0;
  // "audio_fields" group: NAcF + ResNet3D (+ the radiance field in joint mode), Adam eps 1e-15,
  // sine warm-up from 1e-8 over warmup_steps then log-linear decay (neraf-reference.md §2.3).
  ScheduleConfig schedule{1e-4, 1e-8, 1002000, 2000, 1e-8, "sine", 1e-15};

  template <class V>
  void visit(V& v) {
    v("grid", grid);
    v("grid_features", grid_features);
    v("start_step", start_step);
    v("batch_size", batch_size);
    v("grid_resolution", grid_resolution);
    v("cells_per_update", cells_per_update);
    v("nacf_width", nacf_width);
    v("nacf_layers", nacf_layers);
    v("fraction", fraction);
    v("loss", loss);
    v("decay_weight", decay_weight);
    v("decay_rirs", decay_rirs);
    v("early_fraction", early_fraction);
    v("early_frames", early_frames);
    v("energy_calibration", energy_calibration);
    v("relative_geometry", relative_geometry);
    v("position_max_freq_exp", position_max_freq_exp);
    v("decay_heads", decay_heads);
    v("average_fraction", average_fraction);
    v("view_directions", view_directions);
    v("resnet_batch_norm", resnet_batch_norm);
    v("vision_run", vision_run);
    v("vision_runs", vision_runs);
    v("cache_dir", cache_dir);
    v("cache_precision", cache_precision);
    v("max_len", max_len);
    v("schedule", schedule);
  }
};

struct TrainConfig {
  std::string preset = "cpu";
  Modality modality = Modality::vision;
  int64_t steps = 3000;           // total optimisation steps
  int64_t rays_per_batch = 4096;  // vision rays per step
  uint64_t seed = 42;
  int threads = 0;           // 0: LibTorch's default (all cores)
  int64_t save_every = 500;  // checkpoint period in steps (and always at the end)
  // The run's length was not given (cpu preset, no --steps): a new run lengthens its acoustic
  // schedule to the data it finds (fit_run_length_to_data). Recorded, never re-applied on resume.
  bool steps_from_data = false;
  int64_t eval_rays_per_chunk = 16384;
  ScheduleConfig fields;             // "fields" group: the radiance field
  ScheduleConfig proposal_networks;  // "proposal_networks" group
  ScheduleConfig camera_opt{1e-3, 1e-4, 5000};
  nerf::ModelConfig model;
  AudioConfig audio;  // the acoustic branch (modality audio / joint)

  template <class V>
  void visit(V& v) {
    v("preset", preset);
    v("modality", modality);
    v("steps", steps);
    v("rays_per_batch", rays_per_batch);
    v("seed", seed);
    v("threads", threads);
    v("save_every", save_every);
    v("steps_from_data", steps_from_data);
    v("eval_rays_per_chunk", eval_rays_per_chunk);
    v("fields", fields);
    v("proposal_networks", proposal_networks);
    v("camera_opt", camera_opt);
    v("model", model);
    v("audio", audio);
  }
};

// Sets c.steps; schedules whose decay was tied to the run length (max_steps == c.steps) follow.
void set_run_length(TrainConfig& c, int64_t steps);

// How the cpu preset's schedule scales with the data (issue 14). A run of steps_from_data gets
// more audio steps when its training set has more (RIR, frame) slices than the fixed schedule
// covers: audio steps = clamp(kCpuAudioPasses × train_slices / audio.batch_size, the preset's
// audio steps, kCpuMaxAudioSteps), the run lengthened by the difference (set_run_length: the
// tied decays follow, the warm-up keeps its length). A small room (the demo: 371 RIRs) keeps the
// fixed schedule; the 20k-RIR apartment gets the cap, sized to finish in an hour on 2 cores.
// Returns the audio steps before and after; a run without steps_from_data is left as it is.
inline constexpr int64_t kCpuAudioPasses = 8;
inline constexpr int64_t kCpuMaxAudioSteps = 14000;
struct RunLengthFit {
  int64_t audio_steps_before = 0, audio_steps_after = 0;
};
RunLengthFit fit_run_length_to_data(TrainConfig& c, int64_t train_slices);

// The named preset (throws neraf::Error naming --preset for unknown names):
//   paper      the published sizes and schedule, with our grid sampler directions and BatchNorm
//   reference  the published model exactly: paper plus the reference's 18 viewing directions and
//              ResNet3D BatchNorm with running statistics (like paper: no energy calibration, no
//              relative geometry, the reference position encoding)
//   cpu        sized for 2 CPU cores, with our additions (docs/ARCHITECTURE.md)
TrainConfig train_preset(const std::string& name);

// Whether `name` uses the published sizes and run lengths (paper, reference).
bool published_sizes(const std::string& name);

// What `neraf train` was asked for; an unset optional takes the preset's value for the modality.
struct TrainFlags {
  std::string preset = "cpu";                   // --preset
  Modality modality = Modality::joint;          // --modality
  std::optional<int64_t> steps;                 // --steps
  uint64_t seed = 42;                           // --seed
  std::optional<int> threads;                   // --threads
  std::optional<int64_t> rays;                  // --rays
  std::optional<nerf::Precision> precision;     // --precision
  std::string grid = "sampled";                 // --grid
  std::optional<std::string> grid_features;     // --grid-features
  double audio_fraction = 1.0;                  // --audio-fraction
  std::optional<int64_t> audio_start_step;      // --audio-start-step
  std::optional<double> decay_loss;             // --decay-loss
  std::optional<std::string> audio_loss;        // --audio-loss
  std::optional<int64_t> grid_resolution;       // --grid-resolution
  std::optional<double> position_max_freq_exp;  // --position-max-freq-exp
  bool decay_heads = false;                     // --decay-heads
  std::optional<double> audio_average;          // --audio-average
  bool no_relative_geometry = false;            // --no-relative-geometry
  // --vision-run, once per --data (stored as absolute paths); two or more make a multi-scene run.
  std::vector<std::string> vision_runs;
};

// The config a new run trains with: train_preset(flags.preset), then the modality's defaults,
// then the flags, in this order:
//   - run length: cpu joint 3000 steps, vision 2000, audio 1500; paper and reference joint
//     400001 (NeRAF's max_num_iterations), vision 30000, audio 398000. cpu schedules whose decay is
//     tied to the run length follow it (set_run_length), as they follow --steps.
//   - modality audio (the field is final, the grid is filled once): audio from the first step
//     (start_step −1) after a warm-up of 100 steps (cpu) or 2000 (paper, reference), capped at half
//     the audio schedule's length so that a short run still gets a (shorter) warm-up.
//   - --steps N sets the run length (set_run_length) before that cap; without it a cpu run that
//     trains audio is steps_from_data (fit_run_length_to_data, once its data is loaded).
//   - --audio-start-step S: start_step = S, and a warm-up that ended where audio started still
//     ends there (max(0, S)).
//   - --seed, --grid, --grid-resolution, --audio-fraction, --audio-loss, --decay-loss,
//     --audio-average, --no-relative-geometry, --threads, --rays, --precision, --vision-run (made
//     absolute) overwrite their setting; two or more --vision-run fill audio.vision_runs
//     (multi-scene), the first also audio.vision_run.
// neraf::Error naming the flag: --vision-run without --modality audio, an unknown preset.
// The result is not validated here (run_training validates the config it trains).
TrainConfig resolve_train_config(const TrainFlags& flags);

nlohmann::json to_json(const TrainConfig& c);
// Overlays `j` onto a copy of the preset named in j["preset"] (or `cpu`); `where` names the file.
TrainConfig train_config_from_json(const nlohmann::json& j, const std::string& where);

// The number of scenes a run trains on: audio.vision_runs' size, else 1.
int64_t num_scenes(const TrainConfig& c);

// Range checks (neraf::Error "<where>.<key>: ...").
void validate(const TrainConfig& c, const std::string& where);

// RUN/config.json of a finished run, as render, eval, export and calibrate use it: read, overlaid
// on its preset and validated (a damaged value is an error naming the file, never a raw library
// failure later). Its thread count is not checked: the run may come from a bigger machine.
TrainConfig read_run_config(const std::string& config_path);

}  // namespace neraf::infer
