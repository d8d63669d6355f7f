#pragma once
// Room impulse responses of a Scene: image sources + furniture + a statistical late tail, mono or
// binaural (KEMAR HRTF). The user-facing description is docs/SIMULATOR_ACOUSTICS.md.
//
// MODEL (what is simulated, in order; "band" = the 7 octave bands 125 Hz..8 kHz of scene.h)
//  1. Specular image sources of the empty shoebox [0,size]³: the image in cell (kx, ky, kz) of the
//     unfolded lattice (reflection order |kx| + |ky| + |kz|), every image with order ≤
//     acoustics.max_order (exactly that set, nothing dropped). Each wall hit multiplies the band
//     amplitude by sqrt((1 − α_band)(1 − scattering)) of that wall's material: absorbed energy is
//     lost, scattered energy leaves the specular path (it reappears in the late tail, step 6).
//  2. Furniture REFLECTS (first order only): for every box face whose plane has source and
//     microphone in front of it, the source is mirrored in the face plane; if the mirrored path
//     hits the face inside its rectangle, that specular reflection is added with the box
//     material's sqrt((1 − α)(1 − s)). Wall↔furniture combinations (higher orders) are not
//     modelled.
//  3. Furniture OCCLUDES: every straight segment of every path (direct, each wall-reflection leg of
//     the unfolded image path, both legs of furniture reflections) is tested against every box
//     (slab test on the yawed box). An occluded segment is attenuated per band by single-edge
//     diffraction: Kurze–Anderson fit of Maekawa's chart, IL = 5 + 20·log10(√(2πN)/tanh√(2πN)) dB
//     (capped at 25 dB), Fresnel number N = 2δ·f_band/c, with δ the detour over the cheapest of
//     the four silhouette edges of the box seen across the segment (over the top, under, left,
//     right). No transmission through boxes.
//  4. Each arrival: amplitude 1/r (r = unfolded path length; the direct path at 1 m has amplitude
//     1), optional air absorption (ISO 9613-1 at 20 °C / 50 % RH, per band), source directivity
//     D(φ) applied with the DEPARTURE direction φ from the source's facing direction
//     (forward(yaw)): "omni" D = 1, "cardioid" D = f + (1 − f)(0.5 + 0.5 cos φ) with floor
//     f = cardioid_floor (frequency independent).
//  5. Rendering of the early part: every arrival is added at its exact fractional delay r/c
//     (windowed-sinc fractional delay of frac_delay_taps taps, quantised to 1/frac_delay_phases
//     sample) into 7 per-band buffers (per ear) with its 7 band amplitudes; a zero-phase octave
//     filter bank merges them: order-4 Butterworth crossovers at 177, 354, 707, 1414, 2828 and
//     5657 Hz, band_b = HP_0..HP_{b−1}·LP_b, run forward and backward so band b weighs the spectrum
//     by W_b(f) = |band_b(f)|² with Σ_b W_b(f) = 1 exactly. With equal band gains an arrival is an
//     exact (delayed) impulse; otherwise its spectrum is Σ_b gain_b W_b(f).
//     Binaural: each arrival is convolved with the KEMAR HRIR of the nearest measured direction of
//     its ARRIVAL direction in the head frame of the microphone (heading convention of scene.h;
//     no interpolation between measurements), with the SOFA file's Data.Delay if any. All HRIRs are
//     shifted by one common offset so that for a frontal source the ears' onsets (first sample
//     within 20 dB of the IR's peak, mean of both ears) fall at r/c; lateral sources keep their
//     interaural time and level differences around it. HRIRs are truncated to hrir_max_taps
//     with a short fade-out. Mono: an ideal omnidirectional microphone.
//  6. Late diffuse tail: per band, Gaussian noise whose energy envelope is the diffuse-field
//     estimate of the image-source density minus what the rendered images already carry,
//       e_b(t) = P_dir · (4π c / V) · exp(−13.8155 t / T60_b) · [1 − C(c t) · (1 − s̄)^(c t S / 4V)]
//     for t ≥ direct-path time (h² per second; the direct path at r has h² = 1/r²). 4πc/V · decay
//     is the expected energy of ALL image sources arriving at t; the bracket removes the expected
//     specular share that is rendered explicitly: (1 − s̄)^n is the specular (unscattered) fraction
//     after the mean number of reflections n = c t S / 4V (s̄ = area-weighted wall scattering), and
//     C(r) is the fraction of directions (512 fixed directions around the microphone) in which the
//     image at distance r still has order ≤ max_order. So the tail carries the scattered energy
//     from the start and takes over smoothly where the image set thins out (no energy hole after
//     max_order). T60_b is Eyring's with air absorption,
//       T60_b = 24 ln10 · V / (c · (−S ln(1 − ᾱ_b) + 4 m_b V)),
//     V = room volume − furniture volume, S = room surfaces + furniture faces (a box resting on the
//     floor hides its bottom face and the floor area under it), ᾱ_b = area-weighted absorption,
//     m_b = air energy attenuation (0 without air absorption). P_dir = mean of D² over the sphere
//     (1 for omni, ~0.37 for the cardioid with floor 0.1). The noise per band comes from long
//     band-limited Gaussian tables (white noise through the causal band filter, whose powers
//     |band_b|² sum to one; built once per simulator) read at a random offset with a random sign,
//     so a tail costs O(7·length) per ear. Binaural: each band is scaled by the diffuse-field
//     (direction-averaged) HRTF power of that ear and band; the two ears get partially correlated
//     noise with the interaural coherence of a diffuse field at the band centre, sinc(2π f d / c)
//     with d = head_diameter_m.
// NOT MODELLED: diffuse reflections as individual arrivals (scattering only feeds the tail), wave
// effects other than the edge diffraction of occluded segments (no room modes, no interference
// beyond what the image sum gives), frequency-dependent directivity, transmission through
// furniture, furniture in the late-tail geometry other than its area/volume, higher-order paths
// involving furniture, near-field HRTFs (KEMAR was measured at 1.4 m; below −40° elevation the
// lowest measurement is used), moving sources. Known bias: the explicit images of a shoebox decay
// slower than Eyring's diffuse estimate (axial paths hit few walls), so with a high max_order and
// little scattering the 40-150 ms region holds up to ~2 dB more energy than the tail model
// assumes. Distances below 0.1 m are clamped to 0.1 m for the 1/r amplitude.
//
// Determinism: the only randomness is the tail noise, seeded from (options.seed, a hash of the
// source and microphone pose); render() does not depend on thread count or call order.
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "neraf/geometry/vec.h"
#include "neraf/sim/hrtf.h"
#include "neraf/sim/scene.h"

namespace neraf::sim {

struct RirSimOptions {
  bool binaural = true;   // 2 channels (left, right) through `hrtf`; false: 1 omni channel
  uint64_t seed = 0;      // tail noise seed (mixed with the poses)
  bool late_tail = true;  // false: only the image-source / furniture arrivals (for tests)
  bool furniture_reflections = true;
  bool furniture_occlusion = true;
  bool air_absorption = true;
  double cardioid_floor = 0.1;    // "cardioid" directivity never falls below this amplitude
  double head_diameter_m = 0.18;  // only sets the interaural coherence of the binaural tail
  int hrir_max_taps = 256;        // HRIRs are truncated to this many taps (after onset trimming)
  int frac_delay_taps = 16;       // windowed-sinc fractional-delay length (even)
  int frac_delay_phases = 8;      // delays are quantised to 1/frac_delay_phases of a sample
};

// One propagation path (exposed for tests and diagnostics).
struct Arrival {
  double delay_s = 0;              // path length / speed of sound
  double distance_m = 0;           // unfolded path length
  std::array<double, 7> gain{};    // band amplitudes incl. 1/r, walls, air, directivity, occlusion
  geometry::Vec3 direction_world;  // unit, from the microphone towards where the sound comes from
  int order = 0;                   // number of reflections (furniture reflection = 1)
  bool furniture = false;          // a reflection off a furniture face
  bool occluded = false;           // at least one segment crossed a box
};

class RirSimulator {
 public:
  // Precomputes what depends only on the scene (materials per surface, Eyring decay per band, band
  // filters, tail noise tables, HRIR tables). `hrtf` may be null when binaural is false; it must
  // outlive the simulator otherwise, and its sample rate must equal `sample_rate`.
  // sample_rate e.g. 44100 (SoundSpaces) or 48000 (RAF). Throws neraf::Error on a scene it cannot
  // simulate (unknown material name, non-positive size, ...).
  RirSimulator(const Scene& scene, int sample_rate, const Hrtf* hrtf, RirSimOptions options = {});
  ~RirSimulator();
  RirSimulator(const RirSimulator&) = delete;
  RirSimulator& operator=(const RirSimulator&) = delete;

  // One RIR: returns [channels][rir_length_s * sample_rate] (2 channels binaural (left, right),
  // 1 mono). const + thread-safe so callers can run many RIRs in parallel with OpenMP.
  // Deterministic: the late-tail noise is seeded from (options.seed, a hash of the source/mic
  // pose). Source and microphone must lie inside the room (throws neraf::Error otherwise).
  std::vector<std::vector<float>> render(const Source& source, const geometry::Vec3& mic_position,
                                         double mic_yaw_deg) const;

  // The early arrivals render() uses (sorted by delay), for tests and diagnostics.
  std::vector<Arrival> arrivals(const Source& source, const geometry::Vec3& mic_position) const;

  // The Eyring T60 the late tail follows, per octave band (s) - for tests and `neraf info`.
  std::array<double, 7> eyring_t60() const;

  int sample_rate() const;
  int channels() const;
  int length_samples() const;  // round(rir_length_s · sample_rate)
  // True when `p` lies inside a furniture box (callers placing microphones may skip such points).
  bool inside_furniture(const geometry::Vec3& p) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace neraf::sim
