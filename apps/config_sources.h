#pragma once
// `--config FILE` and `--set key=value` (repeatable), as every configurable command takes them:
// a configuration is its struct's defaults, then the file, then the overrides in order.
#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "flowfusion/core/config.h"

namespace ff::app {

struct ConfigSources {
  std::string file;
  std::vector<std::string> overrides;

  // `what` names the configuration in the help text, e.g. "SynthConfig".
  void addTo(CLI::App* cmd, const std::string& what) {
    cmd->add_option("--config", file, "JSON file with " + what + " settings (the config.json a run writes is one)");
    cmd->add_option("--set", overrides, "Override one setting, e.g. --set section.key=value (repeatable)");
  }

  // `extra` overrides (from dedicated flags) come after the --set ones.
  template <class Config>
  Config resolve(const Config& defaults, const std::vector<std::string>& extra = {}) const {
    std::vector<std::string> all = overrides;
    all.insert(all.end(), extra.begin(), extra.end());
    return resolveConfig(defaults, file, all);
  }
};

}  // namespace ff::app
