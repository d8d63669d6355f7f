#pragma once
// The acoustic half of `neraf render` (render rir, render loudness) and the pieces `neraf
// auralize --run` shares with it: pose options and rendering an RIR from a trained run.
#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>
#include <utility>

#include "neraf/io/audio_file.h"

namespace neraf::cli {

// Adds `rir` and `loudness` to the `render` command.
void add_render_audio_commands(CLI::App& render);

struct AudioPoseArgs {
  std::string mic;     // "X,Y,Z"
  std::string src;     // "X,Y,Z"
  double yaw = 0;      // receiver heading (SoundSpaces runs)
  double src_yaw = 0;  // source yaw (RAF runs)
  CLI::Option* yaw_opt = nullptr;
  CLI::Option* src_yaw_opt = nullptr;
  uint64_t seed = 0;
  std::string checkpoint;
};

// --mic (when with_mic), --src, --yaw, --src-yaw, --seed, --checkpoint. With required = false
// (auralize, where --run is optional) they all need `needs` (when given) and the caller checks
// --mic/--src itself. Returns the --mic and --src options.
std::pair<CLI::Option*, CLI::Option*> add_audio_pose_options(CLI::App* cmd, AudioPoseArgs& args,
                                                             bool with_mic, bool required = true,
                                                             CLI::Option* needs = nullptr);

// The text for a command's footer that explains the frame, units and yaw conventions.
std::string audio_pose_help();

// Loads RUN's acoustic field, checks the pose (usage errors for malformed X,Y,Z, a warning for
// positions outside the train audio aabb, an error for the orientation flag of the other layout)
// and renders the RIR with Griffin-Lim. `summary` receives a one-line description.
io::AudioBuffer render_rir_from_run(const std::string& run_dir, const AudioPoseArgs& args,
                                    std::string* summary);

}  // namespace neraf::cli
