// Seeded random numbers for the particle filter. nav2's pf uses drand48() (seeded from the clock) and
// pf_ran_gaussian() (polar Box–Muller); here the same polar method draws from a seeded std::mt19937_64
// whose output sequence the C++ standard fixes, so a run is reproducible for a given seed on any platform.
#pragma once
#include <cmath>
#include <cstdint>
#include <random>

namespace fploc::amcl {

class Rng {
 public:
  explicit Rng(uint64_t seed = 1) : g_(seed) {}
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

}  // namespace fploc::amcl
