#pragma once
// Modes of a configuration (tracking policy, flow backend, ...) are enum classes that files and
// --set name by string. FLOWFUSION_CONFIG_ENUM gives an enum its names and the setting it
// belongs to; an unknown name is an InputError naming the setting and listing the valid names.
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "flowfusion/core/error.h"

namespace ff {

template <class E>
struct ConfigEnum;  // specialised by FLOWFUSION_CONFIG_ENUM: setting, names

template <class E>
std::string enumName(E value) {
  for (const auto& [v, name] : ConfigEnum<E>::names())
    if (v == value) return name;
  return std::to_string(static_cast<int>(value));
}

// "a, b or c"
template <class E>
std::string enumChoices() {
  std::string out;
  const auto& names = ConfigEnum<E>::names();
  for (size_t i = 0; i < names.size(); ++i)
    out += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i].second;
  return out;
}

template <class E>
E enumFromName(const std::string& name) {
  for (const auto& [v, n] : ConfigEnum<E>::names())
    if (n == name) return v;
  throw InputError(std::string(ConfigEnum<E>::setting) + " must be " + enumChoices<E>() + ", got '" +
                   name.substr(0, 80) + "'");
}

}  // namespace ff

// In namespace ff, after the enum: FLOWFUSION_CONFIG_ENUM(TrackingMode, "pipeline.tracking",
// {TrackingMode::FrameToFrame, "frame_to_frame"}, ...). An enum of a nested namespace (ff::synth)
// takes its names in namespace ff, FLOWFUSION_CONFIG_ENUM_NAMES(synth::E, ...), and its JSON in
// its own namespace, FLOWFUSION_CONFIG_ENUM_JSON(E), where the JSON library looks for it.
#define FLOWFUSION_CONFIG_ENUM_NAMES(E, SETTING, ...)                                    \
  template <>                                                                            \
  struct ConfigEnum<E> {                                                                 \
    static constexpr const char* setting = SETTING;                                      \
    static const std::vector<std::pair<E, std::string>>& names() {                       \
      static const std::vector<std::pair<E, std::string>> n = {__VA_ARGS__};             \
      return n;                                                                          \
    }                                                                                    \
  };
#define FLOWFUSION_CONFIG_ENUM_JSON(E)                                                   \
  inline void to_json(nlohmann::json& j, const E& e) { j = ::ff::enumName(e); }          \
  inline void from_json(const nlohmann::json& j, E& e) {                                 \
    if (!j.is_string())                                                                  \
      throw ::ff::InputError(std::string(::ff::ConfigEnum<E>::setting) + " must be a name: " + \
                             ::ff::enumChoices<E>());                                    \
    e = ::ff::enumFromName<E>(j.get<std::string>());                                     \
  }
#define FLOWFUSION_CONFIG_ENUM(E, SETTING, ...)      \
  FLOWFUSION_CONFIG_ENUM_NAMES(E, SETTING, __VA_ARGS__) \
  FLOWFUSION_CONFIG_ENUM_JSON(E)
