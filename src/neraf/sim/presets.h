#pragma once
// Built-in scenes (`neraf synth --preset NAME`). Each is an ordinary Scene value: what
// `scene_to_json(preset_scene(name))` prints can be edited and passed back with --scene.
//   demo       4 × 2.7 × 3.5 m, 3 textured boxes, 29 grid points × 4 headings × 4 sources = 464
//              binaural RIRs (0.6 s), 50 + 10 photos at 96 × 96 — trains in minutes on 2 cores.
//   shoebox    5 × 3 × 4 m empty room, one uniform material (for Sabine/Eyring checks), 20 × 4 × 1
//              = 80 RIRs (1 s), 30 + 10 photos at 96 × 96.
//   furnished  7 × 3 × 6 m, 7 boxes, 0.5 m grid (139 free points) × 4 × 2 sources = 1,112 RIRs
//              (0.8 s), 100 + 20 photos at 128 × 128.
#include <string>
#include <vector>

#include "neraf/sim/scene.h"

namespace neraf::sim {

std::vector<std::string> preset_names();
// Throws neraf::Error naming the known presets for an unknown name.
Scene preset_scene(const std::string& name);
// The layout `neraf synth --preset NAME` writes unless --layout is given: "raf" for the RAF-like
// presets (random omni microphones, directional sources), "soundspaces" for the others. A scene
// JSON (--scene, --print-scene) carries no layout: give --layout raf with it.
std::string preset_layout(const std::string& name);

}  // namespace neraf::sim
