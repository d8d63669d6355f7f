// --cache-precision / a run's audio.cache_precision -> RirLoadOptions::half_precision.
#include <gtest/gtest.h>

#include <string>

#include "neraf/data/rir_set.h"
#include "neraf/util/error.h"

namespace neraf::data {
namespace {

TEST(CachePrecision, Fp32AndFp16) {
  EXPECT_FALSE(parse_cache_precision("fp32"));
  EXPECT_TRUE(parse_cache_precision("fp16"));
}

TEST(CachePrecision, AnythingElseNamesTheFlag) {
  for (const char* bad : {"", "float16", "FP16", "bf16", "fp8"}) {
    try {
      parse_cache_precision(bad, "config.json: audio.cache_precision");
      FAIL() << "accepted " << bad;
    } catch (const Error& e) {
      EXPECT_EQ(std::string(e.what()).rfind("config.json: audio.cache_precision: unknown", 0), 0u)
          << e.what();
      EXPECT_NE(std::string(e.what()).find("use fp32 or fp16"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace neraf::data
