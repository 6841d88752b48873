#pragma once
// Errors that reach the user: each names the file or setting at fault and what is wrong with it.
#include <stdexcept>
#include <string>

namespace ff {

// Bad input (missing or corrupt files, inconsistent data, bad configuration). Executables print
// what() and exit non-zero; library code never prints.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace ff
