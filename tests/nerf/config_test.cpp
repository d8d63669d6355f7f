#include "neraf/nerf/config.h"

#include <gtest/gtest.h>

#include "neraf/util/error.h"

using namespace neraf::nerf;

TEST(NerfConfig, PaperPresetIsNerfacto) {
  const ModelConfig c = model_preset("paper");
  EXPECT_EQ(c.field.grid.num_levels, 16);
  EXPECT_EQ(c.field.grid.log2_hashmap_size, 19);
  EXPECT_EQ(c.field.grid.max_resolution, 2048);
  EXPECT_EQ(c.field.hidden_dim, 64);
  EXPECT_EQ(c.field.geo_feat_dim, 15);
  EXPECT_EQ(c.field.appearance_dim, 32);
  EXPECT_DOUBLE_EQ(c.field.average_init_density, 0.01);
  ASSERT_EQ(c.proposal_nets.size(), 2u);
  EXPECT_EQ(c.proposal_nets[0].grid.max_resolution, 128);
  EXPECT_EQ(c.proposal_nets[1].grid.max_resolution, 256);
  EXPECT_EQ(c.proposal_nets[0].grid.log2_hashmap_size, 17);
  EXPECT_EQ(c.proposal_nets[0].hidden_dim, 16);
  EXPECT_EQ(c.sampler.proposal_samples, (std::vector<int>{256, 96}));
  EXPECT_EQ(c.sampler.nerf_samples, 48);
  EXPECT_DOUBLE_EQ(c.sampler.near_plane, 0.05);
  EXPECT_DOUBLE_EQ(c.sampler.far_plane, 1000.0);
  EXPECT_DOUBLE_EQ(c.loss.distortion_loss_mult, 0.002);
  EXPECT_EQ(c.camera_opt.mode, CameraOptMode::SO3xR3);
  EXPECT_NO_THROW(validate(c, "paper"));
  EXPECT_NO_THROW(validate(model_preset("cpu"), "cpu"));
  EXPECT_THROW(model_preset("gpu"), neraf::Error);
}

TEST(NerfConfig, JsonRoundTripIsExact) {
  for (const auto& name : preset_names()) {
    ModelConfig c = model_preset(name);
    c.precision = Precision::fp32;
    const nlohmann::json j = config_to_json(c);
    ModelConfig back = model_preset(name == "cpu" ? "paper" : "cpu");  // overlay onto another
    config_from_json(j, back, "test");
    EXPECT_EQ(config_to_json(back), j) << name;
    EXPECT_EQ(j["field"]["grid"]["num_levels"], 16);
    EXPECT_EQ(j["precision"], "fp32");
  }
}

TEST(NerfConfig, PartialJsonOverridesAndBadJsonIsAnError) {
  ModelConfig c = model_preset("paper");
  config_from_json(nlohmann::json::parse(R"({"sampler": {"nerf_samples": 24}})"), c, "x.json");
  EXPECT_EQ(c.sampler.nerf_samples, 24);
  EXPECT_EQ(c.sampler.proposal_samples, (std::vector<int>{256, 96}));
  try {
    config_from_json(nlohmann::json::parse(R"({"sampler": {"nerf_sample": 24}})"), c, "x.json");
    FAIL();
  } catch (const neraf::Error& e) {
    EXPECT_NE(std::string(e.what()).find("x.json.sampler.nerf_sample"), std::string::npos);
  }
  EXPECT_THROW(config_from_json(nlohmann::json::parse(R"({"precision": "fp8"})"), c, "x"),
               neraf::Error);
  EXPECT_THROW(config_from_json(nlohmann::json::parse(R"({"field": {"hidden_dim": 1.5}})"), c, "x"),
               neraf::Error);
  // An integer too large for its field (or written as 1e30) names the range, never wraps.
  for (const char* big :
       {R"({"field": {"hidden_dim": 1e30}})", R"({"field": {"hidden_dim": 3000000000}})",
        R"({"field": {"hidden_dim": -3000000000}})"}) {
    try {
      config_from_json(nlohmann::json::parse(big), c, "x.json");
      FAIL() << big;
    } catch (const neraf::Error& e) {
      EXPECT_NE(std::string(e.what()).find("x.json.field.hidden_dim: expected an integer from "),
                std::string::npos)
          << e.what();
    }
  }
  ModelConfig bad = model_preset("paper");
  bad.sampler.proposal_samples = {64};
  EXPECT_THROW(validate(bad, "bad"), neraf::Error);
}

TEST(NerfConfig, PrecisionParsing) {
  EXPECT_EQ(parse_precision("fp32"), Precision::fp32);
  EXPECT_EQ(parse_precision("bf16"), Precision::bf16);
  EXPECT_EQ(parse_precision("auto"), default_precision());
  EXPECT_THROW(parse_precision("half"), neraf::Error);
}
