#include "fploc/matcher/imu_yaw.h"

#include <algorithm>
#include <cmath>

namespace fploc::matcher {

bool ImuYaw::add(int64_t utime, double gyro_z) {
  if (!std::isfinite(gyro_z)) return false;
  if (!s_.empty() && utime <= s_.back().first) return false;
  s_.emplace_back(utime, gyro_z);
  while (s_.size() > max_) s_.pop_front();
  return true;
}

std::optional<double> ImuYaw::integral(int64_t t0, int64_t t1, int64_t slack_us) const {
  if (s_.size() < 2 || t1 <= t0 || s_.front().first > t0 || s_.back().first < t1 - slack_us) return std::nullopt;
  // First sample at or before t0.
  auto it = std::upper_bound(s_.begin(), s_.end(), t0, [](int64_t t, const auto& e) { return t < e.first; });
  size_t i = size_t(std::max<std::ptrdiff_t>(1, it - s_.begin()));
  double sum = 0;
  for (; i < s_.size() && s_[i - 1].first < t1; ++i) {
    if (s_[i].first - s_[i - 1].first > max_hole_us_) return std::nullopt;  // samples lost: the rate is unknown there
    const int64_t a = std::max(s_[i - 1].first, t0), b = std::min(s_[i].first, t1);
    if (b > a) sum += 0.5 * (s_[i - 1].second + s_[i].second) * double(b - a) * 1e-6;
  }
  // Held past the last sample (within the slack).
  if (s_.back().first < t1) sum += s_.back().second * double(t1 - std::max(s_.back().first, t0)) * 1e-6;
  return sum;
}

std::optional<double> ImuYaw::mean_rate(int64_t t0, int64_t t1, int64_t slack_us) const {
  const auto i = integral(t0, t1, slack_us);
  if (!i) return std::nullopt;
  return *i / (double(t1 - t0) * 1e-6);
}

void ImuYaw::drop_before(int64_t utime) {
  while (s_.size() > 2 && s_[1].first < utime) s_.pop_front();
}

}  // namespace fploc::matcher