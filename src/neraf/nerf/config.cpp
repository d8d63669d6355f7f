#include "neraf/nerf/config.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include "neraf/util/error.h"

namespace neraf::nerf {

std::string to_string(Precision p) { return p == Precision::bf16 ? "bf16" : "fp32"; }

Precision parse_precision(const std::string& name, const std::string& where) {
  if (name == "fp32") return Precision::fp32;
  if (name == "bf16") return Precision::bf16;
  if (name == "auto") return default_precision();
  throw Error(where + ": unknown precision '" + name + "'; use fp32, bf16 or auto");
}

bool cpu_supports_bf16() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("flags", 0) != 0) continue;
    std::istringstream words(line);
    std::string w;
    while (words >> w)
      if (w == "avx512_bf16" || w == "amx_bf16") return true;
    return false;  // the first core's flags are representative
  }
  return false;
}

Precision default_precision() {
  static const bool has_bf16 = cpu_supports_bf16();  // immutable after first use
  return has_bf16 ? Precision::bf16 : Precision::fp32;
}

std::string to_string(CameraOptMode m) { return m == CameraOptMode::SO3xR3 ? "SO3xR3" : "off"; }

CameraOptMode parse_enum(CameraOptMode, const std::string& s, const std::string& where) {
  if (s == "off") return CameraOptMode::off;
  if (s == "SO3xR3") return CameraOptMode::SO3xR3;
  throw Error(where + ": unknown camera optimizer mode '" + s + "'; use off or SO3xR3");
}

std::vector<std::string> preset_names() { return {"cpu", "paper"}; }

ModelConfig model_preset(const std::string& name) {
  ModelConfig c;  // defaults = paper
  c.precision = default_precision();
  if (name == "paper") return c;
  if (name != "cpu") throw Error("--preset: unknown preset '" + name + "'; use cpu or paper");
  // cpu: the demo rooms are small and seen from inside at ~100 px, so a 2^17 table up to
  // resolution 512 already resolves the texture, and the proposal + nerf sample counts can be
  // lowered by about half without visible loss; the camera poses of simulated data are exact,
  // so the pose optimizer (which needs positional gradients through the hash grid) is off;
  // appearance embeddings start small (see FieldConfig::appearance_init_std).
  c.field.grid = HashGridConfig{16, 2, 17, 16, 512};
  c.proposal_nets = {ProposalNetConfig{{5, 2, 16, 16, 128}, 2, 16},
                     ProposalNetConfig{{5, 2, 16, 16, 256}, 2, 16}};
  c.sampler.proposal_samples = {128, 64};
  c.sampler.nerf_samples = 32;
  c.camera_opt.mode = CameraOptMode::off;
  c.field.appearance_init_std = 0.01;
  return c;
}

namespace {
void check_grid(const HashGridConfig& g, const std::string& where) {
  require(g.num_levels >= 1 && g.num_levels <= 32, where + ".num_levels: must be in 1..32");
  require(g.features_per_level == 1 || g.features_per_level == 2 || g.features_per_level == 4 ||
              g.features_per_level == 8,
          where + ".features_per_level: must be 1, 2, 4 or 8");
  require(g.log2_hashmap_size >= 4 && g.log2_hashmap_size <= 24,
          where + ".log2_hashmap_size: must be in 4..24");
  require(g.base_resolution >= 2, where + ".base_resolution: must be at least 2");
  require(g.max_resolution >= g.base_resolution,
          where + ".max_resolution: must be at least base_resolution");
}
}  // namespace

void validate(const ModelConfig& c, const std::string& where) {
  check_grid(c.field.grid, where + ".field.grid");
  require(c.field.num_layers >= 1, where + ".field.num_layers: must be at least 1");
  require(c.field.hidden_dim >= 1, where + ".field.hidden_dim: must be positive");
  require(c.field.geo_feat_dim >= 1, where + ".field.geo_feat_dim: must be positive");
  require(c.field.appearance_init_std >= 0 && std::isfinite(c.field.appearance_init_std),
          where + ".field.appearance_init_std: must be a number >= 0");
  require(c.field.num_layers_color >= 1, where + ".field.num_layers_color: must be at least 1");
  require(c.field.hidden_dim_color >= 1, where + ".field.hidden_dim_color: must be positive");
  require(c.field.appearance_dim >= 0, where + ".field.appearance_dim: must be >= 0");
  require(c.field.sh_degree >= 1 && c.field.sh_degree <= 4,
          where + ".field.sh_degree: must be in 1..4");
  require(c.field.average_init_density > 0, where + ".field.average_init_density: must be > 0");
  require(!c.proposal_nets.empty(), where + ".proposal_nets: need at least one proposal network");
  for (size_t i = 0; i < c.proposal_nets.size(); ++i) {
    const std::string w = where + ".proposal_nets[" + std::to_string(i) + "]";
    check_grid(c.proposal_nets[i].grid, w + ".grid");
    require(c.proposal_nets[i].num_layers >= 1, w + ".num_layers: must be at least 1");
    require(c.proposal_nets[i].hidden_dim >= 1, w + ".hidden_dim: must be positive");
  }
  require(c.sampler.proposal_samples.size() == c.proposal_nets.size(),
          where + ".sampler.proposal_samples: need one sample count per proposal network");
  for (int n : c.sampler.proposal_samples)
    require(n >= 2, where + ".sampler.proposal_samples: each count must be at least 2");
  require(c.sampler.nerf_samples >= 2, where + ".sampler.nerf_samples: must be at least 2");
  require(c.sampler.near_plane >= 0 && c.sampler.far_plane > c.sampler.near_plane,
          where + ".sampler: need 0 <= near_plane < far_plane");
  require(c.sampler.histogram_padding >= 0, where + ".sampler.histogram_padding: must be >= 0");
  require(c.sampler.pdf_eps > 0, where + ".sampler.pdf_eps: must be > 0");
  require(c.sampler.proposal_weights_anneal_max_num_iters >= 1,
          where + ".sampler.proposal_weights_anneal_max_num_iters: must be at least 1");
  require(c.sampler.proposal_update_every >= 0 && c.sampler.proposal_warmup >= 1,
          where + ".sampler: proposal_update_every must be >= 0 and proposal_warmup >= 1");
}

}  // namespace neraf::nerf
