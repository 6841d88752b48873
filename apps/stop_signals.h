#pragma once
// SIGINT and SIGTERM as a request to stop after the current frame, for the subcommands that write
// a result frame by frame (`run`, `convert`): they check the flag between frames, write a result
// marked partial (summary.json "complete": false, with the reason) and exit with 128 + the signal,
// as a shell reports a process the signal ended.
#include <atomic>
#include <csignal>

namespace ff::app {

class StopSignals {
 public:
  // Installs the handlers; the destructor restores the default ones.
  StopSignals() {
    requested() = false;
    std::signal(SIGINT, onSignal);
    std::signal(SIGTERM, onSignal);
  }
  ~StopSignals() {
    std::signal(SIGINT, SIG_DFL);
    std::signal(SIGTERM, SIG_DFL);
  }
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

  // Set once a signal arrived; *reason() then says which ("interrupted (SIGINT)").
  const std::atomic<bool>* flag() const { return &requested(); }
  const char* const* reason() const { return &reasonText(); }
  // 130 after SIGINT, 143 after SIGTERM.
  int exitStatus() const { return 128 + signalNumber().load(); }

 private:
  static std::atomic<bool>& requested() {
    static std::atomic<bool> r{false};
    return r;
  }
  static std::atomic<int>& signalNumber() {
    static std::atomic<int> s{0};
    return s;
  }
  static const char*& reasonText() {
    static const char* text = nullptr;
    return text;
  }
  static void onSignal(int sig) {
    reasonText() = sig == SIGINT ? "interrupted (SIGINT)" : "terminated (SIGTERM)";
    signalNumber() = sig;
    requested() = true;
  }
};

}  // namespace ff::app
