#include "flowfusion/core/config.h"

#include <fstream>

#include "flowfusion/core/error.h"

namespace ff {

namespace {

void mergeAt(nlohmann::json& base, const nlohmann::json& patch, const std::string& source, const std::string& path) {
  if (!patch.is_object()) throw InputError(source + ": expected a JSON object at '" + path + "'");
  for (auto it = patch.begin(); it != patch.end(); ++it) {
    const std::string key = path.empty() ? it.key() : path + "." + it.key();
    if (!base.contains(it.key())) throw InputError(source + ": unknown setting '" + key + "'");
    nlohmann::json& dst = base[it.key()];
    const nlohmann::json& src = it.value();
    if (dst.is_object()) {
      mergeAt(dst, src, source, key);
    } else if (dst.is_number() && src.is_number() && !(dst.is_number_integer() && src.is_number_float())) {
      dst = src;
    } else if (dst.is_number_float() && src.is_number()) {
      dst = src.get<double>();
    } else if (dst.type() == src.type()) {
      dst = src;
    } else {
      throw InputError(source + ": setting '" + key + "' must be a " + std::string(dst.type_name()) + ", got " +
                       src.dump());
    }
  }
}

}  // namespace

void mergeConfig(nlohmann::json& base, const nlohmann::json& patch, const std::string& source) {
  mergeAt(base, patch, source, "");
}

void applyOverride(nlohmann::json& base, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError("--set '" + assignment + "': expected key.path=value");
  const std::string key = assignment.substr(0, eq);
  const std::string text = assignment.substr(eq + 1);
  nlohmann::json value = nlohmann::json::parse(text, nullptr, false);
  if (value.is_discarded()) value = text;
  // Build {"a": {"b": value}} from "a.b" and merge it, so the same checks apply.
  nlohmann::json patch = value;
  std::string rest = key;
  std::vector<std::string> parts;
  size_t pos;
  while ((pos = rest.find('.')) != std::string::npos) {
    parts.push_back(rest.substr(0, pos));
    rest = rest.substr(pos + 1);
  }
  parts.push_back(rest);
  for (auto it = parts.rbegin(); it != parts.rend(); ++it) patch = nlohmann::json{{*it, patch}};
  mergeAt(base, patch, "--set " + assignment, "");
}

nlohmann::json readJsonFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open configuration file");
  nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded()) throw InputError(path + ": not valid JSON");
  return j;
}

void writeJsonFile(const std::string& path, const nlohmann::json& j) {
  std::ofstream out(path);
  out << j.dump(2) << '\n';
  if (!out) throw InputError(path + ": cannot write");
}

}  // namespace ff
