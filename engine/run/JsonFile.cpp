#include "engine/run/JsonFile.h"

#include "cutters/Error.h"
#include "engine/run/Output.h"

#include <set>
#include <vector>

namespace engage {

nlohmann::json readJsonFile(const std::string& path) {
  using nlohmann::json;
  std::vector<std::set<std::string>> keys;  // of the objects open at this point
  std::string duplicate;
  const json::parser_callback_t noDuplicates = [&](int, json::parse_event_t event, json& parsed) {
    if (event == json::parse_event_t::object_start) keys.emplace_back();
    if (event == json::parse_event_t::object_end && !keys.empty()) keys.pop_back();
    if (event == json::parse_event_t::key &&
        !keys.back().insert(parsed.get<std::string>()).second && duplicate.empty())
      duplicate = parsed.get<std::string>();
    return true;
  };
  json doc;
  try {
    doc = json::parse(readFile(path), noDuplicates);
  } catch (const json::exception& e) {
    throw Error(path + ": not valid JSON: " + e.what());
  }
  if (!duplicate.empty())
    throw Error(path + ": the key \"" + duplicate + "\" is given twice in one object");
  return doc;
}

}  // namespace engage
