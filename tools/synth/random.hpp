// Deterministic random numbers for scene generation.
//
// std::mt19937's output sequence is fixed by the standard, but the std::*_distribution
// classes are not (libstdc++ and libc++ turn the same bits into different numbers).
// Scenes must be identical everywhere for a given seed, so every draw below is built
// from raw 32-bit outputs with arithmetic written out here.
#pragma once
#include <cstdint>
#include <random>

namespace cs::synth {

class Random {
 public:
  explicit Random(uint32_t seed) : engine_(seed) {}

  // Uniform in [0, 1) with 53 random bits (two engine outputs).
  double unit() {
    const uint64_t high = engine_() >> 5;                            // 27 bits
    const uint64_t low = engine_() >> 6;                             // 26 bits
    return double((high << 26) | low) * (1.0 / 9007199254740992.0);  // / 2^53
  }
  double uniform(double lo, double hi) { return lo + (hi - lo) * unit(); }
  // Uniform integer in [lo, hi] (inclusive).
  int integer(int lo, int hi) {
    const int value = lo + int(unit() * double(hi - lo + 1));
    return value > hi ? hi : value;
  }
  bool chance(double probability) { return unit() < probability; }
  // A fresh 32-bit value, e.g. to seed a texture.
  uint32_t bits() { return uint32_t(engine_()); }

 private:
  std::mt19937 engine_;
};

}  // namespace cs::synth
