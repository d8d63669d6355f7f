// plan_synthesis (synthesize.h): which pictures and RIRs a layout writes, without computing them,
// and how big they are (estimate_synthesis, check_synthesis_size).
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "neraf/sim/layout_writers.h"
#include "neraf/sim/microphones.h"
#include "neraf/sim/seeded_random.h"
#include "neraf/sim/synthesize.h"
#include "neraf/util/error.h"

namespace neraf::sim {

namespace {

std::string gigabytes(double bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, bytes >= 1e9 ? "%.3g GB" : "%.3g MB",
                bytes >= 1e9 ? bytes / 1e9 : bytes / 1e6);
  return buf;
}

}  // namespace

SynthSize estimate_synthesis(const Scene& scene, const std::string& layout) {
  require(layout == "soundspaces" || layout == "raf",
          "--layout: unknown layout \"" + layout + "\"; use soundspaces or raf");
  const bool binaural = layout == "soundspaces";
  const int rate = binaural ? kSoundSpacesSampleRate : kRafSampleRate;
  SynthSize z;
  // Random positions: their count. The grid: its points (validate_scene bounds the grid before
  // they are made).
  z.microphones = scene.microphones.kind == "random"
                      ? int64_t{scene.microphones.random.count}
                      : static_cast<int64_t>(grid_microphone_positions(scene).size());
  z.headings = binaural ? static_cast<int64_t>(microphone_headings(scene).size()) : 1;
  z.sources = static_cast<int64_t>(scene.sources.size());
  z.rirs = z.microphones * z.headings * z.sources;
  z.channels = binaural ? 2 : 1;
  z.samples_per_rir = std::llround(scene.acoustics.rir_length_s * rate);
  z.images = int64_t{scene.cameras.train_count} + scene.cameras.eval_count;
  z.rir_bytes = double(z.rirs) * (44.0 + 4.0 * z.channels * double(z.samples_per_rir));
  z.image_bytes = double(z.images) * 3.0 * scene.cameras.width * scene.cameras.height;
  return z;
}

void check_synthesis_size(const Scene& scene, const std::string& layout, const std::string& origin,
                          const std::string& count_flags) {
  const SynthSize z = estimate_synthesis(scene, layout);
  if (z.rirs <= kMaxSynthRirs && z.total_bytes() <= kMaxSynthBytes) return;
  std::string counts = std::to_string(z.microphones) + " microphone position(s)";
  if (layout == "soundspaces") counts += " x " + std::to_string(z.headings) + " heading(s)";
  counts += " x " + std::to_string(z.sources) + " source(s) = " + std::to_string(z.rirs) + " RIRs";
  throw Error(origin + ": the dataset would be " + counts + ", about " +
              gigabytes(z.total_bytes()) + " (RIRs " + gigabytes(z.rir_bytes) + ", images " +
              gigabytes(z.image_bytes) + "); the limits are " + std::to_string(kMaxSynthRirs) +
              " RIRs and " + gigabytes(kMaxSynthBytes) + "; use fewer microphones (" +
              (count_flags.empty() ? "" : count_flags + ", ") +
              "microphones.*), sources or headings, a shorter acoustics.rir_length_s, or fewer "
              "or smaller camera images");
}

SynthPlan plan_synthesis(const Scene& scene, const std::string& layout, uint64_t seed) {
  SynthPlan plan;
  plan.layout = layout;
  if (layout == "soundspaces") {
    plan.sample_rate = kSoundSpacesSampleRate;
    plan.binaural = true;
  } else if (layout == "raf") {
    plan.sample_rate = kRafSampleRate;
    plan.binaural = false;
  } else {
    throw Error("--layout: unknown layout \"" + layout + "\"; use soundspaces or raf");
  }
  plan.microphones = microphone_positions(scene, seed);
  const int n_mics = static_cast<int>(plan.microphones.size());
  const int n_src = static_cast<int>(scene.sources.size());
  if (plan.binaural) {
    plan.headings_deg = microphone_headings(scene);
    for (double h : plan.headings_deg) {
      for (int r = 0; r < n_mics; ++r) {
        for (int s = 0; s < n_src; ++s) {
          RirJob job;
          // SoundSpaces numbers receivers and sources in one point list: sources follow the mics.
          job.name = soundspaces_rir_name(h, r, n_mics + s);
          job.file = "binaural_rirs/" + job.name + ".wav";
          job.source = s;
          job.microphone = r;
          job.mic_yaw_deg = h;
          plan.jobs.push_back(job);
        }
      }
    }
  } else {
    for (int s = 0; s < n_src; ++s) {
      for (int r = 0; r < n_mics; ++r) {
        RirJob job;
        job.name = raf_id(s * n_mics + r);
        job.file = "data/" + job.name + "/rir.wav";
        job.source = s;
        job.microphone = r;
        plan.jobs.push_back(job);
      }
    }
  }
  plan.train_cameras =
      place_cameras(scene, scene.cameras.train_count, derive_seed(seed, "cameras-train"));
  plan.eval_cameras =
      place_cameras(scene, scene.cameras.eval_count, derive_seed(seed, "cameras-eval"));
  return plan;
}

void check_sound_reaches_microphones(const Scene& scene, const SynthPlan& plan,
                                     const std::string& origin) {
  if (plan.jobs.empty()) return;
  double nearest = INFINITY;
  for (const RirJob& job : plan.jobs)
    nearest = std::min(nearest,
                       norm(scene.sources[job.source].position - plan.microphones[job.microphone]));
  const double travel_s = nearest / scene.acoustics.speed_of_sound;
  if (travel_s < scene.acoustics.rir_length_s) return;
  char buf[400];
  std::snprintf(buf, sizeof buf,
                ": every RIR would be silent: the nearest source and microphone are %.4g m apart, "
                "%.4g s at %.4g m/s, longer than acoustics.rir_length_s (%.4g s); lengthen "
                "acoustics.rir_length_s beyond %.4g s or bring the sources closer",
                nearest, travel_s, scene.acoustics.speed_of_sound, scene.acoustics.rir_length_s,
                travel_s);
  throw Error(origin + buf);
}

}  // namespace neraf::sim
