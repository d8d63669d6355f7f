#pragma once
// Built-in scenes (`neraf synth --preset NAME`). Each is an ordinary Scene value: what
// `scene_to_json(preset_scene(name))` prints can be edited and passed back with --scene.
//   demo       4 × 2.7 × 3.5 m, 3 textured boxes, 29 grid points × 4 headings × 4 sources = 464
//              binaural RIRs (0.6 s), 50 + 10 photos at 96 × 96 — trains in minutes on 2 cores.
//   shoebox    5 × 3 × 4 m empty room, one uniform material (for Sabine/Eyring checks), 20 × 4 × 1
//              = 80 RIRs (1 s), 30 + 10 photos at 96 × 96.
//   furnished  7 × 3 × 6 m, 7 boxes, 0.5 m grid (139 free points) × 4 × 2 sources = 1,112 RIRs
//              (0.8 s), 100 + 20 photos at 128 × 128.
//   occluded   6 × 2.7 × 4 m split at x = 3 by a full-height partition with a 1.1 m doorway: 0.6 m
//              grid (50 points) × 4 × 4 sources (two each side) = 800 RIRs (0.6 s); the direct
//              path is blocked for 86 of the 200 source-microphone pairs (43 %).
//   furnished_room / empty_room   (layout raf) one 6 × 2.8 × 5 m RAF-like room with and without
//              7 low boxes: 300 random omni microphones × 2 cardioid sources = 600 mono RIRs
//              (0.8 s); the same microphone and camera positions for a seed.
//   small_dead 3 × 2.4 × 2.6 m, carpet / absorbing ceiling / curtain: 30 × 4 × 2 = 240 RIRs (0.4 s).
//   large_live 12 × 4.5 × 9 m hall, hard surfaces and a block of seats: 108 × 4 × 2 = 864 (1.5 s).
//   apartment  14 × 2.7 × 9 m, 5 rooms joined by doorways, 11 furniture boxes, 0.5 m grid (411
//              points) × 4 headings × 14 sources = 23,016 binaural RIRs (0.5 s).
//   raf_large  (layout raf) furnished_room with 5,000 random microphones × 4 cardioid source
//              placements = 20,000 mono RIRs (0.6 s).
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
