#pragma once
// Subcommands of the `flowfusion` executable register themselves here, one file each
// (apps/cmd_*.cpp), so the executable's main() needs no list of them.
#include <CLI/CLI.hpp>
#include <functional>
#include <string>
#include <vector>

namespace ff::app {

struct CommandRegistration {
  std::string order_key;  // sorts the help listing
  std::function<void(CLI::App&)> add;  // adds the subcommand and its callback
};

std::vector<CommandRegistration>& commandRegistry();

// Thrown by a subcommand that ends with a particular exit status after saying why (e.g. 130 for
// a run stopped by SIGINT).
struct ExitStatus {
  int code;
};

struct RegisterCommand {
  RegisterCommand(std::string order_key, std::function<void(CLI::App&)> add) {
    commandRegistry().push_back({std::move(order_key), std::move(add)});
  }
};

}  // namespace ff::app
