#pragma once
// Configuration plumbing shared by every stage. Each stage has one struct with documented
// defaults and units, made (de)serialisable with NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT
// beside it. A resolved configuration is the defaults, then a JSON file, then "key.path=value"
// overrides from the command line; unknown keys and wrongly typed values are errors.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace ff {

// Merges `patch` into `base` in place. Every key in the patch must exist in base and keep its
// JSON type (numbers may change between integer and float). Throws InputError naming `source`
// and the key path.
void mergeConfig(nlohmann::json& base, const nlohmann::json& patch, const std::string& source);

// Applies one "a.b.c=value" override; value is parsed as JSON, else taken as a string.
void applyOverride(nlohmann::json& base, const std::string& assignment);

// Reads a JSON file (InputError naming the file on failure).
nlohmann::json readJsonFile(const std::string& path);
void writeJsonFile(const std::string& path, const nlohmann::json& j);

// Checks that converting the merged JSON `given` to the config struct kept every number: an
// integer that does not fit its field (4294967300 for an int, -1 for an unsigned) or a float
// beyond a float field's range is an InputError naming the setting.
void checkConverted(const nlohmann::json& given, const nlohmann::json& converted);

// Defaults -> file (if non-empty) -> overrides, then converted back to T. Conversion errors
// (a value that does not fit its field's type) are reported as InputError.
template <typename T>
T resolveConfig(const T& defaults, const std::string& file, const std::vector<std::string>& overrides) {
  nlohmann::json j = defaults;
  if (!file.empty()) mergeConfig(j, readJsonFile(file), file);
  for (const auto& o : overrides) applyOverride(j, o);
  T result = j.get<T>();
  checkConverted(j, nlohmann::json(result));
  return result;
}

}  // namespace ff
