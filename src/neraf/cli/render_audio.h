#pragma once
// The acoustic half of `neraf render` (render rir, render loudness) and the pieces `neraf
// auralize --run|--model` shares with it: field and pose options, rendering an RIR from a field.
#include <CLI/CLI.hpp>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>

#include "neraf/geometry/vec.h"
#include "neraf/infer/audio_field.h"
#include "neraf/io/audio_file.h"

namespace neraf::cli {

// Adds `rir`, `loudness` and `trajectory` to the `render` command.
void add_render_audio_commands(CLI::App& render);
// `render trajectory` (render_trajectory.cpp).
void add_render_trajectory(CLI::App& render);

// Where the acoustic field comes from: a run folder (LibTorch) or an exported MODEL.nrf (neraf_rt).
struct FieldArgs {
  std::string run;
  std::string model;
  std::string checkpoint;
  std::string precision = "fp32";  // of --run's queries
  std::string scene;               // --scene NAME|INDEX of a multi-scene --run
  bool allow_outside = false;
  CLI::Option* run_opt = nullptr;
  CLI::Option* model_opt = nullptr;
};

// --run, --model (exclusive; load_field requires one), --checkpoint, --precision and --scene
// (need --run) and, when
// `poses` (the command checks poses against the training box), --allow-outside.
void add_field_options(CLI::App* cmd, FieldArgs& args, bool poses);

struct LoadedField {
  std::unique_ptr<infer::AudioField> field;
  std::string name;  // the run folder or the model file, for messages
  int64_t step = 0;  // the training step of the weights
};

// Loads what `args` names (usage error when neither or both are given).
LoadedField load_field(const FieldArgs& args);

struct AudioPoseArgs {
  std::string mic;     // "X,Y,Z"
  std::string src;     // "X,Y,Z"
  double yaw = 0;      // receiver heading (SoundSpaces runs)
  double src_yaw = 0;  // source yaw (RAF runs)
  CLI::Option* yaw_opt = nullptr;
  CLI::Option* src_yaw_opt = nullptr;
  uint64_t seed = 0;
};

// --mic (when with_mic), --src, --yaw, --src-yaw, --seed. With required = false (auralize, where
// the field is optional) they all need `needs` (when given) and the caller checks --mic/--src
// itself. Returns the --mic and --src options.
std::pair<CLI::Option*, CLI::Option*> add_audio_pose_options(CLI::App* cmd, AudioPoseArgs& args,
                                                             bool with_mic, bool required = true,
                                                             CLI::Option* needs = nullptr);

// The text for a command's footer that explains the frame, units and yaw conventions.
std::string audio_pose_help();

// neraf::Error naming `what` (a flag or a file entry) when p is outside the field's training box,
// unless allow_outside (then a warning).
void check_inside(const geometry::Vec3& p, const std::string& what, const data::Aabb& box,
                  bool allow_outside);

// Checks the pose (usage errors for malformed X,Y,Z, an error for positions outside the training
// box unless --allow-outside, an error for the orientation flag of the other layout) and renders
// the RIR with Griffin-Lim. `summary` receives a one-line description.
io::AudioBuffer render_rir_from_field(const LoadedField& field, const FieldArgs& field_args,
                                      const AudioPoseArgs& args, std::string* summary);

// A warning naming `out_path` when `audio` goes beyond full scale: a float WAV keeps such samples
// (playback clips them), a FLAC (24-bit integers) clips them when written. `fix` is the command's
// own remedy ("pass --normalize"; "" for none).
void warn_above_full_scale(const io::AudioBuffer& audio, const std::string& out_path,
                           const std::string& fix);

}  // namespace neraf::cli
