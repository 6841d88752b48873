#pragma once
// Deterministic random numbers for the synthetic scenes. The standard library's distributions are
// implementation-defined, so uniform and normal variates are computed here from mt19937_64 bits
// (same sequence on every platform), and per-pixel noise comes from a counter-based hash so that
// it does not depend on the order in which threads visit pixels.
#include <cmath>
#include <cstdint>
#include <random>

namespace ff::synth {

inline uint64_t splitmix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

inline uint64_t hashCombine(uint64_t a, uint64_t b) { return splitmix64(a ^ splitmix64(b)); }

// Uniform in the open interval (0, 1) from a key.
inline double hashUniform(uint64_t key) { return (static_cast<double>(splitmix64(key) >> 11) + 0.5) * 0x1.0p-53; }

// Approximately standard normal from a key: the Irwin-Hall sum of four 16-bit uniforms from one
// hash, standardised (bounded at +-3.46 sigma). Several times cheaper than Box-Muller, which
// matters for per-pixel sensor noise.
inline double hashNormal(uint64_t key) {
  const uint64_t h = splitmix64(key);
  const double sum = static_cast<double>((h & 0xffff) + ((h >> 16) & 0xffff) + ((h >> 32) & 0xffff) + (h >> 48));
  // Mean 4 * 32767.5, variance 4 * (65536^2 - 1) / 12.
  return (sum - 131070.0) * (1.0 / 37837.2);
}

class Rng {
 public:
  explicit Rng(uint64_t seed) : engine_(seed) {}
  // Uniform in [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // Uniform integer in [lo, hi].
  int uniformInt(int lo, int hi) {
    const int v = lo + static_cast<int>(uniform() * (hi - lo + 1));
    return v > hi ? hi : v;
  }
  bool chance(double p) { return uniform() < p; }
  double normal() {
    const double u1 = 1.0 - uniform();
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }
  double sign() { return uniform() < 0.5 ? -1.0 : 1.0; }

 private:
  std::mt19937_64 engine_;
};

}  // namespace ff::synth
