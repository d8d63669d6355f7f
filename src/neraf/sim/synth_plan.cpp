// plan_synthesis (synthesize.h): which pictures and RIRs a layout writes, without computing them.
#include "neraf/sim/layout_writers.h"
#include "neraf/sim/microphones.h"
#include "neraf/sim/seeded_random.h"
#include "neraf/sim/synthesize.h"
#include "neraf/util/error.h"

namespace neraf::sim {

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

}  // namespace neraf::sim
