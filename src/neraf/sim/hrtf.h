#pragma once
// Head-related impulse responses for the binaural simulator.
//
// Head frame (the SOFA convention): x forward (the direction the listener faces), y towards the
// LEFT ear, z up; directions are unit vectors from the head centre towards the sound source.
// To convert a world direction (scene.h: y up, forward(θ) = (−sin θ, 0, −cos θ), left ear along
// forward(θ + 90°)) use `world_to_head`.
#include <string>
#include <vector>

#include "neraf/geometry/vec.h"

namespace neraf::sim {

// Measured head-related impulse responses (MIT KEMAR from libmysofa's default.sofa), resampled by
// libmysofa to `sample_rate` and loudness-normalised by it (mysofa_open). Every measured direction
// is copied into memory at construction; `lookup` returns the NEAREST measured direction (no
// interpolation between measurements, so no comb filtering from mixing different ITDs).
// Thread-safe after construction (lookups are const and touch no libmysofa state).
class Hrtf {
 public:
  static constexpr const char* kDefaultSofa = "/usr/share/libmysofa/default.sofa";
  // Throws neraf::Error naming the file when it cannot be opened or is not a 2-receiver HRTF.
  explicit Hrtf(int sample_rate, const std::string& sofa_path = kDefaultSofa);
  ~Hrtf();
  Hrtf(const Hrtf&) = delete;
  Hrtf& operator=(const Hrtf&) = delete;

  // direction_head: direction towards the source in the HEAD frame (x forward, y left, z up); need
  // not be normalised (zero → forward). Outputs the left/right impulse responses (length
  // filter_length()) and their extra onset delays in seconds (0 for default.sofa: the measured IRs
  // already contain the propagation delay / ITD; non-zero only for SOFA files with Data.Delay).
  void lookup(const geometry::Vec3& direction_head, std::vector<float>& left,
              std::vector<float>& right, double& left_delay_s, double& right_delay_s) const;
  // Index of the nearest measured direction (for callers that cache per-direction work).
  int nearest_index(const geometry::Vec3& direction_head) const;
  int num_directions() const { return static_cast<int>(directions_.size()); }
  const geometry::Vec3& direction(int index) const { return directions_[index]; }  // unit, head
  // Left (ear 0) / right (ear 1) IR of measured direction `index`, filter_length() floats.
  const float* ir(int index, int ear) const;
  double delay_s(int index, int ear) const { return delays_s_[2 * index + ear]; }

  int filter_length() const { return filter_length_; }
  int sample_rate() const { return sample_rate_; }
  const std::string& path() const { return path_; }

  // World direction → head frame for a listener with heading `yaw_deg` (scene.h convention).
  static geometry::Vec3 world_to_head(const geometry::Vec3& direction_world, double yaw_deg);

 private:
  int sample_rate_ = 0;
  int filter_length_ = 0;
  std::string path_;
  std::vector<geometry::Vec3> directions_;  // [M] unit vectors, head frame
  std::vector<float> irs_;                  // [M, 2, filter_length]
  std::vector<double> delays_s_;            // [M, 2]
};

}  // namespace neraf::sim
