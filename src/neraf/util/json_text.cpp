#include "neraf/util/json_text.h"

#include <set>
#include <string>
#include <vector>

#include "neraf/util/error.h"

namespace neraf {

nlohmann::json parse_json(const std::string& text, const std::string& path,
                          const std::string& fix) {
  // A key given twice in one object is refused: the parser would keep the last one silently, so
  // a hand-edited file could mean something else than it reads.
  std::vector<std::set<std::string>> keys;  // of each open object
  std::string duplicate;
  const nlohmann::json::parser_callback_t check_keys = [&](int, nlohmann::json::parse_event_t event,
                                                           nlohmann::json& parsed) {
    using Event = nlohmann::json::parse_event_t;
    if (event == Event::object_start) keys.emplace_back();
    if (event == Event::object_end && !keys.empty()) keys.pop_back();
    if (event == Event::key && !keys.empty() &&
        !keys.back().insert(parsed.get<std::string>()).second && duplicate.empty())
      duplicate = parsed.get<std::string>();
    return true;
  };
  try {
    nlohmann::json value = nlohmann::json::parse(text, check_keys);
    require(duplicate.empty(),
            path + ": the key \"" + duplicate + "\" appears twice in one object; keep one of them");
    return value;
  } catch (const nlohmann::json::parse_error& e) {
    throw Error(path + ": not valid JSON (at byte " + std::to_string(e.byte) + "); " + fix);
  } catch (const nlohmann::json::out_of_range&) {  // the parser's only one: number overflow
    throw Error(path + ": a number in it is too large for a double (beyond ±1.8e308); " + fix);
  } catch (const nlohmann::json::exception&) {
    throw Error(path + ": not valid JSON; " + fix);
  }
}

std::string json_quoted(const std::string& text) {
  return nlohmann::json(text).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace neraf
