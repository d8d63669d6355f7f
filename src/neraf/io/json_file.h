#pragma once
// JSON files with errors that name the file (and, for parse errors, the byte offset).
#include <nlohmann/json.hpp>
#include <string>

namespace neraf::io {

nlohmann::json read_json(const std::string& path);

void write_json_atomically(const std::string& path, const nlohmann::json& value, int indent = 2);

}  // namespace neraf::io
