#include "neraf/util/json_text.h"

#include <gtest/gtest.h>

#include <string>

#include "neraf/util/error.h"

namespace neraf {
namespace {

TEST(JsonQuoted, EscapesControlCharacters) {
  EXPECT_EQ(json_quoted(std::string("a\0b\nc", 5)), "\"a\\u0000b\\nc\"");
  EXPECT_EQ(json_quoted(""), "\"\"");
}

TEST(JsonQuoted, KeepsShortStringsWhole) {
  const std::string s(kQuotedMaxBytes, 'x');
  EXPECT_EQ(json_quoted(s), "\"" + s + "\"");
}

TEST(JsonQuoted, CutsLongStringsAndSaysHowLong) {
  // G12: a 1 MB key made a 1 MB error line.
  const std::string q = json_quoted(std::string(1000000, 'k'));
  EXPECT_EQ(q, "\"" + std::string(kQuotedMaxBytes, 'k') + "\"… (1000000 characters)");
}

TEST(JsonQuoted, NeverCutsInsideAUtf8Character) {
  // "é" is 2 bytes: with one ASCII byte first, byte kQuotedMaxBytes falls inside a character.
  std::string s = "a";
  for (int i = 0; i < 300; ++i) s += "\xC3\xA9";
  const std::string q = json_quoted(s);
  std::string expected = "\"a";
  for (size_t i = 0; i < (kQuotedMaxBytes - 1) / 2; ++i) expected += "\xC3\xA9";
  EXPECT_EQ(q, expected + "\"… (301 characters)");
  EXPECT_EQ(q.find("\\ufffd"), std::string::npos);
  EXPECT_EQ(q.find("\xEF\xBF\xBD"), std::string::npos);  // no replacement character
}

TEST(JsonQuoted, InvalidUtf8IsReplacedNotThrown) {
  EXPECT_NO_THROW(json_quoted(std::string(500, '\x80')));
  EXPECT_NO_THROW(json_quoted("\xFF"));
}

TEST(ParseJson, DuplicateKeyMessageIsBounded) {
  const std::string key(100000, 'd');
  const std::string text = "{\"" + key + "\": 1, \"" + key + "\": 2}";
  try {
    parse_json(text, "f.json");
    FAIL() << "a key given twice was accepted";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("appears twice"), std::string::npos) << what;
    EXPECT_LT(what.size(), 400u) << what.substr(0, 400);
  }
}

}  // namespace
}  // namespace neraf
