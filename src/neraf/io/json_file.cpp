#include "neraf/io/json_file.h"

#include "neraf/io/atomic_file.h"
#include "neraf/util/error.h"

namespace neraf::io {

nlohmann::json read_json(const std::string& path) {
  const std::string text = read_text_file(path);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw Error(path + ": not valid JSON (at byte " + std::to_string(e.byte) + "); fix or regenerate the file");
  } catch (const nlohmann::json::exception& e) {  // e.g. out_of_range: a number beyond a double
    throw Error(path + ": not valid JSON (" + e.what() + "); fix or regenerate the file");
  }
}

void write_json_atomically(const std::string& path, const nlohmann::json& value, int indent) {
  write_text_atomically(path, value.dump(indent) + "\n");
}

}  // namespace neraf::io
