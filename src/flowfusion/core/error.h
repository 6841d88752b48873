#pragma once
// Errors that reach the user: each names the file or setting at fault and what is wrong with it.
#include <cstdio>
#include <stdexcept>
#include <string>

namespace ff {

// Bad input (missing or corrupt files, inconsistent data, bad configuration). Executables print
// what() and exit non-zero; library code never prints.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// `text` (a user's line or value) for an error message: at most max_chars characters, bytes
// outside printable ASCII as \xNN, and the full length noted when it is cut.
inline std::string quoteForMessage(const std::string& text, size_t max_chars = 80) {
  std::string out;
  for (size_t i = 0; i < text.size() && i < max_chars; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    }
  }
  if (text.size() > max_chars) out += "... (" + std::to_string(text.size()) + " characters)";
  return out;
}

}  // namespace ff
