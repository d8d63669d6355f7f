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
    require(duplicate.empty(), path + ": the key " + json_quoted(duplicate) +
                                   " appears twice in one object; keep one of them");
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
  auto quote = [](const std::string& s) {
    return nlohmann::json(s).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  };
  if (text.size() <= kQuotedMaxBytes) return quote(text);
  // A 1 MB key must not make a 1 MB error line: keep the start, which names it well enough. The
  // cut backs off to the start of a UTF-8 sequence (a continuation byte is 10xxxxxx), so a
  // character is never split into bytes the quoting would replace.
  size_t cut = kQuotedMaxBytes;
  // (At most 3 steps: a longer run of continuation bytes is invalid UTF-8, replaced anyway.)
  for (int i = 0; i < 3 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80; ++i) --cut;
  size_t characters = 0;
  for (const char c : text) characters += (static_cast<unsigned char>(c) & 0xC0) != 0x80;
  return quote(text.substr(0, cut)) + "… (" + std::to_string(characters) + " characters)";
}

}  // namespace neraf
