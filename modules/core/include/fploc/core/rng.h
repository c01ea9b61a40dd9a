// Seeded, portable random numbers: a given seed gives the same sequence on every platform and standard
// library (std::normal_distribution does not guarantee that). Two generators, each kept bit-exact for the
// results that depend on it:
//  - Rng: xoshiro256** seeded by splitmix64, Box-Muller normals (the simulator: scans, motion, worlds);
//  - PolarRng: std::mt19937_64 with nav2's pf_ran_gaussian (polar Box-Muller, one value used) (AMCL; nav2's
//    pf uses drand48() seeded from the clock, here the seed is given).
#pragma once
#include <cmath>
#include <cstdint>
#include <random>

namespace fploc {

inline uint64_t splitmix64(uint64_t& x) {
  uint64_t z = (x += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// Mixes several values into one seed (e.g. run seed, stream id, frame index).
inline uint64_t mix_seed(uint64_t a, uint64_t b, uint64_t c = 0) {
  uint64_t x = a ^ 0x6A09E667F3BCC909ull;
  uint64_t h = splitmix64(x);
  x ^= b * 0x9E3779B97F4A7C15ull + h;
  h ^= splitmix64(x);
  x ^= c * 0xC2B2AE3D27D4EB4Full + h;
  return splitmix64(x);
}

class Rng {
 public:
  explicit Rng(uint64_t seed = 1) { reseed(seed); }
  void reseed(uint64_t seed) {
    uint64_t x = seed;
    for (auto& v : s_) v = splitmix64(x);
    has_spare_ = false;
  }
  uint64_t next() {
    const uint64_t result = rotl(s_[1] * 5, 7) * 9;
    const uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }
  // Uniform in [0, 1).
  double uniform() { return double(next() >> 11) * 0x1.0p-53; }
  double uniform(double a, double b) { return a + (b - a) * uniform(); }
  // Standard normal.
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u = uniform();
    while (u <= 1e-300) u = uniform();
    const double v = uniform();
    const double r = std::sqrt(-2.0 * std::log(u));
    spare_ = r * std::sin(2.0 * M_PI * v);
    has_spare_ = true;
    return r * std::cos(2.0 * M_PI * v);
  }
  double normal(double sigma) { return sigma * normal(); }

 private:
  static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  uint64_t s_[4];
  double spare_ = 0;
  bool has_spare_ = false;
};

class PolarRng {
 public:
  explicit PolarRng(uint64_t seed = 1) : g_(seed) {}
  void seed(uint64_t s) { g_.seed(s); }
  // Uniform in [0, 1) with 53 random bits.
  double uniform() { return double(g_() >> 11) * 0x1.0p-53; }
  // Zero-mean normal with standard deviation sigma (nav2 pf_ran_gaussian: polar Box–Muller, one value used).
  double gaussian(double sigma) {
    double x1, x2, w;
    do {
      double r;
      do r = uniform();
      while (r == 0.0);
      x1 = 2.0 * r - 1.0;
      do r = uniform();
      while (r == 0.0);
      x2 = 2.0 * r - 1.0;
      w = x1 * x1 + x2 * x2;
    } while (w > 1.0 || w == 0.0);
    return sigma * x2 * std::sqrt(-2.0 * std::log(w) / w);
  }

 private:
  std::mt19937_64 g_;
};

}  // namespace fploc
