#include <algorithm>
#include <iostream>

#include "command.h"
#include "flowfusion/core/error.h"

namespace ff::app {
std::vector<CommandRegistration>& commandRegistry() {
  static std::vector<CommandRegistration> r;
  return r;
}
}  // namespace ff::app

int main(int argc, char** argv) {
  CLI::App app{"flowfusion: dynamic dense RGB-D SLAM based on optical flow (Zhang et al., ICRA 2020)"};
  app.require_subcommand(1);
  auto& registry = ff::app::commandRegistry();
  std::sort(registry.begin(), registry.end(),
            [](const auto& a, const auto& b) { return a.order_key < b.order_key; });
  for (const auto& r : registry) r.add(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const ff::app::ExitStatus& e) {
    return e.code;
  } catch (const ff::InputError& e) {
    std::cerr << "flowfusion: error: " << e.what() << '\n';
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "flowfusion: internal error: " << e.what() << '\n';
    return 3;
  }
  return 0;
}
