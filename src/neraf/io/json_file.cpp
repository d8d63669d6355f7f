#include "neraf/io/json_file.h"

#include <string>

#include "neraf/io/atomic_file.h"
#include "neraf/util/error.h"
#include "neraf/util/json_text.h"

namespace neraf::io {

nlohmann::json read_json(const std::string& path) { return parse_json(read_text_file(path), path); }

void write_json_atomically(const std::string& path, const nlohmann::json& value, int indent) {
  write_text_atomically(path, value.dump(indent) + "\n");
}

}  // namespace neraf::io
