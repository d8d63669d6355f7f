#pragma once
// Parsing JSON text strictly: errors name the file and say how to fix it.
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>

namespace neraf {

// JSON `text` read from `path`: neraf::Error naming `path` for a parse error (with its byte
// offset) or a key given twice in one object, followed by `fix` (what to do about it).
nlohmann::json parse_json(const std::string& text, const std::string& path,
                          const std::string& fix = "fix or regenerate the file");

// `text` in double quotes with JSON escapes ("a\u0000b"), for quoting a key or string of a user's
// file in a message: a NUL or newline in it would otherwise cut or split the one-line error.
// Text longer than kQuotedMaxBytes is cut to its first kQuotedMaxBytes bytes (never inside a UTF-8
// character) and followed by `… (N characters)`, so a huge key cannot make a huge message.
constexpr size_t kQuotedMaxBytes = 200;
std::string json_quoted(const std::string& text);

}  // namespace neraf
