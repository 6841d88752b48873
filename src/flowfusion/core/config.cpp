#include "flowfusion/core/config.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>

#include "flowfusion/core/atomic_file.h"
#include "flowfusion/core/error.h"

namespace ff {

namespace {

void mergeAt(nlohmann::json& base, const nlohmann::json& patch, const std::string& source, const std::string& path) {
  if (!patch.is_object()) throw InputError(source + ": expected a JSON object at '" + path + "'");
  for (auto it = patch.begin(); it != patch.end(); ++it) {
    const std::string key = path.empty() ? it.key() : path + "." + it.key();
    if (!base.contains(it.key())) throw InputError(source + ": unknown setting '" + quoteForMessage(key) + "'");
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
                       quoteForMessage(src.dump()));
    }
  }
}

bool sameNumber(const nlohmann::json& a, const nlohmann::json& b) {
  if (a.is_number_float() || b.is_number_float()) {
    // A float field rounds; only a value it cannot hold (beyond its range) changes more.
    const double x = a.get<double>(), y = b.get<double>();
    return std::isfinite(y) && std::abs(x - y) <= 1e-6 * std::max(std::abs(x), std::abs(y));
  }
  if (a.is_number_unsigned() && b.is_number_unsigned()) return a.get<std::uint64_t>() == b.get<std::uint64_t>();
  // Signed against signed or unsigned: equal only when both are representable as int64 and equal.
  const auto asSigned = [](const nlohmann::json& v, std::int64_t& out) {
    if (v.is_number_unsigned()) {
      const auto u = v.get<std::uint64_t>();
      if (u > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) return false;
      out = static_cast<std::int64_t>(u);
    } else {
      out = v.get<std::int64_t>();
    }
    return true;
  };
  std::int64_t x = 0, y = 0;
  return asSigned(a, x) && asSigned(b, y) && x == y;
}

void checkConvertedAt(const nlohmann::json& given, const nlohmann::json& converted, const std::string& path) {
  if (given.is_object() && converted.is_object()) {
    for (auto it = given.begin(); it != given.end(); ++it)
      if (converted.contains(it.key()))
        checkConvertedAt(it.value(), converted[it.key()], path.empty() ? it.key() : path + "." + it.key());
  } else if (given.is_number() && converted.is_number() && !sameNumber(given, converted)) {
    throw InputError("setting '" + path + "': " + quoteForMessage(given.dump()) +
                     " is out of range for this setting's type");
  }
}

}  // namespace

void checkConverted(const nlohmann::json& given, const nlohmann::json& converted) {
  checkConvertedAt(given, converted, "");
}

void mergeConfig(nlohmann::json& base, const nlohmann::json& patch, const std::string& source) {
  mergeAt(base, patch, source, "");
}

void applyOverride(nlohmann::json& base, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError("--set '" + quoteForMessage(assignment) + "': expected key.path=value");
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
  mergeAt(base, patch, "--set " + quoteForMessage(assignment), "");
}

nlohmann::json readJsonFile(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw InputError(path + ": is a folder, not a configuration file (give a JSON file such as a run's config.json)");
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open configuration file");
  nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded()) throw InputError(path + ": not valid JSON");
  return j;
}

void writeJsonFile(const std::string& path, const nlohmann::json& j) {
  writeFileAtomic(path, j.dump(2) + '\n', "JSON file");
}

}  // namespace ff
