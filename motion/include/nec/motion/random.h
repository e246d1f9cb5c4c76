// The project's one seeded generator, for everything that must repeat on any
// machine and standard library (std:: distributions and std::shuffle differ
// between implementations): SplitMix64 and the few draws nec needs.
//
//   SplitMix64 random(mix64(seed ^ mix64(step)));   // an independent stream per (seed, step)
//   const double x = random.uniform(0.8, 1.2);
//   const uint64_t pick = random.below(candidates.size());
//   random.shuffle(candidates);
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace nec {

constexpr uint64_t kSplitMixGamma = 0x9E3779B97F4A7C15ull;  // SplitMix64's increment (golden ratio)

// SplitMix64's output function applied to x + gamma: spreads the bits of a
// value (a hash, a seed combined with an index) so nearby inputs give unrelated outputs.
inline uint64_t mix64(uint64_t x) {
  x += kSplitMixGamma;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

class SplitMix64 {
 public:
  explicit SplitMix64(uint64_t seed) : state_(seed) {}

  // 64 random bits.
  uint64_t next() {
    const uint64_t state = state_;
    state_ += kSplitMixGamma;
    return mix64(state);
  }
  // Uniform in [0, 1), 53 bits.
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  double uniform(double low, double high) { return low + (high - low) * uniform(); }
  // Uniform in [0, n) for n > 0 (modulo: a bias below n / 2^64).
  uint64_t below(uint64_t n) { return next() % n; }
  // Uniform in [low, high].
  int integer(int low, int high) { return low + static_cast<int>(below(static_cast<uint64_t>(high - low) + 1)); }
  bool chance(double probability) { return uniform() < probability; }
  // Fisher-Yates, the same order everywhere.
  template <typename T>
  void shuffle(std::vector<T>& items) {
    for (std::size_t i = items.size(); i > 1; --i) std::swap(items[i - 1], items[below(i)]);
  }

 private:
  uint64_t state_;
};

}  // namespace nec
