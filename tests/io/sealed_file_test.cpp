// Sealed payloads (checkpoints): every kind of damage is one error naming the file.
#include "neraf/io/sealed_file.h"

#include <gtest/gtest.h>

#include <string>

#include "neraf/util/error.h"

namespace neraf::io {
namespace {

std::string error_of(std::string_view file, uint32_t max_version = 1) {
  try {
    unseal(file, "NERAFTST", max_version, "x.pt");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(SealedFile, RoundTripAndLayout) {
  const std::string payload("PK\x03\x04 any bytes \0 here", 22);
  const std::string file = seal("NERAFTST", 1, payload);
  ASSERT_EQ(file.size(), kSealHeaderBytes + payload.size());
  EXPECT_EQ(file.substr(0, 8), "NERAFTST");
  EXPECT_EQ(static_cast<uint8_t>(file[8]), 1);   // version, little-endian
  EXPECT_EQ(static_cast<uint8_t>(file[16]), 22);  // payload size
  const Unsealed u = unseal(file, "NERAFTST", 1, "x.pt");
  EXPECT_EQ(u.version, 1u);
  EXPECT_EQ(u.payload, payload);
  // FNV-1a 64 of "a" (the published test vector).
  EXPECT_EQ(fnv1a64("a"), 0xaf63dc4c8601ec8cull);
}

TEST(SealedFile, DamageOfEveryKindIsNamed) {
  const std::string file = seal("NERAFTST", 2, std::string(1000, 'w'));
  EXPECT_NE(error_of(file.substr(0, file.size() - 1), 2).find("x.pt: truncated"),
            std::string::npos);
  EXPECT_NE(error_of(file.substr(0, 20), 2).find("x.pt: truncated"), std::string::npos);
  EXPECT_NE(error_of(file + "x", 2).find("truncated or extended"), std::string::npos);
  std::string flipped = file;
  flipped[500] ^= 0x01;
  EXPECT_NE(error_of(flipped, 2).find("x.pt: damaged (checksum"), std::string::npos);
  EXPECT_NE(error_of(file, 1).find("format version 2 is newer"), std::string::npos);
  EXPECT_NE(error_of("PK\x03\x04...").find("wrong magic"), std::string::npos);
  EXPECT_NE(error_of("").find("wrong magic"), std::string::npos);
  std::string reserved = file;
  reserved[12] = 0x40;  // found by fuzz/fuzz_sealed_file
  EXPECT_NE(error_of(reserved, 2).find("x.pt: damaged (the reserved"), std::string::npos);
  EXPECT_EQ(error_of(file, 2), "");
}

}  // namespace
}  // namespace neraf::io
